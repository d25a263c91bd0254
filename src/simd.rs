//! The only module that names `wide`: 8-lane f32 / u32 vectors, masks, `Vec3x8`, helpers.
//!
//! Built with AVX2 (see `.cargo/config.toml`), `F32x8` is one 256-bit register. Masks are
//! `F32x8` lanes of all ones (true) or all zeros (false), as the comparisons return them.
//! Only exact IEEE operations (+ - * / sqrt, comparisons) are used by the kernels, never
//! fused multiply-add, so each lane computes exactly what the scalar twin computes.

use std::ops::{Add, Mul, Neg, Sub};

pub use wide::f32x8 as F32x8;
pub use wide::u32x8 as U32x8;

/// A lane mask: all-ones lanes are true.
pub type M32x8 = F32x8;

/// Lanes of every vector type.
pub const LANES: usize = 8;

/// All lanes `v`.
#[inline(always)]
pub fn splat(v: f32) -> F32x8 {
    F32x8::splat(v)
}
/// The lanes as an array.
#[inline(always)]
pub fn lanes(v: F32x8) -> [f32; 8] {
    v.to_array()
}
/// A vector from an array of lanes.
#[inline(always)]
pub fn from_lanes(a: [f32; 8]) -> F32x8 {
    F32x8::from(a)
}
/// `a < b` per lane.
#[inline(always)]
pub fn lt(a: F32x8, b: F32x8) -> M32x8 {
    a.simd_lt(b)
}
/// `a <= b` per lane.
#[inline(always)]
pub fn le(a: F32x8, b: F32x8) -> M32x8 {
    a.simd_le(b)
}
/// `a > b` per lane.
#[inline(always)]
pub fn gt(a: F32x8, b: F32x8) -> M32x8 {
    a.simd_gt(b)
}
/// `a >= b` per lane.
#[inline(always)]
pub fn ge(a: F32x8, b: F32x8) -> M32x8 {
    a.simd_ge(b)
}
/// `a == b` per lane.
#[inline(always)]
pub fn eq(a: F32x8, b: F32x8) -> M32x8 {
    a.simd_eq(b)
}
/// `m ? a : b` per lane.
#[inline(always)]
pub fn select(m: M32x8, a: F32x8, b: F32x8) -> F32x8 {
    m.select(a, b)
}
/// `m ? a : b` per lane, for u32 lanes.
#[inline(always)]
pub fn select_u32(m: M32x8, a: U32x8, b: U32x8) -> U32x8 {
    let mi: U32x8 = wide::bytemuck::cast(m);
    (a & mi) | (b & !mi)
}
/// `a < b` on u32 lanes, as a float mask.
#[inline(always)]
pub fn lt_u32(a: U32x8, b: U32x8) -> M32x8 {
    wide::bytemuck::cast(a.simd_lt(b))
}
/// Whether any lane is set.
#[inline(always)]
pub fn any(m: M32x8) -> bool {
    m.any()
}
/// Whether no lane is set.
#[inline(always)]
pub fn none(m: M32x8) -> bool {
    !m.any()
}
/// The lane mask as bits (bit `i` = lane `i`).
#[inline(always)]
pub fn bitmask(m: M32x8) -> u32 {
    m.to_bitmask()
}
/// The lanes of `v`, whole numbers in `i32`'s range, as integers.
#[inline(always)]
pub fn int_lanes(v: F32x8) -> [i32; 8] {
    v.fast_trunc_int().to_array()
}
/// `a & !b`.
#[inline(always)]
pub fn and_not(a: M32x8, b: M32x8) -> M32x8 {
    a & !b
}
/// A mask from the low 8 bits of `bits` (bit `i` = lane `i`).
#[inline(always)]
pub fn mask_from_bits(bits: u32) -> M32x8 {
    // lane i keeps bit i of the splat, which equals 1 << i exactly when the bit is set.
    let lane_bit = U32x8::from([1, 2, 4, 8, 16, 32, 64, 128]);
    let m = (U32x8::splat(bits) & lane_bit).simd_eq(lane_bit);
    wide::bytemuck::cast(m)
}
/// Whether lane `i` of a mask is set.
#[inline(always)]
pub fn lane_set(m: M32x8, i: usize) -> bool {
    bitmask(m) >> i & 1 == 1
}
/// Per-lane minimum (`fast_min`: a NaN lane gives either operand).
#[inline(always)]
pub fn min(a: F32x8, b: F32x8) -> F32x8 {
    a.fast_min(b)
}
/// Per-lane maximum (`fast_max`: a NaN lane gives either operand).
#[inline(always)]
pub fn max(a: F32x8, b: F32x8) -> F32x8 {
    a.fast_max(b)
}
/// `f32::next_up` per lane, for finite lanes (a hit's `t`; infinite and NaN lanes are not
/// defined here): the bit pattern one step away from zero for positive values, one step
/// towards zero for negative ones, the smallest subnormal for a zero of either sign. Two
/// masked integer steps instead of eight scalar calls through memory.
#[inline(always)]
pub fn next_up(t: F32x8) -> F32x8 {
    use wide::i32x8;
    let bits: i32x8 = wide::bytemuck::cast(t);
    // (a true comparison lane is all ones: -1 as an integer)
    let pos: i32x8 = wide::bytemuck::cast(gt(t, splat(0.0)));
    let neg: i32x8 = wide::bytemuck::cast(lt(t, splat(0.0)));
    let stepped = bits - pos + neg;
    wide::bytemuck::cast((pos | neg).select(stepped, i32x8::splat(1)))
}
/// Per-lane square root (exact IEEE).
#[inline(always)]
pub fn sqrt(a: F32x8) -> F32x8 {
    a.sqrt()
}
/// The u32 lanes as an array.
#[inline(always)]
pub fn u32_lanes(v: U32x8) -> [u32; 8] {
    v.to_array()
}
/// A u32 vector from an array of lanes.
#[inline(always)]
pub fn u32_from_lanes(a: [u32; 8]) -> U32x8 {
    U32x8::from(a)
}

/// Entries `start .. start + 8` of `v` as lanes; lanes past the end are `pad`. The full case
/// is a fixed 32-byte copy (a variable-length `copy_from_slice` would call `memmove`).
#[inline(always)]
pub fn lanes_from<T: Copy>(v: &[T], start: usize, pad: T) -> [T; LANES] {
    match v.get(start..start + LANES) {
        Some(s) => std::array::from_fn(|i| s[i]),
        None => std::array::from_fn(|i| v.get(start + i).copied().unwrap_or(pad)),
    }
}

/// Eight 3-vectors in SoA form.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Vec3x8 {
    /// x components.
    pub x: F32x8,
    /// y components.
    pub y: F32x8,
    /// z components.
    pub z: F32x8,
}

impl Vec3x8 {
    /// From three SoA component vectors.
    #[inline(always)]
    pub fn new(x: F32x8, y: F32x8, z: F32x8) -> Self {
        Vec3x8 { x, y, z }
    }
    /// The same vector in every lane.
    #[inline(always)]
    pub fn splat(v: [f32; 3]) -> Self {
        Vec3x8::new(splat(v[0]), splat(v[1]), splat(v[2]))
    }
    /// `x*x' + y*y' + z*z'`, summed left to right like the scalar kernels.
    #[inline(always)]
    pub fn dot(self, o: Self) -> F32x8 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }
    /// Cross product per lane, in the scalar kernels' operation order.
    #[inline(always)]
    pub fn cross(self, o: Self) -> Self {
        Vec3x8::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }
    /// Each lane scaled by its `s`.
    #[inline(always)]
    pub fn scale(self, s: F32x8) -> Self {
        Vec3x8::new(self.x * s, self.y * s, self.z * s)
    }
    /// As glam's `normalize`: `v * (1 / sqrt(<v, v>))`.
    #[inline(always)]
    pub fn normalize(self) -> Self {
        self.scale(splat(1.0) / sqrt(self.dot(self)))
    }
    /// Component-wise product (glam's `Vec3 * Vec3`).
    #[inline(always)]
    pub fn mul_elem(self, o: Self) -> Self {
        Vec3x8::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }
    /// `m ? a : b` per lane.
    #[inline(always)]
    pub fn select(m: M32x8, a: Self, b: Self) -> Self {
        Vec3x8::new(
            select(m, a.x, b.x),
            select(m, a.y, b.y),
            select(m, a.z, b.z),
        )
    }
    /// Lane `i` as `[x, y, z]`.
    #[inline(always)]
    pub fn lane(&self, i: usize) -> [f32; 3] {
        [lanes(self.x)[i], lanes(self.y)[i], lanes(self.z)[i]]
    }
    /// All lanes at once: `[x lanes, y lanes, z lanes]` (one conversion instead of 8 `lane` calls).
    #[inline(always)]
    pub fn to_lanes(&self) -> [[f32; 8]; 3] {
        [lanes(self.x), lanes(self.y), lanes(self.z)]
    }
    /// Lanes `start .. start + 8` of three SoA arrays; lanes past the end are `pad`.
    #[inline(always)]
    pub fn load(a: &[Vec<f32>; 3], start: usize, pad: f32) -> Self {
        let get = |v: &Vec<f32>| from_lanes(lanes_from(v, start, pad));
        Vec3x8::new(get(&a[0]), get(&a[1]), get(&a[2]))
    }
    /// Lane `i` from `f(i)`.
    pub fn from_fn(f: impl Fn(usize) -> [f32; 3]) -> Self {
        let v: [[f32; 3]; 8] = std::array::from_fn(f);
        Vec3x8::new(
            from_lanes(v.map(|p| p[0])),
            from_lanes(v.map(|p| p[1])),
            from_lanes(v.map(|p| p[2])),
        )
    }
}

impl Add for Vec3x8 {
    type Output = Self;
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        Vec3x8::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl Sub for Vec3x8 {
    type Output = Self;
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        Vec3x8::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl Mul<F32x8> for Vec3x8 {
    type Output = Self;
    #[inline(always)]
    fn mul(self, s: F32x8) -> Self {
        self.scale(s)
    }
}
impl Neg for Vec3x8 {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Vec3x8::new(-self.x, -self.y, -self.z)
    }
}

/// 4096 finite floats for the `next_up` tests: both zeros, the smallest subnormals and
/// normals of both signs, the largest finite values, and pseudo-random bit patterns.
#[cfg(test)]
pub(crate) fn finite_samples() -> Vec<f32> {
    let mut values = vec![
        0.0f32,
        -0.0,
        f32::MIN_POSITIVE,
        -f32::MIN_POSITIVE,
        f32::from_bits(1),
        -f32::from_bits(1),
        f32::MAX,
        -f32::MAX,
    ];
    let mut x = 0x1234_5678u32;
    while values.len() < 4096 {
        x = x.wrapping_mul(1664525).wrapping_add(1013904223);
        let v = f32::from_bits(x);
        if v.is_finite() {
            values.push(v);
        }
    }
    values
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `next_up` in lanes is `f32::next_up` on every finite value, including zeros of both
    /// signs, subnormals, negatives and the largest finite value.
    #[test]
    fn lane_next_up_equals_f32_next_up() {
        let values = finite_samples();
        for chunk in values.chunks(8) {
            let v: [f32; 8] = std::array::from_fn(|i| chunk[i]);
            for (g, v) in lanes(next_up(from_lanes(v))).iter().zip(v) {
                assert_eq!(g.to_bits(), v.next_up().to_bits(), "{v:e}");
            }
        }
    }

    /// `robust::safe_inv8` is `robust::safe_inv` lane by lane, bit for bit: zeros of both signs, the
    /// clamp's edges, subnormals, the largest values, infinities and NaN.
    #[test]
    fn lane_safe_inv_equals_safe_inv() {
        let tiny = crate::accel::SAFE_INV_TINY;
        let mut values = finite_samples();
        values.extend([
            0.0,
            -0.0,
            tiny,
            -tiny,
            tiny.next_down(),
            -tiny.next_down(),
            tiny.next_up(),
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            -f32::NAN,
        ]);
        for chunk in values.chunks(8) {
            let v: [f32; 8] = std::array::from_fn(|i| chunk.get(i).copied().unwrap_or(1.0));
            for (g, v) in lanes(crate::accel::robust::safe_inv8(from_lanes(v)))
                .iter()
                .zip(v)
            {
                let want = crate::accel::safe_inv(v);
                assert!(
                    g.to_bits() == want.to_bits() || (g.is_nan() && want.is_nan()),
                    "safe_inv({v:e}): {g:e} against {want:e}"
                );
            }
        }
    }

    #[test]
    fn masks_and_selects() {
        let a = from_lanes([0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, f32::NAN]);
        let m = lt(a, splat(3.0));
        assert_eq!(bitmask(m), 0b0000_0111, "NaN lanes compare false");
        assert_eq!(
            lanes(select(m, splat(1.0), splat(-1.0)))[..4],
            [1.0, 1.0, 1.0, -1.0]
        );
        for bits in 0..256 {
            let m = mask_from_bits(bits);
            assert_eq!(bitmask(m), bits);
            // whole lanes: all ones or all zeros
            assert!(
                lanes(m)
                    .iter()
                    .all(|v| v.to_bits() == 0 || v.to_bits() == u32::MAX)
            );
        }
        assert_eq!(
            bitmask(mask_from_bits(0x1_00 | 0b11)),
            0b11,
            "bits above 7 ignored"
        );
        assert!(lane_set(m, 2) && !lane_set(m, 3));
        assert!(any(m) && !none(m) && none(and_not(m, m)));
        let ids = select_u32(m, U32x8::splat(7), U32x8::splat(9));
        assert_eq!(u32_lanes(ids), [7, 7, 7, 9, 9, 9, 9, 9]);
        assert_eq!(
            bitmask(lt_u32(
                u32_from_lanes([0, 5, u32::MAX, 3, 0, 0, 0, 0]),
                U32x8::splat(4)
            )),
            0b1111_1001
        );
    }

    #[test]
    fn vec3_ops_match_scalar_order() {
        let a = Vec3x8::from_fn(|i| [i as f32, 0.1, -2.0]);
        let b = Vec3x8::splat([0.3, 0.7, 1e-3]);
        for i in 0..8 {
            let (p, q) = (a.lane(i), b.lane(i));
            assert_eq!(lanes(a.dot(b))[i], p[0] * q[0] + p[1] * q[1] + p[2] * q[2]);
            assert_eq!(a.cross(b).lane(i)[1], p[2] * q[0] - p[0] * q[2]);
        }
    }
}
