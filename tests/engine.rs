//! `auto`'s choice from the rays, and one list of engines for every front end.

mod common;

use glam::Vec3;
use whitted::accel::{Accel, BuildQuality, intersect1};
use whitted::bench::{Workload, Workloads, random_rays, triangles};
use whitted::engine::{self, Choice, Engine, Spread, candidates, choose_by, spread};
use whitted::io::load_mesh;
use whitted::ray::Ray;

fn kitten() -> (whitted::mesh::Mesh, Accel) {
    let (mesh, _) = load_mesh(&common::assets().join("meshes/kitten.m")).unwrap();
    let accel = Accel::build(&triangles(&mesh), BuildQuality::default());
    (mesh, accel)
}

#[test]
fn names_and_aliases() {
    for e in Engine::ALL {
        assert_eq!(Engine::from_name(e.name()), Some(e));
    }
    assert_eq!(Engine::from_name("packet"), Some(Engine::Packet));
    assert_eq!(Engine::from_name("wide"), Some(Engine::Wide));
    assert_eq!(Engine::from_name("hybrid"), Some(Engine::Hybrid));
    assert_eq!(Engine::from_name("packet32"), None);
    assert!(!Engine::CONCRETE.contains(&Engine::Auto));
    assert_eq!(Engine::CONCRETE.len() + 1, Engine::ALL.len());
    // the bench times every engine, auto among them
    for e in Engine::ALL {
        assert!(whitted::bench::ENGINES.contains(&e));
    }
}

#[test]
fn the_rule() {
    let s = |direction, origin, mixed_octants| Spread {
        groups: 64,
        direction,
        origin,
        mixed_octants,
    };
    // beams: 16-ray packets, or hybrid8 without AVX-512
    assert_eq!(choose_by(s(1e-5, 0.0, 0.0), true), Engine::Packet16);
    assert_eq!(choose_by(s(1e-5, 0.0, 0.0), false), Engine::Hybrid);
    assert_eq!(choose_by(s(1e-4, 0.3, 0.1), true), Engine::Packet16);
    // a beam along an axis splits its octants: no longer a beam
    assert_eq!(choose_by(s(1e-4, 0.001, 0.9), true), Engine::Hybrid16);
    // scattered directions from neighbouring origins
    assert_eq!(choose_by(s(0.9, 0.001, 1.0), true), Engine::Hybrid16);
    assert_eq!(choose_by(s(0.9, 0.001, 1.0), false), Engine::Hybrid);
    // scattered in both
    assert_eq!(choose_by(s(1.0, 0.5, 1.0), true), Engine::Wide);
    assert_eq!(choose_by(s(1.0, 0.5, 1.0), false), Engine::Wide);
    // nothing to look at
    assert_eq!(choose_by(Spread::default(), true), Engine::Wide);
}

/// The bench's five workloads on the kitten: camera rays and their compacted hits and the
/// shadow rays are beams, the bounce rays scatter from neighbouring origins, the random
/// rays scatter in both.
#[test]
fn spread_of_the_kitten_workloads() {
    let (mesh, accel) = kitten();
    let work = Workloads::generate_with(&mesh, &accel, 480, 270, 20000);
    let diagonal = {
        let (lo, hi) = mesh.bounds().unwrap();
        (hi - lo).length()
    };
    for (w, rays) in work.sets() {
        let s = spread(rays, diagonal);
        assert_eq!(s.groups, engine::SAMPLE_GROUPS, "{w:?}");
        let (beam, together) = match w {
            Workload::Primary | Workload::PrimaryHits | Workload::Shadow => (true, true),
            Workload::Incoherent => (false, true),
            Workload::Random => (false, false),
        };
        assert_eq!(
            s.direction < engine::BEAM && s.mixed_octants < 0.5,
            beam,
            "{w:?}: {s:?}"
        );
        if !beam {
            assert_eq!(s.origin < engine::TOGETHER, together, "{w:?}: {s:?}");
        }
        let want = match (beam, together) {
            (true, _) => choose_by(s, true),
            (false, true) => Engine::Hybrid16,
            (false, false) => Engine::Wide,
        };
        assert_eq!(choose_by(s, true), want, "{w:?}");
        assert_eq!(
            engine::choose(&accel, rays),
            choose_by(s, whitted::accel::packet16::available())
        );
    }
}

#[test]
fn spread_survives_odd_batches() {
    let (_, accel) = kitten();
    // empty, one ray, a partial group
    assert_eq!(spread(&[], 1.0).groups, 0);
    assert_eq!(engine::choose(&accel, &[]), Engine::Wide);
    let one = [Ray::new(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY)];
    let s = spread(&one, 1.0);
    assert_eq!((s.groups, s.direction, s.origin), (1, 0.0, 0.0));
    // NaN and zero directions, NaN and infinite origins: scattered, no panic
    let odd = [
        Ray::new(Vec3::ZERO, Vec3::NAN, 0.0, 1.0),
        Ray::new(Vec3::NAN, Vec3::X, 0.0, 1.0),
        Ray::new(Vec3::INFINITY, Vec3::ZERO, 0.0, 1.0),
        Ray::new(Vec3::ZERO, Vec3::Y, 0.0, 1.0),
    ];
    let s = spread(&odd, 1.0);
    assert!(s.direction.is_finite() && s.origin.is_finite(), "{s:?}");
    assert_eq!(choose_by(s, true), Engine::Wide);
    // a zero-size scene
    assert!(spread(&odd, 0.0).origin.is_finite());
    for e in Engine::ALL {
        let hits = whitted::trace::trace_rays(&accel, &odd, e, false);
        assert_eq!(hits.len(), odd.len());
    }
}

/// `auto` and every engine return `intersect1`'s hits, bit for bit, on the random workload
/// (and its reversed rays, culled and not) through the batch call.
#[test]
fn every_engine_is_intersect1_on_random_rays() {
    let (mesh, accel) = kitten();
    let mut rays = random_rays(&mesh, 6000);
    rays.extend(
        rays.clone()
            .iter()
            .map(|r| Ray::new(r.origin, -r.dir, 0.0, 0.7)),
    );
    let bits = |h: Option<whitted::ray::Hit>| {
        h.map(|h| (h.tri, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
    };
    for cull in [false, true] {
        let want: Vec<_> = rays
            .iter()
            .map(|r| bits(intersect1(&accel, r, cull)))
            .collect();
        assert!(want.iter().flatten().count() > rays.len() / 10);
        for e in Engine::ALL {
            let got: Vec<_> = whitted::trace::trace_rays(&accel, &rays, e, cull)
                .into_iter()
                .map(bits)
                .collect();
            assert!(got == want, "{} cull {cull}", e.name());
        }
    }
}

/// Rays aimed at the kitten's vertices, where a hit is decided in f64 and every kernel takes
/// the f64 plane distance: every engine returns `intersect1`'s hit. Among them the ray that
/// once split the trees: through the vertex that triangles 16404 and 4456 share, where 4456's
/// f32 plane distance (4e-6 short) put its hit point before its box, so the wide tree, which
/// tests 4456 beside triangles the ray does meet, returned it while the binary tree had culled
/// it (the f64 contract: 16404 at 0.99999989, 4456 at 1.00000056).
#[test]
fn every_engine_is_intersect1_on_rays_through_vertices() {
    let (mesh, accel) = kitten();
    let (lo, hi) = mesh.bounds().unwrap();
    let mut s = 7u64;
    let mut rays = vec![Ray::new(
        Vec3::new(0.94442177, -1.046991, 1.2499499),
        Vec3::new(-0.75752777, 0.978368, -1.5972029),
        0.0,
        f32::INFINITY,
    )];
    for v in mesh.positions.iter().step_by(3) {
        let u = [0; 3].map(|_| whitted::bench::rng_unit(&mut s) as f32);
        let o = lo + (hi - lo) * Vec3::from(u) * 3.0 - (hi - lo);
        rays.push(Ray::new(o, *v - o, 0.0, f32::INFINITY));
    }
    let bits = |h: Option<whitted::ray::Hit>| {
        h.map(|h| (h.tri, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
    };
    assert_eq!(
        intersect1(&accel, &rays[0], false).map(|h| h.tri),
        Some(16404)
    );
    for cull in [false, true] {
        let want: Vec<_> = rays
            .iter()
            .map(|r| bits(intersect1(&accel, r, cull)))
            .collect();
        for e in Engine::ALL {
            let got: Vec<_> = whitted::trace::trace_rays(&accel, &rays, e, cull)
                .into_iter()
                .map(bits)
                .collect();
            let bad = got.iter().zip(&want).position(|(g, w)| g != w);
            assert!(
                bad.is_none(),
                "{} cull {cull}: ray {:?}",
                e.name(),
                bad.map(|i| rays[i])
            );
            let got: Vec<_> = whitted::trace::occluded_rays(&accel, &rays, e, cull);
            let want_occ: Vec<_> = want.iter().map(Option::is_some).collect();
            assert!(got == want_occ, "{} occluded, cull {cull}", e.name());
        }
    }
}

/// Rays with a NaN or infinite origin or direction component, or NaN bounds, hit nothing:
/// brute force over every triangle (no boxes) says so, and every engine, closest and any
/// hit, answers so without walking (`Ray::traceable`), lanes beside them in the same
/// packets keeping `intersect1`'s hits bit for bit.
#[test]
fn rays_that_can_hit_nothing_miss_in_every_engine() {
    let (mesh, accel) = kitten();
    let mut rays = random_rays(&mesh, 3000);
    let poisons: [fn(&mut Ray); 8] = [
        |r| r.origin.x = f32::NAN,
        |r| r.origin.z = f32::INFINITY,
        |r| r.dir.y = f32::NAN,
        |r| r.dir.x = f32::NEG_INFINITY,
        |r| r.tnear = f32::NAN,
        |r| r.tfar = f32::NAN,
        |r| r.dir = Vec3::splat(f32::NAN),
        |r| r.origin = Vec3::new(f32::NAN, 0.0, f32::INFINITY),
    ];
    let mut poisoned = vec![false; rays.len()];
    for (i, r) in rays.iter_mut().enumerate() {
        // (every third ray, so packets hold both kinds)
        if i % 3 == 1 {
            poisons[i / 3 % poisons.len()](r);
            poisoned[i] = true;
            assert!(!r.traceable());
        } else {
            assert!(r.traceable());
        }
    }
    let bits = |h: Option<whitted::ray::Hit>| {
        h.map(|h| (h.tri, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
    };
    for (r, &p) in rays.iter().zip(&poisoned).step_by(7) {
        if p {
            assert_eq!(
                whitted::accel::scalar::intersect_brute1(&accel, r, false),
                None
            );
        }
    }
    for cull in [false, true] {
        let want: Vec<_> = rays
            .iter()
            .map(|r| bits(intersect1(&accel, r, cull)))
            .collect();
        assert!(want.iter().zip(&poisoned).all(|(w, &p)| !p || w.is_none()));
        assert!(want.iter().flatten().count() > rays.len() / 10);
        let occluded: Vec<bool> = want.iter().map(Option::is_some).collect();
        for e in Engine::ALL {
            let got: Vec<_> = whitted::trace::trace_rays(&accel, &rays, e, cull)
                .into_iter()
                .map(bits)
                .collect();
            assert!(got == want, "{} cull {cull}", e.name());
            let got = whitted::trace::occluded_rays(&accel, &rays, e, cull);
            assert!(got == occluded, "{} occluded, cull {cull}", e.name());
        }
    }
}

/// The pieces a caller with its own ray layout uses (the Python package): the spread and
/// the choice from rays given by index equal those from the slice, `resolve_by` keeps a
/// named engine and takes the rule's one candidate for random rays, and `intersect_into` /
/// `occluded_into` on chunks return `intersect1`'s bytes with every engine.
#[test]
fn batches_given_by_index() {
    let (mesh, accel) = kitten();
    let rays = random_rays(&mesh, 5000);
    let at = |i: usize| rays[i];
    assert_eq!(engine::spread_by(rays.len(), at, 2.5), spread(&rays, 2.5));
    assert_eq!(
        engine::choices_by(&accel, rays.len(), at),
        engine::choices(&accel, &rays)
    );
    assert_eq!(engine::choices(&accel, &rays), Choice::One(Engine::Wide));
    for any_hit in [false, true] {
        let n = rays.len();
        let auto = whitted::trace::resolve_by(Engine::Auto, &accel, n, at, any_hit, false);
        assert_eq!(auto, Engine::Wide);
        let named = whitted::trace::resolve_by(Engine::Hybrid, &accel, n, at, any_hit, false);
        assert_eq!(named, Engine::Hybrid);
    }
    let want: Vec<_> = rays.iter().map(|r| intersect1(&accel, r, false)).collect();
    for e in Engine::ALL {
        let mut hits = vec![None; rays.len()];
        let mut blocked = vec![false; rays.len()];
        // (chunks of odd sizes, so packets are cut short)
        for (k, r) in rays.chunks(1000 - 3).enumerate() {
            let at = k * (1000 - 3);
            whitted::trace::intersect_into(&accel, r, e, false, &mut hits[at..]);
            whitted::trace::occluded_into(&accel, r, e, false, &mut blocked[at..]);
        }
        let bits =
            |h: &Option<whitted::ray::Hit>| h.map(|h| (h.tri, h.t.to_bits(), h.b1.to_bits()));
        assert!(
            hits.iter().map(bits).eq(want.iter().map(bits)),
            "{}",
            e.name()
        );
        assert!(
            blocked.iter().copied().eq(want.iter().map(Option::is_some)),
            "{}",
            e.name()
        );
    }
}

/// `wide1`'s batch calls walk scattered rays on a tree larger than the caches interleaved
/// (the kitten subdivided once: 82k triangles, a 5.8 MiB tree), rays in order and small
/// trees two at a time; either way every hit is `intersect1`'s, bit for bit, and every
/// occlusion `occluded1`'s, culled and not, whatever the batch's length.
#[test]
fn wide1_batches_interleaved_or_not_are_intersect1() {
    use whitted::accel::{intersect_wide1_many, occluded_wide1_many, occluded1, wide1};
    let (mesh, small) = kitten();
    let big_mesh = mesh.subdivide(1);
    let big = Accel::build(&triangles(&big_mesh), BuildQuality::default());
    let random = random_rays(&big_mesh, 4000);
    // rays in order: from one point towards a sweep over the mesh (a beam, origins together)
    let eye = Vec3::new(1.6, 0.9, 4.4);
    let aimed: Vec<Ray> = (0..4000)
        .map(|i| {
            let v = big_mesh.positions[i * 7 % big_mesh.positions.len()];
            Ray::new(eye, v - eye, 0.0, f32::INFINITY)
        })
        .collect();
    assert!(wide1::interleaves(&big, &random));
    assert!(!wide1::interleaves(&big, &aimed));
    assert!(!wide1::interleaves(&small, &random));
    assert!(!wide1::interleaves(&big, &random[..15]));
    let bits = |h: &Option<whitted::ray::Hit>| {
        h.map(|h| (h.tri, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()))
    };
    for (accel, rays) in [(&big, &random), (&big, &aimed), (&small, &random)] {
        for cull in [false, true] {
            // (lengths that leave some of the eight walks, or one of two, idle at the end)
            for n in [rays.len(), 37, 16, 1, 0] {
                let rays = &rays[..n];
                let mut hits = vec![None; n];
                let mut occ = vec![false; n];
                intersect_wide1_many(accel, rays, cull, &mut hits);
                occluded_wide1_many(accel, rays, cull, &mut occ);
                for (k, r) in rays.iter().enumerate() {
                    assert_eq!(bits(&hits[k]), bits(&intersect1(accel, r, cull)), "ray {k}");
                    assert_eq!(occ[k], occluded1(accel, r, cull), "ray {k}");
                }
            }
        }
    }
}

#[test]
fn packet_lanes_that_can_hit_nothing() {
    let ok = Ray::new(Vec3::ZERO, Vec3::Z, 0.0, f32::INFINITY);
    let mut nan = ok;
    nan.dir.y = f32::NAN;
    let mut inf = ok;
    inf.origin.x = f32::INFINITY;
    let mut far = ok;
    far.tfar = f32::NAN;
    let lanes = [
        Some(ok),
        Some(nan),
        Some(inf),
        Some(far),
        None,
        Some(ok),
        None,
        None,
    ];
    let (p, active) = whitted::packet::RayPacket8::from_fn(|i| lanes[i]);
    assert_eq!(whitted::simd::bitmask(active), 0b0010_1111);
    assert_eq!(whitted::simd::bitmask(active & p.traceable()), 0b0010_0001);
}

#[test]
fn candidates_by_kind_of_batch() {
    let s = |direction, origin| Spread {
        groups: 64,
        direction,
        origin,
        mixed_octants: 0.0,
    };
    assert_eq!(
        candidates(s(1e-5, 0.0), true),
        Choice::Try([Engine::Packet16, Engine::Hybrid16])
    );
    assert_eq!(
        candidates(s(1e-5, 0.0), false),
        Choice::Try([Engine::Hybrid, Engine::Wide])
    );
    assert_eq!(
        candidates(s(0.9, 0.01), true),
        Choice::Try([Engine::Hybrid16, Engine::Wide])
    );
    assert_eq!(
        candidates(s(0.9, 0.01), false),
        Choice::Try([Engine::Hybrid, Engine::Wide])
    );
    assert_eq!(candidates(s(0.9, 0.6), true), Choice::One(Engine::Wide));
    assert_eq!(
        Choice::Try([Engine::Hybrid, Engine::Wide]).first(),
        Engine::Hybrid
    );
}

#[test]
fn pilot_runs_spread_over_the_batch() {
    assert!(engine::pilot_blocks(engine::PILOT_MIN - 1).is_empty());
    let len = engine::PILOT_RUN * engine::PILOT_BLOCK;
    for n in [engine::PILOT_MIN, 201702, 262144, 2073600, 10_000_001] {
        let b = engine::pilot_blocks(n);
        assert!(b.len() >= engine::PILOT_RUNS_MIN, "{n}");
        assert!(
            b.iter()
                .all(|r| r.len() == len && r.start % 64 == 0 && r.end <= n)
        );
        // at most 1/32 of the rays, and 1/400 of a large batch's
        let rays: usize = b.iter().map(|r| r.len()).sum();
        assert!(rays * 32 <= n, "{n}: {rays}");
        if n >= 2_000_000 {
            assert!(rays * 400 <= n, "{n}: {rays}");
        }
        for w in b.windows(2) {
            assert!(w[0].end <= w[1].start);
        }
        // spread: the first at the start, the last at the end
        assert_eq!(b[0].start, 0);
        assert!(b.last().unwrap().end > n - engine::PILOT_BLOCK - len, "{n}");
    }
}

/// What is left of a batch (or of one chunk of it) once the pilot traced its runs: every ray
/// outside the runs exactly once, in order, nothing inside them.
#[test]
fn left_over_skips_the_pilot_runs() {
    let ranges = |r: std::ops::Range<usize>, done: &[std::ops::Range<usize>]| {
        engine::left_over(r, done).collect::<Vec<_>>()
    };
    assert_eq!(ranges(0..100, &[]), vec![0..100]);
    assert_eq!(ranges(0..100, std::slice::from_ref(&(0..100))), vec![]);
    assert_eq!(
        ranges(0..100, &[0..10, 20..30, 90..100]),
        vec![10..20, 30..90]
    );
    // chunks that cut runs, and runs outside the chunk
    assert_eq!(
        ranges(50..150, &[0..60, 100..110, 140..200]),
        vec![60..100, 110..140]
    );
    assert_eq!(ranges(50..150, &[0..10, 200..300]), vec![50..150]);
    assert_eq!(ranges(50..50, std::slice::from_ref(&(0..10))), vec![]);
    for n in [engine::PILOT_MIN, 201702, 2073600] {
        let runs = engine::pilot_blocks(n);
        for chunk in [4096, 100_000, n] {
            let mut covered = vec![0u8; n];
            for start in (0..n).step_by(chunk) {
                for p in engine::left_over(start..(start + chunk).min(n), &runs) {
                    covered[p].iter_mut().for_each(|c| *c += 1);
                }
            }
            for r in &runs {
                covered[r.clone()].iter_mut().for_each(|c| *c += 1);
            }
            assert!(covered.iter().all(|&c| c == 1), "{n} {chunk}");
        }
    }
}

/// The pilot's decision (given times, no clock): the faster candidate wins; one run slowed
/// far beyond the other engine's does not move it; the runs alternate which engine goes
/// first; small batches take the first without a pilot. And the timed pilot warms each
/// engine on a run's first block, then traces the rest of the run, once each.
#[test]
fn pilot_takes_the_faster() {
    let n = engine::PILOT_MIN;
    let runs = engine::pilot_blocks(n);
    for (slow, fast) in [
        (Engine::Packet16, Engine::Hybrid16),
        (Engine::Hybrid16, Engine::Packet16),
    ] {
        let mut calls = vec![];
        let got = engine::pilot_by([Engine::Packet16, Engine::Hybrid16], n, |e, r| {
            calls.push((e, r.clone()));
            // the fast engine's second run preempted for a long while
            let hiccup = e == fast && calls.iter().filter(|c| c.0 == e).count() == 2;
            if hiccup {
                5e-3
            } else if e == slow {
                3e-4
            } else {
                1e-4
            }
        });
        assert_eq!(got, fast);
        assert_eq!(calls.len(), 2 * runs.len());
        for (k, r) in runs.iter().enumerate() {
            let first = if k % 2 == 0 {
                Engine::Packet16
            } else {
                Engine::Hybrid16
            };
            assert_eq!(calls[2 * k], (first, r.clone()));
            assert_eq!(calls[2 * k + 1].1, *r);
        }
    }
    // costly runs weigh more than cheap ones: a wins 7 cheap runs, b the one costly run
    let mut k = 0;
    let got = engine::pilot_by([Engine::Packet16, Engine::Hybrid16], n, |e, _| {
        k += 1;
        let run = (k - 1) / 2;
        match (run, e) {
            (0, Engine::Packet16) => 1e-2,
            (0, _) => 5e-3,
            (_, Engine::Packet16) => 1e-4,
            _ => 2e-4,
        }
    });
    assert_eq!(got, Engine::Hybrid16);
    // the timed pilot: each engine warms up on a run's first blocks, then the rest, once each
    let mut calls: Vec<(Engine, std::ops::Range<usize>)> = vec![];
    engine::pilot([Engine::Packet16, Engine::Hybrid16], n, |e, r| {
        calls.push((e, r))
    });
    assert_eq!(calls.len(), 4 * runs.len());
    for r in &runs {
        let warm = r.start..r.start + engine::PILOT_WARM * engine::PILOT_BLOCK;
        let timed = warm.end..r.end;
        for e in [Engine::Packet16, Engine::Hybrid16] {
            let at = |x: &std::ops::Range<usize>| {
                calls.iter().position(|c| c.0 == e && c.1 == *x).unwrap()
            };
            assert_eq!(at(&warm) + 1, at(&timed), "{e:?} {r:?}");
        }
    }
    let mut called = false;
    let got = engine::pilot([Engine::Wide, Engine::Hybrid], n - 16, |_, _| called = true);
    assert_eq!((got, called), (Engine::Wide, false));
}

/// A batch large enough for a pilot: `auto`'s hits and occlusion are every engine's.
#[test]
fn auto_with_a_pilot_is_exact() {
    let (mesh, accel) = kitten();
    let work = Workloads::generate_with(&mesh, &accel, 640, 360, engine::PILOT_MIN);
    let random = &work.random;
    let want = whitted::trace::trace_rays(&accel, random, Engine::Wide, false);
    let (got, chosen) = whitted::trace::trace_rays_with(&accel, random, Engine::Auto, false);
    assert!(got == want);
    assert_eq!(chosen, Engine::Wide);
    // bounce rays, repeated up to the pilot's size: two candidates, a pilot decides
    let mut bounce = work.secondary.incoherent.clone();
    while bounce.len() < engine::PILOT_MIN {
        bounce.extend_from_within(..bounce.len().min(engine::PILOT_MIN - bounce.len()));
    }
    let Choice::Try(two) = engine::choices(&accel, &bounce) else {
        panic!("bounce rays have two candidates")
    };
    let want = whitted::trace::trace_rays(&accel, &bounce, Engine::Scalar, true);
    let (got, chosen) = whitted::trace::trace_rays_with(&accel, &bounce, Engine::Auto, true);
    assert!(got == want);
    assert!(two.contains(&chosen), "{chosen:?}");
    // occlusion: shadow rays (beams), repeated likewise
    let mut shadow = work.secondary.shadow.clone();
    while shadow.len() < engine::PILOT_MIN {
        shadow.extend_from_within(..shadow.len().min(engine::PILOT_MIN - shadow.len()));
    }
    let want = whitted::trace::occluded_rays(&accel, &shadow, Engine::Scalar, false);
    assert!(want.iter().any(|&o| o) && !want.iter().all(|&o| o));
    for e in Engine::ALL {
        let (got, chosen) = whitted::trace::occluded_rays_with(&accel, &shadow, e, false);
        assert!(got == want, "{}", e.name());
        assert!(chosen != Engine::Auto);
    }
}
