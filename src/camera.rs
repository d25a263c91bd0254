//! The pinhole camera of SCENES.md §1: basis, pixel-centre rays, stratified sub-samples.

use crate::ray::Ray;
use crate::simd::{self, F32x8, Vec3x8};
use glam::Vec3;

/// A camera ready to generate rays for a `width x height` image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// The eye point, origin of every primary ray.
    pub eye: Vec3,
    /// Forward, right and up unit vectors: `f = normalize(look_at - eye)`,
    /// `r = normalize(cross(f, up))`, `u = cross(r, f)`.
    pub f: Vec3,
    /// Right unit vector `r` (see `f`).
    pub r: Vec3,
    /// Up unit vector `u` (see `f`).
    pub u: Vec3,
    /// `tan(vfov / 2)`.
    pub tan_half: f32,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
}

impl Camera {
    /// The basis of SCENES.md §1 from a placement and an image size (`vfov_deg` in degrees).
    pub fn new(eye: Vec3, look_at: Vec3, up: Vec3, vfov_deg: f32, width: u32, height: u32) -> Self {
        let f = (look_at - eye).normalize();
        let r = f.cross(up).normalize();
        let u = r.cross(f);
        Camera {
            eye,
            f,
            r,
            u,
            tan_half: (vfov_deg.to_radians() * 0.5).tan(),
            width,
            height,
        }
    }

    /// The ray through image position `(px, py)` in pixel units (`(i + 0.5, j + 0.5)` is the
    /// centre of pixel `(i, j)`): `x = (2 px / w - 1) tan(vfov/2) w/h`, `y = (1 - 2 py / h) tan(vfov/2)`.
    pub fn ray_at(&self, px: f32, py: f32) -> Ray {
        let (w, h) = (self.width as f32, self.height as f32);
        let x = (2.0 * px / w - 1.0) * self.tan_half * (w / h);
        let y = (1.0 - 2.0 * py / h) * self.tan_half;
        let dir = (self.f + x * self.r + y * self.u).normalize();
        Ray::new(self.eye, dir, 0.0, f32::INFINITY)
    }

    /// The directions of `ray_at` at eight image positions, computed across lanes with
    /// exactly `ray_at`'s operations (so each lane equals the scalar ray bit for bit).
    pub fn dirs8(&self, px: F32x8, py: F32x8) -> Vec3x8 {
        let (w, h) = (self.width as f32, self.height as f32);
        let (one, two) = (simd::splat(1.0), simd::splat(2.0));
        let x = (two * px / simd::splat(w) - one) * simd::splat(self.tan_half) * simd::splat(w / h);
        let y = (one - two * py / simd::splat(h)) * simd::splat(self.tan_half);
        let [f, r, u] = [self.f, self.r, self.u].map(|v| Vec3x8::splat(v.to_array()));
        (f + r.scale(x) + u.scale(y)).normalize()
    }

    /// The primary ray through the centre of pixel `(i, j)` (column `i`, row `j` from the top).
    pub fn primary_ray(&self, i: u32, j: u32) -> Ray {
        self.ray_at(i as f32 + 0.5, j as f32 + 0.5)
    }
}

/// Sub-pixel offsets of `spp` stratified samples: an `a x b` grid with `a b = spp` as square
/// as possible, each sample at its stratum's centre (deterministic, so both engines agree).
/// `spp = 1` is the pixel centre.
pub fn sample_offsets(spp: u32) -> Vec<(f32, f32)> {
    let spp = spp.max(1);
    let mut a = (spp as f32).sqrt() as u32;
    while !spp.is_multiple_of(a) {
        a -= 1;
    }
    let b = spp / a;
    (0..spp)
        .map(|k| ((k % b) as f32 + 0.5) / b as f32)
        .zip((0..spp).map(|k| ((k / b) as f32 + 0.5) / a as f32))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn canonical(w: u32, h: u32) -> Camera {
        Camera::new(
            Vec3::new(1.6, 0.9, 4.4),
            Vec3::new(0.0, -0.15, 0.0),
            Vec3::Y,
            36.0,
            w,
            h,
        )
    }

    #[test]
    fn basis_is_orthonormal_and_right_handed() {
        let c = canonical(1024, 768);
        assert!((c.f.length() - 1.0).abs() < 1e-6 && (c.r.length() - 1.0).abs() < 1e-6);
        assert!((c.u.length() - 1.0).abs() < 1e-6);
        assert!(c.f.dot(c.r).abs() < 1e-6 && c.f.dot(c.u).abs() < 1e-6);
        assert!(c.u.y > 0.0, "up stays up");
        assert!((c.r.cross(c.u) + c.f).length() < 1e-6, "r x u = -f");
    }

    #[test]
    #[allow(clippy::needless_range_loop)]
    fn pixel_formula_matches_scenes_md() {
        // Hand computation for the canonical camera, 1024x768, pixel (0, 0).
        let c = canonical(1024, 768);
        let t = (18f64).to_radians().tan();
        let x = (2.0 * 0.5 / 1024.0 - 1.0) * t * (1024.0 / 768.0);
        let y = (1.0 - 2.0 * 0.5 / 768.0) * t;
        let e = [1.6f64, 0.9, 4.4];
        let fw = [-e[0], -0.15 - e[1], -e[2]];
        let fl = (fw[0] * fw[0] + fw[1] * fw[1] + fw[2] * fw[2]).sqrt();
        let f = fw.map(|v| v / fl);
        // r = normalize(cross(f, y)) = normalize((-f.z, 0, f.x)); u = cross(r, f).
        let rl = (f[2] * f[2] + f[0] * f[0]).sqrt();
        let r = [-f[2] / rl, 0.0, f[0] / rl];
        let u = [
            r[1] * f[2] - r[2] * f[1],
            r[2] * f[0] - r[0] * f[2],
            r[0] * f[1] - r[1] * f[0],
        ];
        let d: Vec<f64> = (0..3).map(|k| f[k] + x * r[k] + y * u[k]).collect();
        let dl = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let ray = c.primary_ray(0, 0);
        for k in 0..3 {
            assert!(
                (ray.dir[k] as f64 - d[k] / dl).abs() < 1e-6,
                "{k}: {} vs {}",
                ray.dir[k],
                d[k] / dl
            );
        }
        assert_eq!(ray.origin, c.eye);
        // The centre of the image looks straight ahead (even size: between pixels).
        let centre = c.ray_at(512.0, 384.0);
        assert!((centre.dir - c.f).length() < 1e-6);
        // Top-left pixel looks up and left.
        assert!(ray.dir.dot(c.u) > 0.0 && ray.dir.dot(c.r) < 0.0);
    }

    #[test]
    fn stratified_offsets() {
        assert_eq!(sample_offsets(1), vec![(0.5, 0.5)]);
        assert_eq!(
            sample_offsets(4),
            vec![(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)]
        );
        assert_eq!(sample_offsets(6).len(), 6);
    }
}
