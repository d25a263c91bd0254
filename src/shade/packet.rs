//! `shade8`: Whitted's equation across the 8 lanes of a hit packet; twin of `shade1`.
//!
//! Interpolating the hit (normal, colour, uv, material) is a per-lane gather done with the
//! scalar `surface`; the lighting that follows runs across lanes with the same steps and
//! operation order as `direct1`. Shadow rays are not traced here: each lit lane and light
//! becomes a shadow-queue entry carrying the contribution to add if the light is visible.

use super::{Secondary, Surface, phong_pow, secondaries1, surface};
use crate::packet::{HitPacket8, RayPacket8};
use crate::render::{Terms, World};
use crate::simd::{self, F32x8, LANES, M32x8, Vec3x8};
use glam::Vec3;

/// One light's share of a hit packet: the shadow rays and what they carry.
pub struct LightLanes {
    /// Lanes where `<N, l> > 0` (the light can contribute).
    pub lit: M32x8,
    pub origin: Vec3x8,
    pub dir: Vec3x8,
    pub tfar: F32x8,
    /// `Ip [kd Od <N,l> + ks max(<v,r>,0)^n]`, to be added when the light is visible.
    pub contribution: Vec3x8,
}

/// What shading a hit packet produces (reused across packets to avoid allocating).
#[derive(Default)]
pub struct Shade8 {
    /// `Ia ka Od` per lane.
    pub ambient: Vec3x8,
    pub lights: Vec<LightLanes>,
    /// Reflection and refraction rays per lane (scalar `secondaries1`, shared with `shade1`).
    pub secondaries: [[Option<Secondary>; 2]; LANES],
}

#[inline(always)]
fn normalize8(v: Vec3x8) -> Vec3x8 {
    // As glam's `normalize`: v * (1 / sqrt(<v, v>)).
    let r = simd::splat(1.0) / simd::sqrt(v.dot(v));
    v.scale(r)
}

/// Shade the lanes of `mask` (rays that hit); `depth[i]` is lane `i`'s remaining depth.
pub fn shade8(
    world: &World,
    terms: Terms,
    rays: &RayPacket8,
    hits: &HitPacket8,
    mask: M32x8,
    depth: [u32; LANES],
    out: &mut Shade8,
) {
    let sc = &world.scene;
    // surface: per-lane gather (flat default for inactive lanes).
    let flat = Surface {
        q: Vec3::ZERO,
        ng: Vec3::Y,
        n: Vec3::Y,
        back: false,
        od: Vec3::ZERO,
        material: 0,
    };
    let surf: [Surface; LANES] =
        std::array::from_fn(|i| match (simd::lane_set(mask, i), hits.lane(i)) {
            (true, Some(h)) => surface(world, &rays.lane(i), &h),
            _ => flat,
        });
    let mat = |f: &dyn Fn(&crate::scene::Material) -> f32| {
        simd::from_lanes(std::array::from_fn(|i| {
            f(&sc.materials[surf[i].material as usize])
        }))
    };
    let (ka, kd, ks) = (mat(&|m| m.ka), mat(&|m| m.kd), mat(&|m| m.ks));
    let q = Vec3x8::from_fn(|i| surf[i].q.to_array());
    let n = Vec3x8::from_fn(|i| surf[i].n.to_array());
    let ng = Vec3x8::from_fn(|i| surf[i].ng.to_array());
    let od = Vec3x8::from_fn(|i| surf[i].od.to_array());
    // ambient: Ia ka Od
    let ia = Vec3x8::splat(sc.ambient.to_array());
    let ambient = Vec3x8::new(ia.x * ka * od.x, ia.y * ka * od.y, ia.z * ka * od.z);
    let v = -normalize8(rays.d);
    let zero = simd::splat(0.0);
    let eps = simd::splat(world.eps);
    out.lights.clear();
    for light in &sc.lights {
        let lp = Vec3x8::splat(light.position.to_array());
        let l = normalize8(lp - q);
        let ndotl = n.dot(l);
        // Both terms vanish where <N, l> <= 0, so no shadow ray is needed there.
        let lit = mask & simd::gt(ndotl, zero);
        // diffuse: kd Od <N, l>
        let kdod = Vec3x8::new(kd * od.x, kd * od.y, kd * od.z);
        let mut c = kdod.scale(ndotl);
        // specular: r = 2 <N, l> N - l; ks max(<v, r>, 0)^n (phong_pow per lane, as in shade1)
        if terms.specular {
            let r = n.scale(simd::splat(2.0) * ndotl) - l;
            let base = simd::lanes(simd::max(v.dot(r), zero));
            let s = simd::from_lanes(std::array::from_fn(|i| {
                let m = &sc.materials[surf[i].material as usize];
                simd::lanes(ks)[i] * phong_pow(base[i], m.n)
            }));
            c = c + Vec3x8::new(s, s, s);
        }
        let ip = Vec3x8::splat(light.intensity.to_array());
        let contribution = Vec3x8::new(ip.x * c.x, ip.y * c.y, ip.z * c.z);
        // shadow ray: origin offset along +-Ng to the light's side, tfar to the light.
        let side = simd::gt(l.dot(ng), zero);
        let origin = Vec3x8::select(side, q + ng.scale(eps), q - ng.scale(eps));
        let to_light = lp - origin;
        let tfar = simd::sqrt(to_light.dot(to_light));
        out.lights.push(LightLanes {
            lit,
            origin,
            dir: l,
            tfar,
            contribution,
        });
    }
    let dirs = rays.d.to_lanes();
    out.ambient = ambient;
    out.secondaries = std::array::from_fn(|i| {
        if simd::lane_set(mask, i) {
            secondaries1(
                world,
                &surf[i],
                Vec3::new(dirs[0][i], dirs[1][i], dirs[2][i]),
                depth[i],
            )
        } else {
            [None, None]
        }
    });
}
