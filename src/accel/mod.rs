//! Acceleration: an obvhs BVH2 flattened into compact nodes, and the triangles in BVH order.

pub mod hybrid8;
pub mod packet;
pub mod scalar;
pub mod tri_soa;
pub mod wide;
pub mod wide1;

pub use hybrid8::{intersect_hybrid8, occluded_hybrid8};
pub use packet::{intersect8, occluded8};
pub use scalar::{intersect1, occluded1};
pub use tri_soa::TriangleSoa;
pub use wide::Bvh8;
pub use wide1::{intersect_wide1, intersect_wide8, occluded_wide1, occluded_wide8};

use glam::Vec3;
use obvhs::aabb::Aabb;
use obvhs::{BvhBuildParams, bvh2::builder::build_bvh2};
use std::time::{Duration, Instant};

/// A BVH node: bounds, and either two children (`count == 0`: nodes `first`, `first + 1`)
/// or `count` triangles at SoA slots `first .. first + count`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C, align(32))]
pub struct Node {
    pub min: [f32; 3],
    pub count: u32,
    pub max: [f32; 3],
    pub first: u32,
}

/// obvhs build presets, fastest to slowest.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BuildQuality {
    /// The default since the 8-wide tree: its BVH2 builds ~25% faster than Medium's (kitten
    /// subdivided 3 times, one thread: 1.6-2.1 s against 2.1-2.8 s under load), and after the
    /// collapse the engines' speeds on it differ by less than the noise; build time is what
    /// users compare with Embree's MEDIUM.
    #[default]
    Fast,
    Medium,
    Slow,
}

/// Everything traversal needs: nodes (root at 0) and the triangles in leaf order.
#[derive(Clone, Debug, Default)]
pub struct Accel {
    pub nodes: Vec<Node>,
    pub tris: TriangleSoa,
    /// Deepest root-to-leaf path (sizes traversal stacks).
    pub depth: usize,
    /// The same tree collapsed to 8-wide nodes with SoA triangle blocks (`wide.rs`).
    pub wide: Bvh8,
    /// The whole build, and of that the 8-wide collapse.
    pub build_time: Duration,
    pub collapse_time: Duration,
}

impl Accel {
    /// Build over `tris` (each `[v0, v1, v2]`); hits report indices into `tris`.
    pub fn build(tris: &[[Vec3; 3]], quality: BuildQuality) -> Accel {
        let start = Instant::now();
        if tris.is_empty() {
            return Accel::default();
        }
        let aabbs: Vec<Aabb> = tris
            .iter()
            .map(|t| {
                let lo = t[0].min(t[1]).min(t[2]);
                let hi = t[0].max(t[1]).max(t[2]);
                Aabb::new(lo.into(), hi.into())
            })
            .collect();
        let params = match quality {
            BuildQuality::Fast => BvhBuildParams::fast_build(),
            BuildQuality::Medium => BvhBuildParams::medium_build(),
            // slow_build enables spatial pre-splits, which need triangles, not boxes; keep
            // its search effort without splits so each triangle sits in exactly one leaf.
            BuildQuality::Slow => BvhBuildParams {
                pre_split: false,
                ..BvhBuildParams::slow_build()
            },
        };
        let bvh = build_bvh2(&aabbs, params, &mut Duration::default());
        let nodes: Vec<Node> = bvh
            .nodes
            .iter()
            .map(|n| {
                // Pad every box a little: a ray running exactly in a face plane of a box
                // (direction component 0, origin on the plane) then starts strictly inside
                // that slab, and rounding in the slab test can never drop a boundary hit.
                let (lo, hi) = (Vec3::from(n.aabb.min), Vec3::from(n.aabb.max));
                let pad = BOX_PAD * lo.abs().max(hi.abs()).max_element() + f32::MIN_POSITIVE;
                Node {
                    min: (lo - pad).into(),
                    max: (hi + pad).into(),
                    count: n.prim_count,
                    first: n.first_index,
                }
            })
            .collect();
        let tris = TriangleSoa::new(tris, &bvh.primitive_indices);
        let depth = tree_depth(&nodes);
        let mut accel = Accel {
            nodes,
            tris,
            depth,
            wide: Bvh8::default(),
            build_time: Duration::ZERO,
            collapse_time: Duration::ZERO,
        };
        let collapse = Instant::now();
        accel.wide = Bvh8::collapse(&accel);
        accel.collapse_time = collapse.elapsed();
        accel.build_time = start.elapsed();
        accel
    }
}

fn tree_depth(nodes: &[Node]) -> usize {
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

/// Relative padding of node boxes (see `Accel::build`).
pub const BOX_PAD: f32 = 4.0 * f32::EPSILON;

/// Reciprocal direction for slab tests. A zero component becomes `±1e30` instead of `±inf`,
/// so `(bound - origin) * inv` is never `0 * inf = NaN` for a ray starting on a slab plane.
#[inline(always)]
pub fn safe_inv(d: f32) -> f32 {
    const TINY: f32 = 1e-30;
    1.0 / if d.abs() < TINY { TINY.copysign(d) } else { d }
}

/// Slab tests round; widen the far distance by `1 + 2 gamma(3)` (pbrt's bound) so a box is
/// never missed by a ray that hits a triangle on its boundary.
pub const SLAB_FAR_SCALE: f32 =
    1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);
