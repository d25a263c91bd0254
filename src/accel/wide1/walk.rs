//! The single-ray walks of the 8-wide tree, closest hit and any hit, as steps (one node
//! visit each) over a walk's state, so that [`super::interleave`] can take several walks in
//! turn; [`walk`] runs one to its end (with a stack of `accel::stack`).

use super::interleave::prefetch_leaf;
use super::{NodeHits, RayWide, hit_block1, hit_node1};
use crate::accel::robust::nearer;
use crate::accel::wide::{Bvh8, LEAF_BIT, Node8, leaf_blocks};
use crate::accel::{Accel, ORIGIN_LAST, SLAB_FAR_SCALE};
use crate::ray::Hit;

/// Single-ray traversal of the subtree at wide reference `start` (a node or a leaf): the
/// nearest hit with `tnear < t < tfar` ([`walk_closest`]), or with `ANY_HIT` the first
/// ([`walk_any`]). `stack` holds at least [`stack_need`](crate::accel::stack::stack_need)
/// entries.
#[inline(always)]
pub(in crate::accel) fn walk<const ANY_HIT: bool>(
    accel: &Accel,
    bvh: &Bvh8,
    start: u32,
    r: &RayWide,
    tfar: f32,
    cull: bool,
    stack: &mut [(u32, f32)],
) -> Option<Hit> {
    if ANY_HIT {
        walk_any(accel, bvh, start, r, tfar, cull, stack)
    } else {
        walk_closest(accel, bvh, start, r, tfar, cull, stack)
    }
}

/// The closest-hit walk. Hit children are visited nearest first by entry distance (two
/// children compared, more pushed in the octant's precomputed order), and a popped entry
/// farther than the closest hit so far is dropped.
///
/// A node's hit leaf children are tested at the node, before its inner children are
/// descended into or pushed: the walk then only ever steps to nodes (no leaf-or-node branch
/// after each step, which went either way on 2.5 steps of an incoherent ray, and no stack
/// entries for leaves). A leaf is skipped when a hit found at the same node already lies
/// before its box.
#[inline(always)]
fn walk_closest(
    accel: &Accel,
    bvh: &Bvh8,
    start: u32,
    r: &RayWide,
    tfar: f32,
    cull: bool,
    stack: &mut [(u32, f32)],
) -> Option<Hit> {
    let mut w = Closest::new(*r, tfar, start);
    if start & LEAF_BIT != 0 {
        w.test_leaf(accel, start, cull);
        return w.best;
    }
    while !w.step(accel, bvh, cull, stack) {}
    w.best
}

/// A closest-hit walk between two steps: the ray, the closest hit so far and the limit it
/// sets, the node to visit next and the height of the walk's stack.
#[derive(Clone, Copy)]
pub(super) struct Closest {
    pub(super) r: RayWide,
    pub(super) tfar: f32,
    pub(super) best: Option<Hit>,
    pub(super) cur: u32,
    pub(super) sp: usize,
    /// [`Closest::step_deferred`]: the hit leaves of node `pending_node` still to test, and
    /// that node's entry distances.
    pending: u32,
    pending_node: u32,
    pending_lo: [f32; 8],
}

impl Closest {
    /// A walk of `r` within `tfar` from wide reference `start`.
    #[inline(always)]
    pub(super) fn new(r: RayWide, tfar: f32, start: u32) -> Closest {
        Closest {
            r,
            tfar,
            best: None,
            cur: start,
            sp: 0,
            pending: 0,
            pending_node: 0,
            pending_lo: [0.0; 8],
        }
    }

    /// The blocks of leaf `leaf` against the ray: the best hit so far and the limit updated.
    #[inline(always)]
    fn test_leaf(&mut self, accel: &Accel, leaf: u32, cull: bool) {
        let (first, count) = leaf_blocks(leaf);
        for block in first..first + count {
            if let Some(h) = hit_block1::<false>(accel, block, &self.r, self.tfar, cull) {
                // record hit: as in intersect1, the new limit is the next float above t
                // and an exact tie keeps the lower original triangle index.
                if self.best.is_none_or(|b| nearer(h.t, h.tri, b.t, b.tri)) {
                    self.best = Some(h);
                    self.tfar = h.t.next_up();
                }
            }
        }
    }

    /// Visit node `cur`: test its hit leaves, then descend into the nearest hit inner child
    /// or pop the next entry still in front of the closest hit. `true` when the walk is
    /// over (the stack ran empty).
    #[inline(always)]
    pub(super) fn step(
        &mut self,
        accel: &Accel,
        bvh: &Bvh8,
        cull: bool,
        stack: &mut [(u32, f32)],
    ) -> bool {
        let node = &bvh.nodes[self.cur as usize];
        let NodeHits { bits, lo, .. } = hit_node1(node, &self.r, self.tfar);
        let leaves = bits & node.leaves();
        self.test_leaves(accel, node, leaves, &lo, cull);
        !self.advance(node, bits & !leaves, &lo, stack)
    }

    /// [`Closest::step`] with the node's hit leaves tested at the next step rather than
    /// this one, their blocks prefetched meanwhile (for [`interleaved`], where the other
    /// walks' steps come between). The order in which leaves are tested does not change
    /// the closest hit; a limit not yet lowered by them only prunes less.
    #[inline(always)]
    pub(super) fn step_deferred(
        &mut self,
        accel: &Accel,
        bvh: &Bvh8,
        cull: bool,
        stack: &mut [(u32, f32)],
    ) -> bool {
        if self.pending != 0 {
            let node = &bvh.nodes[self.pending_node as usize];
            let lo = self.pending_lo;
            self.test_leaves(accel, node, self.pending, &lo, cull);
            self.pending = 0;
        }
        if self.cur == LEAF_BIT {
            return true;
        }
        let node = &bvh.nodes[self.cur as usize];
        let NodeHits { bits, lo, .. } = hit_node1(node, &self.r, self.tfar);
        let leaves = bits & node.leaves();
        if leaves != 0 {
            self.pending = leaves;
            self.pending_node = self.cur;
            self.pending_lo = lo;
            let mut m = leaves;
            while m != 0 {
                let slot = m.trailing_zeros() as usize;
                m &= m - 1;
                prefetch_leaf(accel, node.child[slot]);
            }
        }
        if self.advance(node, bits & !leaves, &lo, stack) {
            return false;
        }
        // the stack ran empty: one more step for leaves still pending
        self.cur = LEAF_BIT;
        self.pending == 0
    }

    /// The hit leaves `m` of `node` (entry distances `lo`) against the ray, each unless a
    /// hit found already lies before its box.
    #[inline(always)]
    fn test_leaves(&mut self, accel: &Accel, node: &Node8, mut m: u32, lo: &[f32; 8], cull: bool) {
        while m != 0 {
            let slot = m.trailing_zeros() as usize;
            m &= m - 1;
            if lo[slot] > self.tfar * SLAB_FAR_SCALE {
                continue;
            }
            self.test_leaf(accel, node.child[slot], cull);
        }
    }

    /// From `node`, whose hit inner children are `inner` (entry distances `lo`): descend
    /// into the nearest, pushing the others, or pop the next entry still in front of the
    /// closest hit. `false` when there is none (the walk is over).
    #[inline(always)]
    fn advance(
        &mut self,
        node: &Node8,
        inner: u32,
        lo: &[f32; 8],
        stack: &mut [(u32, f32)],
    ) -> bool {
        if inner != 0 {
            let rest = inner & (inner - 1);
            if rest == 0 {
                // one child: descend, unless a hit at this node lies before it.
                let slot = inner.trailing_zeros() as usize;
                if lo[slot] <= self.tfar * SLAB_FAR_SCALE {
                    self.cur = node.child[slot];
                    return true;
                }
            } else if rest & (rest - 1) == 0 {
                // two children (the usual case): nearer first by entry distance, the other
                // pushed.
                let (a, b) = (
                    inner.trailing_zeros() as usize,
                    rest.trailing_zeros() as usize,
                );
                let (first, later) = if lo[b] < lo[a] { (b, a) } else { (a, b) };
                stack[self.sp] = (node.child[later], lo[later]);
                self.sp += 1;
                if lo[first] <= self.tfar * SLAB_FAR_SCALE {
                    self.cur = node.child[first];
                    return true;
                }
            } else {
                // several: push the hit ones farthest first in the octant's order (no
                // branches: every slot is written, the pointer moves only for hit ones),
                // then go on with the nearest (through the pop below).
                let order = node.order[self.r.octant];
                for k in (0..8).rev() {
                    let slot = (order >> (3 * k) & 7) as usize;
                    stack[self.sp] = (node.child[slot], lo[slot]);
                    self.sp += (inner >> slot & 1) as usize;
                }
            }
        }
        // pop the next node still in front of the closest hit.
        loop {
            if self.sp == 0 {
                return false;
            }
            self.sp -= 1;
            let (next, tentry) = stack[self.sp];
            if tentry <= self.tfar * SLAB_FAR_SCALE {
                self.cur = next;
                return true;
            }
        }
    }
}

/// The any-hit walk (shadow rays), which stops at the first hit. It keeps no entry distances
/// and sorts nothing, as Embree's any-hit traversal: `tfar` never moves, so no pushed
/// entry is ever dropped, and an unoccluded ray (70% of the bench's shadow rays) visits
/// every box it meets whatever the order. The one order kept is `ORIGIN_LAST`: at a node,
/// the hit leaves the ray does not start in are tested before those it starts in, and the
/// inner children it starts in are pushed before the others, so they are visited after
/// them; within each group, slot order. Against the distance-ordered walk (the closest-hit
/// walk's order with the origin-last choice on top) this traced 1.08-1.10x as fast on the
/// kitten's shadow rays and 1.05-1.10x at 1.3M triangles (alternating runs in one
/// process): no lane extraction of the entry distances, no branch on the number of
/// children hit, no octant-order pass. Ordering two children by distance on top cost back
/// half the gain; dropping the origin-last groups (plain slot order) traced 0.97-0.98x.
#[inline(always)]
fn walk_any(
    accel: &Accel,
    bvh: &Bvh8,
    start: u32,
    r: &RayWide,
    tfar: f32,
    cull: bool,
    stack: &mut [(u32, f32)],
) -> Option<Hit> {
    let mut w = Any::new(*r, tfar, start);
    if start & LEAF_BIT != 0 {
        w.test_leaf(accel, start, cull);
        return w.hit;
    }
    while !w.step(accel, bvh, cull, stack) {}
    w.hit
}

/// An any-hit walk between two steps: the ray and its limit, the hit once found, the node
/// to visit next and the height of the walk's stack.
#[derive(Clone, Copy)]
pub(super) struct Any {
    pub(super) r: RayWide,
    pub(super) tfar: f32,
    pub(super) hit: Option<Hit>,
    pub(super) cur: u32,
    pub(super) sp: usize,
    /// [`Any::step_deferred`]: the hit leaves of node `pending_node` still to test, and the
    /// boxes of that node the ray starts in.
    pending: u32,
    pending_node: u32,
    pending_inside: u32,
}

impl Any {
    /// A walk of `r` within `tfar` from wide reference `start`.
    #[inline(always)]
    pub(super) fn new(r: RayWide, tfar: f32, start: u32) -> Any {
        Any {
            r,
            tfar,
            hit: None,
            cur: start,
            sp: 0,
            pending: 0,
            pending_node: 0,
            pending_inside: 0,
        }
    }

    /// The blocks of leaf `leaf` against the ray, until one hits (`true`: `hit` is set).
    #[inline(always)]
    fn test_leaf(&mut self, accel: &Accel, leaf: u32, cull: bool) -> bool {
        let (first, count) = leaf_blocks(leaf);
        for block in first..first + count {
            if let Some(h) = hit_block1::<true>(accel, block, &self.r, self.tfar, cull) {
                self.hit = Some(h);
                return true;
            }
        }
        false
    }

    /// Visit node `cur`: test its hit leaves (the walk is over at a hit), push its hit inner
    /// children and pop the next. `true` when the walk is over.
    #[inline(always)]
    pub(super) fn step(
        &mut self,
        accel: &Accel,
        bvh: &Bvh8,
        cull: bool,
        stack: &mut [(u32, f32)],
    ) -> bool {
        let node = &bvh.nodes[self.cur as usize];
        let NodeHits { bits, inside, .. } = hit_node1(node, &self.r, self.tfar);
        let leaves = bits & node.leaves();
        if self.test_leaves(accel, node, leaves, inside, cull) {
            return true;
        }
        !self.advance(node, bits & !leaves, inside, stack)
    }

    /// [`Any::step`] with the node's hit leaves tested at the next step, their blocks
    /// prefetched meanwhile (as [`Closest::step_deferred`]).
    #[inline(always)]
    pub(super) fn step_deferred(
        &mut self,
        accel: &Accel,
        bvh: &Bvh8,
        cull: bool,
        stack: &mut [(u32, f32)],
    ) -> bool {
        if self.pending != 0 {
            let node = &bvh.nodes[self.pending_node as usize];
            let (m, inside) = (self.pending, self.pending_inside);
            self.pending = 0;
            if self.test_leaves(accel, node, m, inside, cull) {
                return true;
            }
        }
        if self.cur == LEAF_BIT {
            return true;
        }
        let node = &bvh.nodes[self.cur as usize];
        let NodeHits { bits, inside, .. } = hit_node1(node, &self.r, self.tfar);
        let leaves = bits & node.leaves();
        if leaves != 0 {
            (self.pending, self.pending_node, self.pending_inside) = (leaves, self.cur, inside);
            let mut m = leaves;
            while m != 0 {
                let slot = m.trailing_zeros() as usize;
                m &= m - 1;
                prefetch_leaf(accel, node.child[slot]);
            }
        }
        if self.advance(node, bits & !leaves, inside, stack) {
            return false;
        }
        // the stack ran empty: one more step for leaves still pending
        self.cur = LEAF_BIT;
        self.pending == 0
    }

    /// The hit leaves `m` of `node` against the ray, those the ray does not start in first
    /// (`inside`: the boxes it starts in), until one hits (`true`).
    #[inline(always)]
    fn test_leaves(
        &mut self,
        accel: &Accel,
        node: &Node8,
        m: u32,
        inside: u32,
        cull: bool,
    ) -> bool {
        let (inside, outside) = if ORIGIN_LAST {
            (inside, !inside)
        } else {
            (0, u32::MAX)
        };
        if m != 0 {
            for mut m in [m & outside, m & inside] {
                while m != 0 {
                    let slot = m.trailing_zeros() as usize;
                    m &= m - 1;
                    if self.test_leaf(accel, node.child[slot], cull) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// Push the hit inner children `inner` of `node` and pop the next node to visit; `false`
    /// when there is none (the walk is over).
    #[inline(always)]
    fn advance(&mut self, node: &Node8, inner: u32, inside: u32, stack: &mut [(u32, f32)]) -> bool {
        let (inside, outside) = if ORIGIN_LAST {
            (inside, !inside)
        } else {
            (0, u32::MAX)
        };
        // pushed: the boxes the ray starts in first (so visited last), then the others; the
        // last one pushed is popped at once.
        for mut m in [inner & inside, inner & outside] {
            while m != 0 {
                let slot = m.trailing_zeros() as usize;
                m &= m - 1;
                stack[self.sp].0 = node.child[slot];
                self.sp += 1;
            }
        }
        if self.sp == 0 {
            return false;
        }
        self.sp -= 1;
        self.cur = stack[self.sp].0;
        true
    }
}
