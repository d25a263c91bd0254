//! The single-ray walks of the 8-wide tree, closest hit and any hit, as steps (one node
//! visit each) over a walk's state ([`Walker`]), so that [`super::interleave`] can take
//! several walks in turn; [`walk`] runs one to its end (with a stack of `accel::stack`). The
//! two walks share their steps and differ in what they do at a node ([`Kind`]).

use super::interleave::prefetch_leaf;
use super::{NodeHits, RayWide, hit_block1, hit_node1};
use crate::accel::robust::nearer;
use crate::accel::wide::{Bvh8, LEAF_BIT, Node8, leaf_blocks};
use crate::accel::{Accel, ORIGIN_LAST, SLAB_FAR_SCALE};
use crate::ray::Hit;

/// Single-ray traversal of the subtree at wide reference `start` (a node or a leaf): the
/// nearest hit with `tnear < t < tfar` ([`ClosestHit`]), or with `ANY_HIT` the first
/// ([`AnyHit`]). `stack` holds at least [`stack_need`](crate::accel::stack::stack_need)
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
        walk_from::<AnyHit>(accel, bvh, start, r, tfar, cull, stack)
    } else {
        walk_from::<ClosestHit>(accel, bvh, start, r, tfar, cull, stack)
    }
}

/// One walk of kind `K` from `start` to its end.
#[inline(always)]
fn walk_from<K: Kind>(
    accel: &Accel,
    bvh: &Bvh8,
    start: u32,
    r: &RayWide,
    tfar: f32,
    cull: bool,
    stack: &mut [(u32, f32)],
) -> Option<Hit> {
    let mut w = Walker::<K>::new(*r, tfar, start);
    if start & LEAF_BIT != 0 {
        K::test_leaf(&mut w, accel, start, cull);
        return w.found;
    }
    while !w.step(accel, bvh, cull, stack) {}
    w.found
}

/// A closest-hit walk between two steps.
pub(super) type Closest = Walker<ClosestHit>;

/// An any-hit walk between two steps.
pub(super) type Any = Walker<AnyHit>;

/// A walk between two steps: the ray and its limit, the hit found so far (the closest, or
/// the one that ends an any-hit walk), the node to visit next and the height of the walk's
/// stack.
pub(super) struct Walker<K: Kind> {
    pub(super) r: RayWide,
    pub(super) tfar: f32,
    pub(super) found: Option<Hit>,
    pub(super) cur: u32,
    pub(super) sp: usize,
    /// [`Walker::step_deferred`]: the hit leaves of node `pending_node` still to test, and
    /// what that node's test said of them ([`Kind::Info`]).
    pending: u32,
    pending_node: u32,
    pending_info: K::Info,
}

impl<K: Kind> Clone for Walker<K> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<K: Kind> Copy for Walker<K> {}

/// What a walk does at a node: test the hit leaves and go on to the next node, in its own
/// order and with its own stopping rule.
pub(super) trait Kind: Sized {
    /// What the node test tells the leaves and inner children: entry distances (closest
    /// hit) or the boxes the ray starts in (any hit).
    type Info: Copy + Default;
    /// [`Kind::Info`] of a node test.
    fn info(h: &NodeHits) -> Self::Info;
    /// The blocks of leaf `leaf` against the ray; `true` when the walk is over.
    fn test_leaf(w: &mut Walker<Self>, accel: &Accel, leaf: u32, cull: bool) -> bool;
    /// The hit leaves `m` of `node`; `true` when the walk is over.
    fn test_leaves(
        w: &mut Walker<Self>,
        accel: &Accel,
        node: &Node8,
        m: u32,
        info: &Self::Info,
        cull: bool,
    ) -> bool;
    /// From `node`, whose hit inner children are `inner`, on to the next node to visit
    /// (`w.cur`): `false` when there is none (the walk is over).
    fn advance(
        w: &mut Walker<Self>,
        node: &Node8,
        inner: u32,
        info: &Self::Info,
        stack: &mut [(u32, f32)],
    ) -> bool;
}

impl<K: Kind> Walker<K> {
    /// A walk of `r` within `tfar` from wide reference `start`.
    #[inline(always)]
    pub(super) fn new(r: RayWide, tfar: f32, start: u32) -> Self {
        Walker {
            r,
            tfar,
            found: None,
            cur: start,
            sp: 0,
            pending: 0,
            pending_node: 0,
            pending_info: K::Info::default(),
        }
    }

    /// Visit node `cur`: test its hit leaves, then go on to the next node. `true` when the
    /// walk is over.
    #[inline(always)]
    pub(super) fn step(
        &mut self,
        accel: &Accel,
        bvh: &Bvh8,
        cull: bool,
        stack: &mut [(u32, f32)],
    ) -> bool {
        let node = &bvh.nodes[self.cur as usize];
        let hits = hit_node1(node, &self.r, self.tfar);
        let info = K::info(&hits);
        let leaves = hits.bits & node.leaves();
        if K::test_leaves(self, accel, node, leaves, &info, cull) {
            return true;
        }
        !K::advance(self, node, hits.bits & !leaves, &info, stack)
    }

    /// [`Walker::step`] with the node's hit leaves tested at the next step rather than
    /// this one, their blocks prefetched meanwhile (for [`super::interleave`], where the
    /// other walks' steps come between). The order in which leaves are tested does not
    /// change the closest hit, nor whether there is any; a limit not yet lowered by them
    /// only prunes less.
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
            let (m, info) = (self.pending, self.pending_info);
            self.pending = 0;
            if K::test_leaves(self, accel, node, m, &info, cull) {
                return true;
            }
        }
        if self.cur == LEAF_BIT {
            return true;
        }
        let node = &bvh.nodes[self.cur as usize];
        let hits = hit_node1(node, &self.r, self.tfar);
        let info = K::info(&hits);
        let leaves = hits.bits & node.leaves();
        if leaves != 0 {
            (self.pending, self.pending_node, self.pending_info) = (leaves, self.cur, info);
            let mut m = leaves;
            while m != 0 {
                let slot = m.trailing_zeros() as usize;
                m &= m - 1;
                prefetch_leaf(accel, node.child[slot]);
            }
        }
        if K::advance(self, node, hits.bits & !leaves, &info, stack) {
            return false;
        }
        // the stack ran empty: one more step for leaves still pending
        self.cur = LEAF_BIT;
        self.pending == 0
    }
}

/// The closest-hit walk. Hit children are pushed farthest first in the octant's
/// precomputed order, however many there are, and popped nearest first; a popped entry
/// farther than the closest hit so far is dropped.
///
/// A node's hit leaf children are tested at the node, before its inner children are
/// descended into or pushed: the walk then only ever steps to nodes (no leaf-or-node branch
/// after each step, which went either way on 2.5 steps of an incoherent ray, and no stack
/// entries for leaves). A leaf is skipped when a hit found at the same node already lies
/// before its box.
#[derive(Clone, Copy)]
pub(super) struct ClosestHit;

impl Kind for ClosestHit {
    type Info = [f32; 8];

    #[inline(always)]
    fn info(h: &NodeHits) -> [f32; 8] {
        h.lo
    }

    /// The best hit so far and the limit updated; never ends the walk.
    #[inline(always)]
    fn test_leaf(w: &mut Walker<Self>, accel: &Accel, leaf: u32, cull: bool) -> bool {
        let (first, count) = leaf_blocks(leaf);
        for block in first..first + count {
            if let Some(h) = hit_block1::<false>(accel, block, &w.r, w.tfar, cull) {
                // record hit: as in intersect1, the new limit is the next float above t
                // and an exact tie keeps the lower original triangle index.
                if w.found.is_none_or(|b| nearer(h.t, h.tri, b.t, b.tri)) {
                    w.found = Some(h);
                    w.tfar = h.t.next_up();
                }
            }
        }
        false
    }

    /// Each hit leaf unless a hit found already lies before its box (`lo`: the entry
    /// distances).
    #[inline(always)]
    fn test_leaves(
        w: &mut Walker<Self>,
        accel: &Accel,
        node: &Node8,
        mut m: u32,
        lo: &[f32; 8],
        cull: bool,
    ) -> bool {
        while m != 0 {
            let slot = m.trailing_zeros() as usize;
            m &= m - 1;
            if lo[slot] > w.tfar * SLAB_FAR_SCALE {
                continue;
            }
            Self::test_leaf(w, accel, node.child[slot], cull);
        }
        false
    }

    /// From `node`, whose hit inner children are `inner` (entry distances `lo`): push them,
    /// then pop the next entry still in front of the closest hit. `false` when there is none
    /// (the walk is over). No branch asks how many children were hit (on random rays such a
    /// branch goes either way): every slot is written in the octant's order, farthest first,
    /// and the stack pointer moves by the hit bit.
    #[inline(always)]
    fn advance(
        w: &mut Walker<Self>,
        node: &Node8,
        inner: u32,
        lo: &[f32; 8],
        stack: &mut [(u32, f32)],
    ) -> bool {
        if inner != 0 {
            // pushed farthest first, so the nearest is popped next
            let order = node.order[w.r.octant];
            for k in (0..8).rev() {
                let slot = (order >> (3 * k) & 7) as usize;
                stack[w.sp] = (node.child[slot], lo[slot]);
                w.sp += (inner >> slot & 1) as usize;
            }
        }
        // pop the next node still in front of the closest hit.
        loop {
            if w.sp == 0 {
                return false;
            }
            w.sp -= 1;
            let (next, tentry) = stack[w.sp];
            if tentry <= w.tfar * SLAB_FAR_SCALE {
                w.cur = next;
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
#[derive(Clone, Copy)]
pub(super) struct AnyHit;

/// The children the ray starts in and the others, as two bit sets to take in turn, the
/// others first (`ORIGIN_LAST`; off, every child counts as another).
#[inline(always)]
fn origin_last(inside: u32) -> (u32, u32) {
    if ORIGIN_LAST {
        (inside, !inside)
    } else {
        (0, u32::MAX)
    }
}

impl Kind for AnyHit {
    type Info = u32;

    #[inline(always)]
    fn info(h: &NodeHits) -> u32 {
        h.inside
    }

    /// Until one block hits (`true`: `found` is set).
    #[inline(always)]
    fn test_leaf(w: &mut Walker<Self>, accel: &Accel, leaf: u32, cull: bool) -> bool {
        let (first, count) = leaf_blocks(leaf);
        for block in first..first + count {
            if let Some(h) = hit_block1::<true>(accel, block, &w.r, w.tfar, cull) {
                w.found = Some(h);
                return true;
            }
        }
        false
    }

    /// Those the ray does not start in first (`inside`: the boxes it starts in), until one
    /// hits.
    #[inline(always)]
    fn test_leaves(
        w: &mut Walker<Self>,
        accel: &Accel,
        node: &Node8,
        m: u32,
        inside: &u32,
        cull: bool,
    ) -> bool {
        let (inside, outside) = origin_last(*inside);
        if m != 0 {
            for mut m in [m & outside, m & inside] {
                while m != 0 {
                    let slot = m.trailing_zeros() as usize;
                    m &= m - 1;
                    if Self::test_leaf(w, accel, node.child[slot], cull) {
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
    fn advance(
        w: &mut Walker<Self>,
        node: &Node8,
        inner: u32,
        inside: &u32,
        stack: &mut [(u32, f32)],
    ) -> bool {
        let (inside, outside) = origin_last(*inside);
        // pushed: the boxes the ray starts in first (so visited last), then the others; the
        // last one pushed is popped at once.
        for mut m in [inner & inside, inner & outside] {
            while m != 0 {
                let slot = m.trailing_zeros() as usize;
                m &= m - 1;
                stack[w.sp].0 = node.child[slot];
                w.sp += 1;
            }
        }
        if w.sp == 0 {
            return false;
        }
        w.sp -= 1;
        w.cur = stack[w.sp].0;
        true
    }
}
