//! Packet traversal: 8 rays through the BVH together, the assignment's test in SIMD lanes.
//!
//! `intersect8` / `occluded8` are the 8-wide twins of `intersect1` / `occluded1`: same steps,
//! same arithmetic per lane (so each lane equals the scalar result bit for bit), plus an
//! `active` mask: inactive and padding lanes never produce hits.

use super::hand_off::hand_off;
use super::robust::{BARY_SAFE, nearer8, safe_inv8};
use super::scalar::hit_f64;
use super::tri_soa::Leaf;
use super::wide::{LEAF_BIT, NO_ENTRY, TriBlock8, leaf_blocks};
use super::{Accel, ORIGIN_LAST, SLAB_FAR_SCALE};
use crate::packet::{HitPacket8, RayPacket8};
use crate::ray::Hit;
use crate::simd::{self, F32x8, M32x8, U32x8, Vec3x8};

/// The plane + barycentric test of the `j`-th triangle of `leaf` (SoA slot `leaf.slot(j)`)
/// against 8 rays. Returns the lanes that hit with `tnear < t < tfar` and their
/// `(t, b1, b2)`; `dlen` is `|d|` per lane (computed once per packet, as `Ray1` does per
/// ray). Steps as in `hit_triangle1`:
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn hit_triangle8(
    accel: &Accel,
    leaf: &impl Leaf,
    j: usize,
    rays: &RayPacket8,
    dlen: F32x8,
    tfar: F32x8,
    active: M32x8,
    cull: bool,
) -> (M32x8, F32x8, F32x8, F32x8) {
    let n = Vec3x8::splat(leaf.n(j));
    let v0 = Vec3x8::splat(leaf.v0(j));
    // plane hit: t = <v0 - p, n> / <d, n> (in-plane rays and zero-area triangles give
    // inf or NaN and fail the depth test).
    let dn = rays.d.dot(n);
    let mut mask = active;
    // culling: skip back faces (<d, n> >= 0).
    if cull {
        mask = simd::and_not(mask, simd::ge(dn, simd::splat(0.0)));
        if simd::none(mask) {
            return (mask, dn, dn, dn);
        }
    }
    let t = (v0 - rays.o).dot(n) / dn;
    // depth test, near side (NaN fails it and so misses); the far side for the clear lanes
    // below, a near-edge lane's from its f64 distance (`hit_f64`, as `hit_triangle1`).
    mask &= simd::gt(t, rays.tnear);
    if simd::none(mask) {
        return (mask, t, t, t);
    }
    // barycentric: signed sub-triangle areas over the whole, as linear forms of w = q - v0.
    let q = rays.o + rays.d * t;
    let w = q - v0;
    let b1 = w.dot(Vec3x8::splat(leaf.p1(j)));
    let b2 = w.dot(Vec3x8::splat(leaf.p2(j)));
    let b0 = simd::splat(1.0) - b1 - b2;
    // inside when no coordinate is negative: clear lanes here, lanes within BARY_SAFE of an
    // edge by the f64 edge signs, exactly as hit_triangle1 does.
    let s = simd::splat(BARY_SAFE) * (dlen * simd::splat(leaf.n_len(j)) / dn.abs());
    let ns = -s;
    let sure = simd::ge(b0, s) & simd::ge(b1, s) & simd::ge(b2, s);
    let near = simd::ge(b0, ns) & simd::ge(b1, ns) & simd::ge(b2, ns);
    let unsure = simd::and_not(mask & near, sure);
    let mut hit = mask & sure & simd::lt(t, tfar);
    let mut t = t;
    if simd::any(unsure) {
        let bits = simd::bitmask(unsure);
        let i = leaf.slot(j);
        let (tnear, far) = (simd::lanes(rays.tnear), simd::lanes(tfar));
        let mut tl = simd::lanes(t);
        let mut resolved = 0;
        for lane in 0..simd::LANES {
            if bits >> lane & 1 == 1 {
                let (o, d) = (rays.o.lane(lane), rays.d.lane(lane));
                if let Some(t64) = hit_f64(accel, i, o, d, tnear[lane], far[lane]) {
                    resolved |= 1 << lane;
                    tl[lane] = t64;
                }
            }
        }
        hit |= simd::mask_from_bits(resolved);
        t = simd::from_lanes(tl);
    }
    (hit, t, b1, b2)
}

/// A leaf read from its wide block: the block itself (one pointer; each field's lane `j` at a
/// fixed offset from it), `|n|` per lane ([`TriBlock8::n_len`], the float `TriangleSoa`
/// stores) and the number of triangles.
pub struct BlockLeaf<'a> {
    block: &'a TriBlock8,
    n_len: [f32; 8],
    len: usize,
}

impl<'a> BlockLeaf<'a> {
    /// The first `len` lanes of `block`.
    #[inline(always)]
    pub fn new(block: &'a TriBlock8, len: u32) -> BlockLeaf<'a> {
        BlockLeaf {
            block,
            n_len: simd::lanes(block.n_len()),
            len: (len as usize).min(8),
        }
    }
    #[inline(always)]
    fn get(v: &Vec3x8, j: usize) -> [f32; 3] {
        let lane = |c: &F32x8| wide::bytemuck::cast_ref::<F32x8, [f32; 8]>(c)[j];
        [lane(&v.x), lane(&v.y), lane(&v.z)]
    }
}

impl Leaf for BlockLeaf<'_> {
    #[inline(always)]
    fn len(&self) -> usize {
        self.len
    }
    #[inline(always)]
    fn n(&self, j: usize) -> [f32; 3] {
        Self::get(&self.block.n, j)
    }
    #[inline(always)]
    fn v0(&self, j: usize) -> [f32; 3] {
        Self::get(&self.block.v0, j)
    }
    #[inline(always)]
    fn p1(&self, j: usize) -> [f32; 3] {
        Self::get(&self.block.p1, j)
    }
    #[inline(always)]
    fn p2(&self, j: usize) -> [f32; 3] {
        Self::get(&self.block.p2, j)
    }
    #[inline(always)]
    fn n_len(&self, j: usize) -> f32 {
        self.n_len[j]
    }
    #[inline(always)]
    fn slot(&self, j: usize) -> usize {
        self.block.slot[j] as usize
    }
}

/// Packet slab test: lanes of `active` whose ray meets the box within `[tnear, tfar]`, and
/// their entry and exit distances.
#[inline(always)]
pub(super) fn hit_box8(
    node: &super::Node,
    o: &Vec3x8,
    inv: &Vec3x8,
    tnear: F32x8,
    tfar: F32x8,
    active: M32x8,
) -> (M32x8, F32x8, F32x8) {
    let t0x = (simd::splat(node.min[0]) - o.x) * inv.x;
    let t1x = (simd::splat(node.max[0]) - o.x) * inv.x;
    let t0y = (simd::splat(node.min[1]) - o.y) * inv.y;
    let t1y = (simd::splat(node.max[1]) - o.y) * inv.y;
    let t0z = (simd::splat(node.min[2]) - o.z) * inv.z;
    let t1z = (simd::splat(node.max[2]) - o.z) * inv.z;
    let lo = simd::max(
        simd::max(simd::min(t0x, t1x), simd::min(t0y, t1y)),
        simd::max(simd::min(t0z, t1z), tnear),
    );
    let hi = simd::min(
        simd::min(simd::max(t0x, t1x), simd::max(t0y, t1y)),
        simd::min(simd::max(t0z, t1z), tfar),
    );
    (
        active & simd::le(lo, hi * simd::splat(SLAB_FAR_SCALE)),
        lo,
        hi,
    )
}

/// [`hit_box8`] for a packet whose active lanes share one direction octant: each axis's
/// near and far plane are picked once for the packet (`near[k]`: the box maximum is the
/// near plane, the direction component being negative), which gives exactly the `min` /
/// `max` of the two plane distances of [`hit_box8`]; the far distances come widened through
/// `inv_far = inv * SLAB_FAR_SCALE` (rounded once: the same bound as scaling the minimum,
/// see `wide1::hit_node1`) and `tfar_wide = tfar * SLAB_FAR_SCALE`. Six min / max and the
/// final multiply fewer per box.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn hit_box8_octant(
    node: &super::Node,
    o: &Vec3x8,
    inv: &Vec3x8,
    inv_far: &Vec3x8,
    near: [bool; 3],
    tnear: F32x8,
    tfar_wide: F32x8,
    active: M32x8,
) -> (M32x8, F32x8, F32x8) {
    let corner = |k: usize, max: bool| simd::splat(if max { node.max[k] } else { node.min[k] });
    let nx = (corner(0, near[0]) - o.x) * inv.x;
    let fx = (corner(0, !near[0]) - o.x) * inv_far.x;
    let ny = (corner(1, near[1]) - o.y) * inv.y;
    let fy = (corner(1, !near[1]) - o.y) * inv_far.y;
    let nz = (corner(2, near[2]) - o.z) * inv.z;
    let fz = (corner(2, !near[2]) - o.z) * inv_far.z;
    let lo = simd::max(simd::max(nx, ny), simd::max(nz, tnear));
    let hi = simd::min(simd::min(fx, fy), simd::min(fz, tfar_wide));
    (active & simd::le(lo, hi), lo, hi)
}

/// One traversal for closest hit and any hit (`ANY_HIT`: a lane retires at its first hit and
/// the walk stops when no lane is left), shared by the packet and hybrid engines. Each visited
/// node carries `here`, the lanes whose ray meets its box (a child's box lies inside its
/// parent's, and the slab test rounds monotonically, so no other lane can meet anything
/// below); leaves test only those. With `SWITCH > 0` (hybrid), a node reached by at most
/// `SWITCH` lanes that has a twin in the wide tree is handed to single-ray traversal lane by
/// lane (`hand_off::hand_off`); `SWITCH = 0` is the plain packet engine.
#[inline(always)]
pub(super) fn traverse8<const ANY_HIT: bool, const SWITCH: u32>(
    accel: &Accel,
    rays: &RayPacket8,
    mut active: M32x8,
    cull: bool,
) -> (HitPacket8, M32x8) {
    let mut hits = HitPacket8::none();
    let mut occluded = simd::splat(0.0);
    // (lanes that can hit nothing leave before the walk: see `RayPacket8::traceable`)
    active &= rays.traceable();
    if accel.nodes.is_empty() || simd::none(active) {
        return (hits, occluded);
    }
    let d = rays.d;
    let inv = Vec3x8::new(safe_inv8(d.x), safe_inv8(d.y), safe_inv8(d.z));
    let mut tfar = rays.tfar;
    let dlen = simd::sqrt(rays.d.dot(rays.d));
    // entries: a node and the bits of the lanes that met its box when it was pushed.
    let mut stack: super::stack::Stack<(u32, u32), 64> = super::stack::Stack::new();
    let mut lanes = None;
    let mut node = 0u32;
    // Hybrid: when the active lanes share one direction octant, near and far planes are
    // picked per packet (`hit_box8_octant`). Measured (README, "Engines"): hybrid8 1.03-1.08x
    // on the kitten's incoherent, primary-hits and primary rays, level at 1.3M; the packet
    // engine keeps the per-lane test, which measured 0.91x on its shadow rays with it. (With
    // SWITCH = 0 the octant is not even looked at.)
    let octant = (SWITCH > 0).then(|| {
        let act = simd::bitmask(active);
        let neg = [inv.x, inv.y, inv.z].map(|v| simd::bitmask(simd::lt(v, simd::splat(0.0))) & act);
        let one = neg.iter().all(|&b| b == 0 || b == act);
        one.then(|| (neg.map(|b| b != 0), inv * simd::splat(SLAB_FAR_SCALE)))
    });
    let boxes = |n: u32, tfar: F32x8, m: M32x8| {
        let node = &accel.nodes[n as usize];
        if let Some(Some((near, inv_far))) = octant {
            let tfar_wide = tfar * simd::splat(SLAB_FAR_SCALE);
            hit_box8_octant(
                node, &rays.o, &inv, &inv_far, near, rays.tnear, tfar_wide, m,
            )
        } else {
            hit_box8(node, &rays.o, &inv, rays.tnear, tfar, m)
        }
    };
    // The root must be hit by some lane.
    let (mut here, ..) = boxes(0, tfar, active);
    if simd::none(here) {
        return (hits, occluded);
    }
    loop {
        let entry = if SWITCH > 0 {
            accel.wide.entry[node as usize]
        } else {
            NO_ENTRY
        };
        let n = accel.nodes[node as usize];
        if entry != NO_ENTRY && simd::bitmask(here).count_ones() <= SWITCH {
            // switch: the few lanes here walk this subtree's wide twin one by one.
            let occ = hand_off::<ANY_HIT>(
                accel, rays, &mut lanes, here, entry, cull, &mut hits, &mut tfar,
            );
            if ANY_HIT {
                occluded |= occ;
                active = simd::and_not(active, occ);
                if simd::none(active) {
                    return (hits, occluded);
                }
            }
        } else if n.count > 0 {
            // every triangle of `leaf` against the lanes here (written once for both kinds
            // of leaf: as a function taking the walk's state by reference it cost the packet
            // engine 6% on shadow rays)
            macro_rules! test_leaf {
                ($leaf:expr) => {{
                    let leaf = $leaf;
                    for j in 0..leaf.len() {
                        let slot = leaf.slot(j);
                        let (mask, t, b1, b2) =
                            hit_triangle8(accel, &leaf, j, rays, dlen, tfar, here, cull);
                        if simd::none(mask) {
                            continue;
                        }
                        if ANY_HIT {
                            occluded |= mask;
                            active = simd::and_not(active, mask);
                            here = simd::and_not(here, mask);
                            if simd::none(active) {
                                return (hits, occluded);
                            }
                            continue;
                        }
                        // record hit: as in intersect1, the new limit is the next float above
                        // t and an exact tie keeps the lower original triangle index.
                        let id = U32x8::splat(accel.tris.prim[slot]);
                        let better = nearer8(t, id, hits.t, hits.tri);
                        let take = mask & better;
                        hits.tri = simd::select_u32(take, id, hits.tri);
                        hits.t = simd::select(take, t, hits.t);
                        hits.b1 = simd::select(take, b1, hits.b1);
                        hits.b2 = simd::select(take, b2, hits.b2);
                        tfar = simd::select(take, simd::next_up(t), tfar);
                    }
                }};
            }
            // hybrid: the leaf's triangles from its block of the wide tree when it is one
            // block (the lines the single-ray walks read too), else from the columns
            if SWITCH > 0 && entry & LEAF_BIT != 0 && leaf_blocks(entry).1 == 1 {
                let b = leaf_blocks(entry).0;
                test_leaf!(BlockLeaf::new(&accel.wide.blocks[b], n.count));
            } else {
                test_leaf!(accel.tris.leaf(n.first as usize, n.count as usize));
            }
        } else {
            // ordered children: both boxes tested for the lanes here, the side nearer for
            // most lanes first (any hit: see `ORIGIN_LAST`).
            let (l, r) = (n.first, n.first + 1);
            let (ml, tl, hl) = boxes(l, tfar, here);
            let (mr, tr, hr) = boxes(r, tfar, here);
            match (simd::any(ml), simd::any(mr)) {
                (true, true) => {
                    let both = ml & mr;
                    // per lane: the nearer box first, or with any hit the box not holding
                    // the origin, else (both hold it) the one left later (see
                    // `ORIGIN_LAST`); the side most lanes prefer goes first.
                    let near_l = simd::le(tl, tr);
                    let pref = if ANY_HIT && ORIGIN_LAST {
                        let (il, ir) = (simd::le(tl, rays.tnear), simd::le(tr, rays.tnear));
                        let same = simd::select(il, simd::ge(hl, hr), near_l);
                        simd::and_not(ir, il) | simd::and_not(same, il ^ ir)
                    } else {
                        near_l
                    };
                    let left_first = simd::bitmask(both & pref).count_ones() * 2
                        >= simd::bitmask(both).count_ones();
                    let (first, later, m, ml_later) = if left_first {
                        (l, r, ml, mr)
                    } else {
                        (r, l, mr, ml)
                    };
                    // (the lane bits serve only any-hit pops; closest hit tests again)
                    stack.push((later, if ANY_HIT { simd::bitmask(ml_later) } else { 0 }));
                    (node, here) = (first, m);
                    continue;
                }
                (true, false) => {
                    (node, here) = (l, ml);
                    continue;
                }
                (false, true) => {
                    (node, here) = (r, mr);
                    continue;
                }
                (false, false) => {}
            }
        }
        // pop the next node some lane still reaches before its closest hit. With ANY_HIT,
        // `tfar` has not moved since the push, so the lanes that met the box then and are
        // still active are exactly those a new slab test would find (a lane that missed the
        // parent's box misses this one too); closest hit tests again with the lanes' new
        // limits.
        loop {
            let Some((next, bits)) = stack.pop() else {
                return (hits, occluded);
            };
            let m = if ANY_HIT {
                active & simd::mask_from_bits(bits)
            } else {
                boxes(next, tfar, active).0
            };
            if simd::any(m) {
                (node, here) = (next, m);
                break;
            }
        }
    }
}

/// Closest hits of the `active` lanes (others report no hit).
pub fn intersect8(accel: &Accel, rays: &RayPacket8, active: M32x8, cull: bool) -> HitPacket8 {
    traverse8::<false, 0>(accel, rays, active, cull).0
}

/// Lanes of `active` whose ray hits anything with `tnear < t < tfar`.
pub fn occluded8(accel: &Accel, rays: &RayPacket8, active: M32x8, cull: bool) -> M32x8 {
    traverse8::<true, 0>(accel, rays, active, cull).1
}

/// Hit of lane `i` as the scalar API reports it (for tests and tools).
pub fn lane_hit(h: &HitPacket8, i: usize) -> Option<Hit> {
    h.lane(i)
}
