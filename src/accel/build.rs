//! whitted's own BVH2 builder: top-down binned SAH (Wald 2007, the scheme of Embree's
//! MEDIUM builder), written for one thread and for the 8-wide collapse that follows it.
//!
//! - Each node's primitives are binned by centroid into [`BINS`] slots on all three axes;
//!   the split with the least SAH cost `A(l) N(l) + A(r) N(r)` is taken. Primitive boxes
//!   and ids are moved, not indexed, so every pass reads memory in order.
//! - Nodes above [`SAMPLE`] triangles bin an even sample of about that many (the partition
//!   still sees every triangle and computes exact child boxes).
//! - Down to depth [`BIG_DEPTH`], a node also weighs setting its largest triangles apart
//!   (at least `1 / BIG` of its area: a floor or a wall among small triangles, which binned by
//!   centroid would stretch every box above the small ones they share a bin with).
//! - A node of at most [`MAX_LEAF`] triangles is a leaf: the 8-wide collapse makes such a
//!   subtree one block of 8 lanes anyway, and the packet engine's leaves stay as in the obvhs
//!   presets (whose leaf cap is also 8). Measured against SAH-terminated leaves (of 1 to 8)
//!   (C_trav = 1) made 3.4x the nodes on the 1.3M-triangle kitten, built slower, and traversed
//!   no faster.
//! - Where binning cannot separate the centroids (all in one bin, or all equal), or the tree
//!   is already [`MEDIAN_DEPTH`] deep, the node is split at the middle of its range
//!   instead, so the depth stays logarithmic on any input.
//! - Children are allocated in pairs (`first`, `first + 1`) as `Node` requires, depth first,
//!   and a leaf's triangles are the range `first .. first + count` of the returned order.

use super::Node;
use glam::{Vec3, Vec3A};
use rayon::prelude::*;

/// Centroid bins per axis.
pub const BINS: usize = 16;
/// Most triangles in a leaf (the packet engine tests a leaf's triangles one by one).
pub const MAX_LEAF: usize = 8;
/// Nodes of more triangles bin a sample of about this many.
pub const SAMPLE: usize = 256;
/// Down to this depth, a node also considers setting apart its triangles of at least
/// `1 / BIG` of its box's area (a floor or a wall among many small triangles: binned by
/// centroid, they share bins with small neighbours and stretch every box above those).
pub const BIG_DEPTH: u32 = 4;
/// See [`BIG_DEPTH`].
pub const BIG: f32 = 32.0;
/// From this depth on, nodes are split at the middle of their range.
pub const MEDIAN_DEPTH: u32 = 56;

#[derive(Clone, Copy, Debug)]
struct Box3 {
    lo: Vec3A,
    hi: Vec3A,
}

impl Box3 {
    const EMPTY: Box3 = Box3 {
        lo: Vec3A::splat(f32::INFINITY),
        hi: Vec3A::splat(f32::NEG_INFINITY),
    };
    #[inline(always)]
    fn grow(&mut self, lo: Vec3A, hi: Vec3A) {
        self.lo = self.lo.min(lo);
        self.hi = self.hi.max(hi);
    }
    #[inline(always)]
    fn join(self, o: Box3) -> Box3 {
        Box3 {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
        }
    }
    /// Half the surface area (0 for an empty box).
    #[inline(always)]
    fn area(self) -> f32 {
        let e = (self.hi - self.lo).max(Vec3A::ZERO);
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// Half the surface area of the box `lo .. hi`.
#[inline(always)]
fn half_area(lo: Vec3A, hi: Vec3A) -> f32 {
    Box3 { lo, hi }.area()
}

#[derive(Clone, Copy)]
struct Bin {
    b: Box3,
    n: u32,
}

const EMPTY_BIN: Bin = Bin {
    b: Box3::EMPTY,
    n: 0,
};

/// One node waiting to be split: its index, its primitive range, the box of its centroids
/// (as `lo + hi`, twice the centroid) and its depth.
struct Task {
    node: usize,
    start: usize,
    end: usize,
    cent: Box3,
    depth: u32,
}

/// Build over `tris`: the nodes (root at 0, unpadded boxes) and the triangle order
/// (`order[slot]` = index into `tris`). `tris` must not be empty. Subtrees of at least
/// [`PARALLEL_MIN`] triangles are built on rayon's current pool, two at a time; the tree is
/// the same whatever the number of threads.
pub fn build_bvh2(tris: &[[Vec3; 3]]) -> (Vec<Node>, Vec<u32>) {
    let (mut lo, mut hi): (Vec<Vec3A>, Vec<Vec3A>) = tris
        .par_iter()
        .with_min_len(4096)
        .map(|t| {
            let (a, b, c) = (Vec3A::from(t[0]), Vec3A::from(t[1]), Vec3A::from(t[2]));
            (a.min(b).min(c), a.max(b).max(c))
        })
        .unzip();
    let (root, cent) = lo
        .par_iter()
        .zip(&hi)
        .with_min_len(4096)
        .fold(
            || (Box3::EMPTY, Box3::EMPTY),
            |(mut b, mut c), (&l, &h)| {
                b.grow(l, h);
                c.grow(l + h, l + h);
                (b, c)
            },
        )
        .reduce(
            || (Box3::EMPTY, Box3::EMPTY),
            |(b0, c0), (b1, c1)| (b0.join(b1), c0.join(c1)),
        );
    let mut ids: Vec<u32> = (0..tris.len() as u32).collect();
    let prims = Prims::new(&mut lo, &mut hi, &mut ids);
    let nodes = subtree(prims, 0, root, cent, 0);
    (nodes, ids)
}

/// Subtrees of at least this many triangles split their two halves across threads.
pub const PARALLEL_MIN: usize = 1 << 12;

/// The subtree over `p` (slots `offset ..` of the whole order), its box `bbox` and centroid
/// box `cent`, at `depth`: nodes with the subtree's root at 0, leaves naming global slots.
/// Large subtrees split their root here and build both halves with `rayon::join`, then lay
/// them out as the serial walk would (root, the pair, the left half's nodes, the right
/// half's), so the result does not depend on the thread count.
fn subtree(mut p: Prims, offset: usize, bbox: Box3, cent: Box3, depth: u32) -> Vec<Node> {
    let count = p.lo.len();
    if count < PARALLEL_MIN || depth >= MEDIAN_DEPTH {
        return serial(p, offset, bbox, cent, depth);
    }
    let t = Task {
        node: 0,
        start: 0,
        end: count,
        cent,
        depth,
    };
    let s = p
        .binned(&t, bbox.area())
        .unwrap_or_else(|| p.median(0, count));
    let Prims { lo, hi, ids, sets } = p;
    let ((llo, rlo), (lhi, rhi), (lids, rids)) = (
        lo.split_at_mut(s.mid),
        hi.split_at_mut(s.mid),
        ids.split_at_mut(s.mid),
    );
    let left = Prims {
        lo: llo,
        hi: lhi,
        ids: lids,
        sets,
    };
    let right = Prims::new(rlo, rhi, rids);
    let (l, r) = rayon::join(
        || subtree(left, offset, s.lbox, s.lcent, depth + 1),
        || subtree(right, offset + s.mid, s.rbox, s.rcent, depth + 1),
    );
    // [root, l[0], r[0], l[1..], r[1..]]: a subtree's node i > 0 moves to base + i - 1.
    let (lbase, rbase) = (3, 3 + l.len() as u32 - 1);
    let moved = |n: Node, base: u32| {
        if n.count == 0 {
            Node {
                first: base + n.first - 1,
                ..n
            }
        } else {
            n
        }
    };
    let mut nodes = Vec::with_capacity(1 + l.len() + r.len());
    // (the final array for big trees: `Accel::build` pads its boxes in place, the same
    // allocation, so the advice reaches traversal)
    super::pages::advise_huge(&nodes);
    nodes.push(node_of(bbox, 1, 0));
    nodes.push(moved(l[0], lbase));
    nodes.push(moved(r[0], rbase));
    nodes.extend(l[1..].iter().map(|&n| moved(n, lbase)));
    nodes.extend(r[1..].iter().map(|&n| moved(n, rbase)));
    nodes
}

/// [`subtree`] on one thread: an explicit stack, depth first.
fn serial(mut prims: Prims, offset: usize, bbox: Box3, cent: Box3, depth: u32) -> Vec<Node> {
    let n = prims.lo.len();
    let mut nodes = Vec::with_capacity(2 * n.div_ceil(MAX_LEAF / 2));
    nodes.push(node_of(bbox, 0, 0));
    let mut stack = vec![Task {
        node: 0,
        start: 0,
        end: n,
        cent,
        depth,
    }];
    while let Some(t) = stack.pop() {
        let count = t.end - t.start;
        let split = if count <= MAX_LEAF {
            None
        } else if t.depth >= MEDIAN_DEPTH {
            Some(prims.median(t.start, t.end))
        } else {
            let n = &nodes[t.node];
            let area = Box3 {
                lo: Vec3A::from(n.min),
                hi: Vec3A::from(n.max),
            }
            .area();
            Some(
                prims
                    .binned(&t, area)
                    .unwrap_or_else(|| prims.median(t.start, t.end)),
            )
        };
        let Some(s) = split else {
            nodes[t.node].first = (offset + t.start) as u32;
            nodes[t.node].count = count as u32;
            continue;
        };
        let l = nodes.len();
        nodes.push(node_of(s.lbox, 0, 0));
        nodes.push(node_of(s.rbox, 0, 0));
        nodes[t.node].first = l as u32;
        nodes[t.node].count = 0;
        let depth = t.depth + 1;
        // right first, so the left child is split next (depth-first allocation).
        stack.push(Task {
            node: l + 1,
            start: s.mid,
            end: t.end,
            cent: s.rcent,
            depth,
        });
        stack.push(Task {
            node: l,
            start: t.start,
            end: s.mid,
            cent: s.lcent,
            depth,
        });
    }
    nodes
}

/// The SAH weight of `n` binned triangles: with every triangle binned (`stride == 1`), the
/// lanes of the 8-wide blocks they fill (`n` rounded up to a multiple of [`MAX_LEAF`], as
/// Embree's builders count primitive blocks), since a block of 5 costs a ray what a block of
/// 8 does; a sampled node's counts are too coarse for that and stay as they are.
#[inline(always)]
fn lanes(n: u32, stride: usize) -> f32 {
    if stride == 1 {
        n.div_ceil(MAX_LEAF as u32) as f32 * MAX_LEAF as f32
    } else {
        n as f32
    }
}

fn node_of(b: Box3, first: u32, count: u32) -> Node {
    Node {
        min: Vec3::from(b.lo).into(),
        count,
        max: Vec3::from(b.hi).into(),
        first,
    }
}

/// Triangle boxes and ids of one subtree, moved together while partitioning.
struct Prims<'a> {
    lo: &'a mut [Vec3A],
    hi: &'a mut [Vec3A],
    ids: &'a mut [u32],
    /// Two sets of bins per axis, reused from node to node.
    sets: Box<[[[Bin; BINS]; 3]; 2]>,
}

/// A chosen split: children's boxes, their centroid boxes, and where the right range begins.
struct Split {
    mid: usize,
    lbox: Box3,
    rbox: Box3,
    lcent: Box3,
    rcent: Box3,
}

impl Split {
    /// Grow the left (`left`) or right child's box and centroid box by one triangle's box.
    #[inline(always)]
    fn take(&mut self, left: bool, l: Vec3A, h: Vec3A) {
        let (b, c) = if left {
            (&mut self.lbox, &mut self.lcent)
        } else {
            (&mut self.rbox, &mut self.rcent)
        };
        b.grow(l, h);
        c.grow(l + h, l + h);
    }
}

impl<'a> Prims<'a> {
    fn new(lo: &'a mut [Vec3A], hi: &'a mut [Vec3A], ids: &'a mut [u32]) -> Prims<'a> {
        Prims {
            lo,
            hi,
            ids,
            sets: Box::new([[[EMPTY_BIN; BINS]; 3]; 2]),
        }
    }

    #[inline(always)]
    fn swap(&mut self, i: usize, j: usize) {
        self.lo.swap(i, j);
        self.hi.swap(i, j);
        self.ids.swap(i, j);
    }

    /// Boxes and centroid boxes of `range`.
    fn bounds(&self, start: usize, end: usize) -> (Box3, Box3) {
        let (mut b, mut c) = (Box3::EMPTY, Box3::EMPTY);
        for i in start..end {
            let (l, h) = (self.lo[i], self.hi[i]);
            b.grow(l, h);
            c.grow(l + h, l + h);
        }
        (b, c)
    }

    /// Split at the middle of the range, in its current order.
    fn median(&mut self, start: usize, end: usize) -> Split {
        let mid = start + (end - start) / 2;
        let (lbox, lcent) = self.bounds(start, mid);
        let (rbox, rcent) = self.bounds(mid, end);
        Split {
            mid,
            lbox,
            rbox,
            lcent,
            rcent,
        }
    }

    /// The best binned SAH split of task `t` (whose box has half-area `area`), partitioned in
    /// place; `None` when no bin boundary separates the centroids.
    fn binned(&mut self, t: &Task, area: f32) -> Option<Split> {
        let ext = t.cent.hi - t.cent.lo;
        if ext.max_element() <= 0.0 || !ext.is_finite() {
            return None;
        }
        // as many bins as triangles, up to BINS: small nodes sweep fewer boundaries.
        let nb = if t.end - t.start > 64 { BINS } else { BINS / 2 };
        // bin k of axis a holds centroids in [lo + k ext / BINS, lo + (k + 1) ext / BINS);
        // an axis without extent puts everything in bin 0 and never splits.
        let scale = Vec3A::select(
            ext.cmpgt(Vec3A::ZERO),
            Vec3A::splat(nb as f32 * (1.0 - 1e-6)) / ext,
            Vec3A::ZERO,
        );
        // the bin coordinate, clamped to [0, nb - 1]: its integer part is the bin.
        let top = Vec3A::splat(nb as f32 - 1.0);
        let coord = |l: Vec3A, h: Vec3A| ((l + h - t.cent.lo) * scale).max(Vec3A::ZERO).min(top);
        let bin_of = |l: Vec3A, h: Vec3A| {
            let f = coord(l, h);
            // (through i32: f32 to usize conversion costs several instructions more)
            [
                f.x as i32 as usize,
                f.y as i32 as usize,
                f.z as i32 as usize,
            ]
        };
        // Big nodes bin a sample (every `stride`-th triangle, at least SAMPLE of them): the
        // split only needs the cost curve's shape; the partition below sees every triangle
        // and computes the children's exact boxes. Two sets of bins take turns, so runs of
        // triangles falling in the same bin (the usual case: meshes are stored coherently)
        // do not wait on each other's stores.
        let count = t.end - t.start;
        // near the root, the cost of setting the largest triangles apart; where there are
        // such triangles the whole node is binned (a sample would likely miss them, and
        // underrate every split that keeps them).
        let big_cost = if t.depth <= BIG_DEPTH {
            self.big_cost(t, area)
        } else {
            None
        };
        let stride = if big_cost.is_some() {
            1
        } else {
            (count / SAMPLE).max(1)
        };
        let sets = &mut *self.sets;
        for set in sets.iter_mut() {
            for bins in set.iter_mut() {
                bins[..nb].fill(EMPTY_BIN);
            }
        }
        let (lo, hi) = (&self.lo[t.start..t.end], &self.hi[t.start..t.end]);
        let mut i = 0;
        while i + stride < lo.len() {
            for (set, i) in sets.iter_mut().zip([i, i + stride]) {
                let (l, h) = (lo[i], hi[i]);
                let b = bin_of(l, h);
                for (axis, bins) in set.iter_mut().enumerate() {
                    let bin = &mut bins[b[axis]];
                    bin.b.grow(l, h);
                    bin.n += 1;
                }
            }
            i += 2 * stride;
        }
        if i < lo.len() {
            let (l, h) = (lo[i], hi[i]);
            let b = bin_of(l, h);
            for (axis, bins) in sets[0].iter_mut().enumerate() {
                let bin = &mut bins[b[axis]];
                bin.b.grow(l, h);
                bin.n += 1;
            }
        }
        let [bins, odd] = sets;
        for (bins, odd) in bins.iter_mut().zip(odd.iter()) {
            for (b, o) in bins[..nb].iter_mut().zip(&odd[..nb]) {
                b.b = b.b.join(o.b);
                b.n += o.n;
            }
        }
        // (only the first nb bins: the others keep counts of an earlier, larger node)
        let binned: u32 = bins[0][..nb].iter().map(|b| b.n).sum();
        // sweep: right-to-left areas and counts, then each boundary left to right.
        let mut best = (f32::INFINITY, 0usize, 0usize);
        for (axis, bins) in bins.iter().enumerate() {
            let mut right_area = [0f32; BINS];
            let mut acc = EMPTY_BIN;
            for k in (1..nb).rev() {
                acc.b = acc.b.join(bins[k].b);
                acc.n += bins[k].n;
                right_area[k] = acc.b.area() * lanes(acc.n, stride);
            }
            let mut left = EMPTY_BIN;
            for k in 1..nb {
                left.b = left.b.join(bins[k - 1].b);
                left.n += bins[k - 1].n;
                if left.n == 0 || left.n == binned {
                    continue;
                }
                let cost = left.b.area() * lanes(left.n, stride) + right_area[k];
                if cost < best.0 {
                    best = (cost, axis, k);
                }
            }
        }
        // k = 0: no boundary with triangles on both sides had a finite cost.
        let (cost, axis, k) = best;
        if k == 0 {
            return None;
        }
        let cost = cost * stride as f32;
        // a cheaper split that sets the node's largest triangles apart (near the root only).
        if big_cost.is_some_and(|b| b < cost) {
            let limit = area / BIG;
            return Some(self.partition(t, |l, h| half_area(l, h) >= limit));
        }
        let (kk, bit) = (Vec3A::splat(k as f32), 1 << axis);
        // bin < k exactly when the clamped coordinate is below k.
        Some(self.partition(t, |l, h| coord(l, h).cmplt(kk).bitmask() & bit != 0))
    }

    /// SAH cost (area times triangles, summed over both sides) of splitting task `t`, whose
    /// box has half-area `area`, into the triangles of at least `area / BIG` and the rest;
    /// `None` when one side would be empty.
    fn big_cost(&self, t: &Task, area: f32) -> Option<f32> {
        let limit = area / BIG;
        let (mut big, mut rest) = (EMPTY_BIN, EMPTY_BIN);
        for (&l, &h) in self.lo[t.start..t.end].iter().zip(&self.hi[t.start..t.end]) {
            let side = if half_area(l, h) >= limit {
                &mut big
            } else {
                &mut rest
            };
            side.b.grow(l, h);
            side.n += 1;
        }
        (big.n > 0 && rest.n > 0)
            .then(|| big.b.area() * big.n as f32 + rest.b.area() * rest.n as f32)
    }

    /// Partition task `t`'s range in place, `left` triangles first, with the children's boxes
    /// and centroid boxes.
    fn partition(&mut self, t: &Task, left: impl Fn(Vec3A, Vec3A) -> bool) -> Split {
        let (mut i, mut j) = (t.start, t.end);
        let mut s = Split {
            mid: 0,
            lbox: Box3::EMPTY,
            rbox: Box3::EMPTY,
            lcent: Box3::EMPTY,
            rcent: Box3::EMPTY,
        };
        // Hoare's scheme: each triangle is classified once, and only misplaced pairs move.
        loop {
            while i < j && left(self.lo[i], self.hi[i]) {
                s.take(true, self.lo[i], self.hi[i]);
                i += 1;
            }
            while i < j && !left(self.lo[j - 1], self.hi[j - 1]) {
                j -= 1;
                s.take(false, self.lo[j], self.hi[j]);
            }
            if i >= j {
                break;
            }
            // lo[i] belongs right and lo[j - 1] left: swap them into place.
            j -= 1;
            self.swap(i, j);
            s.take(true, self.lo[i], self.hi[i]);
            s.take(false, self.lo[j], self.hi[j]);
            i += 1;
        }
        s.mid = i;
        s
    }
}

#[cfg(test)]
mod tests;
