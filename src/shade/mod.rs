//! Whitted's equation at one hit (SCENES.md §3), the scalar reference `shade1`.
//!
//! `I = ke + Ia ka Od + sum_i S_i Ip_i [kd Od max(<N,l_i>,0) + ks max(<v,r_i>,0)^n] + kr Ir + kt It`
//! with RGB coefficients (`kr = ks` and `ke = 0` unless a material says otherwise).

pub mod packet;

pub use packet::{Shade8, shade8, shade8_in};

use crate::ray::{Hit, Ray, offset_origin, reflect, refract};
use crate::scene::{Albedo, Geometry, Material};
use crate::world::{NOT_INSTANCED, Placed, Terms, World};
use glam::Vec3;

/// Everything shading needs at a hit point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Surface {
    /// `q = p + t d`.
    pub q: Vec3,
    /// Geometric and shading normals, both flipped to face the ray on a back-face hit.
    pub ng: Vec3,
    /// The interpolated shading normal `N` (unit, facing the ray).
    pub n: Vec3,
    /// The ray hit a back face (`<d, Ng> > 0`): it is leaving the object.
    pub back: bool,
    /// The surface colour `Od` at the hit.
    pub od: Vec3,
    /// Index of the material.
    pub material: u32,
}

/// A reflection or refraction ray with the weight (`ks` or `kt`) its colour is added with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Secondary {
    /// The ray to trace.
    pub ray: Ray,
    /// What its colour is multiplied by before it is added.
    pub weight: Vec3,
    /// Reflection or refraction.
    pub kind: SecondaryKind,
}

/// Which kind of secondary ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SecondaryKind {
    /// Along the mirror direction.
    Reflection,
    /// Through the surface (or totally internally reflected).
    Refraction,
}

/// Interpolate the hit: normal, colour, uv; flip normals on back faces.
pub fn surface(world: &World, ray: &Ray, hit: &Hit) -> Surface {
    surface_in(world, ray, hit, NOT_INSTANCED)
}

/// [`surface`] of a hit on instance `inst` ([`NOT_INSTANCED`]: on the flattened geometry).
pub fn surface_in(world: &World, ray: &Ray, hit: &Hit, inst: u32) -> Surface {
    let on = world.shading(inst);
    let g = on.0;
    let [i0, i1, i2] = g.triangles[hit.tri as usize].map(|i| i as usize);
    let (b1, b2) = (hit.b1, hit.b2);
    let b0 = 1.0 - b1 - b2;
    let q = ray.origin + hit.t * ray.dir;
    let ([n0, n1, n2], ng) = normals(on, hit.tri);
    let mut ng = ng;
    // shading normal: interpolated and normalised; the geometric normal if that vanishes.
    let mut n = (b0 * n0 + b1 * n1 + b2 * n2).try_normalize().unwrap_or(ng);
    // back face: flip Ng and N before shading.
    let back = ray.dir.dot(ng) > 0.0;
    if back {
        ng = -ng;
        n = -n;
    }
    let material = triangle_material(on, hit.tri);
    let m = &world.scene.materials[material as usize];
    Surface {
        q,
        ng,
        n,
        back,
        od: albedo(g, m, [i0, i1, i2], b0, b1, b2),
        material,
    }
}

/// Index of the material of triangle `tri` of the geometry and placement `on` (from
/// [`World::shading`]): the placement's material, else the triangle's own.
#[inline]
pub fn triangle_material(on: (&Geometry, Option<Placed>), tri: u32) -> u32 {
    match on {
        (_, Some((_, Some(m)))) => m,
        (g, _) => g.tri_material[tri as usize],
    }
}

/// The vertex normals and the geometric normal of triangle `tri` of the geometry and
/// placement `on` (from [`World::shading`]), in world space: through a placement, carried
/// by the inverse transpose of its transform and normalised, as the flattened scene's would
/// be ([`crate::mesh::Mesh::transformed`]). A mirroring placement keeps the front the front (as glTF's mirrored nodes, and as the
/// engines' back-face test in object space): the geometric normal is the object's carried
/// over, not `cross(v1 - v0, v2 - v0)` of the placed corners, which turns round.
///
/// (The arrays are written out element by element rather than with `array::map`, whose
/// temporaries `shade8`'s gather stored piecewise and then read back whole: a store-forwarding
/// stall per lane.)
#[inline(always)]
pub fn normals((g, placed): (&Geometry, Option<Placed>), tri: u32) -> ([Vec3; 3], Vec3) {
    let [a, b, c] = g.triangles[tri as usize];
    let v = [
        g.normals[a as usize],
        g.normals[b as usize],
        g.normals[c as usize],
    ];
    let ng = g.face_normals[tri as usize];
    match placed {
        None => (v, ng),
        Some((p, _)) => {
            let m = p.to_object.matrix3.transpose();
            let f = |n: Vec3| (m * n).normalize_or_zero();
            ([f(v[0]), f(v[1]), f(v[2])], f(ng))
        }
    }
}

/// `Od` at barycentric weights `b0 b1 b2` of the triangle with vertices `v`: the material's
/// colour, the interpolated vertex colour or the texture at the interpolated `uv`.
/// Shared by `surface` and `shade8`. (Inlined: called, its result came back through memory
/// and was read a float at a time, which stalled on the call's wider stores.)
#[inline(always)]
pub fn albedo(g: &Geometry, m: &Material, v: [usize; 3], b0: f32, b1: f32, b2: f32) -> Vec3 {
    let [i0, i1, i2] = v;
    match &m.albedo {
        Albedo::Color(c) => *c,
        Albedo::VertexColor => b0 * g.colors[i0] + b1 * g.colors[i1] + b2 * g.colors[i2],
        Albedo::Texture(t) => t.sample_uv(b0 * g.uvs[i0] + b1 * g.uvs[i1] + b2 * g.uvs[i2]),
    }
}

/// `x^n` for the Phong lobe: whole exponents (the usual case, 40 and 60 in the canonical
/// scenes) by repeated squaring, which is several times cheaper than `powf` and within a few
/// ulps of it; other exponents by `powf`. Shared by `shade1` and `shade8`.
#[inline]
pub fn phong_pow(x: f32, n: f32) -> f32 {
    if whole_exponent(n) {
        powi_by_squaring(x, n as u32, 1.0)
    } else {
        x.powf(n)
    }
}

/// Exponents `phong_pow` takes by repeated squaring.
#[inline]
pub fn whole_exponent(n: f32) -> bool {
    n.fract() == 0.0 && (0.0..=4096.0).contains(&n)
}

/// `x^e` by binary exponentiation (compiler-rt's `__powisf2` loop, written out), for `f32`
/// and for `F32x8` lanes alike, so that `shade1` and `shade8` perform the same
/// multiplications.
#[inline(always)]
pub fn powi_by_squaring<T: Copy + std::ops::Mul<Output = T>>(mut x: T, mut e: u32, one: T) -> T {
    let mut r = one;
    loop {
        if e & 1 == 1 {
            r = r * x;
        }
        e >>= 1;
        if e == 0 {
            return r;
        }
        x = x * x;
    }
}

/// Shadow ray from `q` towards a light: offset origin, unit direction, `tfar` = distance to
/// the light from the offset origin.
pub fn shadow_ray(s: &Surface, light: Vec3, eps: f32) -> Ray {
    let l = (light - s.q).normalize();
    let origin = offset_origin(s.q, s.ng, l, eps);
    Ray::new(origin, l, 0.0, (light - origin).length())
}

/// The local part of the equation (ambient + lights) at `s`, seen along `d`, with `visible(i)`
/// giving `S_i` for light `i` (called only where light `i` can contribute).
pub fn direct1(
    world: &World,
    terms: Terms,
    s: &Surface,
    d: Vec3,
    mut visible: impl FnMut(usize) -> bool,
) -> Vec3 {
    let m: &Material = &world.scene.materials[s.material as usize];
    let sc = &world.scene;
    // ambient
    let mut color = sc.ambient * m.ka * s.od;
    // emission (lamps): their own colour, lit or not
    if m.emits() {
        color += m.ke;
    }
    let v = -d.normalize();
    for (i, light) in sc.lights.iter().enumerate() {
        let l = (light.position - s.q).normalize();
        let ndotl = s.n.dot(l);
        // Both terms vanish where <N, l> <= 0 (the specular one by definition), so no shadow
        // ray is needed there.
        if !(ndotl > 0.0) {
            continue;
        }
        // diffuse
        let mut c = m.kd * s.od * ndotl;
        // specular: r = 2 <N, l> N - l
        if terms.specular {
            let r = 2.0 * ndotl * s.n - l;
            c += m.ks * phong_pow(v.dot(r).max(0.0), m.n);
        }
        let share = light.intensity * c;
        // A share of exactly 0 (every channel) adds nothing whether the light is visible or
        // not, so no shadow ray is traced for it: `kd = 0` where the Phong lobe rounds to 0.
        if share == Vec3::ZERO {
            continue;
        }
        // shadow
        if terms.shadows && !visible(i) {
            continue;
        }
        color += share;
    }
    color
}

/// Reflection and refraction rays leaving `s` (none at depth 0).
pub fn secondaries1(world: &World, s: &Surface, d: Vec3, depth: u32) -> [Option<Secondary>; 2] {
    let m = &world.scene.materials[s.material as usize];
    let mut out = [None, None];
    if depth == 0 {
        return out;
    }
    let d = d.normalize();
    let dr = reflect(d, s.n).normalize();
    // reflection: d_r = d - 2 <d, N> N
    if m.reflects() {
        out[0] = Some(Secondary {
            ray: Ray::new(
                offset_origin(s.q, s.ng, dr, world.eps),
                dr,
                0.0,
                f32::INFINITY,
            ),
            weight: m.kr,
            kind: SecondaryKind::Reflection,
        });
    }
    // refraction: eta = 1/ior entering through a front face, ior leaving through a back face;
    // total internal reflection traces It along d_r.
    if m.refracts() {
        let eta = if s.back { m.ior } else { 1.0 / m.ior };
        // "with N facing against d": an interpolated normal can still lean along d after the
        // back-face flip; turn it so cosi >= 0 (only for the refraction formula).
        let nt = if d.dot(s.n) > 0.0 { -s.n } else { s.n };
        let dt = refract(d, nt, eta).map_or(dr, |t| t.normalize());
        out[1] = Some(Secondary {
            ray: Ray::new(
                offset_origin(s.q, s.ng, dt, world.eps),
                dt,
                0.0,
                f32::INFINITY,
            ),
            weight: m.kt,
            kind: SecondaryKind::Refraction,
        });
    }
    out
}

/// Shade one hit: local illumination with shadow rays traced by `occluded1`, plus the
/// secondary rays to trace. `stats[0]` counts the shadow rays traced.
pub fn shade1(
    world: &World,
    terms: Terms,
    ray: &Ray,
    (hit, inst): (&Hit, u32),
    depth: u32,
    shadow_rays: &mut u64,
) -> (Vec3, [Option<Secondary>; 2]) {
    let s = surface_in(world, ray, hit, inst);
    let color = direct1(world, terms, &s, ray.dir, |i| {
        *shadow_rays += 1;
        !world.occluded1(&shadow_ray(&s, world.scene.lights[i].position, world.eps))
    });
    (color, secondaries1(world, &s, ray.dir, depth))
}

#[cfg(test)]
mod tests {
    use super::phong_pow;

    #[test]
    fn phong_pow_matches_powf() {
        for &n in &[0.0f32, 1.0, 2.0, 40.0, 60.0, 200.0, 500.0, 2.5, 33.3] {
            for k in 0..=100 {
                let x = k as f32 / 100.0;
                let (a, b) = (phong_pow(x, n), x.powf(n));
                assert!(
                    (a - b).abs() <= 1e-5 * b.max(1e-30) + 1e-30,
                    "{x}^{n}: {a} vs {b}"
                );
            }
        }
        assert_eq!(phong_pow(0.0, 0.0), 1.0);
    }
}
