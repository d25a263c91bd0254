//! 16-ray packets on AVX-512: the packet engine's walk of the binary tree (`traverse8`) with
//! 16 lanes in one 512-bit register, so each box and triangle test serves twice the rays
//! for about the instructions of one 8-lane test. Embree traces its 16-wide packets the same
//! way on these machines. `packet16` never leaves the packet. `hybrid16`'s closest hit hands
//! a node's lanes to single-ray traversal of the wide tree once at most [`SWITCH16`] remain,
//! as `hybrid8` does; its any hit takes the 16 rays down the wide tree itself
//! (`traverse_wide16_any`, Embree's hybrid scheme), each lane alone once at most
//! [`SWITCH_WIDE16`] remain.
//!
//! The build targets x86-64-v3 (AVX2), so these kernels are compiled for AVX-512 on their
//! own (`#[target_feature]`) and chosen at run time ([`available`]); without AVX-512 the
//! entry points trace the two halves with the 8-lane engines. Either way every lane equals
//! `intersect1` / `occluded1` bit for bit: each step is `hit_triangle8`'s IEEE operation in
//! the same order (no FMA; `min` / `max` with the same operand order and NaN rule), boxes
//! are `hit_box8`'s padded test, and near-edge lanes take the same f64 edge test.

use super::hybrid8::{intersect_hybrid8, occluded_hybrid8};
use super::packet::{intersect8, occluded8};
use super::robust::{BARY_SAFE, nearer};
use super::scalar::hit_f64;
use super::stack::{STACK, Stack, grow_stack};
use super::tri_soa::Leaf;
use super::wide::NO_ENTRY;
use super::wide1::{RayWide, walk};
use super::{Accel, ORIGIN_LAST, SLAB_FAR_SCALE};
use crate::packet::{HitPacket8, RayPacket8};
use crate::ray::Hit;
use crate::simd::{self, M32x8};
use lanes::*;
use std::arch::x86_64::*;

mod lanes;

/// Whether the AVX-512 kernels run (the CPU has AVX-512 F and DQ, and `WHITTED_NO_AVX512` is
/// not set: with it the 16-ray engines trace as on a CPU without AVX-512), checked once.
pub fn available() -> bool {
    static HAVE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *HAVE.get_or_init(|| {
        std::env::var_os("WHITTED_NO_AVX512").is_none()
            && std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512dq")
    })
}

/// The AVX-512 walk when the CPU has AVX-512, else `None` (the caller's 8-lane fallback).
#[inline(always)]
fn run16<const ANY_HIT: bool, const SWITCH: u32>(
    accel: &Accel,
    rays: [&RayPacket8; 2],
    active: [M32x8; 2],
    cull: bool,
) -> Option<([HitPacket8; 2], u16)> {
    // SAFETY: `available()` checked that the CPU has AVX-512 F and DQ, the only features
    // the kernel is compiled for beyond the crate's baseline.
    #[allow(unsafe_code)]
    available().then(|| unsafe { traverse16::<ANY_HIT, SWITCH>(accel, rays, active, cull) })
}

/// Closest hits of two packets traced as one 16-ray packet (lanes `0..8` from `rays[0]`).
pub fn intersect16(
    accel: &Accel,
    rays: [&RayPacket8; 2],
    active: [M32x8; 2],
    cull: bool,
) -> [HitPacket8; 2] {
    let active = traceable(rays, active);
    run16::<false, 0>(accel, rays, active, cull).map_or_else(
        || [0, 1].map(|h| intersect8(accel, rays[h], active[h], cull)),
        |(hits, _)| hits,
    )
}

/// Occluded lanes of two packets traced as one 16-ray packet (any hit).
pub fn occluded16(
    accel: &Accel,
    rays: [&RayPacket8; 2],
    active: [M32x8; 2],
    cull: bool,
) -> [M32x8; 2] {
    let active = traceable(rays, active);
    run16::<true, 0>(accel, rays, active, cull).map_or_else(
        || [0, 1].map(|h| occluded8(accel, rays[h], active[h], cull)),
        |(_, occ)| halves(occ),
    )
}

/// Hand a node's lanes to single-ray traversal when at most this many of 16 remain
/// (`hybrid16`'s closest hit of packets with mixed octants, i.e. incoherent rays). Set to 6
/// when a hand-off rebuilt each lane's splat from scratch (kitten incoherent rays, best of 5,
/// one thread: 3 -> 7.78, 6 -> 7.88, 10 -> 7.62 Mrays/s). With the splats taken from the
/// packet's lanes (`Rays16::walker`), the bench's incoherent rays at 1.3M triangles, against
/// `wide1` alternating in one process (medians of 9 and 15 passes): 6 0.95x and 1.01x, 8
/// 1.01x, 10 1.01x and 1.06x, 12 1.01x and 1.05x, 14 1.00x, 16 (every lane at the root)
/// 0.91x; on the kitten 10 ran 1.02x and 12 1.00x the rate of 6.
pub const SWITCH16: u32 = 10;

/// `hybrid16`'s any hit (`traverse_wide16_any`): a node or leaf reached by at most this
/// many of 16 lanes is walked or tested by each lane alone. At 1.3M triangles (bench shadow
/// rays, alternating in one process, medians against `packet16`): 0 (the packet to every
/// leaf) 1.04x, 4 1.26x, 8 1.21x, 12 1.10x, 14 (Embree's `switchThresholdIncoherent` for
/// 16-ray packets) 1.05x; 2, 3, 5 and 6 within 3% of 4. On the kitten 4 ran 1.04x
/// `packet16`, 8 0.97x and 12 0.88x.
pub const SWITCH_WIDE16: u32 = 4;

/// Closest hits of two packets as one 16-ray hybrid packet. When the active lanes' directions
/// share an octant (camera rays, coherent reflections) the 16 rays go down the wide tree
/// together (`traverse_wide16_closest`); otherwise `packet16`'s walk of the binary tree
/// while more than [`SWITCH16`] lanes share a node, then each remaining lane alone down the
/// wide tree (`hybrid8` on both halves without AVX-512).
///
/// Measured (alternating in one process, medians of 7-9 passes): at 1.3M triangles the wide
/// walk traced the bench's primary-hits-only rays 1.19x as fast as the binary one (switch 2:
/// 1.12x, 6: 1.19x, 8: 1.13x, 12: 1.09x), on the kitten 0.93x; incoherent rays, whose
/// packets of 16 never share an octant, ran 0.91x (1.3M) and 0.89x (kitten) that way, so
/// they keep the binary walk.
pub fn intersect_hybrid16(
    accel: &Accel,
    rays: [&RayPacket8; 2],
    active: [M32x8; 2],
    cull: bool,
) -> [HitPacket8; 2] {
    let active = traceable(rays, active);
    if available() && one_octant(rays, active) {
        // SAFETY: `available()` checked that the CPU has AVX-512 F and DQ, the only
        // features the kernel is compiled for beyond the crate's baseline.
        #[allow(unsafe_code)]
        return unsafe { traverse_wide16_closest(accel, rays, active, cull) };
    }
    run16::<false, SWITCH16>(accel, rays, active, cull).map_or_else(
        || [0, 1].map(|h| intersect_hybrid8(accel, rays[h], active[h], cull)),
        |(hits, _)| hits,
    )
}

/// `active` less the lanes that can hit nothing ([`RayPacket8::traceable`]), which leave
/// before the walk.
#[inline(always)]
fn traceable(rays: [&RayPacket8; 2], active: [M32x8; 2]) -> [M32x8; 2] {
    [
        active[0] & rays[0].traceable(),
        active[1] & rays[1].traceable(),
    ]
}

/// Whether the active lanes of both packets point into one octant (each direction
/// component's sign the same in every active lane).
fn one_octant(rays: [&RayPacket8; 2], active: [M32x8; 2]) -> bool {
    let bits = |p: &RayPacket8, a: M32x8| {
        let a = simd::bitmask(a);
        [p.d.x, p.d.y, p.d.z].map(|c| (simd::bitmask(c) & a, a))
    };
    let (x, y) = (bits(rays[0], active[0]), bits(rays[1], active[1]));
    (0..3).all(|k| {
        let (neg, all) = (x[k].0 | y[k].0 << 8, x[k].1 | y[k].1 << 8);
        neg == 0 || neg == all
    })
}

/// Occluded lanes of two packets as one 16-ray hybrid packet (any hit) down the wide tree
/// (`traverse_wide16_any`; `hybrid8` on both halves without AVX-512).
pub fn occluded_hybrid16(
    accel: &Accel,
    rays: [&RayPacket8; 2],
    active: [M32x8; 2],
    cull: bool,
) -> [M32x8; 2] {
    let active = traceable(rays, active);
    if !available() {
        return [0, 1].map(|h| occluded_hybrid8(accel, rays[h], active[h], cull));
    }
    // SAFETY: `available()` checked that the CPU has AVX-512 F and DQ, the only features
    // the kernel is compiled for beyond the crate's baseline.
    #[allow(unsafe_code)]
    halves(unsafe { traverse_wide16_any(accel, rays, active, cull) })
}

/// The two packets' masks of 16 lane bits.
fn halves(bits: u16) -> [M32x8; 2] {
    [
        simd::mask_from_bits(bits as u32 & 0xff),
        simd::mask_from_bits(bits as u32 >> 8),
    ]
}

/// `hit_triangle8` in 16 lanes: the lanes of `active` that hit the `j`-th triangle of `leaf`
/// with `tnear < t < tfar`, and their `(t, b1, b2)`. (A macro: as a function, which cannot be
/// `#[inline(always)]` with `#[target_feature]`, LLVM kept it out of line, with its four
/// results going through memory.)
macro_rules! hit_triangle16 {
    ($accel:expr, $leaf:expr, $j:expr, $r:expr, $tfar:expr, $active:expr, $cull:expr) => {
        'tri: {
            let (accel, leaf, j, r, tfar): (&Accel, _, usize, &Rays16, __m512) =
                ($accel, $leaf, $j, $r, $tfar);
            let n = splat3(leaf.n(j));
            let v0 = splat3(leaf.v0(j));
            // plane hit: t = <v0 - p, n> / <d, n>
            let dn = dot(r.d, n);
            let mut mask: u16 = $active;
            // culling: skip back faces (<d, n> >= 0).
            if $cull {
                mask &= !_mm512_cmp_ps_mask::<_CMP_GE_OQ>(dn, splat(0.0));
                if mask == 0 {
                    break 'tri (0u16, dn, dn, dn);
                }
            }
            let t = _mm512_div_ps(dot(sub3(v0, r.o), n), dn);
            // depth test, near side (NaN fails it and so misses); the far side for the
            // clear lanes below, a near-edge lane's from its f64 distance (`hit_f64`, as
            // `hit_triangle1`).
            mask = _mm512_mask_cmp_ps_mask::<_CMP_GT_OQ>(mask, t, r.tnear);
            if mask == 0 {
                break 'tri (0, t, t, t);
            }
            // barycentric: signed sub-triangle areas over the whole, as linear forms of
            // w = q - v0.
            let q = V3 {
                x: _mm512_add_ps(r.o.x, _mm512_mul_ps(r.d.x, t)),
                y: _mm512_add_ps(r.o.y, _mm512_mul_ps(r.d.y, t)),
                z: _mm512_add_ps(r.o.z, _mm512_mul_ps(r.d.z, t)),
            };
            let w = sub3(q, v0);
            let b1 = dot(w, splat3(leaf.p1(j)));
            let b2 = dot(w, splat3(leaf.p2(j)));
            let b0 = _mm512_sub_ps(_mm512_sub_ps(splat(1.0), b1), b2);
            // inside when no coordinate is negative; lanes within BARY_SAFE of an edge by
            // the f64 edge signs, as hit_triangle1 does.
            let s = _mm512_mul_ps(
                splat(BARY_SAFE),
                _mm512_div_ps(
                    _mm512_mul_ps(r.dlen, splat(leaf.n_len(j))),
                    _mm512_abs_ps(dn),
                ),
            );
            let ns = _mm512_xor_ps(s, splat(-0.0));
            let ge = |m: u16, a: __m512, b: __m512| _mm512_mask_cmp_ps_mask::<_CMP_GE_OQ>(m, a, b);
            let sure = ge(ge(ge(mask, b0, s), b1, s), b2, s);
            let near = ge(ge(ge(mask, b0, ns), b1, ns), b2, ns);
            let mut hit = _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(sure, t, tfar);
            let mut unsure = near & !sure;
            let mut t = t;
            if unsure != 0 {
                let (tn, tf) = (lanes16(r.tnear), lanes16(tfar));
                let mut tl = lanes16(t);
                while unsure != 0 {
                    let lane = unsure.trailing_zeros() as usize;
                    unsure &= unsure - 1;
                    let (o, d) = (r.o1(lane), r.d1(lane));
                    if let Some(t64) = hit_f64(accel, leaf.slot(j), o, d, tn[lane], tf[lane]) {
                        hit |= 1 << lane;
                        tl[lane] = t64;
                    }
                }
                t = bytemuck::cast(tl);
            }
            (hit, t, b1, b2)
        }
    };
}

/// [`nearer`] in 16 lanes: the lanes whose hit (`t`, `tri`) replaces the best so far. A
/// macro, as the other 16-lane steps, so that it inlines into the AVX-512 walks.
macro_rules! nearer16 {
    ($t:expr, $tri:expr, $than_t:expr, $than_tri:expr) => {{
        let (t, than_t) = ($t, $than_t);
        _mm512_cmp_ps_mask::<_CMP_LT_OQ>(t, than_t)
            | (_mm512_cmp_ps_mask::<_CMP_EQ_OQ>(t, than_t)
                & _mm512_cmplt_epu32_mask($tri, $than_tri))
    }};
}

/// Record hits in the lanes of `take` (already the lanes whose hit is nearer, or as near with
/// a lower triangle index): triangle `id`, `(t, b1, b2)`, and the new `limit`, the next
/// float above `t` (as in `intersect1`). A macro over the walk's hit vectors, like
/// `hit_triangle16`.
macro_rules! take_hits16 {
    ($take:expr, $id:expr, $t:expr, $b1:expr, $b2:expr, $limit:expr;
     $tri:ident, $t_hit:ident, $b1_hit:ident, $b2_hit:ident, $tfar:ident) => {{
        let (take, t) = ($take, $t);
        $tri = _mm512_mask_mov_epi32($tri, take, $id);
        $t_hit = _mm512_mask_mov_ps($t_hit, take, t);
        $b1_hit = _mm512_mask_mov_ps($b1_hit, take, $b1);
        $b2_hit = _mm512_mask_mov_ps($b2_hit, take, $b2);
        $tfar = _mm512_mask_mov_ps($tfar, take, $limit);
    }};
}

/// Record lane `i`'s hit `h` from a single-ray walk, found below the lane's limit: so nearer,
/// or as near with a lower index (as `hand_off::HitLanes::take`).
macro_rules! take_lane16 {
    ($i:expr, $h:expr; $tri:ident, $t_hit:ident, $b1_hit:ident, $b2_hit:ident, $tfar:ident) => {{
        let (i, h): (usize, Hit) = ($i, $h);
        let (old_tri, old_t) = (bytemuck::cast::<_, [u32; 16]>($tri)[i], lanes16($t_hit)[i]);
        if old_tri == Hit::NONE_ID || nearer(h.t, h.tri, old_t, old_tri) {
            take_hits16!(1u16 << i, _mm512_set1_epi32(h.tri as i32), splat(h.t), splat(h.b1),
                splat(h.b2), splat(h.t.next_up()); $tri, $t_hit, $b1_hit, $b2_hit, $tfar);
        }
    }};
}

/// `traverse8` in 16 lanes: closest hits, and with `ANY_HIT` the occluded lanes. With
/// `SWITCH > 0` (`hybrid16`) a node reached by at most `SWITCH` lanes that has a twin in the
/// wide tree is walked by each of those lanes alone (`wide1::walk`).
#[target_feature(enable = "avx512f,avx512dq")]
fn traverse16<const ANY_HIT: bool, const SWITCH: u32>(
    accel: &Accel,
    rays: [&RayPacket8; 2],
    active: [M32x8; 2],
    cull: bool,
) -> ([HitPacket8; 2], u16) {
    let none = [HitPacket8::none(); 2];
    let mut active = (simd::bitmask(active[0]) | simd::bitmask(active[1]) << 8) as u16;
    if accel.nodes.is_empty() || active == 0 {
        return (none, 0);
    }
    let (mut r, mut tfar) = rays16(rays);
    r.octant = octant_of([r.inv.x, r.inv.y, r.inv.z], active);
    let mut occluded = 0u16;
    let mut tri = _mm512_set1_epi32(Hit::NONE_ID as i32);
    let mut t_hit = splat(f32::INFINITY);
    let (mut b1_hit, mut b2_hit) = (splat(0.0), splat(0.0));
    // entries: a node and the lanes that met its box when it was pushed.
    let mut stack: Stack<(u32, u16), 64> = Stack::new();
    let mut node = 0u32;
    // hybrid: each lane's splat for the single-ray walks, made at its first hand-off
    let mut walkers: [Option<RayWide>; 16] = [None; 16];
    let (mut here, ..) = hit_box16(&accel.nodes[0], &r, tfar, active);
    if here == 0 {
        return (none, 0);
    }
    loop {
        // every triangle of `leaf` against the lanes here (a macro, as in `traverse8`)
        macro_rules! test_leaf {
            ($leaf:expr) => {{
                let leaf = $leaf;
                for j in 0..leaf.len() {
                    let (mask, t, b1, b2) = hit_triangle16!(accel, &leaf, j, &r, tfar, here, cull);
                    if mask == 0 {
                        continue;
                    }
                    if ANY_HIT {
                        occluded |= mask;
                        active &= !mask;
                        here &= !mask;
                        if active == 0 {
                            return (none, occluded);
                        }
                        continue;
                    }
                    // record hit: as in intersect1, the new limit is the next float above t and
                    // an exact tie keeps the lower original triangle index.
                    let id = _mm512_set1_epi32(accel.tris.prim[leaf.slot(j)] as i32);
                    let better = nearer16!(t, id, t_hit, tri);
                    take_hits16!(mask & better, id, t, b1, b2, next_up(t); tri, t_hit, b1_hit, b2_hit, tfar);
                }
            }};
        }
        let n = accel.nodes[node as usize];
        let entry = if SWITCH > 0 {
            accel.wide.entry[node as usize]
        } else {
            NO_ENTRY
        };
        if entry != NO_ENTRY && here.count_ones() <= SWITCH {
            // switch: the few lanes here walk this subtree's wide twin one by one, from their
            // current closest hit (as `hybrid8::hand_off`).
            let tf = lanes16(tfar);
            let mut bits = here;
            STACK.with_borrow_mut(|st| {
                grow_stack(st, &accel.wide);
                while bits != 0 {
                    let i = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    // (each lane's splat built once per packet)
                    let rw = walkers[i].get_or_insert_with(|| r.walker(i));
                    let Some(h) = walk::<ANY_HIT>(accel, &accel.wide, entry, rw, tf[i], cull, st)
                    else {
                        continue;
                    };
                    let lane = 1u16 << i;
                    if ANY_HIT {
                        occluded |= lane;
                        active &= !lane;
                        continue;
                    }
                    take_lane16!(i, h; tri, t_hit, b1_hit, b2_hit, tfar);
                }
            });
            if ANY_HIT && active == 0 {
                return (none, occluded);
            }
        } else if n.count > 0 {
            test_leaf!(accel.tris.leaf(n.first as usize, n.count as usize));
        } else {
            // ordered children: both boxes tested for the lanes here, the side nearer for
            // most lanes first (any hit: see `ORIGIN_LAST`).
            let (l, rr) = (n.first, n.first + 1);
            let (ml, tl, hl) = hit_box16(&accel.nodes[l as usize], &r, tfar, here);
            let (mr, tr, hr) = hit_box16(&accel.nodes[rr as usize], &r, tfar, here);
            match (ml != 0, mr != 0) {
                (true, true) => {
                    let both = ml & mr;
                    let near_l = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(tl, tr);
                    let pref = if ANY_HIT && ORIGIN_LAST {
                        let il = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(tl, r.tnear);
                        let ir = _mm512_cmp_ps_mask::<_CMP_LE_OQ>(tr, r.tnear);
                        let ge = _mm512_cmp_ps_mask::<_CMP_GE_OQ>(hl, hr);
                        let same = (il & ge) | (!il & near_l);
                        (ir & !il) | (same & !(il ^ ir))
                    } else {
                        near_l
                    };
                    let left_first = (both & pref).count_ones() * 2 >= both.count_ones();
                    let (first, later, m, m_later) = if left_first {
                        (l, rr, ml, mr)
                    } else {
                        (rr, l, mr, ml)
                    };
                    stack.push((later, if ANY_HIT { m_later } else { 0 }));
                    (node, here) = (first, m);
                    continue;
                }
                (true, false) => {
                    (node, here) = (l, ml);
                    continue;
                }
                (false, true) => {
                    (node, here) = (rr, mr);
                    continue;
                }
                (false, false) => {}
            }
        }
        // pop the next node some lane still reaches before its closest hit (any hit: the
        // lanes that met it when pushed and are still active, as in `traverse8`).
        loop {
            let Some((next, bits)) = stack.pop() else {
                if ANY_HIT {
                    return (none, occluded);
                }
                let (tri, t, b1, b2): ([u32; 16], [f32; 16], [f32; 16], [f32; 16]) = (
                    bytemuck::cast(tri),
                    lanes16(t_hit),
                    lanes16(b1_hit),
                    lanes16(b2_hit),
                );
                let half = |h: usize| {
                    let s = |a: &[f32; 16]| simd::from_lanes(std::array::from_fn(|i| a[8 * h + i]));
                    HitPacket8 {
                        tri: simd::u32_from_lanes(std::array::from_fn(|i| tri[8 * h + i])),
                        t: s(&t),
                        b1: s(&b1),
                        b2: s(&b2),
                    }
                };
                return ([half(0), half(1)], 0);
            };
            let m = if ANY_HIT {
                active & bits
            } else {
                hit_box16(&accel.nodes[next as usize], &r, tfar, active).0
            };
            if m != 0 {
                (node, here) = (next, m);
                break;
            }
        }
    }
}

// The 16-lane walks of the wide tree (`hybrid16`), after the steps they share above: the
// macros' scope reaches the modules declared below them.
mod wide16;
use wide16::{traverse_wide16_any, traverse_wide16_closest};

#[cfg(test)]
mod tests;
