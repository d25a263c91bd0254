//! `shade8`: Whitted's equation across the 8 lanes of a hit packet; twin of `shade1`.
//!
//! Per lane there are only loads: the triangle's vertex and face normals, its material's
//! constants and `Od` (the material colour, interpolated vertex colours or the texture, through
//! `albedo`, shared with `surface`). Everything after that runs across lanes with the same
//! operations in the same order as `surface`, `direct1` and `secondaries1`: interpolation and
//! normalisation of N, the back-face flip, ambient, diffuse, the Phong lobe, shadow-ray
//! origins, reflection and refraction directions (with total internal reflection) and their
//! offset origins. Shadow rays are not traced here: each lit lane and light becomes a
//! shadow-queue entry carrying the contribution to add if the light is visible.

use super::{albedo, normals, phong_pow, powi_by_squaring, triangle_material, whole_exponent};
use crate::packet::{HitPacket8, RayPacket8};
use crate::simd::{self, F32x8, LANES, M32x8, Vec3x8};
use crate::world::{NOT_INSTANCED, Terms, World};

/// One light's share of a hit packet: the shadow rays and what they carry.
#[derive(Clone, Copy, Debug, Default)]
pub struct LightLanes {
    /// Lanes where `<N, l> > 0` (the light can contribute).
    pub lit: M32x8,
    /// Shadow-ray origins (offset from the hit towards the light's side).
    pub origin: Vec3x8,
    /// Unit directions towards the light.
    pub dir: Vec3x8,
    /// Distance to the light.
    pub tfar: F32x8,
    /// `Ip [kd Od <N,l> + ks max(<v,r>,0)^n]`, to be added when the light is visible.
    pub contribution: Vec3x8,
}

/// The reflection or the refraction rays of a hit packet.
#[derive(Clone, Copy, Debug, Default)]
pub struct SecondaryLanes {
    /// Lanes that spawn this ray (a hit with depth left and `ks > 0`, resp. `kt > 0`).
    pub mask: M32x8,
    /// Ray origins (offset from the hit).
    pub origin: Vec3x8,
    /// Ray directions.
    pub dir: Vec3x8,
    /// `ks` or `kt` (RGB): the weight the ray's colour is added with.
    pub weight: Vec3x8,
    /// Refraction only: the lanes whose ray is, bit for bit, the reflection ray of the same
    /// lane (total internal reflection traces `It` along `d_r`, from the same offset origin,
    /// where a reflection ray is spawned too).
    pub mirror: M32x8,
}

/// What shading a hit packet produces (reused across packets to avoid allocating).
#[derive(Clone, Debug, Default)]
pub struct Shade8 {
    /// `Ia ka Od` (+ `ke` on emitting lanes) per lane.
    pub ambient: Vec3x8,
    /// One entry per light.
    pub lights: Vec<LightLanes>,
    /// The reflection rays.
    pub reflection: SecondaryLanes,
    /// The refraction rays.
    pub refraction: SecondaryLanes,
}

/// Per-lane loads of a hit packet (inactive lanes zero).
#[derive(Default)]
struct Gathered {
    /// Vertex normals of the hit triangle: `vn[vertex][axis][lane]`.
    vn: [[[f32; LANES]; 3]; 3],
    ng: [[f32; LANES]; 3],
    od: Vec3x8,
    /// `ka kd ks kt ke kr`.
    kc: [Vec3x8; 6],
    /// Phong exponent and index of refraction.
    n: F32x8,
    ior: F32x8,
    /// Lanes whose material emits.
    emits: u32,
    /// The material of every active lane, when they share one.
    uniform: Option<u32>,
}

fn gather(
    world: &World,
    hits: &HitPacket8,
    insts: &[u32; LANES],
    bits: u32,
    b: [[f32; LANES]; 3],
) -> Gathered {
    let tri = simd::u32_lanes(hits.tri);
    let mut out = Gathered::default();
    let active = || (0..LANES).filter(move |&i| bits >> i & 1 == 1);
    let mut material = [0u32; LANES];
    let mut od = [[0.0; LANES]; 3];
    for i in active() {
        let t = tri[i];
        // the lane's geometry and placement, once for its material, normals and colour
        let on = world.shading(insts[i]);
        let g = on.0;
        material[i] = triangle_material(on, t);
        let v = g.triangles[t as usize].map(|x| x as usize);
        let (vn, ng) = normals(on, t);
        for (vk, n) in vn.iter().enumerate() {
            out.vn[vk][0][i] = n.x;
            out.vn[vk][1][i] = n.y;
            out.vn[vk][2][i] = n.z;
        }
        let m = &world.scene.materials[material[i] as usize];
        let c = albedo(g, m, v, b[0][i], b[1][i], b[2][i]);
        for a in 0..3 {
            out.ng[a][i] = ng[a];
            od[a][i] = c[a];
        }
    }
    // (`od` is loaded as vectors only after the materials: right after the lane loop, the
    // loads waited on its last scalar stores)
    let first = material[bits.trailing_zeros() as usize % LANES];
    if active().all(|i| material[i] == first) {
        // one material: its constants splatted (the inactive lanes zeroed by the mask, as
        // the per-lane loads leave them), not 20 scalar stores per lane
        let m = &world.scene.materials[first as usize];
        let on = simd::mask_from_bits(bits);
        let zero = Vec3x8::splat([0.0; 3]);
        // (each written out: `array::map` over the six stored them piecewise and read them
        // back whole, a store-forwarding stall per packet)
        let f = |c: glam::Vec3| Vec3x8::select(on, Vec3x8::splat(c.to_array()), zero);
        out.kc = [f(m.ka), f(m.kd), f(m.ks), f(m.kt), f(m.ke), f(m.kr)];
        out.n = simd::select(on, simd::splat(m.n), simd::splat(0.0));
        out.ior = simd::select(on, simd::splat(m.ior), simd::splat(0.0));
        out.emits = if m.emits() { bits } else { 0 };
        out.uniform = Some(first);
        out.od = vec3x8(&od);
        return out;
    }
    let mut kc = [[[0.0; LANES]; 3]; 6];
    let (mut n, mut ior) = ([0.0; LANES], [0.0; LANES]);
    for i in active() {
        let m = &world.scene.materials[material[i] as usize];
        for (k, value) in [m.ka, m.kd, m.ks, m.kt, m.ke, m.kr].into_iter().enumerate() {
            for a in 0..3 {
                kc[k][a][i] = value[a];
            }
        }
        n[i] = m.n;
        ior[i] = m.ior;
        out.emits |= (m.emits() as u32) << i;
    }
    out.kc = kc.map(|c| vec3x8(&c));
    (out.n, out.ior) = (simd::from_lanes(n), simd::from_lanes(ior));
    out.od = vec3x8(&od);
    out
}

fn vec3x8(a: &[[f32; LANES]; 3]) -> Vec3x8 {
    Vec3x8::new(
        simd::from_lanes(a[0]),
        simd::from_lanes(a[1]),
        simd::from_lanes(a[2]),
    )
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
    shade8_in(
        world,
        terms,
        rays,
        (hits, &[NOT_INSTANCED; LANES]),
        mask,
        depth,
        out,
    )
}

/// [`shade8`] of hits through instances: `insts[i]` is lane `i`'s instance
/// ([`NOT_INSTANCED`]: on the flattened geometry).
pub fn shade8_in(
    world: &World,
    terms: Terms,
    rays: &RayPacket8,
    (hits, insts): (&HitPacket8, &[u32; LANES]),
    mask: M32x8,
    depth: [u32; LANES],
    out: &mut Shade8,
) {
    let sc = &world.scene;
    let bits = simd::bitmask(mask);
    let (zero, one) = (simd::splat(0.0), simd::splat(1.0));

    // surface: q, interpolated N (Ng where it vanishes), back-face flip, Od, material.
    let (b1, b2) = (hits.b1, hits.b2);
    let b0 = one - b1 - b2;
    let gl = gather(world, hits, insts, bits, [b0, b1, b2].map(simd::lanes));
    let q = rays.o + rays.d.scale(hits.t);
    let mut ng = vec3x8(&gl.ng);
    let ni =
        vec3x8(&gl.vn[0]).scale(b0) + vec3x8(&gl.vn[1]).scale(b1) + vec3x8(&gl.vn[2]).scale(b2);
    // glam's try_normalize: 1 / |n| must be finite and positive.
    let rcp = one / simd::sqrt(ni.dot(ni));
    let ok = simd::gt(rcp, zero) & simd::lt(rcp, simd::splat(f32::INFINITY));
    let mut n = Vec3x8::select(ok, ni.scale(rcp), ng);
    let back = simd::gt(rays.d.dot(ng), zero);
    ng = Vec3x8::select(back, -ng, ng);
    n = Vec3x8::select(back, -n, n);
    let od = gl.od;
    let [ka, kd, ks, kt, ke, kr] = gl.kc;
    let (n_exp, ior) = (gl.n, gl.ior);

    // ambient: Ia ka Od
    let ia = Vec3x8::splat(sc.ambient.to_array());
    out.ambient = Vec3x8::new(ia.x * ka.x * od.x, ia.y * ka.y * od.y, ia.z * ka.z * od.z);
    // emission (lamps): + ke on the lanes whose material emits
    if gl.emits & bits != 0 {
        let m = simd::mask_from_bits(gl.emits);
        out.ambient = Vec3x8::select(m, out.ambient + ke, out.ambient);
    }

    // One Phong exponent for the whole packet (the usual case) is raised across lanes.
    let uniform_n = gl
        .uniform
        .map(|m| sc.materials[m as usize].n)
        .filter(|&e| whole_exponent(e));

    let v = -rays.d.normalize();
    let eps = simd::splat(world.eps);
    out.lights.clear();
    for light in &sc.lights {
        let lp = Vec3x8::splat(light.position.to_array());
        let l = (lp - q).normalize();
        let ndotl = n.dot(l);
        // Both terms vanish where <N, l> <= 0, so no shadow ray is needed there (nor where
        // the light's share rounds to 0, below).
        let facing = mask & simd::gt(ndotl, zero);
        // diffuse: kd Od <N, l>
        let kdod = Vec3x8::new(kd.x * od.x, kd.y * od.y, kd.z * od.z);
        let mut c = kdod.scale(ndotl);
        // specular: r = 2 <N, l> N - l; ks max(<v, r>, 0)^n
        if terms.specular {
            let r = n.scale(simd::splat(2.0) * ndotl) - l;
            let base = simd::max(v.dot(r), zero);
            let pow = match uniform_n {
                Some(e) => powi_by_squaring(base, e as u32, one),
                None => {
                    let (b, e) = (simd::lanes(base), simd::lanes(n_exp));
                    simd::from_lanes(std::array::from_fn(|i| phong_pow(b[i], e[i])))
                }
            };
            c = c + ks.scale(pow);
        }
        let ip = Vec3x8::splat(light.intensity.to_array());
        let contribution = ip.mul_elem(c);
        // a share of exactly 0 in every channel adds nothing visible or not, so it needs no
        // shadow ray (`direct1` skips it too): `kd = 0` where the Phong lobe rounds to 0, as
        // on most of `refraction`'s glass. NaN is not 0 and keeps its ray.
        let nothing = simd::eq(contribution.x, zero)
            & simd::eq(contribution.y, zero)
            & simd::eq(contribution.z, zero);
        let lit = simd::and_not(facing, nothing);
        // shadow ray: origin offset along +-Ng to the light's side, tfar to the light.
        let side = simd::gt(l.dot(ng), zero);
        let origin = Vec3x8::select(side, q + ng.scale(eps), q - ng.scale(eps));
        let to_light = lp - origin;
        out.lights.push(LightLanes {
            lit,
            origin,
            dir: l,
            tfar: simd::sqrt(to_light.dot(to_light)),
            contribution,
        });
    }

    // secondaries (lanes with depth left): d_r = d - 2 <d, N> N, offset origins.
    let alive =
        mask & simd::mask_from_bits((0..LANES).fold(0, |b, i| b | ((depth[i] > 0) as u32) << i));
    let d = rays.d.normalize();
    let dr = (d - n.scale(simd::splat(2.0) * d.dot(n))).normalize();
    let offset = |dir: Vec3x8| {
        let side = simd::gt(dir.dot(ng), zero);
        Vec3x8::select(side, q + ng.scale(eps), q - ng.scale(eps))
    };
    let any = |k: Vec3x8| simd::gt(simd::max(simd::max(k.x, k.y), k.z), zero);
    out.reflection = SecondaryLanes {
        mask: alive & any(kr),
        origin: offset(dr),
        dir: dr,
        weight: kr,
        mirror: simd::splat(0.0),
    };
    // refraction: eta = 1/ior entering through a front face, ior leaving through a back
    // face; N turned against d; total internal reflection (k < 0) takes d_r.
    let refr = alive & any(kt);
    out.refraction = if simd::any(refr) {
        let eta = simd::select(back, ior, one / ior);
        let nt = Vec3x8::select(simd::gt(d.dot(n), zero), -n, n);
        let cosi = -d.dot(nt);
        let k = one - eta * eta * (one - cosi * cosi);
        let t = (d.scale(eta) + nt.scale(eta * cosi - simd::sqrt(k))).normalize();
        let tir = simd::lt(k, zero);
        let dt = Vec3x8::select(tir, dr, t);
        SecondaryLanes {
            mask: refr,
            origin: offset(dt),
            dir: dt,
            weight: kt,
            mirror: refr & tir & out.reflection.mask,
        }
    } else {
        SecondaryLanes::default()
    };
}
