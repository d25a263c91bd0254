use super::*;
use crate::ray::Ray;

/// `next_up` in lanes is `f32::next_up` on every finite value (a hit's `t`), including
/// zeros of both signs, subnormals, negatives and the largest finite value.
#[test]
fn lane_next_up_equals_f32_next_up() {
    if !available() {
        eprintln!("no AVX-512 here: the 16-lane kernels are not run");
        return;
    }
    let values = crate::simd::finite_samples();
    for chunk in values.chunks(16) {
        let mut lanes = [0.0f32; 16];
        lanes[..chunk.len()].copy_from_slice(chunk);
        // SAFETY: the CPU has AVX-512 F and DQ (checked above).
        #[allow(unsafe_code)]
        let got = lanes16(unsafe { next_up(bytemuck::cast(lanes)) });
        for (g, v) in got.iter().zip(lanes) {
            assert_eq!(g.to_bits(), v.next_up().to_bits(), "{v:e}");
        }
    }
}

/// The packet's reciprocal directions in lanes are `safe_inv` bit for bit: zeros of both
/// signs, values below and at the clamp, subnormals, infinities and NaN.
#[test]
fn lane_safe_inv_equals_safe_inv() {
    if !available() {
        eprintln!("no AVX-512 here: the 16-lane kernels are not run");
        return;
    }
    let mut values = crate::simd::finite_samples();
    values.extend([
        0.0,
        -0.0,
        1e-30,
        -1e-30,
        1e-30f32.next_down(),
        -1e-30f32.next_up(),
        f32::INFINITY,
        f32::NEG_INFINITY,
        f32::NAN,
        -f32::NAN,
    ]);
    for chunk in values.chunks(16) {
        let v = |i: usize| chunk.get(i).copied().unwrap_or(1.0);
        let packet = |h: usize| {
            RayPacket8::from_fn(|i| {
                let k = 8 * h + i;
                Some(Ray::new(
                    glam::Vec3::ZERO,
                    glam::Vec3::new(v(k), v((k + 5) % 16), -v((k + 11) % 16)),
                    0.0,
                    f32::INFINITY,
                ))
            })
            .0
        };
        let (p0, p1) = (packet(0), packet(1));
        // SAFETY: the CPU has AVX-512 F and DQ (checked above).
        #[allow(unsafe_code)]
        let (r, _) = unsafe { rays16([&p0, &p1]) };
        for (axis, inv) in [r.inv.x, r.inv.y, r.inv.z].into_iter().enumerate() {
            for (i, got) in lanes16(inv).into_iter().enumerate() {
                let d = r.d1(i)[axis];
                let want = crate::accel::safe_inv(d);
                assert!(
                    got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                    "safe_inv({d:e}): {got:e} against {want:e}"
                );
            }
        }
    }
}
