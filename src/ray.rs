//! Rays, hits, and the secondary-ray rules of SCENES.md §3 (reflect, refract, origin offset).

use glam::Vec3;

/// A ray `origin + t dir`, accepting hits with `tnear < t < tfar`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Where the ray starts.
    pub origin: Vec3,
    /// Its direction (unit length for rendered rays).
    pub dir: Vec3,
    /// Hits need `t > tnear`.
    pub tnear: f32,
    /// Hits need `t < tfar`.
    pub tfar: f32,
}

impl Ray {
    /// A ray from its parts.
    pub fn new(origin: Vec3, dir: Vec3, tnear: f32, tfar: f32) -> Self {
        Ray {
            origin,
            dir,
            tnear,
            tfar,
        }
    }

    /// Whether the ray can hit anything: its origin and direction are finite and its bounds
    /// are not NaN. Any other ray misses every triangle under the contract's test (a
    /// non-finite origin or direction makes the plane distance or the barycentric weights
    /// NaN or infinite, which fail the depth and inside tests), but it can meet every box
    /// (the slab test's `min`/`max` pass the non-NaN operand), so every engine answers it
    /// "no hit" before walking: 20,000 NaN rays on the kitten took 0.97 s with `wide1`.
    #[inline(always)]
    pub fn traceable(&self) -> bool {
        self.origin.is_finite()
            && self.dir.is_finite()
            && !self.tnear.is_nan()
            && !self.tfar.is_nan()
    }
}

/// The nearest hit of a ray: the triangle's index in the scene's original triangle order, the
/// ray parameter and the barycentric weights of the triangle's second and third vertex.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Index of the triangle hit.
    pub tri: u32,
    /// Ray parameter of the hit point.
    pub t: f32,
    /// Barycentric weight of the triangle's second vertex.
    pub b1: f32,
    /// Barycentric weight of the third vertex.
    pub b2: f32,
}

impl Hit {
    /// Marker for "no hit" in trace-rays files and hit packets.
    pub const NONE_ID: u32 = u32::MAX;
}

/// Mirror direction: `d_r = d - 2 <d, N> N`.
#[inline]
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Refraction direction per SCENES.md §3, or `None` on total internal reflection.
/// `n` faces against `d`; `eta` is `1/ior` entering through a front face, `ior` leaving.
#[inline]
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cosi = -d.dot(n);
    let k = 1.0 - eta * eta * (1.0 - cosi * cosi);
    if k < 0.0 {
        None
    } else {
        Some(eta * d + (eta * cosi - k.sqrt()) * n)
    }
}

/// Secondary ray origin: `q` moved by `eps` along `+ng` when `dir` leaves on the `ng` side,
/// else along `-ng` (SCENES.md §3). `ng` may be flipped or not: the side test is relative.
#[inline]
pub fn offset_origin(q: Vec3, ng: Vec3, dir: Vec3, eps: f32) -> Vec3 {
    if dir.dot(ng) > 0.0 {
        q + eps * ng
    } else {
        q - eps * ng
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflect_mirrors_about_normal() {
        let d = Vec3::new(1.0, -1.0, 0.0).normalize();
        let r = reflect(d, Vec3::Y);
        assert!((r - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn refract_straight_through_at_normal_incidence() {
        let t = refract(-Vec3::Y, Vec3::Y, 1.0 / 1.5).unwrap();
        assert!((t + Vec3::Y).length() < 1e-6);
    }

    #[test]
    fn refract_snell_and_total_internal_reflection() {
        // 30 degrees incidence from glass (ior 1.5) into air: sin t = 1.5 * 0.5 = 0.75.
        let s = 30f32.to_radians();
        let d = Vec3::new(s.sin(), -s.cos(), 0.0);
        let t = refract(d, Vec3::Y, 1.5).unwrap();
        assert!((t.x - 0.75).abs() < 1e-5, "{t}");
        assert!((t.length() - 1.0).abs() < 1e-5);
        // 60 degrees: 1.5 * sin 60 > 1, total internal reflection.
        let s = 60f32.to_radians();
        let d = Vec3::new(s.sin(), -s.cos(), 0.0);
        assert!(refract(d, Vec3::Y, 1.5).is_none());
    }

    #[test]
    fn offset_follows_direction_side() {
        let q = Vec3::ZERO;
        assert_eq!(
            offset_origin(q, Vec3::Y, Vec3::new(0.3, 1.0, 0.0), 0.5),
            Vec3::new(0.0, 0.5, 0.0)
        );
        assert_eq!(
            offset_origin(q, Vec3::Y, Vec3::new(0.3, -1.0, 0.0), 0.5),
            Vec3::new(0.0, -0.5, 0.0)
        );
        assert_eq!(
            offset_origin(q, -Vec3::Y, Vec3::new(0.3, -1.0, 0.0), 0.5),
            Vec3::new(0.0, -0.5, 0.0)
        );
    }
}
