//! The peer's workloads, reproduced step for step: mesh subdivision, camera, the five ray sets.

use crate::accel::{Accel, intersect1};
use crate::mesh::Mesh;
use crate::ray::Ray;
use glam::Vec3;
use rayon::prelude::*;

/// Image width of the primary workload (pixels), the peer's default.
pub const WIDTH: u32 = 1920;
/// Image height of the primary workload (pixels), the peer's default.
pub const HEIGHT: u32 = 1080;
/// Seed of the incoherent directions (splitmix64).
pub const SEED: u64 = 1234567;
/// Seed of the random workload (splitmix64), the peer's `--random`.
pub const RANDOM_SEED: u64 = 7654321;
/// Rays of the random workload unless told otherwise (the peer's `--random` in `whitted bench`).
pub const RANDOM_RAYS: usize = 262144;
/// Rays per work item with more than one thread (the peer's `CHUNK`, a multiple of 16).
pub const CHUNK: usize = 4096;

/// The peer's canonical view (SCENES.md) and the kitten's box centre and half diagonal.
const EYE: [f64; 3] = [1.6, 0.9, 4.4];
const LOOK: [f64; 3] = [0.0, -0.15, 0.0];
const L1: [f64; 3] = [5.0, 6.0, 3.0];
const KC: [f64; 3] = [-0.0096955, 0.0, -0.009271];
const KR: f64 = 1.3328798140238487;

// ---------------------------------------------------------------- f64 helpers (as in rt_bench.c)

fn vnorm(v: &mut [f64; 3]) {
    let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
}

fn vcross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn vdot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The peer's `rays_set`: origin and direction rounded to f32.
fn ray_f32(o: [f64; 3], d: [f64; 3], tnear: f32, tfar: f32) -> Ray {
    let v = |a: [f64; 3]| Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32);
    Ray::new(v(o), v(d), tnear, tfar)
}

/// splitmix64, the peer's `rng_u64`.
pub fn rng_u64(s: &mut u64) -> u64 {
    *s = s.wrapping_add(0x9E3779B97F4A7C15);
    let mut z = *s;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
    z ^ (z >> 31)
}

/// Top 53 bits as a double in `[0, 1)`, the peer's `rng_unit`.
pub fn rng_unit(s: &mut u64) -> f64 {
    (rng_u64(s) >> 11) as f64 * (1.0 / 9007199254740992.0)
}

// ---------------------------------------------------------------- mesh

/// Midpoint subdivision exactly as the peer does it, `levels` times: old vertices keep their
/// indices, edge midpoints `(p[a] + p[b]) * 0.5` (f32) are appended in ascending order of
/// `(min, max)` vertex index, and triangle `t` becomes `4t..4t+3` =
/// `[c0 m0 m2] [m0 c1 m1] [m2 m1 c2] [m0 m1 m2]` (`m_k` on edge `c_k c_k+1`).
/// (`Mesh::subdivide` makes the same triangles with other vertex numbers and rotations
/// `[v1 m12 m01]`, `[v2 m20 m12]`; the rotation changes the f32 rounding of a plane normal,
/// so the bench uses this one to trace the peer's triangles exactly.) Attributes are dropped.
pub fn subdivide_like_peer(mesh: &Mesh, levels: u32) -> Mesh {
    let mut pos = mesh.positions.clone();
    let mut idx = mesh.triangles.clone();
    for _ in 0..levels {
        let nv = pos.len() as u64;
        let key = |a: u32, b: u32| {
            let (a, b) = (a.min(b) as u64, a.max(b) as u64);
            a * nv + b
        };
        let mut keys: Vec<u64> = idx
            .iter()
            .flat_map(|c| (0..3).map(move |k| key(c[k], c[(k + 1) % 3])))
            .collect();
        keys.sort_unstable();
        keys.dedup();
        for &k in &keys {
            let (a, b) = ((k / nv) as usize, (k % nv) as usize);
            pos.push((pos[a] + pos[b]) * 0.5);
        }
        let mut out = Vec::with_capacity(idx.len() * 4);
        for c in &idx {
            let m: [u32; 3] = std::array::from_fn(|k| {
                let r = keys
                    .binary_search(&key(c[k], c[(k + 1) % 3]))
                    .expect("edge");
                (nv as usize + r) as u32
            });
            out.extend([
                [c[0], m[0], m[2]],
                [m[0], c[1], m[1]],
                [m[2], m[1], c[2]],
                [m[0], m[1], m[2]],
            ]);
        }
        idx = out;
    }
    Mesh {
        positions: pos,
        triangles: idx,
        ..Default::default()
    }
}

/// The triangles of `mesh` as vertex triples (what `Accel::build` takes).
pub fn triangles(mesh: &Mesh) -> Vec<[Vec3; 3]> {
    mesh.triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect()
}

/// Embree's geometric normal (AVX2 kernels): `cross(v2 - v0, v0 - v1)` with fused
/// multiply-adds, unnormalised. The direction of `cross(v1 - v0, v2 - v0)`.
pub fn embree_ng(mesh: &Mesh, tri: u32) -> [f32; 3] {
    let [v0, v1, v2] = mesh.triangles[tri as usize].map(|i| mesh.positions[i as usize]);
    let e1 = v0 - v1;
    let e2 = v2 - v0;
    [
        e2.y.mul_add(e1.z, -(e2.z * e1.y)),
        e2.z.mul_add(e1.x, -(e2.x * e1.z)),
        e2.x.mul_add(e1.y, -(e2.y * e1.x)),
    ]
}

/// FNV-1a 64 over bytes (the peer notes' ray and mesh hashes).
pub fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf29ce484222325, |h, b| {
        (h ^ b as u64).wrapping_mul(0x100000001b3)
    })
}

/// FNV-1a of ray records `ox oy oz dx dy dz tnear tfar` (f32 LE), as the peer's dumps.
pub fn ray_hash(rays: &[Ray]) -> u64 {
    fnv1a(rays.iter().flat_map(|r| {
        let v = [
            r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.tnear, r.tfar,
        ];
        v.into_iter().flat_map(f32::to_le_bytes)
    }))
}

// ---------------------------------------------------------------- workloads

/// Camera, light and offset of the peer for one mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Framing {
    /// The kitten's box (to 1e-5): eye, look-at and light are the literal constants.
    pub canonical: bool,
    /// Bounding-box centre.
    pub center: [f64; 3],
    /// Half the bounding box's diagonal (the peer's `R`).
    pub radius: f64,
    /// Camera position: the canonical eye, or it moved and scaled with the box.
    pub eye: [f64; 3],
    /// Look-at point, placed like `eye`.
    pub look: [f64; 3],
    /// Point light L1, placed like `eye` (the shadow rays' target).
    pub light: [f64; 3],
    /// Secondary origin offset `1e-5 * 2 * R`.
    pub eps: f64,
}

impl Framing {
    /// The peer's framing of `mesh` (box over all vertices, even unreferenced ones).
    pub fn of(mesh: &Mesh) -> Framing {
        let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
        let mut c = [0.0; 3];
        let mut r = 0.0;
        for j in 0..3 {
            c[j] = 0.5 * (lo[j] as f64 + hi[j] as f64);
            r += (hi[j] as f64 - lo[j] as f64) * (hi[j] as f64 - lo[j] as f64);
        }
        let r = 0.5 * r.sqrt();
        let sc = r / KR;
        let canonical = (sc - 1.0).abs() < 1e-5 && (0..3).all(|j| (c[j] - KC[j]).abs() < 1e-5);
        let place = |p: [f64; 3]| -> [f64; 3] {
            if canonical {
                p
            } else {
                std::array::from_fn(|j| c[j] + (p[j] - KC[j]) * sc)
            }
        };
        Framing {
            canonical,
            center: c,
            radius: r,
            eye: place(EYE),
            look: place(LOOK),
            light: place(L1),
            eps: 1e-5 * 2.0 * r,
        }
    }
}

/// `tan(36 pi / 360)`, the half-height of the image plane (vfov 36).
pub fn tan_half_fov() -> f64 {
    (36.0 * std::f64::consts::PI / 360.0).tan()
}

/// The peer's primary rays: pixel centres of a `w x h` image in 4x4 blocks (blocks row-major,
/// pixels row-major within a block; partial blocks truncated), `tnear 0`, `tfar inf`.
pub fn primary_rays(fr: &Framing, w: u32, h: u32) -> Vec<Ray> {
    let mut f = std::array::from_fn(|j| fr.look[j] - fr.eye[j]);
    vnorm(&mut f);
    let mut rr = vcross(f, [0.0, 1.0, 0.0]);
    vnorm(&mut rr);
    let uu = vcross(rr, f);
    let th = tan_half_fov();
    let asp = w as f64 / h as f64;
    let mut rays = Vec::with_capacity(w as usize * h as usize);
    for by in (0..h).step_by(4) {
        for bx in (0..w).step_by(4) {
            for y in by..(by + 4).min(h) {
                for x in bx..(bx + 4).min(w) {
                    let px = (2.0 * (x as f64 + 0.5) / w as f64 - 1.0) * th * asp;
                    let py = (1.0 - 2.0 * (y as f64 + 0.5) / h as f64) * th;
                    let mut d = std::array::from_fn(|j| f[j] + px * rr[j] + py * uu[j]);
                    vnorm(&mut d);
                    rays.push(ray_f32(fr.eye, d, 0.0, f32::INFINITY));
                }
            }
        }
    }
    rays
}

/// A primary hit as the secondary rays need it: the ray parameter and the geometric normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    /// Hit distance along the primary ray, in units of its direction.
    pub t: f32,
    /// Geometric normal, unnormalised, as [`embree_ng`] gives it ([`secondary_rays`]
    /// normalises it and turns it towards the viewer).
    pub ng: [f32; 3],
}

/// The three secondary sets of the peer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Secondary {
    /// The primary rays that hit, in block order (`tnear 0`, `tfar inf`).
    pub primary_hits: Vec<Ray>,
    /// One ray per hit towards the light, `tfar` one ulp short of it (any hit).
    pub shadow: Vec<Ray>,
    /// One uniform hemisphere ray per hit about the viewer-facing normal (closest hit).
    pub incoherent: Vec<Ray>,
}

/// The peer's secondary sets from the primary rays and their hits (`None` = miss), in one pass
/// in block order, two RNG draws per hit (verbatim arithmetic of rt_bench.c).
pub fn secondary_rays(fr: &Framing, primary: &[Ray], hits: &[Option<SurfaceHit>]) -> Secondary {
    let mut out = Secondary::default();
    let mut seed = SEED;
    let eps = fr.eps;
    for (ray, hit) in primary.iter().zip(hits) {
        let Some(hit) = hit else { continue };
        let o = ray.origin.to_array().map(f64::from);
        let d = ray.dir.to_array().map(f64::from);
        out.primary_hits.push(ray_f32(o, d, 0.0, f32::INFINITY));
        let t = hit.t as f64;
        let q: [f64; 3] = std::array::from_fn(|j| o[j] + t * d[j]);
        let mut n = hit.ng.map(f64::from);
        vnorm(&mut n);
        if vdot(n, d) > 0.0 {
            n = n.map(|v| -v);
        }
        // shadow: towards the light from q, origin on the light's side of the surface
        let l_: [f64; 3] = std::array::from_fn(|j| fr.light[j] - q[j]);
        let dist = vdot(l_, l_).sqrt();
        let l = l_.map(|v| v / dist);
        let sgn = if vdot(l, n) > 0.0 { eps } else { -eps };
        let so: [f64; 3] = std::array::from_fn(|j| q[j] + sgn * n[j]);
        out.shadow
            .push(ray_f32(so, l, 0.0, (dist as f32).next_down()));
        // incoherent: uniform on the hemisphere about n
        let z = rng_unit(&mut seed);
        let phi = 2.0 * std::f64::consts::PI * rng_unit(&mut seed);
        let s2 = (1.0 - z * z).max(0.0).sqrt();
        let a = if n[0].abs() > 0.9 {
            [0.0, 1.0, 0.0]
        } else {
            [1.0, 0.0, 0.0]
        };
        let mut t_ = vcross(n, a);
        vnorm(&mut t_);
        let b_ = vcross(n, t_);
        let mut dd: [f64; 3] =
            std::array::from_fn(|e| z * n[e] + s2 * (phi.cos() * t_[e] + phi.sin() * b_[e]));
        vnorm(&mut dd);
        let o2: [f64; 3] = std::array::from_fn(|j| q[j] + eps * n[j]);
        out.incoherent.push(ray_f32(o2, dd, 0.0, f32::INFINITY));
    }
    out
}

/// The peer's `--random n` rays: no coherence at all, as visibility sampling, lidar or
/// inside/outside tests cast them. Ray `k` draws from splitmix64 seeded [`RANDOM_SEED`], in
/// this order: the origin `lo + u * (hi - lo)` per axis x, y, z (uniform in the f32 box of all
/// vertices, computed in f64), then `z = 2u - 1` and `phi = 2 pi u`; the direction is
/// `(sqrt(1 - z^2) cos phi, sqrt(1 - z^2) sin phi, z)`; all in f64, stored as f32; `tnear 0`,
/// `tfar inf`. On the kitten 133,563 of the first 262,144 hit.
pub fn random_rays(mesh: &Mesh, n: usize) -> Vec<Ray> {
    let (lo, hi) = mesh.bounds().unwrap_or((Vec3::ZERO, Vec3::ZERO));
    let mut s = RANDOM_SEED;
    (0..n)
        .map(|_| {
            let o: [f64; 3] = std::array::from_fn(|e| {
                lo[e] as f64 + rng_unit(&mut s) * (hi[e] as f64 - lo[e] as f64)
            });
            let z = 2.0 * rng_unit(&mut s) - 1.0;
            let phi = 2.0 * std::f64::consts::PI * rng_unit(&mut s);
            let s2 = (1.0 - z * z).max(0.0).sqrt();
            ray_f32(o, [s2 * phi.cos(), s2 * phi.sin(), z], 0.0, f32::INFINITY)
        })
        .collect()
}

/// All five workloads of one mesh.
#[derive(Clone, Debug)]
pub struct Workloads {
    /// Camera, light and offset the sets were made with.
    pub framing: Framing,
    /// Image width of the primary rays, pixels.
    pub width: u32,
    /// Image height of the primary rays, pixels.
    pub height: u32,
    /// One ray per pixel centre, in 4x4 blocks ([`primary_rays`]).
    pub primary: Vec<Ray>,
    /// The sets made from the primary hits ([`secondary_rays`]).
    pub secondary: Secondary,
    /// Rays with origins anywhere in the box and directions anywhere ([`random_rays`]).
    pub random: Vec<Ray>,
}

impl Workloads {
    /// The peer's workloads for `mesh` (traced by `accel`, built over `triangles(mesh)`),
    /// the secondary sets from whitted's own single-ray hits, [`RANDOM_RAYS`] random rays.
    /// No culling.
    pub fn generate(mesh: &Mesh, accel: &Accel, width: u32, height: u32) -> Workloads {
        Workloads::generate_with(mesh, accel, width, height, RANDOM_RAYS)
    }

    /// [`Workloads::generate`] with `random` random rays (0: no random workload).
    pub fn generate_with(
        mesh: &Mesh,
        accel: &Accel,
        width: u32,
        height: u32,
        random: usize,
    ) -> Workloads {
        let framing = Framing::of(mesh);
        let primary = primary_rays(&framing, width, height);
        let hits: Vec<Option<SurfaceHit>> = primary
            .par_iter()
            .map(|r| {
                intersect1(accel, r, false).map(|h| SurfaceHit {
                    t: h.t,
                    ng: embree_ng(mesh, h.tri),
                })
            })
            .collect();
        let secondary = secondary_rays(&framing, &primary, &hits);
        Workloads {
            framing,
            width,
            height,
            primary,
            secondary,
            random: random_rays(mesh, random),
        }
    }

    /// `(workload, rays)` in the peer's order (see [`Workload::any_hit`] for the query); the
    /// random set only when it has rays.
    pub fn sets(&self) -> Vec<(Workload, &[Ray])> {
        let mut sets: Vec<(Workload, &[Ray])> = vec![
            (Workload::Primary, &self.primary),
            (Workload::PrimaryHits, &self.secondary.primary_hits),
            (Workload::Shadow, &self.secondary.shadow),
            (Workload::Incoherent, &self.secondary.incoherent),
        ];
        if !self.random.is_empty() {
            sets.push((Workload::Random, &self.random));
        }
        sets
    }
}

/// The five ray sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Workload {
    /// Pixel-centre camera rays (`primary`), closest hit.
    Primary,
    /// The primary rays that hit (`primary-hits-only`), closest hit.
    PrimaryHits,
    /// Rays from the primary hits towards the light (`shadow`), any hit.
    Shadow,
    /// Hemisphere rays from the primary hits (`incoherent`), closest hit.
    Incoherent,
    /// Origins uniform in the box, directions uniform on the sphere (`random`), closest hit.
    Random,
}

impl Workload {
    /// Every workload, in the peer's order.
    pub const ALL: [Workload; 5] = [
        Workload::Primary,
        Workload::PrimaryHits,
        Workload::Shadow,
        Workload::Incoherent,
        Workload::Random,
    ];

    /// The peer's name (first word of its kernel lines).
    pub fn name(self) -> &'static str {
        match self {
            Workload::Primary => "primary",
            Workload::PrimaryHits => "primary-hits-only",
            Workload::Shadow => "shadow",
            Workload::Incoherent => "incoherent",
            Workload::Random => "random",
        }
    }

    /// The workload whose [`name`](Workload::name) is `s` exactly, if any.
    pub fn from_name(s: &str) -> Option<Workload> {
        Workload::ALL.into_iter().find(|w| w.name() == s)
    }

    /// Shadow rays ask for any hit, the others for the closest.
    pub fn any_hit(self) -> bool {
        self == Workload::Shadow
    }
}
