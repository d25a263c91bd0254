//! The hybrids' switch: the lanes still active at a binary node, each alone down the wide
//! subtree of the same triangles (`Bvh8::entry`), from its current closest hit. Used by the
//! 8-ray walk (`packet::traverse8` with a switch, the `hybrid8` engine).

use super::Accel;
use super::robust::nearer;
use super::stack::{STACK, grow_stack};
use super::wide1::{Lanes, RayWide, walk};
use crate::packet::{HitPacket8, RayPacket8};
use crate::ray::Hit;
use crate::simd::{self, F32x8, M32x8};

/// Hand a node's lanes to single-ray traversal when at most this many remain. Measured on the
/// bench workloads (`docs/engines.md`).
pub const SWITCH: u32 = 3;

/// The switch of `traverse8`: each lane of `here` walks the wide subtree at `entry` alone,
/// from its current closest hit (`hits`, `tfar`, updated) or, with `ANY_HIT`, until its first
/// hit; returns the lanes found occluded (any hit).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn hand_off<const ANY_HIT: bool>(
    accel: &Accel,
    rays: &RayPacket8,
    lanes: &mut Option<Lanes>,
    here: M32x8,
    entry: u32,
    cull: bool,
    hits: &mut HitPacket8,
    tfar: &mut F32x8,
) -> M32x8 {
    let bvh = &accel.wide;
    let l = lanes.get_or_insert_with(|| Lanes::of(rays));
    let mut tf = simd::lanes(*tfar);
    let mut new = HitLanes::of(hits);
    let mut occ = 0u32;
    let mut b = simd::bitmask(here);
    STACK.with_borrow_mut(|st| {
        grow_stack(st, bvh);
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
    if !ANY_HIT {
        *hits = new.packet();
        *tfar = simd::from_lanes(tf);
    }
    simd::mask_from_bits(occ)
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
        let better = self.tri[i] == Hit::NONE_ID || nearer(h.t, h.tri, self.t[i], self.tri[i]);
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
