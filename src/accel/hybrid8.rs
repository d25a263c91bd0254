//! Hybrid packets: 8 rays down the binary tree together while they stay together, then each
//! remaining ray alone down the 8-wide tree (Embree's hybrid intersector switches the same
//! way, by the number of rays still active at a node).
//!
//! The packet part is `traverse8` with one change: each visited node carries the mask of the
//! lanes whose ray meets its box, and leaves test only those. When that mask has at most
//! [`SWITCH`] lanes and the node has a twin in the wide tree (`Bvh8::entry`), every such lane
//! walks that wide subtree single-ray from its current closest hit. Results are bit for bit
//! `intersect1`'s: each lane's answer is the smallest `(t, triangle)` among the triangles its
//! ray meets in the subtrees it visits, however they are split between the two walks.

use super::packet::{hit_box8, hit_triangle8};
use super::scalar::Stack;
use super::wide::NO_ENTRY;
use super::wide1::{Lanes, RayWide, STACK, walk};
use super::{Accel, safe_inv};
use crate::packet::{HitPacket8, RayPacket8};
use crate::ray::Hit;
use crate::simd::{self, M32x8, U32x8, Vec3x8};

/// Hand a node's lanes to single-ray traversal when at most this many remain. Measured on the
/// bench workloads (README, "Engines"): see there for the sweep.
pub const SWITCH: u32 = 3;

#[inline(always)]
fn traverse_hybrid8<const ANY_HIT: bool>(
    accel: &Accel,
    rays: &RayPacket8,
    mut active: M32x8,
    cull: bool,
) -> (HitPacket8, M32x8) {
    let mut hits = HitPacket8::none();
    let mut occluded = simd::splat(0.0);
    if accel.nodes.is_empty() || simd::none(active) {
        return (hits, occluded);
    }
    let bvh = &accel.wide;
    let d = rays.d;
    let inv = Vec3x8::new(
        simd::from_lanes(simd::lanes(d.x).map(safe_inv)),
        simd::from_lanes(simd::lanes(d.y).map(safe_inv)),
        simd::from_lanes(simd::lanes(d.z).map(safe_inv)),
    );
    let mut tfar = rays.tfar;
    let dlen = simd::sqrt(rays.d.dot(rays.d));
    let mut stack: Stack<u32, 64> = Stack::new();
    let mut lanes: Option<Lanes> = None;
    let mut node = 0u32;
    let (mut here, _) = hit_box8(&accel.nodes[0], &rays.o, &inv, rays.tnear, tfar, active);
    if simd::none(here) {
        return (hits, occluded);
    }
    loop {
        let bits = simd::bitmask(here);
        let entry = bvh.entry[node as usize];
        if bits.count_ones() <= SWITCH && entry != NO_ENTRY {
            // switch: each lane still here walks the wide twin of this subtree alone.
            let l = lanes.get_or_insert_with(|| Lanes::of(rays));
            let mut tf = simd::lanes(tfar);
            let mut new = HitLanes::of(&hits);
            let mut occ = 0u32;
            let mut b = bits;
            STACK.with_borrow_mut(|st| {
                let need = bvh.depth * 7 + 8;
                if st.len() < need {
                    st.resize(need, (0, 0.0));
                }
                while b != 0 {
                    let i = b.trailing_zeros() as usize;
                    b &= b - 1;
                    let r = RayWide::new(&l.ray(i));
                    let Some(h) = walk::<ANY_HIT>(accel, bvh, entry, &r, tf[i], cull, st) else {
                        continue;
                    };
                    if ANY_HIT {
                        occ |= 1 << i;
                    } else if new.take(i, h) {
                        tf[i] = h.t.next_up();
                    }
                }
            });
            if ANY_HIT {
                let m = simd::mask_from_bits(occ);
                occluded |= m;
                active = simd::and_not(active, m);
                if simd::none(active) {
                    return (hits, occluded);
                }
            } else {
                hits = new.packet();
                tfar = simd::from_lanes(tf);
            }
        } else {
            let n = accel.nodes[node as usize];
            if n.count > 0 {
                for slot in n.first..n.first + n.count {
                    let slot = slot as usize;
                    let (mask, t, b1, b2) =
                        hit_triangle8(accel, slot, rays, dlen, tfar, here, cull);
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
                    // record hit: as in intersect1 (the next float above t, lower index on ties).
                    let id = U32x8::splat(accel.tris.prim[slot]);
                    let better = simd::lt(t, hits.t) | simd::lt_u32(id, hits.tri);
                    let take = mask & better;
                    hits.tri = simd::select_u32(take, id, hits.tri);
                    hits.t = simd::select(take, t, hits.t);
                    hits.b1 = simd::select(take, b1, hits.b1);
                    hits.b2 = simd::select(take, b2, hits.b2);
                    let next_up = simd::from_lanes(simd::lanes(t).map(f32::next_up));
                    tfar = simd::select(take, next_up, tfar);
                }
            } else {
                // ordered children: both boxes tested for the lanes here, the side nearer
                // for most lanes first.
                let (l, r) = (n.first, n.first + 1);
                let (ml, tl) = hit_box8(
                    &accel.nodes[l as usize],
                    &rays.o,
                    &inv,
                    rays.tnear,
                    tfar,
                    here,
                );
                let (mr, tr) = hit_box8(
                    &accel.nodes[r as usize],
                    &rays.o,
                    &inv,
                    rays.tnear,
                    tfar,
                    here,
                );
                match (simd::any(ml), simd::any(mr)) {
                    (true, true) => {
                        let both = ml & mr;
                        let left_first = simd::bitmask(both & simd::le(tl, tr)).count_ones() * 2
                            >= simd::bitmask(both).count_ones();
                        let (near, far, m) = if left_first { (l, r, ml) } else { (r, l, mr) };
                        stack.push(far);
                        node = near;
                        here = m;
                        continue;
                    }
                    (true, false) => {
                        node = l;
                        here = ml;
                        continue;
                    }
                    (false, true) => {
                        node = r;
                        here = mr;
                        continue;
                    }
                    (false, false) => {}
                }
            }
        }
        // pop the next node some lane still reaches before its closest hit.
        loop {
            let Some(next) = stack.pop() else {
                return (hits, occluded);
            };
            let (m, _) = hit_box8(
                &accel.nodes[next as usize],
                &rays.o,
                &inv,
                rays.tnear,
                tfar,
                active,
            );
            if simd::any(m) {
                node = next;
                here = m;
                break;
            }
        }
    }
}

/// A hit packet as plain lanes while single-ray walks update it.
struct HitLanes {
    tri: [u32; 8],
    t: [f32; 8],
    b1: [f32; 8],
    b2: [f32; 8],
}

impl HitLanes {
    fn of(h: &HitPacket8) -> HitLanes {
        HitLanes {
            tri: simd::u32_lanes(h.tri),
            t: simd::lanes(h.t),
            b1: simd::lanes(h.b1),
            b2: simd::lanes(h.b2),
        }
    }
    /// Record `h` in lane `i` if it is the better hit (as in intersect1: it was found below
    /// the lane's limit, so it is nearer, or as near with a lower index).
    fn take(&mut self, i: usize, h: Hit) -> bool {
        let better = self.tri[i] == Hit::NONE_ID || h.t < self.t[i] || h.tri < self.tri[i];
        if better {
            (self.tri[i], self.t[i], self.b1[i], self.b2[i]) = (h.tri, h.t, h.b1, h.b2);
        }
        better
    }
    fn packet(&self) -> HitPacket8 {
        HitPacket8 {
            tri: simd::u32_from_lanes(self.tri),
            t: simd::from_lanes(self.t),
            b1: simd::from_lanes(self.b1),
            b2: simd::from_lanes(self.b2),
        }
    }
}

/// Closest hits of the `active` lanes, hybrid (equals `intersect8` and `intersect1` bit for bit).
pub fn intersect_hybrid8(
    accel: &Accel,
    rays: &RayPacket8,
    active: M32x8,
    cull: bool,
) -> HitPacket8 {
    traverse_hybrid8::<false>(accel, rays, active, cull).0
}

/// Lanes of `active` whose ray hits anything with `tnear < t < tfar`, hybrid.
pub fn occluded_hybrid8(accel: &Accel, rays: &RayPacket8, active: M32x8, cull: bool) -> M32x8 {
    traverse_hybrid8::<true>(accel, rays, active, cull).1
}
