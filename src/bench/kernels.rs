//! The engines on a ray set: result buffers, one pass of an engine, results and checksums.

use super::*;
use crate::accel::{
    Accel, intersect_hybrid8, intersect_hybrid16, intersect_wide1_many, intersect1, intersect8,
    intersect16, occluded_hybrid8, occluded_hybrid16, occluded_wide1_many, occluded1, occluded8,
    occluded16,
};
use crate::engine::Choice;
use crate::packet::{HitPacket8, RayPacket8};
use crate::ray::Hit;
use crate::ray::Ray;
use crate::simd::{self, M32x8};
use rayon::prelude::*;

// ---------------------------------------------------------------- kernels

/// Rays grouped 8 consecutive per packet (the peer's `run_8`), padding lanes inactive.
pub struct Packets {
    /// Packet `j` holds rays `8j .. 8j + 8`.
    pub rays: Vec<RayPacket8>,
    /// Per packet, the lanes that carry a ray (all but the last packet's padding).
    pub active: Vec<M32x8>,
    /// Number of rays (not packets).
    pub len: usize,
}

impl Packets {
    /// Group `rays` in order, 8 per packet.
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
    /// Hit triangle per ray (original index), `u32::MAX` on a miss; empty for any-hit sets.
    pub tri: Vec<u32>,
    /// Hit distance per ray (units of the ray's `d`), `f32::INFINITY` on a miss; empty for
    /// any-hit sets.
    pub t: Vec<f32>,
    /// Occlusion per ray; empty for closest-hit sets.
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
/// `HitPacket8` or an occlusion bitmask; beside each, the engine's kernel.
pub enum Out {
    /// Single-ray closest hit: per ray its hit, if any.
    Hits(Vec<Option<Hit>>, Intersect1),
    /// Single-ray any hit: per ray whether it is occluded.
    Occ(Vec<bool>, Occluded1),
    /// Packet closest hit: one `HitPacket8` per packet of [`Packets`].
    Hits8(Vec<HitPacket8>, Intersect8),
    /// Packet any hit: per packet the occluded lanes, bit `i` for lane `i`.
    Occ8(Vec<u8>, Occluded8),
    /// 16-ray packets (two of [`Packets`] at a time) closest hit, stored as `Hits8`.
    Hits16(Vec<HitPacket8>, Intersect16),
    /// 16-ray packets any hit, stored as `Occ8`.
    Occ16(Vec<u8>, Occluded16),
    /// `auto`: the buffers of each candidate for the set; each pass chooses again (the
    /// choice and its pilot are part of the timed pass, as of every `auto` batch call).
    Auto(Vec<(Engine, Out)>, Engine),
}

/// A single-ray closest-hit kernel on a run of rays, one hit per ray into the output
/// (`intersect1` ray by ray, `intersect_wide1_many`; the peer's threads likewise hand
/// `rtcIntersect1` and `rtcIntersect8` runs of rays).
pub type Intersect1 = fn(&Accel, &[Ray], bool, &mut [Option<Hit>]);
/// A single-ray any-hit kernel on a run of rays.
pub type Occluded1 = fn(&Accel, &[Ray], bool, &mut [bool]);

/// `intersect1` on each ray of a run.
fn intersect1_each(accel: &Accel, rays: &[Ray], cull: bool, out: &mut [Option<Hit>]) {
    for (r, o) in rays.iter().zip(out) {
        *o = intersect1(accel, r, cull);
    }
}

/// `occluded1` on each ray of a run.
fn occluded1_each(accel: &Accel, rays: &[Ray], cull: bool, out: &mut [bool]) {
    for (r, o) in rays.iter().zip(out) {
        *o = occluded1(accel, r, cull);
    }
}
/// A packet closest-hit kernel (`intersect8`, `intersect_hybrid8`).
pub type Intersect8 = fn(&Accel, &RayPacket8, M32x8, bool) -> HitPacket8;
/// A packet any-hit kernel.
pub type Occluded8 = fn(&Accel, &RayPacket8, M32x8, bool) -> M32x8;

/// A 16-ray closest-hit kernel (`intersect16`) on two packets of 8.
pub type Intersect16 = fn(&Accel, [&RayPacket8; 2], [M32x8; 2], bool) -> [HitPacket8; 2];
/// A 16-ray any-hit kernel (`occluded16`).
pub type Occluded16 = fn(&Accel, [&RayPacket8; 2], [M32x8; 2], bool) -> [M32x8; 2];

pub use crate::engine::Engine;

/// The engines timed, in report order ([`Engine::ALL`]: the reference first, `auto` last).
pub const ENGINES: [Engine; 7] = Engine::ALL;

fn hits8(
    accel: &Accel,
    f: Intersect8,
    rays: &[RayPacket8],
    active: &[M32x8],
    out: &mut [HitPacket8],
) {
    for ((r, a), o) in rays.iter().zip(active).zip(out) {
        *o = f(accel, r, *a, false);
    }
}

fn occ8(accel: &Accel, f: Occluded8, rays: &[RayPacket8], active: &[M32x8], out: &mut [u8]) {
    for ((r, a), o) in rays.iter().zip(active).zip(out) {
        *o = simd::bitmask(f(accel, r, *a, false)) as u8;
    }
}

/// Pairs of packets (a last odd one with an inactive twin) and their outputs.
fn pairs<'a, T>(
    rays: &'a [RayPacket8],
    active: &'a [M32x8],
    out: &'a mut [T],
) -> impl Iterator<Item = ([&'a RayPacket8; 2], [M32x8; 2], &'a mut [T])> {
    rays.chunks(2)
        .zip(active.chunks(2))
        .zip(out.chunks_mut(2))
        .map(|((r, a), o)| match (r, a) {
            ([r0, r1], [a0, a1]) => ([r0, r1], [*a0, *a1], o),
            _ => ([&r[0], &r[0]], [a[0], simd::mask_from_bits(0)], o),
        })
}

fn hits16(
    accel: &Accel,
    f: Intersect16,
    rays: &[RayPacket8],
    active: &[M32x8],
    out: &mut [HitPacket8],
) {
    for (r, a, o) in pairs(rays, active, out) {
        let h = f(accel, r, a, false);
        o.copy_from_slice(&h[..o.len()]);
    }
}

fn occ16(accel: &Accel, f: Occluded16, rays: &[RayPacket8], active: &[M32x8], out: &mut [u8]) {
    for (r, a, o) in pairs(rays, active, out) {
        let m = f(accel, r, a, false);
        for (o, m) in o.iter_mut().zip(m) {
            *o = simd::bitmask(m) as u8;
        }
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
    if let Out::Auto(outs, chosen) = out {
        fn of(outs: &mut [(Engine, Out)], e: Engine) -> &mut Out {
            &mut outs.iter_mut().find(|o| o.0 == e).expect("a candidate").1
        }
        let mut choose = || match crate::engine::choices(accel, rays) {
            Choice::One(e) => (e, vec![]),
            Choice::Try(two) => (
                crate::engine::pilot(two, rays.len(), |e, r| {
                    pass_range(accel, rays, packets, of(outs, e), r)
                }),
                crate::engine::pilot_blocks(rays.len()),
            ),
        };
        // (with a pool, on one of its threads, as the passes run: the calling thread would
        // share the cores with the pool's threads still spinning after the last pass)
        let done;
        (*chosen, done) = match pool {
            Some(pool) => pool.install(choose),
            None => choose(),
        };
        // (the pilot's runs are in the chosen engine's buffers already)
        return pass_except(accel, rays, packets, of(outs, *chosen), pool, &done);
    }
    pass_except(accel, rays, packets, out, pool, &[]);
}

/// [`pass`] of a concrete engine over the rays outside `done` (sorted, disjoint ranges that
/// start and end at multiples of 16, or at the set's end: `auto`'s pilot runs).
fn pass_except(
    accel: &Accel,
    rays: &[Ray],
    packets: &Packets,
    out: &mut Out,
    pool: Option<&rayon::ThreadPool>,
    done: &[std::ops::Range<usize>],
) {
    let (pr, pa) = (&packets.rays[..], &packets.active[..]);
    let Some(pool) = pool else {
        for r in crate::engine::left_over(0..rays.len(), done) {
            pass_range(accel, rays, packets, out, r);
        }
        return;
    };
    const P: usize = CHUNK / 8;
    // the rays of work item `k` (of `len` rays) to trace, as ranges within it
    let todo = |k: usize, len: usize| {
        let base = k * CHUNK;
        crate::engine::left_over(base..base + len, done).map(move |p| p.start - base..p.end - base)
    };
    // the same in packets of 8 (`len` packets)
    let todo8 = |k: usize, len: usize| {
        todo(k, rays.len().saturating_sub(k * CHUNK).min(len * 8))
            .map(|p| p.start / 8..p.end.div_ceil(8))
    };
    pool.install(|| match out {
        Out::Hits(o, f) => o
            .par_chunks_mut(CHUNK)
            .zip(rays.par_chunks(CHUNK))
            .enumerate()
            .for_each(|(k, (o, r))| {
                for p in todo(k, r.len()) {
                    f(accel, &r[p.clone()], false, &mut o[p]);
                }
            }),
        Out::Occ(o, f) => o
            .par_chunks_mut(CHUNK)
            .zip(rays.par_chunks(CHUNK))
            .enumerate()
            .for_each(|(k, (o, r))| {
                for p in todo(k, r.len()) {
                    f(accel, &r[p.clone()], false, &mut o[p]);
                }
            }),
        Out::Hits8(o, f) => o
            .par_chunks_mut(P)
            .zip(pr.par_chunks(P).zip(pa.par_chunks(P)))
            .enumerate()
            .for_each(|(k, (o, (r, a)))| {
                for p in todo8(k, r.len()) {
                    hits8(accel, *f, &r[p.clone()], &a[p.clone()], &mut o[p]);
                }
            }),
        Out::Occ8(o, f) => o
            .par_chunks_mut(P)
            .zip(pr.par_chunks(P).zip(pa.par_chunks(P)))
            .enumerate()
            .for_each(|(k, (o, (r, a)))| {
                for p in todo8(k, r.len()) {
                    occ8(accel, *f, &r[p.clone()], &a[p.clone()], &mut o[p]);
                }
            }),
        // (P is even, and so is every range's start: pairs never straddle two pieces)
        Out::Hits16(o, f) => o
            .par_chunks_mut(P)
            .zip(pr.par_chunks(P).zip(pa.par_chunks(P)))
            .enumerate()
            .for_each(|(k, (o, (r, a)))| {
                for p in todo8(k, r.len()) {
                    hits16(accel, *f, &r[p.clone()], &a[p.clone()], &mut o[p]);
                }
            }),
        Out::Occ16(o, f) => o
            .par_chunks_mut(P)
            .zip(pr.par_chunks(P).zip(pa.par_chunks(P)))
            .enumerate()
            .for_each(|(k, (o, (r, a)))| {
                for p in todo8(k, r.len()) {
                    occ16(accel, *f, &r[p.clone()], &a[p.clone()], &mut o[p]);
                }
            }),
        Out::Auto(..) => unreachable!("auto passes on to its engine above"),
    })
}

/// A pass over `rays[range]` alone on the calling thread (`range` starts at a multiple of 16).
fn pass_range(
    accel: &Accel,
    rays: &[Ray],
    packets: &Packets,
    out: &mut Out,
    range: std::ops::Range<usize>,
) {
    let p = range.start / 8..range.end.div_ceil(8);
    let (pr, pa) = (&packets.rays[p.clone()], &packets.active[p.clone()]);
    match out {
        Out::Hits(o, f) => f(accel, &rays[range.clone()], false, &mut o[range]),
        Out::Occ(o, f) => f(accel, &rays[range.clone()], false, &mut o[range]),
        Out::Hits8(o, f) => hits8(accel, *f, pr, pa, &mut o[p]),
        Out::Occ8(o, f) => occ8(accel, *f, pr, pa, &mut o[p]),
        Out::Hits16(o, f) => hits16(accel, *f, pr, pa, &mut o[p]),
        Out::Occ16(o, f) => occ16(accel, *f, pr, pa, &mut o[p]),
        Out::Auto(..) => unreachable!("auto passes on to its engine"),
    }
}

impl Out {
    /// Buffers for `engine` on `rays` in `accel`, closest hit or any hit (for `auto`, those
    /// of the engine it chooses).
    pub fn new(accel: &Accel, engine: Engine, any_hit: bool, rays: &[Ray]) -> Out {
        if engine == Engine::Auto {
            let choice = crate::engine::choices(accel, rays);
            let cands = match choice {
                Choice::One(e) => vec![e],
                Choice::Try(two) => two.to_vec(),
            };
            let outs = cands
                .into_iter()
                .map(|e| (e, Out::new(accel, e, any_hit, rays)))
                .collect();
            return Out::Auto(outs, choice.first());
        }
        let packets = rays.len().div_ceil(8);
        let (hits, occ) = (vec![None; rays.len()], vec![false; rays.len()]);
        let (hits8, occ8) = (vec![HitPacket8::none(); packets], vec![0; packets]);
        match (engine, any_hit) {
            (Engine::Scalar, false) => Out::Hits(hits, intersect1_each),
            (Engine::Scalar, true) => Out::Occ(occ, occluded1_each),
            (Engine::Packet, false) => Out::Hits8(hits8, intersect8),
            (Engine::Packet, true) => Out::Occ8(occ8, occluded8),
            (Engine::Wide, false) => Out::Hits(hits, intersect_wide1_many),
            (Engine::Wide, true) => Out::Occ(occ, occluded_wide1_many),
            (Engine::Hybrid, false) => Out::Hits8(hits8, intersect_hybrid8),
            (Engine::Hybrid, true) => Out::Occ8(occ8, occluded_hybrid8),
            (Engine::Packet16, false) => Out::Hits16(hits8, intersect16),
            (Engine::Packet16, true) => Out::Occ16(occ8, occluded16),
            (Engine::Hybrid16, false) => Out::Hits16(hits8, intersect_hybrid16),
            (Engine::Hybrid16, true) => Out::Occ16(occ8, occluded_hybrid16),
            (Engine::Auto, _) => unreachable!("auto is resolved above"),
        }
    }

    /// `auto`'s choice (`None` for the other engines).
    pub fn chosen(&self) -> Option<Engine> {
        match self {
            Out::Auto(_, chosen) => Some(*chosen),
            _ => None,
        }
    }

    /// The results of the last pass over `n` rays.
    pub fn results(&self, n: usize) -> Results {
        results_of(self, n)
    }
}

pub(super) fn results_of(out: &Out, n: usize) -> Results {
    match out {
        Out::Auto(outs, chosen) => results_of(
            &outs.iter().find(|o| o.0 == *chosen).expect("a candidate").1,
            n,
        ),
        Out::Hits(h, _) => hit_results(h.iter().copied()),
        Out::Occ(o, _) => Results {
            occluded: o.clone(),
            ..Default::default()
        },
        Out::Hits8(h, _) | Out::Hits16(h, _) => {
            hit_results(h.iter().flat_map(|p| (0..8).map(|i| p.lane(i))).take(n))
        }
        Out::Occ8(o, _) | Out::Occ16(o, _) => Results {
            occluded: o
                .iter()
                .flat_map(|b| (0..8).map(move |i| b >> i & 1 == 1))
                .take(n)
                .collect(),
            ..Default::default()
        },
    }
}

/// Per ray `(triangle, t)`, `(u32::MAX, inf)` on a miss.
fn hit_results(hits: impl Iterator<Item = Option<Hit>>) -> Results {
    let (tri, t) = hits
        .map(|h| h.map_or((u32::MAX, f32::INFINITY), |h| (h.tri, h.t)))
        .unzip();
    Results {
        tri,
        t,
        occluded: vec![],
    }
}
