//! Tracing bare ray batches (no shading) with any engine: `whitted trace-rays`, the library's
//! batch calls. Closest hits ([`trace_rays`]) and occlusion ([`occluded_rays`]), in input
//! order, in parallel; `Engine::Auto` chooses the engine from the rays
//! ([`crate::engine`]: the rule, and a pilot for large batches).

use crate::accel::{
    Accel, intersect_hybrid8, intersect_hybrid16, intersect_wide1_many, intersect1, intersect8,
    intersect16, occluded_hybrid8, occluded_hybrid16, occluded_wide1_many, occluded1, occluded8,
    occluded16,
};
use crate::engine::Choice;
use crate::packet::RayPacket8;
use crate::ray::{Hit, Ray};
use crate::simd;
use rayon::prelude::*;

pub use crate::engine::Engine;

/// Rays per parallel work item (a multiple of 16).
const CHUNK: usize = 4096;

/// Closest hits of `rays`, in parallel, in input order; `Engine::Auto` chooses the engine
/// from the rays ([`resolve`]).
pub fn trace_rays(accel: &Accel, rays: &[Ray], engine: Engine, cull: bool) -> Vec<Option<Hit>> {
    trace_rays_with(accel, rays, engine, cull).0
}

/// [`trace_rays`], and the engine that traced them (`auto`'s choice).
pub fn trace_rays_with(
    accel: &Accel,
    rays: &[Ray],
    engine: Engine,
    cull: bool,
) -> (Vec<Option<Hit>>, Engine) {
    crate::cpu::warn_if_slow_build();
    let mut out = output(rays.len(), None);
    // (the pilot on a thread of the pool that traces the batch, as the bench's: a calling
    // thread outside it shares the cores with the pool's threads)
    let (engine, done) = rayon::scope(|_| {
        resolve(engine, accel, rays, |e, r| {
            intersect_into(accel, &rays[r.clone()], e, cull, &mut out[r])
        })
    });
    out.par_chunks_mut(CHUNK)
        .zip(rays.par_chunks(CHUNK))
        .enumerate()
        .for_each(|(k, (o, r))| {
            for p in left_over_in_chunk(k, r.len(), &done) {
                intersect_into(accel, &r[p.clone()], engine, cull, &mut o[p]);
            }
        });
    (out, engine)
}

/// Whether each ray of `rays` is blocked within `(tnear, tfar)` (any hit), in parallel, in
/// input order; `Engine::Auto` chooses the engine from the rays ([`resolve`]).
pub fn occluded_rays(accel: &Accel, rays: &[Ray], engine: Engine, cull: bool) -> Vec<bool> {
    occluded_rays_with(accel, rays, engine, cull).0
}

/// [`occluded_rays`], and the engine that traced them (`auto`'s choice).
pub fn occluded_rays_with(
    accel: &Accel,
    rays: &[Ray],
    engine: Engine,
    cull: bool,
) -> (Vec<bool>, Engine) {
    crate::cpu::warn_if_slow_build();
    let mut out = output(rays.len(), false);
    let (engine, done) = rayon::scope(|_| {
        resolve(engine, accel, rays, |e, r| {
            occluded_into(accel, &rays[r.clone()], e, cull, &mut out[r])
        })
    });
    out.par_chunks_mut(CHUNK)
        .zip(rays.par_chunks(CHUNK))
        .enumerate()
        .for_each(|(k, (o, r))| {
            for p in left_over_in_chunk(k, r.len(), &done) {
                occluded_into(accel, &r[p.clone()], engine, cull, &mut o[p]);
            }
        });
    (out, engine)
}

/// The rays of chunk `k` (of `len` rays) still to trace after the pilot traced `done`
/// ([`crate::engine::left_over`]), as ranges within the chunk.
fn left_over_in_chunk(
    k: usize,
    len: usize,
    done: &[std::ops::Range<usize>],
) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
    let base = k * CHUNK;
    crate::engine::left_over(base..base + len, done).map(move |p| p.start - base..p.end - base)
}

/// An output array of `n` entries, on huge pages where the kernel has them: a batch's
/// results are written once, so faulting in small pages (2M camera rays: 41 MB, 10,000
/// faults) is a cost of its own.
fn output<T: Clone>(n: usize, fill: T) -> Vec<T> {
    let mut v = Vec::with_capacity(n);
    crate::accel::pages::advise_huge(&v);
    v.resize(n, fill);
    v
}

/// `engine`, or for `auto` the engine for `rays`: the rule's one candidate, or of two the
/// faster on a pilot (`run(engine, range)` traces `rays[range]` into the batch's output;
/// see [`crate::engine::pilot`]), on the calling thread; beside it the ranges of rays the
/// pilot traced (sorted, disjoint; empty without a pilot), which need no second trace
/// ([`crate::engine::left_over`]).
pub fn resolve(
    engine: Engine,
    accel: &Accel,
    rays: &[Ray],
    run: impl FnMut(Engine, std::ops::Range<usize>),
) -> (Engine, Vec<std::ops::Range<usize>>) {
    if engine != Engine::Auto {
        return (engine, vec![]);
    }
    match crate::engine::choices(accel, rays) {
        Choice::One(e) => (e, vec![]),
        Choice::Try(two) => (
            crate::engine::pilot(two, rays.len(), run),
            crate::engine::pilot_blocks(rays.len()),
        ),
    }
}

/// `engine`, or for `auto` the rule's first candidate for `rays` (no pilot).
fn concrete(engine: Engine, accel: &Accel, rays: &[Ray]) -> Engine {
    if engine == Engine::Auto {
        crate::engine::choose(accel, rays)
    } else {
        engine
    }
}

/// `engine`, or for `auto` the engine for a batch of `n` rays given by index (`ray_at(i)`,
/// `i < n`): the rule's one candidate, or of two the faster on a pilot over the batch
/// ([`crate::engine::pilot`]), closest hits or with `any_hit` occlusion, with `cull`. For
/// callers that keep their rays in a layout of their own (a numpy array of rows) and trace
/// it chunk by chunk with [`intersect_into`] / [`occluded_into`]: the choice is made once
/// for the batch, as [`trace_rays`] makes it, and only the sampled and piloted rays are
/// made into `Ray`s here. Run it on a thread of the pool that traces the batch (inside
/// `rayon::scope` or the pool's `install`): a pilot timed beside the pool's busy threads
/// measures the wrong thing.
pub fn resolve_by(
    engine: Engine,
    accel: &Accel,
    n: usize,
    ray_at: impl Fn(usize) -> Ray,
    any_hit: bool,
    cull: bool,
) -> Engine {
    if engine != Engine::Auto {
        return engine;
    }
    match crate::engine::choices_by(accel, n, &ray_at) {
        Choice::One(e) => e,
        Choice::Try(two) => {
            let (mut rays, mut hits, mut blocked) = (Vec::new(), Vec::new(), Vec::new());
            crate::engine::pilot(two, n, |e, range| {
                rays.clear();
                rays.extend(range.map(&ray_at));
                if any_hit {
                    blocked.resize(rays.len(), false);
                    occluded_into(accel, &rays, e, cull, &mut blocked);
                } else {
                    hits.resize(rays.len(), None);
                    intersect_into(accel, &rays, e, cull, &mut hits);
                }
            })
        }
    }
}

/// 8 or 16 consecutive rays as packets of 8 (padding lanes inactive).
fn packets<const N: usize>(group: &[Ray]) -> [(RayPacket8, simd::M32x8); N] {
    std::array::from_fn(|h| RayPacket8::from_fn(|i| group.get(8 * h + i).copied()))
}

/// A hit packet's lanes into `out` (up to 8 entries), each field's lanes read out once.
#[inline(always)]
fn unpack(h: &crate::packet::HitPacket8, out: &mut [Option<Hit>]) {
    let (tri, t, b1, b2) = (
        simd::u32_lanes(h.tri),
        simd::lanes(h.t),
        simd::lanes(h.b1),
        simd::lanes(h.b2),
    );
    for (i, o) in out.iter_mut().enumerate() {
        *o = (tri[i] != Hit::NONE_ID).then_some(Hit {
            tri: tri[i],
            t: t[i],
            b1: b1[i],
            b2: b2[i],
        });
    }
}

/// Closest hits of `rays` with `engine` on the calling thread, into `out` (the same length):
/// the piece of a batch that a caller with its own parallel loop and ray layout traces per
/// chunk, with the engine chosen once for the batch ([`resolve_by`]). `auto` here takes the
/// rule's first candidate for these rays ([`crate::engine::choose`]).
///
/// # Panics
/// If `out` is shorter than `rays`.
pub fn intersect_into(
    accel: &Accel,
    rays: &[Ray],
    engine: Engine,
    cull: bool,
    out: &mut [Option<Hit>],
) {
    let engine = concrete(engine, accel, rays);
    let out = &mut out[..rays.len()];
    match engine {
        Engine::Scalar => {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = intersect1(accel, r, cull);
            }
        }
        Engine::Wide => intersect_wide1_many(accel, rays, cull, out),
        Engine::Packet16 | Engine::Hybrid16 => {
            let f = if engine == Engine::Hybrid16 {
                intersect_hybrid16
            } else {
                intersect16
            };
            for (group, o) in rays.chunks(16).zip(out.chunks_mut(16)) {
                let [(p0, a0), (p1, a1)] = packets::<2>(group);
                let hits = f(accel, [&p0, &p1], [a0, a1], cull);
                for (h, o) in hits.iter().zip(o.chunks_mut(8)) {
                    unpack(h, o);
                }
            }
        }
        // (`concrete` resolved `auto`)
        Engine::Auto | Engine::Packet | Engine::Hybrid => {
            let f = if engine == Engine::Hybrid {
                intersect_hybrid8
            } else {
                intersect8
            };
            for (group, o) in rays.chunks(8).zip(out.chunks_mut(8)) {
                let [(p, a)] = packets::<1>(group);
                unpack(&f(accel, &p, a, cull), o);
            }
        }
    }
}

/// Whether each of `rays` is blocked (any hit), with `engine` on the calling thread, into
/// `out` (the same length): [`intersect_into`]'s twin.
///
/// # Panics
/// If `out` is shorter than `rays`.
pub fn occluded_into(accel: &Accel, rays: &[Ray], engine: Engine, cull: bool, out: &mut [bool]) {
    let engine = concrete(engine, accel, rays);
    let out = &mut out[..rays.len()];
    match engine {
        Engine::Scalar => {
            for (o, r) in out.iter_mut().zip(rays) {
                *o = occluded1(accel, r, cull);
            }
        }
        Engine::Wide => occluded_wide1_many(accel, rays, cull, out),
        Engine::Packet16 | Engine::Hybrid16 => {
            let f = if engine == Engine::Hybrid16 {
                occluded_hybrid16
            } else {
                occluded16
            };
            for (group, o) in rays.chunks(16).zip(out.chunks_mut(16)) {
                let [(p0, a0), (p1, a1)] = packets::<2>(group);
                let m = f(accel, [&p0, &p1], [a0, a1], cull).map(simd::bitmask);
                for (i, o) in o.iter_mut().enumerate() {
                    *o = m[i / 8] >> (i % 8) & 1 == 1;
                }
            }
        }
        Engine::Auto | Engine::Packet | Engine::Hybrid => {
            let f = if engine == Engine::Hybrid {
                occluded_hybrid8
            } else {
                occluded8
            };
            for (group, o) in rays.chunks(8).zip(out.chunks_mut(8)) {
                let [(p, a)] = packets::<1>(group);
                let m = simd::bitmask(f(accel, &p, a, cull));
                for (i, o) in o.iter_mut().enumerate() {
                    *o = m >> i & 1 == 1;
                }
            }
        }
    }
}
