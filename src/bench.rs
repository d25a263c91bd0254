//! Throughput on the Embree peer's workloads (`whitted bench`, `benches/`), side by side with it.
//!
//! The peer is `rt-bench` (`shared/peers/embree`). Its workloads are reproduced here from its
//! source, step for step in the same f64 arithmetic and order:
//! - the mesh: loaded, then midpoint-subdivided with the peer's vertex numbering and child
//!   order ([`subdivide_like_peer`]), so both trace the very same triangles;
//! - the camera: the canonical kitten view, or the same view scaled onto another mesh's box;
//! - **primary**: 1920x1080 pixel-centre rays in 4x4 pixel blocks (an 8-ray packet is the top
//!   or bottom 4x2 half of a block), bit for bit the peer's rays;
//! - **primary-hits-only**: the primary rays that hit, in block order;
//! - **shadow**: from each primary hit towards the light L1, origin pushed `eps` off the
//!   surface on the light's side, `tfar` one ulp short of the light (any hit);
//! - **incoherent**: one uniform hemisphere direction about the geometric normal per hit
//!   (splitmix64, seed 1234567), origin pushed `eps` to the viewer's side (closest hit).
//!
//! The secondary sets are built from whitted's *own* primary hits (`t` and the triangle's
//! normal). Embree computes `t` with a different (unpublished) formula, so these two sets agree
//! with Embree's to about one ulp per ray, not bit for bit; fed Embree's `(prim, t, Ng)` the
//! same code reproduces Embree's sets exactly ([`secondary_rays`]).

use crate::accel::{Accel, BuildQuality, intersect1, intersect8, occluded1, occluded8};
use crate::mesh::Mesh;
use crate::packet::{HitPacket8, RayPacket8};
use crate::ray::Ray;
use crate::simd::{self, M32x8};
use glam::Vec3;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Image size of the primary workload.
pub const WIDTH: u32 = 1920;
pub const HEIGHT: u32 = 1080;
/// Seed of the incoherent directions (splitmix64).
pub const SEED: u64 = 1234567;
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
    /// Bounding-box centre and half diagonal (the peer's `R`).
    pub center: [f64; 3],
    pub radius: f64,
    pub eye: [f64; 3],
    pub look: [f64; 3],
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
    pub t: f32,
    pub ng: [f32; 3],
}

/// The three secondary sets of the peer.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Secondary {
    pub primary_hits: Vec<Ray>,
    pub shadow: Vec<Ray>,
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

/// All four workloads of one mesh.
#[derive(Clone, Debug)]
pub struct Workloads {
    pub framing: Framing,
    pub width: u32,
    pub height: u32,
    pub primary: Vec<Ray>,
    pub secondary: Secondary,
}

impl Workloads {
    /// The peer's workloads for `mesh` (traced by `accel`, built over `triangles(mesh)`),
    /// the secondary sets from whitted's own single-ray hits. No culling.
    pub fn generate(mesh: &Mesh, accel: &Accel, width: u32, height: u32) -> Workloads {
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
        }
    }

    /// `(name, rays, any-hit)` in the peer's order.
    pub fn sets(&self) -> [(Workload, &[Ray]); 4] {
        [
            (Workload::Primary, &self.primary),
            (Workload::PrimaryHits, &self.secondary.primary_hits),
            (Workload::Shadow, &self.secondary.shadow),
            (Workload::Incoherent, &self.secondary.incoherent),
        ]
    }
}

/// The four ray sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Workload {
    Primary,
    PrimaryHits,
    Shadow,
    Incoherent,
}

impl Workload {
    pub const ALL: [Workload; 4] = [
        Workload::Primary,
        Workload::PrimaryHits,
        Workload::Shadow,
        Workload::Incoherent,
    ];

    /// The peer's name (first word of its kernel lines).
    pub fn name(self) -> &'static str {
        match self {
            Workload::Primary => "primary",
            Workload::PrimaryHits => "primary-hits-only",
            Workload::Shadow => "shadow",
            Workload::Incoherent => "incoherent",
        }
    }

    pub fn from_name(s: &str) -> Option<Workload> {
        Workload::ALL.into_iter().find(|w| w.name() == s)
    }

    /// Shadow rays ask for any hit, the others for the closest.
    pub fn any_hit(self) -> bool {
        self == Workload::Shadow
    }
}

// ---------------------------------------------------------------- kernels

/// Rays grouped 8 consecutive per packet (the peer's `run_8`), padding lanes inactive.
pub struct Packets {
    pub rays: Vec<RayPacket8>,
    pub active: Vec<M32x8>,
    pub len: usize,
}

impl Packets {
    pub fn new(rays: &[Ray]) -> Packets {
        let (rays_, active) = rays
            .chunks(8)
            .map(|g| RayPacket8::from_fn(|i| g.get(i).copied()))
            .unzip();
        Packets {
            rays: rays_,
            active,
            len: rays.len(),
        }
    }
}

/// What a pass leaves behind, per ray: the hit triangle (or `u32::MAX`) and `t`, or occlusion.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Results {
    pub tri: Vec<u32>,
    pub t: Vec<f32>,
    pub occluded: Vec<bool>,
}

impl Results {
    /// Rays that hit (closest-hit sets) or are occluded (shadow).
    pub fn count(&self) -> usize {
        self.tri.iter().filter(|&&t| t != u32::MAX).count()
            + self.occluded.iter().filter(|&&o| o).count()
    }

    /// Order-dependent checksum of the results (ids, `t` bits, occlusion).
    pub fn checksum(&self) -> u64 {
        fnv1a(
            self.tri
                .iter()
                .zip(&self.t)
                .flat_map(|(i, t)| [i.to_le_bytes(), t.to_bits().to_le_bytes()])
                .flatten()
                .chain(self.occluded.iter().map(|&o| o as u8)),
        )
    }
}

/// Output buffers of one engine on one set, written in place by every pass (as the peer
/// writes its result arrays): per ray `(triangle, t)` or occlusion, per packet a
/// `HitPacket8` or an occlusion bitmask.
pub enum Out {
    Hits(Vec<(u32, f32)>),
    Occ(Vec<bool>),
    Hits8(Vec<HitPacket8>),
    Occ8(Vec<u8>),
}

/// The engines timed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Engine {
    /// `intersect1` / `occluded1`, ray by ray.
    Scalar,
    /// `intersect8` / `occluded8` on 8 consecutive rays.
    Packet,
}

impl Engine {
    pub fn name(self) -> &'static str {
        match self {
            Engine::Scalar => "scalar",
            Engine::Packet => "packet8",
        }
    }
}

fn hits1(accel: &Accel, rays: &[Ray], out: &mut [(u32, f32)]) {
    for (r, o) in rays.iter().zip(out) {
        *o = intersect1(accel, r, false).map_or((u32::MAX, f32::INFINITY), |h| (h.tri, h.t));
    }
}

fn occ1(accel: &Accel, rays: &[Ray], out: &mut [bool]) {
    for (r, o) in rays.iter().zip(out) {
        *o = occluded1(accel, r, false);
    }
}

fn hits8(accel: &Accel, rays: &[RayPacket8], active: &[M32x8], out: &mut [HitPacket8]) {
    for ((r, a), o) in rays.iter().zip(active).zip(out) {
        *o = intersect8(accel, r, *a, false);
    }
}

fn occ8(accel: &Accel, rays: &[RayPacket8], active: &[M32x8], out: &mut [u8]) {
    for ((r, a), o) in rays.iter().zip(active).zip(out) {
        *o = simd::bitmask(occluded8(accel, r, *a, false)) as u8;
    }
}

/// One pass of an engine over a set, in place; with a pool, chunks of [`CHUNK`] rays in
/// parallel (the peer's threads pull 4096-ray chunks from a shared counter).
pub fn pass(
    accel: &Accel,
    rays: &[Ray],
    packets: &Packets,
    out: &mut Out,
    pool: Option<&rayon::ThreadPool>,
) {
    let (pr, pa) = (&packets.rays[..], &packets.active[..]);
    let Some(pool) = pool else {
        match out {
            Out::Hits(o) => hits1(accel, rays, o),
            Out::Occ(o) => occ1(accel, rays, o),
            Out::Hits8(o) => hits8(accel, pr, pa, o),
            Out::Occ8(o) => occ8(accel, pr, pa, o),
        }
        return;
    };
    const P: usize = CHUNK / 8;
    pool.install(|| match out {
        Out::Hits(o) => o
            .par_chunks_mut(CHUNK)
            .zip(rays.par_chunks(CHUNK))
            .for_each(|(o, r)| hits1(accel, r, o)),
        Out::Occ(o) => o
            .par_chunks_mut(CHUNK)
            .zip(rays.par_chunks(CHUNK))
            .for_each(|(o, r)| occ1(accel, r, o)),
        Out::Hits8(o) => o
            .par_chunks_mut(P)
            .zip(pr.par_chunks(P).zip(pa.par_chunks(P)))
            .for_each(|(o, (r, a))| hits8(accel, r, a, o)),
        Out::Occ8(o) => o
            .par_chunks_mut(P)
            .zip(pr.par_chunks(P).zip(pa.par_chunks(P)))
            .for_each(|(o, (r, a))| occ8(accel, r, a, o)),
    })
}

impl Out {
    /// Buffers for `engine` on `rays`, closest hit or any hit.
    pub fn new(engine: Engine, any_hit: bool, rays: &[Ray]) -> Out {
        let packets = rays.len().div_ceil(8);
        match (engine, any_hit) {
            (Engine::Scalar, false) => Out::Hits(vec![(0, 0.0); rays.len()]),
            (Engine::Scalar, true) => Out::Occ(vec![false; rays.len()]),
            (Engine::Packet, false) => Out::Hits8(vec![HitPacket8::none(); packets]),
            (Engine::Packet, true) => Out::Occ8(vec![0; packets]),
        }
    }

    /// The results of the last pass over `n` rays.
    pub fn results(&self, n: usize) -> Results {
        results_of(self, n)
    }
}

fn results_of(out: &Out, n: usize) -> Results {
    match out {
        Out::Hits(h) => Results {
            tri: h.iter().map(|h| h.0).collect(),
            t: h.iter().map(|h| h.1).collect(),
            occluded: vec![],
        },
        Out::Occ(o) => Results {
            occluded: o.clone(),
            ..Default::default()
        },
        Out::Hits8(h) => {
            let hits: Vec<(u32, f32)> = h
                .iter()
                .flat_map(|p| {
                    (0..8).map(|i| {
                        p.lane(i)
                            .map_or((u32::MAX, f32::INFINITY), |h| (h.tri, h.t))
                    })
                })
                .take(n)
                .collect();
            results_of(&Out::Hits(hits), n)
        }
        Out::Occ8(o) => Results {
            occluded: o
                .iter()
                .flat_map(|b| (0..8).map(move |i| b >> i & 1 == 1))
                .take(n)
                .collect(),
            ..Default::default()
        },
    }
}

/// Best and median of timed passes (the peer's `median = sorted[reps / 2]`), wall-clock and
/// CPU seconds (of this thread with one thread, of all the process's threads otherwise).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    pub wall_best: f64,
    pub wall_median: f64,
    pub cpu_best: Option<f64>,
    pub cpu_median: Option<f64>,
}

impl Timing {
    fn of(mut wall: Vec<f64>, cpu: Vec<Option<f64>>) -> Timing {
        wall.sort_by(f64::total_cmp);
        let mut cpu: Option<Vec<f64>> = cpu.into_iter().collect();
        if let Some(c) = &mut cpu {
            c.sort_by(f64::total_cmp);
        }
        let m = wall.len() / 2;
        Timing {
            wall_best: wall[0],
            wall_median: wall[m],
            cpu_best: cpu.as_ref().map(|c| c[0]),
            cpu_median: cpu.as_ref().map(|c| c[m]),
        }
    }

    /// Millions of items per second for `n` items: `(wall best, wall median, cpu best)`.
    pub fn rate(&self, n: usize) -> (f64, f64, Option<f64>) {
        let r = |s: f64| n as f64 / s / 1e6;
        (r(self.wall_best), r(self.wall_median), self.cpu_best.map(r))
    }
}

/// CPU time in seconds: this thread's (`all = false`) or the whole process's, from
/// `/proc/.../schedstat` (nanoseconds on CPU; Linux only, `None` elsewhere).
pub fn cpu_seconds(all: bool) -> Option<f64> {
    let read = |p: &Path| -> Option<u64> {
        std::fs::read_to_string(p)
            .ok()?
            .split_whitespace()
            .next()?
            .parse()
            .ok()
    };
    let ns = if all {
        let mut sum = 0;
        for e in std::fs::read_dir("/proc/self/task").ok()? {
            sum += read(&e.ok()?.path().join("schedstat"))?;
        }
        sum
    } else {
        read(Path::new("/proc/thread-self/schedstat"))?
    };
    Some(ns as f64 * 1e-9)
}

/// Time `f` after one untimed warm-up call: `reps` timed calls.
pub fn time_reps(reps: usize, threads: usize, mut f: impl FnMut()) -> Timing {
    f();
    let (mut wall, mut cpu) = (vec![], vec![]);
    for _ in 0..reps.max(1) {
        let c0 = cpu_seconds(threads > 1);
        let t0 = Instant::now();
        f();
        wall.push(t0.elapsed().as_secs_f64());
        let c1 = cpu_seconds(threads > 1);
        cpu.push(c0.zip(c1).map(|(a, b)| b - a));
    }
    Timing::of(wall, cpu)
}

/// One engine on one set.
#[derive(Clone, Debug)]
pub struct Measured {
    pub workload: Workload,
    pub engine: Engine,
    pub rays: usize,
    pub timing: Timing,
    pub results: Results,
}

/// Time both engines on every workload (`reps` passes after a warm-up each), on the calling
/// thread (`threads <= 1`) or on a pool of `threads`.
pub fn measure(accel: &Accel, work: &Workloads, threads: usize, reps: usize) -> Vec<Measured> {
    let pool = (threads > 1).then(|| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("thread pool")
    });
    let mut all = vec![];
    for (workload, rays) in work.sets() {
        let packets = Packets::new(rays);
        for engine in [Engine::Scalar, Engine::Packet] {
            let mut out = Out::new(engine, workload.any_hit(), rays);
            let timing = time_reps(reps, threads, || {
                pass(accel, rays, &packets, &mut out, pool.as_ref())
            });
            all.push(Measured {
                workload,
                engine,
                rays: rays.len(),
                timing,
                results: results_of(&out, rays.len()),
            });
        }
    }
    all
}

/// BVH build time over `tris` (whitted's default quality), best and median of `reps` builds
/// after a warm-up. obvhs builds on one thread.
pub fn time_build(tris: &[[Vec3; 3]], reps: usize) -> (Accel, Timing) {
    let mut accel = Accel::default();
    let t = time_reps(reps, 1, || {
        accel = Accel::build(tris, BuildQuality::default());
    });
    (accel, t)
}

// ---------------------------------------------------------------- the peer's output

/// One kernel line of rt-bench: `  {label} {rays} rays  wall best {b} med {m} | cpu best .. med ..`.
#[derive(Clone, Debug, PartialEq)]
pub struct PeerKernel {
    pub workload: Workload,
    /// Rays per call: 1, 8 or 16.
    pub width: u32,
    pub rays: usize,
    pub wall_best: f64,
    pub wall_median: f64,
    pub cpu_best: f64,
    pub cpu_median: f64,
}

/// What rt-bench printed for one build quality.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PeerReport {
    /// `embree 3.13.5, device config ...` line.
    pub version: String,
    pub triangles: Option<usize>,
    pub camera: String,
    /// Build time in ms, wall best / median.
    pub build_best_ms: Option<f64>,
    pub build_median_ms: Option<f64>,
    pub kernels: Vec<PeerKernel>,
    pub primary_hits: Option<usize>,
    pub mismatches: Option<usize>,
    pub occluded: Option<usize>,
    pub incoherent_hits: Option<usize>,
}

impl PeerReport {
    pub fn kernel(&self, w: Workload, width: u32) -> Option<&PeerKernel> {
        self.kernels
            .iter()
            .find(|k| k.workload == w && k.width == width)
    }
}

/// Parse rt-bench's text output (the first build quality only; run it with
/// `--quality medium`). Kernel lines are the 2-space indented ones with `rays  wall best`.
pub fn parse_peer(text: &str) -> Result<PeerReport, String> {
    let mut p = PeerReport::default();
    let num = |s: &str| s.parse::<f64>().map_err(|e| format!("'{s}': {e}"));
    let first_int = |s: &str| -> Option<usize> { s.split_whitespace().next()?.parse().ok() };
    let mut builds = 0;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("mesh ") {
            // mesh PATH subdivide K: V vertices, T triangles (load ..)
            p.triangles = rest
                .rsplit_once(" vertices, ")
                .and_then(|(_, t)| first_int(t));
        } else if line.starts_with("embree ") {
            p.version = line.to_string();
        } else if let Some(rest) = line.strip_prefix("camera ") {
            p.camera = rest.split(':').next().unwrap_or("").to_string();
        } else if let Some(rest) = line.strip_prefix("build ") {
            builds += 1;
            if builds > 1 {
                break; // a second quality follows; keep the first
            }
            let w: Vec<&str> = rest.split_whitespace().collect();
            let at = |key: &str| w.iter().position(|x| *x == key).and_then(|i| w.get(i + 1));
            p.build_best_ms = at("best").and_then(|s| s.parse().ok());
            p.build_median_ms = at("median").and_then(|s| s.parse().ok());
        } else if let Some(rest) = line.trim_start().strip_prefix("primary hits ") {
            p.primary_hits = first_int(rest);
            p.mismatches = rest
                .rsplit_once("mismatches ")
                .and_then(|(_, m)| first_int(m));
        } else if let Some(rest) = line.trim_start().strip_prefix("occluded ") {
            p.occluded = first_int(rest);
        } else if let Some(rest) = line.trim_start().strip_prefix("incoherent hits ") {
            p.incoherent_hits = first_int(rest);
        } else if line.starts_with("  ") && line.contains(" rays  wall best ") {
            let (head, tail) = line.split_once(" rays  wall best ").unwrap();
            let head: Vec<&str> = head.split_whitespace().collect();
            if head.len() < 3 {
                return Err(format!("kernel line: {line}"));
            }
            let workload = Workload::from_name(head[0])
                .ok_or_else(|| format!("unknown workload '{}' in: {line}", head[0]))?;
            let width: u32 = head[1]
                .trim_start_matches(|c: char| !c.is_ascii_digit())
                .parse()
                .map_err(|_| format!("kernel width in: {line}"))?;
            let rays: usize = head[head.len() - 1]
                .parse()
                .map_err(|_| format!("ray count in: {line}"))?;
            // "{b} med {m} | cpu best {cb} med {cm} Mrays/s"
            let v: Vec<&str> = tail.split_whitespace().collect();
            if v.len() < 8 {
                return Err(format!("kernel line: {line}"));
            }
            p.kernels.push(PeerKernel {
                workload,
                width,
                rays,
                wall_best: num(v[0])?,
                wall_median: num(v[2])?,
                cpu_best: num(v[6])?,
                cpu_median: num(v[8.min(v.len() - 1)])?,
            });
        }
    }
    if p.kernels.is_empty() {
        return Err("no kernel lines in rt-bench's output".into());
    }
    Ok(p)
}

/// The peer binary: `explicit`, else `$WHITTED_PEER`, else `rt-bench` on `PATH`.
pub fn find_peer(explicit: Option<&Path>) -> Option<PathBuf> {
    if let Some(p) = explicit {
        return Some(p.to_path_buf());
    }
    if let Some(p) = std::env::var_os("WHITTED_PEER").filter(|p| !p.is_empty()) {
        return Some(PathBuf::from(p));
    }
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join("rt-bench"))
            .find(|p| p.is_file())
    })
}

/// Run the peer on `mesh` with the same options (`--quality medium`) and parse its output.
pub fn run_peer(
    peer: &Path,
    mesh: &Path,
    threads: usize,
    subdivide: u32,
    reps: usize,
    (width, height): (u32, u32),
) -> Result<(PeerReport, String), String> {
    let out = std::process::Command::new(peer)
        .arg(mesh)
        .args(["--width", &width.to_string()])
        .args(["--height", &height.to_string()])
        .args(["--threads", &threads.to_string()])
        .args(["--subdivide", &subdivide.to_string()])
        .args(["--reps", &reps.to_string()])
        .args(["--quality", "medium"])
        .output()
        .map_err(|e| format!("{}: {e}", peer.display()))?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        return Err(format!(
            "{} exited with {}: {}",
            peer.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    parse_peer(&text).map(|p| (p, text))
}

// ---------------------------------------------------------------- `whitted bench`

/// Options of `whitted bench`.
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Meshes (`.m` or `.obj`); default `meshes/kitten.m` under `WHITTED_ASSETS`.
    pub meshes: Vec<PathBuf>,
    /// Tracing threads (also the peer's `--threads`); 1 traces on the calling thread.
    #[cfg_attr(feature = "cli", arg(long, short = 't', default_value_t = 1))]
    pub threads: usize,
    /// Midpoint subdivision levels (x4 triangles each, the peer's vertex and child order).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 0))]
    pub subdivide: u32,
    /// Image width of the camera workloads (also the peer's `--width`).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = WIDTH))]
    pub width: u32,
    /// Image height of the camera workloads (also the peer's `--height`).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = HEIGHT))]
    pub height: u32,
    /// Timed passes per workload after one warm-up (best and median are reported).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 5))]
    pub reps: usize,
    /// Print one JSON object instead of tables.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
    /// The Embree peer binary (default: `$WHITTED_PEER`, else `rt-bench` on `PATH`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub peer: Option<PathBuf>,
    /// Do not run the peer even when it is found.
    #[cfg_attr(feature = "cli", arg(long))]
    pub no_peer: bool,
}

/// Everything measured on one mesh.
#[derive(Clone, Debug)]
pub struct Report {
    pub mesh: PathBuf,
    pub subdivide: u32,
    pub vertices: usize,
    pub triangles: usize,
    pub threads: usize,
    pub reps: usize,
    pub framing: Framing,
    pub width: u32,
    pub height: u32,
    pub build: Timing,
    pub measured: Vec<Measured>,
    /// The peer's figures, or why there are none.
    pub peer: Result<PeerReport, String>,
}

impl Report {
    pub fn get(&self, w: Workload, e: Engine) -> Option<&Measured> {
        self.measured
            .iter()
            .find(|m| m.workload == w && m.engine == e)
    }

    /// Results of scalar and packet differ on this many rays (0: the engines agree).
    pub fn mismatches(&self) -> usize {
        Workload::ALL
            .iter()
            .filter_map(|&w| Some((self.get(w, Engine::Scalar)?, self.get(w, Engine::Packet)?)))
            .map(|(s, p)| {
                let r = (&s.results, &p.results);
                r.0.tri.iter().zip(&r.1.tri).filter(|(a, b)| a != b).count()
                    + r.0
                        .occluded
                        .iter()
                        .zip(&r.1.occluded)
                        .filter(|(a, b)| a != b)
                        .count()
            })
            .sum()
    }
}

/// Caps of `whitted bench --subdivide` (the peer's kitten level 3 is 1.3M triangles).
pub const MAX_SUBDIVIDE: u32 = 6;
pub const MAX_TRIANGLES: u64 = 1 << 25;
/// Cap of `whitted bench --width x --height` (8K is 2^25).
pub const MAX_PIXELS: u64 = 1 << 26;

/// Load, subdivide, build, generate and time one mesh (and run the peer on it).
pub fn bench_mesh(path: &Path, opts: &Options) -> crate::Result<Report> {
    let (mesh, _warnings) = crate::io::load_mesh(path)?;
    if opts.subdivide > MAX_SUBDIVIDE
        || (mesh.triangles.len() as u64) << (2 * opts.subdivide.min(MAX_SUBDIVIDE)) > MAX_TRIANGLES
    {
        return Err(crate::Error::Usage(format!(
            "--subdivide {}: over the cap ({MAX_SUBDIVIDE} levels, {MAX_TRIANGLES} triangles)",
            opts.subdivide
        )));
    }
    // 0 (the `Default` of `Options`) means the peer's default size.
    let width = if opts.width == 0 { WIDTH } else { opts.width };
    let height = if opts.height == 0 {
        HEIGHT
    } else {
        opts.height
    };
    if width as u64 * height as u64 > MAX_PIXELS {
        return Err(crate::Error::Usage(format!(
            "--width {width} --height {height}: over the cap of {MAX_PIXELS} pixels"
        )));
    }
    let mesh = subdivide_like_peer(&mesh, opts.subdivide);
    let tris = triangles(&mesh);
    let threads = opts.threads.max(1);
    let reps = opts.reps.clamp(1, 64);
    let (accel, build) = time_build(&tris, reps);
    let work = Workloads::generate(&mesh, &accel, width, height);
    let measured = measure(&accel, &work, threads, reps);
    let peer = if opts.no_peer {
        Err("not run (--no-peer)".to_string())
    } else {
        match find_peer(opts.peer.as_deref()) {
            None => Err("rt-bench not found (PATH, --peer or WHITTED_PEER)".to_string()),
            Some(p) => {
                run_peer(&p, path, threads, opts.subdivide, reps, (width, height)).map(|r| r.0)
            }
        }
    };
    Ok(Report {
        mesh: path.to_path_buf(),
        subdivide: opts.subdivide,
        vertices: mesh.positions.len(),
        triangles: mesh.triangles.len(),
        threads,
        reps,
        framing: work.framing,
        width: work.width,
        height: work.height,
        build,
        measured,
        peer,
    })
}

/// The peer's kernel widths compared per engine: scalar to 1, packet to 8 and 16.
const RATIOS: [(Engine, u32); 3] = [
    (Engine::Scalar, 1),
    (Engine::Packet, 8),
    (Engine::Packet, 16),
];

fn fmt_v3(v: [f64; 3]) -> String {
    format!("({:.4} {:.4} {:.4})", v[0], v[1], v[2])
}

/// The report as text tables.
pub fn format_report(r: &Report) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let fr = &r.framing;
    let _ = writeln!(
        s,
        "whitted bench {} subdivide {}: {} vertices, {} triangles | threads {}, reps {} | {}",
        r.mesh.display(),
        r.subdivide,
        r.vertices,
        r.triangles,
        r.threads,
        r.reps,
        if cfg!(target_feature = "avx2") {
            "AVX2 build"
        } else {
            "no AVX2 in this build (f32x8 runs as two SSE halves)"
        }
    );
    let _ = writeln!(
        s,
        "camera {}: eye {} look_at {} L1 {}, {}x{} vfov 36, eps {:.4e}",
        if fr.canonical { "canonical" } else { "framed" },
        fmt_v3(fr.eye),
        fmt_v3(fr.look),
        fmt_v3(fr.light),
        r.width,
        r.height,
        fr.eps
    );
    let peer = r.peer.as_ref().ok();
    let _ = write!(
        s,
        "BVH build (obvhs, 1 thread): best {:.2} ms, median {:.2} ms",
        r.build.wall_best * 1e3,
        r.build.wall_median * 1e3
    );
    match peer {
        Some(p) => {
            let _ = writeln!(
                s,
                " | Embree MEDIUM (threads {}): best {:.2} ms, median {:.2} ms",
                r.threads,
                p.build_best_ms.unwrap_or(f64::NAN),
                p.build_median_ms.unwrap_or(f64::NAN)
            );
        }
        None => s.push('\n'),
    }
    for cpu in [false, true] {
        let _ = writeln!(
            s,
            "\n{} Mrays/s, best (median) of {} passes{}:",
            if cpu { "CPU-time" } else { "Wall-clock" },
            r.reps,
            if cpu {
                " (rays per CPU-second of the tracing threads; steadier on a busy machine)"
            } else {
                ""
            }
        );
        let _ = write!(
            s,
            "{:<18} {:>8} | {:>15} {:>15}",
            "workload", "rays", "whitted scalar", "packet8"
        );
        if peer.is_some() {
            let _ = write!(
                s,
                " | {:>15} {:>15} {:>15} | {:>9} {:>9} {:>10}",
                "Embree x1", "x8", "x16", "scalar/x1", "packet/x8", "packet/x16"
            );
        }
        s.push('\n');
        for w in Workload::ALL {
            let Some(sc) = r.get(w, Engine::Scalar) else {
                continue;
            };
            let ours = |e: Engine| -> Option<(f64, f64)> {
                let m = r.get(w, e)?;
                let n = m.rays as f64 / 1e6;
                if cpu {
                    Some((n / m.timing.cpu_best?, n / m.timing.cpu_median?))
                } else {
                    Some((n / m.timing.wall_best, n / m.timing.wall_median))
                }
            };
            let theirs = |width: u32| -> Option<(f64, f64)> {
                let k = peer?.kernel(w, width)?;
                Some(if cpu {
                    (k.cpu_best, k.cpu_median)
                } else {
                    (k.wall_best, k.wall_median)
                })
            };
            let cell = |v: Option<(f64, f64)>| match v {
                Some((b, m)) => format!("{b:.2} ({m:.2})"),
                None => "-".into(),
            };
            let _ = write!(
                s,
                "{:<18} {:>8} | {:>15} {:>15}",
                w.name(),
                sc.rays,
                cell(ours(Engine::Scalar)),
                cell(ours(Engine::Packet))
            );
            if peer.is_some() {
                let _ = write!(
                    s,
                    " | {:>15} {:>15} {:>15} |",
                    cell(theirs(1)),
                    cell(theirs(8)),
                    cell(theirs(16))
                );
                for (k, (e, width)) in RATIOS.into_iter().enumerate() {
                    let ratio = ours(e).zip(theirs(width)).map(|(a, b)| a.0 / b.0);
                    let cellw = [10, 10, 11][k];
                    let _ = match ratio {
                        Some(x) => write!(s, "{:>cellw$.2}", x),
                        None => write!(s, "{:>cellw$}", "-"),
                    };
                }
            }
            s.push('\n');
        }
    }
    let count = |w: Workload| r.get(w, Engine::Scalar).map_or(0, |m| m.results.count());
    let _ = write!(
        s,
        "\nchecks: primary hits {}, occluded {}, incoherent hits {}",
        count(Workload::Primary),
        count(Workload::Shadow),
        count(Workload::Incoherent)
    );
    if let Some(p) = peer {
        let o = |v: Option<usize>| v.map_or("-".into(), |v| v.to_string());
        let _ = write!(
            s,
            " (Embree {}, {}, {})",
            o(p.primary_hits),
            o(p.occluded),
            o(p.incoherent_hits)
        );
    }
    let _ = writeln!(s, "; packet-vs-scalar mismatches {}", r.mismatches());
    let _ = writeln!(
        s,
        "note: primary rays are the peer's bit for bit; the shadow and incoherent rays are built from whitted's own\n      hits (t, Ng), so they match Embree's sets to ~1 ulp per ray, not bit for bit. Ratios use the best pass."
    );
    match &r.peer {
        Ok(p) => {
            let _ = writeln!(
                s,
                "peer: {} (run in this invocation, --quality medium)",
                p.version
            );
        }
        Err(e) => {
            let _ = writeln!(s, "peer: {e}; whitted's figures only");
        }
    }
    s
}

/// The report as JSON.
pub fn report_json(r: &Report) -> serde_json::Value {
    use serde_json::json;
    let t = |t: &Timing| {
        json!({"wall_best_s": t.wall_best, "wall_median_s": t.wall_median,
               "cpu_best_s": t.cpu_best, "cpu_median_s": t.cpu_median})
    };
    let rate = |n: usize, t: &Timing| {
        let (b, m, c) = t.rate(n);
        json!({"wall_best": b, "wall_median": m, "cpu_best": c,
               "cpu_median": t.cpu_median.map(|s| n as f64 / s / 1e6)})
    };
    let peer = r.peer.as_ref().ok();
    let workloads: Vec<serde_json::Value> = Workload::ALL
        .iter()
        .filter_map(|&w| {
            let sc = r.get(w, Engine::Scalar)?;
            let pk = r.get(w, Engine::Packet)?;
            let mut ratios = serde_json::Map::new();
            if let Some(p) = peer {
                for (e, width) in RATIOS {
                    let m = if e == Engine::Scalar { sc } else { pk };
                    if let Some(k) = p.kernel(w, width) {
                        let (b, _, c) = m.timing.rate(m.rays);
                        ratios.insert(
                            format!("{}_vs_x{width}", e.name()),
                            json!({"wall_best": b / k.wall_best,
                                   "cpu_best": c.map(|c| c / k.cpu_best)}),
                        );
                    }
                }
            }
            let embree: Vec<_> = peer
                .map(|p| {
                    p.kernels
                        .iter()
                        .filter(|k| k.workload == w)
                        .map(|k| {
                            json!({"width": k.width, "rays": k.rays,
                                   "wall_best": k.wall_best, "wall_median": k.wall_median,
                                   "cpu_best": k.cpu_best, "cpu_median": k.cpu_median})
                        })
                        .collect()
                })
                .unwrap_or_default();
            Some(json!({
                "workload": w.name(),
                "rays": sc.rays,
                "hits": sc.results.count(),
                "checksum": format!("{:016x}", sc.results.checksum()),
                "whitted_mrays": {"scalar": rate(sc.rays, &sc.timing), "packet8": rate(pk.rays, &pk.timing)},
                "embree_mrays": embree,
                "ratio": ratios,
            }))
        })
        .collect();
    let fr = &r.framing;
    json!({
        "mesh": r.mesh.display().to_string(),
        "subdivide": r.subdivide,
        "vertices": r.vertices,
        "triangles": r.triangles,
        "threads": r.threads,
        "reps": r.reps,
        "avx2": cfg!(target_feature = "avx2"),
        "camera": {"canonical": fr.canonical, "eye": fr.eye, "look_at": fr.look, "light": fr.light,
                   "width": r.width, "height": r.height, "eps": fr.eps},
        "build": t(&r.build),
        "workloads": workloads,
        "packet_scalar_mismatches": r.mismatches(),
        "secondary_rays_from": "whitted's own primary hits (match Embree's sets to ~1 ulp)",
        "peer": match &r.peer {
            Ok(p) => json!({"version": p.version, "build_best_ms": p.build_best_ms,
                            "build_median_ms": p.build_median_ms, "primary_hits": p.primary_hits,
                            "occluded": p.occluded, "incoherent_hits": p.incoherent_hits}),
            Err(e) => json!({"error": e}),
        },
    })
}

/// `whitted bench`: every mesh, tables or one JSON object on stdout.
pub fn run(opts: &Options) -> crate::Result<()> {
    let mut meshes = opts.meshes.clone();
    if meshes.is_empty() {
        let dir = std::env::var_os("WHITTED_ASSETS")
            .and_then(|v| std::env::split_paths(&v).next())
            .ok_or_else(|| {
                crate::Error::Usage("no mesh given and WHITTED_ASSETS is not set".into())
            })?;
        meshes.push(dir.join("meshes/kitten.m"));
    }
    let mut reports = vec![];
    for m in &meshes {
        let r = bench_mesh(m, opts)?;
        if opts.json {
            reports.push(report_json(&r));
        } else {
            println!("{}", format_report(&r));
        }
    }
    if opts.json {
        println!("{}", serde_json::json!({ "whitted_bench": reports }));
    }
    Ok(())
}
