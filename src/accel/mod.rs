//! Acceleration: a BVH2 (whitted's binned SAH builder, or an obvhs preset) as compact nodes,
//! the triangles in BVH order, and the 8-wide collapse of the tree; the traversals of both.
//!
//! The traversals by tree and rays per call (every one returns `intersect1`'s hits bit for
//! bit; `crate::engine` names the engines built on them):
//!
//! | tree | 1 ray | 8 rays | 16 rays (AVX-512) |
//! |---|---|---|---|
//! | BVH2 (`Accel::nodes`) | `scalar`: `intersect1` (the reference) | `packet`: `intersect8` | `packet16`: `intersect16` |
//! | BVH8 (`Accel::wide`, `wide`) | `wide1`: `intersect_wide1`, `intersect_wide1_many` | `wide8` (`hybrid8`'s any hit); `wide1`: `intersect_wide8` (lane by lane) | `packet16::wide16` (`hybrid16`'s any hit, and closest hit in one octant) |
//! | BVH2, then BVH8 per lane | - | `hybrid8`'s closest hit (`packet`'s walk, `hand_off` the switch) | `packet16`: `intersect_hybrid16` |
//!
//! Each has its `occluded*` twin (any hit). Shared by all: the robustness constants and the
//! closest-hit rule (`robust`), the traversal stacks (`stack`), the SoA triangle columns
//! (`tri_soa`), the builders (`build`, `wide`).

pub mod build;
mod hand_off;
pub mod hybrid8;
pub mod packet;
pub mod packet16;
pub mod pages;
pub mod robust;
pub mod scalar;
mod stack;
pub mod tri_soa;
pub mod wide;
pub mod wide1;
mod wide8;

pub use hybrid8::{intersect_hybrid8, occluded_hybrid8};
pub use packet::{intersect8, occluded8};
pub use packet16::{intersect_hybrid16, intersect16, occluded_hybrid16, occluded16};
pub use robust::{
    BARY_SAFE, BOX_PAD, ORIGIN_LAST, SAFE_INV_TINY, SLAB_FAR_SCALE, nearer, safe_inv,
};
pub use scalar::{intersect1, occluded1};
pub use tri_soa::TriangleSoa;
pub use wide::Bvh8;
pub use wide1::{
    intersect_wide1, intersect_wide1_many, intersect_wide8, occluded_wide1, occluded_wide1_many,
    occluded_wide8,
};

use glam::Vec3;
use obvhs::aabb::Aabb;
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2};
use std::time::{Duration, Instant};

/// A BVH node: bounds, and either two children (`count == 0`: nodes `first`, `first + 1`)
/// or `count` triangles at SoA slots `first .. first + count`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct Node {
    /// Minimum corner of the box, padded outward by [`BOX_PAD`] (relative) plus `f32::MIN_POSITIVE`.
    pub min: [f32; 3],
    /// Triangles in the leaf; 0 marks an interior node.
    pub count: u32,
    /// Maximum corner of the box, padded like `min`.
    pub max: [f32; 3],
    /// Interior: index of the left child (the right is `first + 1`). Leaf: first SoA slot.
    pub first: u32,
}

/// BVH2 builders: whitted's own binned SAH (the default), or an obvhs preset.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BuildQuality {
    /// whitted's binned SAH builder (`build.rs`), the default: on the kitten subdivided
    /// three times (1.3M triangles) it builds in about 0.6x the time of obvhs's `fast_build`,
    /// and every engine traverses its tree faster (1.04-1.55x over the four bench workloads).
    #[default]
    Binned,
    /// obvhs `fast_build` (PLOC), the default before `Binned`.
    Fast,
    /// obvhs `medium_build`.
    Medium,
    /// obvhs `slow_build` without its spatial pre-splits, so each triangle stays in one leaf.
    Slow,
}

impl BuildQuality {
    /// Every builder, the default first.
    pub const ALL: [BuildQuality; 4] = [
        BuildQuality::Binned,
        BuildQuality::Fast,
        BuildQuality::Medium,
        BuildQuality::Slow,
    ];

    /// The name `whitted bench --quality` takes.
    pub fn name(self) -> &'static str {
        match self {
            BuildQuality::Binned => "binned",
            BuildQuality::Fast => "fast",
            BuildQuality::Medium => "medium",
            BuildQuality::Slow => "slow",
        }
    }
}

/// Everything traversal needs: nodes (root at 0) and the triangles in leaf order.
#[derive(Clone, Debug, Default)]
pub struct Accel {
    /// The BVH2, root at index 0; empty when built over no triangles.
    pub nodes: Vec<Node>,
    /// The triangles in leaf order; `tris.prim` maps a slot back to its input index.
    pub tris: TriangleSoa,
    /// Deepest root-to-leaf path (sizes traversal stacks).
    pub depth: usize,
    /// The same tree collapsed to 8-wide nodes with SoA triangle blocks (`wide.rs`).
    pub wide: Bvh8,
    /// Wall time of the whole build (BVH2, flattening, SoA, collapse).
    pub build_time: Duration,
    /// Time of the 8-wide collapse alone (planning the nodes, which runs beside the SoA
    /// layout, plus filling the blocks; part of `build_time`).
    pub collapse_time: Duration,
}

impl Accel {
    /// Bytes of everything traversal reads: the BVH2's nodes, the triangles' SoA columns, the
    /// wide tree with its blocks, and the hybrids' entry map.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>()
            + self.tris.bytes()
            + self.wide.bytes()
            + self.wide.entry.len() * size_of::<u32>()
    }

    /// Build over `tris` (each `[v0, v1, v2]`); hits report indices into `tris`.
    pub fn build(tris: &[[Vec3; 3]], quality: BuildQuality) -> Accel {
        let start = Instant::now();
        if tris.is_empty() {
            return Accel::default();
        }
        let (nodes, order) = match quality {
            BuildQuality::Binned => build::build_bvh2(tris),
            _ => obvhs_bvh2(tris, quality),
        };
        // Pad every box a little: a ray running exactly in a face plane of a box (direction
        // component 0, origin on the plane) then starts strictly inside that slab, and
        // rounding in the slab test can never drop a boundary hit.
        let nodes: Vec<Node> = nodes
            .into_iter()
            .map(|n| {
                let (lo, hi) = (Vec3::from(n.min), Vec3::from(n.max));
                let pad = BOX_PAD * lo.abs().max(hi.abs()).max_element() + f32::MIN_POSITIVE;
                Node {
                    min: (lo - pad).into(),
                    max: (hi + pad).into(),
                    ..n
                }
            })
            .collect();
        // The SoA layout and the wide tree's nodes need only the order and the binary tree:
        // built side by side, then the blocks' lanes filled from the SoA columns.
        let (tris, (depth, mut wide, plan_time)) = rayon::join(
            || TriangleSoa::new(tris, &order),
            || {
                let plan = Instant::now();
                let wide = Bvh8::plan(&nodes);
                (tree_depth(&nodes), wide, plan.elapsed())
            },
        );
        let fill = Instant::now();
        wide.fill(&tris);
        Accel {
            nodes,
            tris,
            depth,
            wide,
            build_time: start.elapsed(),
            collapse_time: plan_time + fill.elapsed(),
        }
    }
}

/// An obvhs BVH2 over `tris` as unpadded nodes and its triangle order.
fn obvhs_bvh2(tris: &[[Vec3; 3]], quality: BuildQuality) -> (Vec<Node>, Vec<u32>) {
    let aabbs: Vec<Aabb> = tris
        .iter()
        .map(|t| {
            let lo = t[0].min(t[1]).min(t[2]);
            let hi = t[0].max(t[1]).max(t[2]);
            Aabb::new(lo.into(), hi.into())
        })
        .collect();
    let params = match quality {
        BuildQuality::Binned | BuildQuality::Fast => BvhBuildParams::fast_build(),
        BuildQuality::Medium => BvhBuildParams::medium_build(),
        // slow_build enables spatial pre-splits, which need triangles, not boxes; keep
        // its search effort without splits so each triangle sits in exactly one leaf.
        BuildQuality::Slow => BvhBuildParams {
            pre_split: false,
            ..BvhBuildParams::slow_build()
        },
    };
    let bvh = build_bvh2(&aabbs, params, &mut Duration::default());
    let nodes = bvh
        .nodes
        .iter()
        .map(|n| Node {
            min: n.aabb.min.into(),
            max: n.aabb.max.into(),
            count: n.prim_count,
            first: n.first_index,
        })
        .collect();
    (nodes, bvh.primitive_indices)
}

/// Nodes on the deepest root-to-leaf path of a BVH2 (0 for an empty tree).
pub(crate) fn tree_depth(nodes: &[Node]) -> usize {
    if nodes.is_empty() {
        return 0;
    }
    let mut max = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((i, d)) = stack.pop() {
        max = max.max(d);
        let n = nodes[i];
        if n.count == 0 {
            stack.push((n.first as usize, d + 1));
            stack.push((n.first as usize + 1, d + 1));
        }
    }
    max
}
