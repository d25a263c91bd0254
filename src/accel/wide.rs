//! The 8-wide BVH: the BVH2 (`build.rs`, or an obvhs preset) collapsed into nodes of up to 8 children whose boxes are
//! stored SoA (one ray meets all 8 boxes in one slab test), and leaves of SoA triangle blocks
//! (one ray against up to 8 triangles in lanes, with `hit_triangle1`'s arithmetic).
//!
//! Collapse (`Bvh8::collapse`), top down from the BVH2 root:
//! - a subtree of at most [`BLOCK`] triangles becomes one leaf block: testing 8 triangles in
//!   lanes costs what testing one does, so splitting such a subtree further only adds boxes
//!   (its SAH cost as one leaf, `C_block * A(node)`, is below any split's, `C_node * A(node) +
//!   C_block * (A(l) + A(r))`, whenever `C_block <= C_node`, which holds here);
//! - otherwise it becomes a node whose up to 8 children are chosen by dynamic programming
//!   over the binary tree (`Dp`, after Ylitie et al. 2017): per binary node and number of
//!   slots, the least SAH cost of its subtree as that many children, where a wide node costs
//!   its box's area (the chance that a random ray visits it) and leaves cost the same in
//!   every tree. This replaced the greedy step of Embree's wide builders (open the child of
//!   largest area until 8 children or only leaves remain): at 1.3M triangles 31% fewer
//!   nodes (6.05 children each against 4.46; the greedy made a node of every subtree of 9-16
//!   triangles) for 3% less node area, and in alternating bench runs `hybrid16` traced
//!   shadow rays 1.19x as fast (kitten 1.16x) and incoherent rays 1.05x, `wide1` 1.02-1.07x,
//!   in the same collapse time.
//!
//! Boxes are the BVH2's padded boxes (`Accel::build`), so every slab-test guarantee of the
//! binary tree holds for the wide one and both find the same hits.

use super::{Accel, Node, TriangleSoa};
use crate::simd::{F32x8, Vec3x8};
use rayon::prelude::*;

/// Children per node and triangles per leaf block.
pub const BLOCK: usize = 8;

/// A child reference with this bit set is a leaf: bits 0..28 the first block, bits 28..31
/// the number of blocks minus one. Otherwise it is an index into `Bvh8::nodes`.
pub const LEAF_BIT: u32 = 1 << 31;
const LEAF_BLOCKS_SHIFT: u32 = 28;
const LEAF_FIRST_MASK: u32 = (1 << LEAF_BLOCKS_SHIFT) - 1;

/// The first block and the block count of a leaf reference.
#[inline(always)]
pub fn leaf_blocks(r: u32) -> (usize, usize) {
    (
        (r & LEAF_FIRST_MASK) as usize,
        ((r & !LEAF_BIT) >> LEAF_BLOCKS_SHIFT) as usize + 1,
    )
}

/// A node (256 bytes, four cache lines): the boxes of up to 8 children, SoA (`min[axis]`
/// lane `i` = child `i`), their references, and per direction octant the order in which to
/// visit them (after Fuetterling et al. 2017, as tinybvh's `perm8`): `order[oct]` holds 8
/// slots of 3 bits, nearest first along the octant's diagonal, so traversal sorts nothing at
/// run time. The top byte of `order[0]` has bit `i` set when slot `i` is in use.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub struct Node8 {
    /// The children's boxes, SoA: `bounds[0][axis]` lane `i` is the minimum corner of child
    /// `i`, `bounds[1][axis]` its maximum corner (0 in unused slots). Corners are indexed (not
    /// named) so a ray picks each axis's near and far plane by a precomputed index.
    pub bounds: [[F32x8; 3]; 2],
    /// Reference per slot: a `nodes` index, or a leaf with [`LEAF_BIT`] set (see [`leaf_blocks`]).
    pub child: [u32; BLOCK],
    /// Per octant (bit `k` set: direction component `k` negative), 8 slot indices of 3 bits,
    /// nearest first, unused slots last; bits 24..32 of `order[0]` are the in-use mask.
    pub order: [u32; BLOCK],
}

/// Up to 8 triangles in lanes, as `hit_triangle1` reads them (`TriangleSoa`'s fields), then
/// their ids: 448 bytes, seven cache lines. A single-ray test reads the first six (`n`, `v0`
/// for the depth test, then `p1`, `p2`), and the ids' line only for a hit or a near-edge
/// lane; `|n|` is recomputed from `n` (`TriangleSoa::n_len` is `n.length()`, the same
/// float). Unused lanes have `n = 0` (and `v0 = p1 = p2 = 0`): their plane test is
/// `0 / 0 = NaN`, which fails the depth test, so they never hit (culled too: `<d, 0> >= 0`).
///
/// The ids sit in the block's last line rather than in an array of their own: at 1.3M
/// triangles, where the blocks come from L3, `wide1` ran 1.02-1.06x on hits, shadow and
/// incoherent rays that way (three alternating bench runs; kitten level), the hit's line
/// being one line past the lines just read instead of a miss of its own.
#[derive(Clone, Copy, Debug, Default)]
#[repr(C, align(64))]
pub struct TriBlock8 {
    /// Unnormalised normal per lane (`TriangleSoa::n`; 0 in unused lanes and degenerate triangles).
    pub n: Vec3x8,
    /// First vertex per lane.
    pub v0: Vec3x8,
    /// Barycentric form of `v1`'s weight per lane (`TriangleSoa::p1`).
    pub p1: Vec3x8,
    /// Barycentric form of `v2`'s weight per lane (`TriangleSoa::p2`).
    pub p2: Vec3x8,
    /// Original triangle index per lane (`u32::MAX` in unused lanes).
    pub prim: [u32; BLOCK],
    /// SoA slot in `Accel::tris` per lane (for the f64 edge test).
    pub slot: [u32; BLOCK],
}

impl TriBlock8 {
    /// `|n|` per lane, computed as `TriangleSoa::new` computes `n_len` (`n.length()`: the same
    /// products, sums and square root), so it is the same float.
    #[inline(always)]
    pub fn n_len(&self) -> F32x8 {
        self.n.dot(self.n).sqrt()
    }

    /// Triangles in the block (lanes in use, which come first).
    pub fn triangles(&self) -> usize {
        self.prim.iter().filter(|&&p| p != u32::MAX).count()
    }
}
/// The wide tree: `nodes[0]` is the root (absent for an empty scene), leaves in `blocks`.
#[derive(Clone, Debug, Default)]
pub struct Bvh8 {
    /// Wide nodes, root at 0; children are referenced by index (`Node8::child`).
    pub nodes: Vec<Node8>,
    /// Triangle blocks; a leaf is a run of consecutive blocks.
    pub blocks: Vec<TriBlock8>,
    /// Deepest root-to-leaf path in nodes (sizes traversal stacks).
    pub depth: usize,
    /// Per binary node, the wide reference of the same subtree ([`NO_ENTRY`] for binary
    /// nodes that were opened into a wide node's children): where a hybrid packet hands its
    /// remaining lanes to single-ray traversal.
    pub entry: Vec<u32>,
    /// Slots of the leaf being made (reused from leaf to leaf while collapsing).
    scratch: Vec<u32>,
    /// Per block, the SoA slots of its triangles (`u32::MAX` past them), recorded by
    /// [`Bvh8::plan`] and turned into `blocks` by [`Bvh8::fill`].
    pending: Vec<[u32; BLOCK]>,
}

/// `Bvh8::entry` of a binary node without a wide twin.
pub const NO_ENTRY: u32 = LEAF_BIT - 1;

impl Bvh8 {
    /// Collapse `accel`'s binary tree (see the module header): [`Bvh8::plan`], then
    /// [`Bvh8::fill`] from its triangles.
    pub fn collapse(accel: &Accel) -> Bvh8 {
        let mut out = Bvh8::plan(&accel.nodes);
        out.fill(&accel.tris);
        out
    }

    /// The wide nodes over the binary tree `nodes` (padded boxes), and per block the SoA
    /// slots of its triangles: it needs no triangle data, so `Accel::build` runs it beside
    /// the SoA layout, then [`Bvh8::fill`] makes the blocks.
    pub fn plan(nodes: &[Node]) -> Bvh8 {
        let mut out = Bvh8::default();
        if nodes.is_empty() {
            return out;
        }
        let counts = subtree_counts(nodes);
        let dp = Dp::new(nodes, &counts);
        let src = Src { nodes, counts, dp };
        out.entry = vec![NO_ENTRY; nodes.len()];
        out.nodes.reserve(nodes.len() / 4 + 1);
        out.pending.reserve(src.counts[0] as usize / 4 + 1);
        super::pages::advise_huge(&out.nodes);
        let root = &nodes[0];
        if src.counts[0] as usize <= BLOCK || root.count > 0 {
            // The whole scene is one leaf: a root node with a single child.
            out.nodes.push(Node8::default());
            let leaf = out.leaf(&src, 0);
            out.nodes[0].set_child(0, root, leaf);
            out.nodes[0].set_order(1);
            out.depth = 1;
            out.entry[0] = 0;
        } else {
            out.depth = out.node(&src, 0, 1);
        }
        out
    }

    /// Make the blocks from the slots [`Bvh8::plan`] recorded: each block's ids and its
    /// triangles' lanes from `t`, blocks in parallel on rayon's current pool. The blocks'
    /// array is first written here, so its fresh pages are faulted in by every thread of the
    /// pool, not by the collapse's one (kitten on two threads, six builds per process, seven
    /// processes alternating: best 2.54-2.83 ms and median 2.73-2.98 against 2.73-3.86 and
    /// 3.14-4.43 when the collapse wrote the ids; one thread and 1.3M triangles level). Once
    /// the blocks are made, a further call changes nothing.
    pub fn fill(&mut self, t: &TriangleSoa) {
        if self.pending.is_empty() {
            return;
        }
        let pending = std::mem::take(&mut self.pending);
        let mut blocks = Vec::with_capacity(pending.len());
        super::pages::advise_huge(&blocks);
        // (each block written once, by the thread that fills it: the pages are first
        // touched here, on every thread of the pool, not in the serial collapse)
        pending
            .par_iter()
            .with_min_len(256)
            .map(|slots| TriBlock8::of_slots(slots, t))
            .collect_into_vec(&mut blocks);
        self.blocks = blocks;
    }

    /// Bytes of the tree and its blocks (the triangles' hot layout).
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node8>() + self.blocks.len() * size_of::<TriBlock8>()
    }

    /// Make the wide node for binary node `b` (not a leaf) and its subtree; returns the depth
    /// below and including it.
    fn node(&mut self, src: &Src, b: usize, depth: usize) -> usize {
        let me = self.nodes.len();
        self.nodes.push(Node8::default());
        self.entry[b] = me as u32;
        // the binary nodes the programme chose as children
        let mut kids = [0usize; BLOCK];
        let mut len = 0;
        let first = src.nodes[b].first as usize;
        let k = src.dp.split[b] as usize;
        for (c, slots) in [(first, k), (first + 1, BLOCK - k)] {
            src.dp.expand(src.nodes, c, slots, &mut |c| {
                kids[len] = c;
                len += 1;
            });
        }
        let mut deepest = depth;
        for (slot, &k) in kids[..len].iter().enumerate() {
            let r = if src.is_leaf(k) {
                self.leaf(src, k)
            } else {
                let r = self.nodes.len() as u32;
                deepest = deepest.max(self.node(src, k, depth + 1));
                r
            };
            self.nodes[me].set_child(slot, &src.nodes[k], r);
        }
        self.nodes[me].set_order(len);
        deepest
    }

    /// Blocks for all triangles below binary node `b`; returns the leaf reference.
    fn leaf(&mut self, src: &Src, b: usize) -> u32 {
        let mut slots = std::mem::take(&mut self.scratch);
        slots.clear();
        slots.reserve(src.counts[b] as usize);
        collect_slots(src.nodes, b, &mut slots);
        let first = self.pending.len();
        for chunk in slots.chunks(BLOCK) {
            let mut lanes = [u32::MAX; BLOCK];
            lanes[..chunk.len()].copy_from_slice(chunk);
            self.pending.push(lanes);
        }
        self.scratch = slots;
        let n = self.pending.len() - first;
        let r = LEAF_BIT | ((n as u32).saturating_sub(1) << LEAF_BLOCKS_SHIFT) | first as u32;
        self.entry[b] = r;
        assert!(
            (1..=8).contains(&n) && first <= LEAF_FIRST_MASK as usize,
            "leaf of {n} blocks at {first}: the BVH2 leaf size or scene cap changed"
        );
        r
    }
}

impl Node8 {
    fn set_child(&mut self, slot: usize, box_: &Node, r: u32) {
        let [lo, hi]: &mut [[[f32; BLOCK]; 3]; 2] = wide::bytemuck::cast_mut(&mut self.bounds);
        for ((lo, hi), (min, max)) in lo.iter_mut().zip(hi).zip(box_.min.iter().zip(&box_.max)) {
            (lo[slot], hi[slot]) = (*min, *max);
        }
        self.child[slot] = r;
    }

    /// The per-octant visiting orders of the first `n` slots, and the in-use bits.
    fn set_order(&mut self, n: usize) {
        let b: &[[[f32; BLOCK]; 3]; 2] = wide::bytemuck::cast_ref(&self.bounds);
        let mut centre = [[0f32; 3]; BLOCK];
        for (i, c) in centre.iter_mut().enumerate().take(n) {
            *c = [0, 1, 2].map(|k| b[0][k][i] + b[1][k][i]);
        }
        for oct in 0..8 {
            // octant bit k set: the direction's component k is negative; the key is the
            // centre's distance along the octant's diagonal (summed in axis order).
            let sign = |k: usize| if oct >> k & 1 == 1 { -1.0 } else { 1.0 };
            let mut key = [0f32; BLOCK];
            for (key, c) in key.iter_mut().zip(&centre).take(n) {
                *key = c[0] * sign(0) + c[1] * sign(1) + c[2] * sign(2);
            }
            // each slot's rank in a stable sort by key (ties keep slot order), unused slots
            // last: as integers ordered like `total_cmp`, every pair compared, no branches.
            let ikey: [i32; BLOCK] = std::array::from_fn(|i| {
                if i < n {
                    let b = key[i].to_bits() as i32;
                    b ^ (((b >> 31) as u32) >> 1) as i32
                } else {
                    i32::MAX
                }
            });
            let mut order = 0u32;
            for i in 0..BLOCK {
                let rank = (0..BLOCK)
                    .map(|j| u32::from(ikey[j] < ikey[i] || (ikey[j] == ikey[i] && j < i)))
                    .sum::<u32>();
                order |= (i as u32) << (3 * rank);
            }
            self.order[oct] = order;
        }
        self.order[0] |= ((1u32 << n) - 1) << 24;
    }

    /// Bit `i` set when child slot `i` holds a leaf (unused slots hold 0, not leaves).
    #[inline(always)]
    pub fn leaves(&self) -> u32 {
        let refs: F32x8 = wide::bytemuck::cast(self.child);
        crate::simd::bitmask(refs)
    }

    /// Bit `i` set when child slot `i` is in use.
    #[inline(always)]
    pub fn valid(&self) -> u32 {
        self.order[0] >> 24
    }
}

impl TriBlock8 {
    /// The block of the triangles at `slots` (at most 8; an entry `u32::MAX` ends them):
    /// their ids, then their lanes from `t`.
    fn of_slots(slots: &[u32], t: &TriangleSoa) -> TriBlock8 {
        let mut block = TriBlock8 {
            prim: [u32::MAX; BLOCK],
            ..TriBlock8::default()
        };
        for (j, &sl) in slots.iter().take_while(|&&sl| sl != u32::MAX).enumerate() {
            (block.prim[j], block.slot[j]) = (t.prim[sl as usize], sl);
        }
        block.fill(t);
        block
    }

    /// The lanes of the triangles at the slots recorded in `slot` (lanes past the
    /// triangles stay 0).
    fn fill(&mut self, t: &TriangleSoa) {
        let len = self.triangles();
        let slots = &self.slot[..len];
        // (whitted's builder: a subtree's triangles are consecutive slots, copied as runs)
        let contiguous = slots.windows(2).all(|w| w[1] == w[0] + 1);
        let fields = [&mut self.n, &mut self.v0, &mut self.p1, &mut self.p2];
        for (field, src) in fields.into_iter().zip([&t.n, &t.v0, &t.p1, &t.p2]) {
            for (axis, column) in [&mut field.x, &mut field.y, &mut field.z]
                .into_iter()
                .zip(src)
            {
                let lanes: &mut [f32; BLOCK] = wide::bytemuck::cast_mut(axis);
                if contiguous && len > 0 {
                    let s0 = slots[0] as usize;
                    lanes[..len].copy_from_slice(&column[s0..s0 + len]);
                } else {
                    for (lane, &sl) in lanes.iter_mut().zip(slots) {
                        *lane = column[sl as usize];
                    }
                }
            }
        }
    }
}

/// What the collapse reads: the binary tree and the triangles below each binary node.
struct Src<'a> {
    nodes: &'a [Node],
    counts: Vec<u32>,
    dp: Dp,
}

/// [`Dp::pick`]: the binary node itself is the child (a leaf, or a wide node of its own).
const ITSELF: u8 = 0;
/// [`Dp::pick`]: as with one slot fewer.
const FEWER: u8 = u8::MAX;

/// The collapse's choice of children by dynamic programming over the binary tree (Ylitie et
/// al. 2017), minimising the SAH cost: per binary node `b` and `i + 1` slots, the least cost
/// of its subtree as at most `i + 1` children of one wide node.
struct Dp {
    /// `cost[b][i]`: the least cost with at most `i + 1` slots.
    cost: Vec<[f32; BLOCK]>,
    /// How `cost[b][i]` is reached: [`ITSELF`], [`FEWER`], or `k` (`k` slots to the left
    /// child, `i + 1 - k` to the right).
    pick: Vec<[u8; BLOCK]>,
    /// For a binary node that becomes a wide node: slots of its left child (of 8).
    split: Vec<u8>,
}

impl Dp {
    fn new(nodes: &[Node], counts: &[u32]) -> Dp {
        let n = nodes.len();
        let mut dp = Dp {
            cost: vec![[0.0; BLOCK]; n],
            pick: vec![[ITSELF; BLOCK]; n],
            split: vec![0; n],
        };
        if n == 0 {
            return dp;
        }
        let mut stack = vec![(0usize, false)];
        while let Some((b, children_done)) = stack.pop() {
            let node = &nodes[b];
            let f = node.first as usize;
            if becomes_leaf(node, counts[b]) {
                // a leaf whatever the choice above it: its blocks' cost is the same in every
                // tree, so it is left out (cost 0).
                continue;
            }
            if !children_done {
                stack.extend([(b, true), (f, false), (f + 1, false)]);
                continue;
            }
            let (l, r) = (dp.cost[f], dp.cost[f + 1]);
            // best split of j slots (j = 2..=8) between the children
            let mut best = [(f32::INFINITY, 0u8); BLOCK + 1];
            for (j, best) in best.iter_mut().enumerate().skip(2) {
                for k in 1..j {
                    let c = l[k - 1] + r[j - k - 1];
                    if c < best.0 {
                        *best = (c, k as u8);
                    }
                }
            }
            let a = area(node);
            let mut cost = [0f32; BLOCK];
            let mut pick = [ITSELF; BLOCK];
            cost[0] = a + best[BLOCK].0;
            for i in 1..BLOCK {
                let (c, k) = best[i + 1];
                (cost[i], pick[i]) = if c < cost[i - 1] {
                    (c, k)
                } else {
                    (cost[i - 1], FEWER)
                };
            }
            dp.cost[b] = cost;
            dp.pick[b] = pick;
            dp.split[b] = best[BLOCK].1;
        }
        dp
    }

    /// The children that binary node `b` becomes with `slots` slots, in order.
    fn expand(&self, nodes: &[Node], b: usize, slots: usize, out: &mut impl FnMut(usize)) {
        match self.pick[b][slots - 1] {
            ITSELF => out(b),
            FEWER => self.expand(nodes, b, slots - 1, out),
            k => {
                let f = nodes[b].first as usize;
                self.expand(nodes, f, k as usize, out);
                self.expand(nodes, f + 1, slots - k as usize, out);
            }
        }
    }
}

/// Whether a binary node with `count` triangles below it becomes one wide leaf (a binary
/// leaf, or at most a block).
fn becomes_leaf(node: &Node, count: u32) -> bool {
    node.count > 0 || count as usize <= BLOCK
}

impl Src<'_> {
    /// Whether binary node `b` becomes one wide leaf ([`becomes_leaf`]).
    fn is_leaf(&self, b: usize) -> bool {
        becomes_leaf(&self.nodes[b], self.counts[b])
    }
}

/// Half the surface area of a node's box (the SAH weight; the factor 2 does not matter).
fn area(n: &Node) -> f32 {
    let e = [0, 1, 2].map(|k| (n.max[k] - n.min[k]).max(0.0));
    e[0] * e[1] + e[1] * e[2] + e[2] * e[0]
}

/// Triangles below each binary node (post-order, explicit stack: obvhs does not promise
/// that children follow their parent in the array).
fn subtree_counts(nodes: &[Node]) -> Vec<u32> {
    let mut counts = vec![0u32; nodes.len()];
    let mut stack = vec![(0usize, false)];
    while let Some((i, children_done)) = stack.pop() {
        let n = &nodes[i];
        let f = n.first as usize;
        if n.count > 0 {
            counts[i] = n.count;
        } else if children_done {
            counts[i] = counts[f] + counts[f + 1];
        } else {
            stack.extend([(i, true), (f, false), (f + 1, false)]);
        }
    }
    counts
}

fn collect_slots(nodes: &[Node], b: usize, out: &mut Vec<u32>) {
    let n = &nodes[b];
    if n.count > 0 {
        out.extend(n.first..n.first + n.count);
    } else {
        collect_slots(nodes, n.first as usize, out);
        collect_slots(nodes, n.first as usize + 1, out);
    }
}

/// The wide tree taken from obvhs's compressed wide BVH instead of our collapse: its child
/// boxes dequantized (and padded as `Accel::build` pads, so they stay conservative) and its
/// leaves (at most 3 triangles each, obvhs's cap for CWBVH) as blocks. Kept to measure the two
/// ways of building the tree against each other (`tests/measure.rs`, README "Engines");
/// `entry` is left empty, so hybrid packets never switch on it.
pub fn from_cwbvh(accel: &Accel, cw: &obvhs::cwbvh::CwBvh) -> Bvh8 {
    let mut slot_of = vec![0u32; accel.tris.len()];
    for (slot, &p) in accel.tris.prim.iter().enumerate() {
        slot_of[p as usize] = slot as u32;
    }
    let mut out = Bvh8 {
        nodes: vec![Node8::default(); cw.nodes.len()],
        ..Bvh8::default()
    };
    for (i, n) in cw.nodes.iter().enumerate() {
        let mut k = 0;
        for c in 0..BLOCK {
            if n.is_child_empty(c) {
                continue;
            }
            let b = n.child_aabb(c);
            let (lo, hi) = (glam::Vec3::from(b.min), glam::Vec3::from(b.max));
            let pad = super::BOX_PAD * lo.abs().max(hi.abs()).max_element() + f32::MIN_POSITIVE;
            let bx = Node {
                min: (lo - pad).into(),
                max: (hi + pad).into(),
                count: 0,
                first: 0,
            };
            let r = if n.is_leaf(c) {
                let (start, count) = n.child_primitives(c);
                let slots: Vec<u32> = (start..start + count)
                    .map(|j| slot_of[cw.primitive_indices[j as usize] as usize])
                    .collect();
                out.blocks.push(TriBlock8::of_slots(&slots, &accel.tris));
                LEAF_BIT | (out.blocks.len() - 1) as u32
            } else {
                n.child_node_index(c)
            };
            out.nodes[i].set_child(k, &bx, r);
            k += 1;
        }
        out.nodes[i].set_order(k);
    }
    // depth, for stack sizing
    let mut stack = vec![(0u32, 1usize)];
    while let Some((i, d)) = stack.pop() {
        out.depth = out.depth.max(d);
        let n = &out.nodes[i as usize];
        for c in 0..BLOCK {
            if n.valid() >> c & 1 == 1 && n.child[c] & LEAF_BIT == 0 {
                stack.push((n.child[c], d + 1));
            }
        }
    }
    out
}

#[cfg(test)]
pub(super) mod tests;
