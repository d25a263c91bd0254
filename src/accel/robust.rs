//! The robustness constants of every traversal and the closest-hit rule, in one place: what
//! makes every engine find exactly `intersect1`'s hits (padded boxes, widened slab exits,
//! reciprocals that are never infinite, the f64 edge test near edges) and which of two hits
//! is the closer.

/// [`safe_inv`] per lane: the same comparison, the same replacement and the same division,
/// so the same floats (NaN stays NaN). One division for 8 lanes instead of 8: it was a
/// quarter of `packet8`'s per-packet set-up on camera rays.
#[inline(always)]
pub fn safe_inv8(v: crate::simd::F32x8) -> crate::simd::F32x8 {
    use crate::simd::{lt, select, splat};
    let tiny = splat(SAFE_INV_TINY);
    let signed = (v & splat(-0.0)) | tiny;
    splat(1.0) / select(lt(v.abs(), tiny), signed, v)
}

/// Relative padding of node boxes (see `Accel::build`).
pub const BOX_PAD: f32 = 4.0 * f32::EPSILON;

/// Reciprocal direction for slab tests. A zero component becomes `±1e30` instead of `±inf`,
/// so `(bound - origin) * inv` is never `0 * inf = NaN` for a ray starting on a slab plane.
#[inline(always)]
pub fn safe_inv(d: f32) -> f32 {
    1.0 / if d.abs() < SAFE_INV_TINY {
        SAFE_INV_TINY.copysign(d)
    } else {
        d
    }
}

/// The smallest direction component magnitude [`safe_inv`] divides by ([`safe_inv8`] and
/// the 16-lane set-up clamp the same way).
pub const SAFE_INV_TINY: f32 = 1e-30;

/// Any-hit walks (shadow rays) visit a child box the ray starts in after one it does not.
/// A shadow ray starts on a surface, so the boxes around its origin hold the triangles it
/// leaves without hitting, and what blocks it lies farther on; near-first tested that
/// neighbourhood before reaching the occluder. Where both boxes hold the origin, the one the
/// ray leaves later goes first (it reaches farther); where neither does, the nearer (a
/// blocker close to the surface, as under a body's own limbs, is found early). A packet
/// takes the side most of its lanes prefer. `wide1`'s any-hit walk keeps only the two
/// groups (the children the ray starts in after the others, each group in slot order, no
/// distances: see `wide1::walk_any`). An
/// unoccluded ray visits every box it meets in any order, and any order finds an occluder
/// when there is one, so answers do not change.
/// Measured (README, "Engines", instructions of `occluded8`): bench shadow rays 0.85x,
/// `refraction`'s shadow rays (from inside the glass kitten) 0.73x, `phong`'s 1.04x; visiting
/// every farther child first measured 0.80x / 0.62x / 1.24x, so the floor scenes rendered
/// slower with it.
pub const ORIGIN_LAST: bool = true;

/// Slab tests round; widen the far distance by `1 + 2 gamma(3)` (pbrt's bound) so a box is
/// never missed by a ray that hits a triangle on its boundary.
pub const SLAB_FAR_SCALE: f32 =
    1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// Barycentrics this close to 0 (or closer) are decided by `scalar::inside_f64`. The f32 areas
/// carry noise of about `ulp(|q|) / height`, far below this for any sane mesh.
pub const BARY_SAFE: f32 = 1e-3;

/// The closest-hit rule of every engine: a hit at `t` on triangle `tri` replaces the best so
/// far (`than_t`, `than_tri`) when it is nearer, or exactly as near with a lower original
/// triangle index, so the answer does not depend on the order in which triangles are met.
#[inline(always)]
pub fn nearer(t: f32, tri: u32, than_t: f32, than_tri: u32) -> bool {
    t < than_t || (t == than_t && tri < than_tri)
}

/// [`nearer`] in 8 lanes: the lanes whose hit (`t`, `tri`) replaces the best so far.
#[inline(always)]
pub fn nearer8(
    t: crate::simd::F32x8,
    tri: crate::simd::U32x8,
    than_t: crate::simd::F32x8,
    than_tri: crate::simd::U32x8,
) -> crate::simd::M32x8 {
    use crate::simd::{eq, lt, lt_u32};
    lt(t, than_t) | (eq(t, than_t) & lt_u32(tri, than_tri))
}
