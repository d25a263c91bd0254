//! The 16-lane pieces of `packet16`'s walks, as `simd.rs` has the 8-lane ones: three
//! coordinates in lanes and their arithmetic, the rays of two packets as one 16-lane ray set,
//! the direction octant, the padded box test and `next_up` in lanes. Each is compiled for
//! AVX-512 (`#[target_feature]`) and reached only after [`super::available`].

use super::*;

/// Sixteen lanes of three coordinates.
#[derive(Clone, Copy)]
pub(super) struct V3 {
    pub(super) x: __m512,
    pub(super) y: __m512,
    pub(super) z: __m512,
}

/// The 16 lanes as an array.
pub(super) fn lanes16(v: __m512) -> [f32; 16] {
    bytemuck::cast(v)
}

#[target_feature(enable = "avx512f,avx512dq")]
#[inline]
pub(super) fn splat(v: f32) -> __m512 {
    _mm512_set1_ps(v)
}

#[target_feature(enable = "avx512f,avx512dq")]
#[inline]
pub(super) fn splat3(v: [f32; 3]) -> V3 {
    V3 {
        x: _mm512_set1_ps(v[0]),
        y: _mm512_set1_ps(v[1]),
        z: _mm512_set1_ps(v[2]),
    }
}

/// `a - b` per coordinate.
#[target_feature(enable = "avx512f,avx512dq")]
#[inline]
pub(super) fn sub3(a: V3, b: V3) -> V3 {
    V3 {
        x: _mm512_sub_ps(a.x, b.x),
        y: _mm512_sub_ps(a.y, b.y),
        z: _mm512_sub_ps(a.z, b.z),
    }
}

/// `a.x b.x + a.y b.y + a.z b.z` in `Vec3x8::dot`'s order: `(x + y) + z`.
#[target_feature(enable = "avx512f,avx512dq")]
#[inline]
pub(super) fn dot(a: V3, b: V3) -> __m512 {
    _mm512_add_ps(
        _mm512_add_ps(_mm512_mul_ps(a.x, b.x), _mm512_mul_ps(a.y, b.y)),
        _mm512_mul_ps(a.z, b.z),
    )
}

/// The packet: origins, directions, their reciprocals and lengths, as `traverse8` has them.
pub(super) struct Rays16 {
    pub(super) o: V3,
    pub(super) d: V3,
    pub(super) inv: V3,
    /// `inv * SLAB_FAR_SCALE` per lane (rounded once).
    pub(super) inv_far: V3,
    /// Per axis, whether the box maximum is the near plane, when every lane's direction
    /// lies in one octant.
    pub(super) octant: Option<[bool; 3]>,
    pub(super) tnear: __m512,
    pub(super) dlen: __m512,
    /// Origins and directions as arrays, component by component (for the f64 edge test and
    /// the single-ray walks: see [`Rays16::o1`], [`Rays16::d1`]).
    pub(super) o_lanes: [[f32; 16]; 3],
    pub(super) d_lanes: [[f32; 16]; 3],
}

impl Rays16 {
    /// Lane `i` splatted for the single-ray walks, from the lanes' reciprocals and lengths
    /// (the floats `RayWide::new` computes).
    #[inline(always)]
    pub(super) fn walker(&self, i: usize) -> RayWide {
        let lane = |v: __m512| lanes16(v)[i];
        RayWide::from_parts(
            self.o1(i),
            self.d1(i),
            [lane(self.inv.x), lane(self.inv.y), lane(self.inv.z)],
            lane(self.dlen),
            lane(self.tnear),
        )
    }
    /// Lane `i`'s origin.
    #[inline(always)]
    pub(super) fn o1(&self, i: usize) -> [f32; 3] {
        self.o_lanes.map(|c| c[i])
    }
    /// Lane `i`'s direction.
    #[inline(always)]
    pub(super) fn d1(&self, i: usize) -> [f32; 3] {
        self.d_lanes.map(|c| c[i])
    }
}

/// The two packets as one (`safe_inv` and `|d|` per lane as `traverse8` computes them), and
/// their `tfar` (`octant` unset: see [`octant_of`]).
#[target_feature(enable = "avx512f,avx512dq")]
#[inline]
pub(super) fn rays16(rays: [&RayPacket8; 2]) -> (Rays16, __m512) {
    let [a, b] = rays;
    // lanes 0..8 from the first packet, 8..16 from the second
    let join = |p: simd::F32x8, q: simd::F32x8| -> __m512 {
        _mm512_insertf32x8::<1>(_mm512_castps256_ps512(bytemuck::cast(p)), bytemuck::cast(q))
    };
    let v3 = |p: &simd::Vec3x8, q: &simd::Vec3x8| V3 {
        x: join(p.x, q.x),
        y: join(p.y, q.y),
        z: join(p.z, q.z),
    };
    let (o, d) = (v3(&a.o, &b.o), v3(&a.d, &b.d));
    // `safe_inv` in lanes: 1 / d, with |d| below TINY replaced by TINY of d's sign (the same
    // comparison, the same division; NaN stays NaN)
    let inv1 = |d: __m512| {
        const TINY: f32 = crate::accel::SAFE_INV_TINY;
        let sign = _mm512_set1_ps(-0.0);
        let tiny = _mm512_or_ps(_mm512_and_ps(d, sign), splat(TINY));
        let small = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(_mm512_andnot_ps(sign, d), splat(TINY));
        _mm512_div_ps(splat(1.0), _mm512_mask_mov_ps(d, small, tiny))
    };
    let inv = V3 {
        x: inv1(d.x),
        y: inv1(d.y),
        z: inv1(d.z),
    };
    let r = Rays16 {
        o,
        d,
        inv,
        inv_far: V3 {
            x: _mm512_mul_ps(inv.x, splat(SLAB_FAR_SCALE)),
            y: _mm512_mul_ps(inv.y, splat(SLAB_FAR_SCALE)),
            z: _mm512_mul_ps(inv.z, splat(SLAB_FAR_SCALE)),
        },
        octant: None,
        tnear: join(a.tnear, b.tnear),
        dlen: _mm512_sqrt_ps(dot(d, d)),
        o_lanes: [lanes16(o.x), lanes16(o.y), lanes16(o.z)],
        d_lanes: [lanes16(d.x), lanes16(d.y), lanes16(d.z)],
    };
    (r, join(a.tfar, b.tfar))
}

/// The octant the `active` lanes' directions share, if they share one (usual for shadow and
/// camera rays), from their reciprocals `inv` (x, y, z): the slab tests then pick each
/// axis's planes once for the packet (in `traverse16`: kitten shadow rays 1.05x,
/// primary-hits 1.07x; 1.3M level). (Taking the three vectors by value: with the packet
/// passed by reference the walks ran 0.5-1.4% more instructions.)
#[target_feature(enable = "avx512f,avx512dq")]
#[inline]
pub(super) fn octant_of(inv: [__m512; 3], active: u16) -> Option<[bool; 3]> {
    let neg = inv.map(|v| _mm512_mask_cmp_ps_mask::<_CMP_LT_OQ>(active, v, splat(0.0)));
    neg.iter()
        .all(|&b| b == 0 || b == active)
        .then(|| neg.map(|b| b != 0))
}

/// `hit_box8` in 16 lanes: the lanes of `active` whose ray meets the box within
/// `[tnear, tfar]`, with entry and exit distances.
#[target_feature(enable = "avx512f,avx512dq")]
#[inline]
pub(super) fn hit_box16(
    node: &crate::accel::Node,
    r: &Rays16,
    tfar: __m512,
    active: u16,
) -> (u16, __m512, __m512) {
    if let Some(near) = r.octant {
        // one octant: each axis's near and far plane picked once for the packet (as
        // `hit_box8_octant`), the far distances widened through `inv_far`.
        let c = |k: usize, max: bool| splat(if max { node.max[k] } else { node.min[k] });
        let t = |b: __m512, o: __m512, inv: __m512| _mm512_mul_ps(_mm512_sub_ps(b, o), inv);
        let nx = t(c(0, near[0]), r.o.x, r.inv.x);
        let fx = t(c(0, !near[0]), r.o.x, r.inv_far.x);
        let ny = t(c(1, near[1]), r.o.y, r.inv.y);
        let fy = t(c(1, !near[1]), r.o.y, r.inv_far.y);
        let nz = t(c(2, near[2]), r.o.z, r.inv.z);
        let fz = t(c(2, !near[2]), r.o.z, r.inv_far.z);
        let lo = _mm512_max_ps(_mm512_max_ps(nx, ny), _mm512_max_ps(nz, r.tnear));
        let far = _mm512_mul_ps(tfar, splat(SLAB_FAR_SCALE));
        let hi = _mm512_min_ps(_mm512_min_ps(fx, fy), _mm512_min_ps(fz, far));
        return (
            _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(active, lo, hi),
            lo,
            hi,
        );
    }
    let t = |b: f32, o: __m512, inv: __m512| _mm512_mul_ps(_mm512_sub_ps(splat(b), o), inv);
    let t0x = t(node.min[0], r.o.x, r.inv.x);
    let t1x = t(node.max[0], r.o.x, r.inv.x);
    let t0y = t(node.min[1], r.o.y, r.inv.y);
    let t1y = t(node.max[1], r.o.y, r.inv.y);
    let t0z = t(node.min[2], r.o.z, r.inv.z);
    let t1z = t(node.max[2], r.o.z, r.inv.z);
    let lo = _mm512_max_ps(
        _mm512_max_ps(_mm512_min_ps(t0x, t1x), _mm512_min_ps(t0y, t1y)),
        _mm512_max_ps(_mm512_min_ps(t0z, t1z), r.tnear),
    );
    let hi = _mm512_min_ps(
        _mm512_min_ps(_mm512_max_ps(t0x, t1x), _mm512_max_ps(t0y, t1y)),
        _mm512_min_ps(_mm512_max_ps(t0z, t1z), tfar),
    );
    let far = _mm512_mul_ps(hi, splat(SLAB_FAR_SCALE));
    (
        _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(active, lo, far),
        lo,
        hi,
    )
}

/// `f32::next_up` per lane, for the finite lanes (a hit's `t`; other lanes are not used):
/// the bit pattern one step away from zero for positive values, one step towards zero for
/// negative ones, the smallest subnormal for a zero of either sign.
#[target_feature(enable = "avx512f,avx512dq")]
#[inline]
pub(super) fn next_up(t: __m512) -> __m512 {
    let bits = _mm512_castps_si512(t);
    let pos = _mm512_cmp_ps_mask::<_CMP_GT_OQ>(t, splat(0.0));
    let neg = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(t, splat(0.0));
    let one = _mm512_set1_epi32(1);
    let up = _mm512_mask_sub_epi32(_mm512_mask_add_epi32(one, pos, bits, one), neg, bits, one);
    _mm512_castsi512_ps(up)
}
