//! The bench's workload generator against the Embree peer's spec, and the peer-output parser.

mod common;

use glam::Vec3;
use whitted::accel::{Accel, BuildQuality, intersect1};
use whitted::bench::{self, Framing, Workload, Workloads};
use whitted::mesh::Mesh;

/// A small closed mesh away from the kitten's box (so the camera is framed): an octahedron
/// subdivided twice (128 triangles).
fn small_mesh() -> Mesh {
    let p = |x: f32, y: f32, z: f32| Vec3::new(x, y, z) + Vec3::new(3.0, -1.0, 0.5);
    let m = Mesh {
        positions: vec![
            p(1.0, 0.0, 0.0),
            p(-1.0, 0.0, 0.0),
            p(0.0, 1.0, 0.0),
            p(0.0, -1.0, 0.0),
            p(0.0, 0.0, 1.0),
            p(0.0, 0.0, -1.0),
        ],
        triangles: vec![
            [0, 2, 4],
            [2, 1, 4],
            [1, 3, 4],
            [3, 0, 4],
            [2, 0, 5],
            [1, 2, 5],
            [3, 1, 5],
            [0, 3, 5],
        ],
        ..Default::default()
    };
    bench::subdivide_like_peer(&m, 2)
}

fn build(m: &Mesh) -> Accel {
    Accel::build(&bench::triangles(m), BuildQuality::default())
}

#[test]
#[allow(clippy::excessive_precision)] // the peer notes' 17-digit values, kept verbatim
fn rng_and_constants_are_the_peers() {
    let mut s = bench::SEED;
    let u: Vec<u64> = (0..4).map(|_| bench::rng_u64(&mut s)).collect();
    assert_eq!(
        u,
        [
            0x599ed017fb08fc85,
            0x2c73f08458540fa5,
            0x883ebce5a3f27c77,
            0x3fbef740e9177b3f
        ]
    );
    let mut s = bench::SEED;
    assert_eq!(bench::rng_unit(&mut s), 0.35007954202140812);
    assert_eq!(bench::rng_unit(&mut s), 0.17364409667091263);
    assert_eq!(bench::tan_half_fov().to_bits(), 0x3fd4cb7bfb4961ae);
}

#[test]
fn small_mesh_workloads() {
    let mesh = small_mesh();
    assert_eq!(mesh.triangles.len(), 128);
    assert_eq!(mesh.open_edges(), 0);
    let accel = build(&mesh);
    let (w, h) = (96, 54);
    let work = Workloads::generate_with(&mesh, &accel, w, h, 4096);
    let fr = work.framing;
    assert!(!fr.canonical);
    // counts: every pixel once; one shadow and one incoherent ray per primary hit
    assert_eq!(work.primary.len(), (w * h) as usize);
    let hits: Vec<_> = work
        .primary
        .iter()
        .filter_map(|r| intersect1(&accel, r, false).map(|hit| (r, hit)))
        .collect();
    let sec = &work.secondary;
    assert!(hits.len() > 100, "the framed mesh fills part of the image");
    assert!(hits.len() < work.primary.len());
    assert_eq!(sec.primary_hits.len(), hits.len());
    assert_eq!(sec.shadow.len(), hits.len());
    assert_eq!(sec.incoherent.len(), hits.len());
    let light = Vec3::new(fr.light[0] as f32, fr.light[1] as f32, fr.light[2] as f32);
    let eps = fr.eps as f32;
    for (k, (ray, hit)) in hits.iter().enumerate() {
        assert_eq!(
            sec.primary_hits[k], **ray,
            "hits-only keeps the primary ray"
        );
        let q = ray.origin + hit.t * ray.dir;
        let ng = Vec3::from(bench::embree_ng(&mesh, hit.tri)).normalize();
        let n = if ng.dot(ray.dir) > 0.0 { -ng } else { ng };
        // shadow: from just off the surface, on the light's side, towards the light
        let s = &sec.shadow[k];
        let to_light = (light - q).normalize();
        assert!((s.dir - to_light).length() < 1e-5, "{k}");
        assert!((s.dir.length() - 1.0).abs() < 1e-6);
        let off = s.origin - q;
        assert!((off.length() - eps).abs() < 0.05 * eps, "{k}: {off}");
        assert!(off.dot(n).signum() == to_light.dot(n).signum(), "{k}");
        // tfar: one ulp short of the distance from q (computed in f64 by the generator)
        let dist = (light - q).length();
        assert!(
            (s.tfar - dist).abs() < 1e-5 * dist,
            "{k}: {} {dist}",
            s.tfar
        );
        assert_eq!(s.tnear, 0.0);
        // incoherent: unit, in the hemisphere of the surface's viewer side, origin off it
        let i = &sec.incoherent[k];
        assert!((i.dir.length() - 1.0).abs() < 1e-6, "{k}");
        assert!(i.dir.dot(n) >= -1e-6, "{k}: {} {n}", i.dir);
        assert!(((i.origin - q) - eps * n).length() < 0.05 * eps, "{k}");
        assert_eq!((i.tnear, i.tfar), (0.0, f32::INFINITY));
    }
    // directions cover the hemisphere: mean cos about 1/2
    let mean: f32 = hits
        .iter()
        .zip(&sec.incoherent)
        .map(|((r, h), i)| {
            let ng = Vec3::from(bench::embree_ng(&mesh, h.tri)).normalize();
            i.dir.dot(if ng.dot(r.dir) > 0.0 { -ng } else { ng })
        })
        .sum::<f32>()
        / hits.len() as f32;
    assert!((mean - 0.5).abs() < 0.1, "{mean}");
    // determinism
    let again = Workloads::generate_with(&mesh, &build(&mesh), w, h, 4096);
    for ((_, a), (_, b)) in work.sets().into_iter().zip(again.sets()) {
        assert_eq!(bench::ray_hash(a), bench::ray_hash(b));
    }
    // every engine agrees with the scalar reference on every set, and the counts are consistent
    let m = bench::measure(&accel, &work, 1, 1);
    let engines = bench::Engine::ALL.len();
    assert_eq!(m.len(), 5 * engines);
    for set in m.chunks(engines) {
        for other in &set[1..] {
            assert_eq!(set[0].workload, other.workload);
            assert_eq!(set[0].engine, bench::Engine::Scalar);
            assert_eq!(
                set[0].results, other.results,
                "{:?} {:?}",
                other.workload, other.engine
            );
        }
    }
    assert_eq!(m[0].results.count(), hits.len());
    let m2 = bench::measure(&accel, &work, 2, 1);
    for (a, b) in m.iter().zip(&m2) {
        assert_eq!(a.results, b.results, "threads do not change results");
    }
    // rounds (as `whitted bench` alternates them with the peer's) gather their passes
    let mut rounds = bench::Measuring::default();
    rounds.round(&accel, &work, 1, 1);
    // (results forgotten between rounds, as `whitted bench` does before each build, are
    // recorded again by the next round)
    rounds.forget_results();
    rounds.round(&accel, &work, 1, 2);
    for (a, b) in m.iter().zip(rounds.finish()) {
        assert_eq!((a.workload, a.engine), (b.workload, b.engine));
        assert_eq!(a.results, b.results, "rounds do not change results");
        assert!(b.timing.wall_best <= b.timing.wall_median);
    }
}

/// The kitten at the peer's full size: mesh (sub 0 and 1) and primary set hash to the values
/// the peer's dumps hash to (notes: embree_workloads.md §12); the hit counts are Embree's.
#[test]
fn kitten_matches_the_peers_hashes() {
    let (mesh, _) = whitted::io::load_mesh(&common::assets().join("meshes/kitten.m")).unwrap();
    let mesh_hash = |m: &Mesh| {
        (
            bench::fnv1a(
                m.positions
                    .iter()
                    .flat_map(|p| p.to_array())
                    .flat_map(f32::to_le_bytes),
            ),
            bench::fnv1a(m.triangles.iter().flatten().flat_map(|i| i.to_le_bytes())),
        )
    };
    let m0 = bench::subdivide_like_peer(&mesh, 0);
    assert_eq!(mesh_hash(&m0), (0xc2cf83efc5617984, 0xf61501028921e877));
    let m1 = bench::subdivide_like_peer(&mesh, 1);
    assert_eq!((m1.positions.len(), m1.triangles.len()), (40876, 81752));
    assert_eq!(mesh_hash(&m1), (0xe322aef8f62694fe, 0x4983114951a4a5c7));
    let fr = Framing::of(&m0);
    assert!(fr.canonical);
    assert_eq!(fr.eps, 2.665759649173855e-05);
    let primary = bench::primary_rays(&fr, bench::WIDTH, bench::HEIGHT);
    assert_eq!(primary.len(), 2073600);
    assert_eq!(primary[0].dir.x.to_bits(), 0xbf402759);
    assert_eq!(primary[1].dir.z.to_bits(), 0xbf27f12e);
    assert_eq!(bench::ray_hash(&primary), 0xd3ab0067417fd591);
    let work = Workloads::generate(&m0, &build(&m0), bench::WIDTH, bench::HEIGHT);
    // whitted hits the same 201702 pixels as Embree, so hits-only is Embree's set exactly
    assert_eq!(work.secondary.primary_hits.len(), 201702);
    assert_eq!(
        bench::ray_hash(&work.secondary.primary_hits),
        0xa8257c5afcd906a3
    );
    // the peer's `--random 262144`: the same rays, so the same 133563 hits
    assert_eq!(work.random.len(), bench::RANDOM_RAYS);
    assert_eq!(work.random, bench::random_rays(&m0, bench::RANDOM_RAYS));
    let accel = build(&m0);
    let random_hits =
        whitted::trace::trace_rays(&accel, &work.random, whitted::trace::Engine::Wide, false);
    assert_eq!(random_hits.iter().flatten().count(), 133563);
    let sets: Vec<Workload> = work.sets().iter().map(|s| s.0).collect();
    assert_eq!(sets, Workload::ALL);
}

/// The random rays follow the peer's draws: origin x, y, z in the box, then z and phi.
#[test]
fn random_rays_are_the_peers_draws() {
    let mesh = small_mesh();
    let (lo, hi) = mesh.bounds().unwrap();
    let rays = bench::random_rays(&mesh, 1000);
    assert_eq!(rays.len(), 1000);
    let mut s = bench::RANDOM_SEED;
    let mut u = || bench::rng_unit(&mut s);
    let o: Vec<f64> = (0..3)
        .map(|e| lo[e] as f64 + u() * (hi[e] as f64 - lo[e] as f64))
        .collect();
    let z = 2.0 * u() - 1.0;
    let phi = 2.0 * std::f64::consts::PI * u();
    let r = (1.0 - z * z).sqrt();
    assert_eq!(
        rays[0].origin.to_array(),
        [o[0] as f32, o[1] as f32, o[2] as f32]
    );
    assert_eq!(
        rays[0].dir.to_array(),
        [(r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32]
    );
    for r in &rays {
        assert!(r.origin.cmpge(lo).all() && r.origin.cmple(hi).all());
        assert!((r.dir.length() - 1.0).abs() < 1e-6);
        assert_eq!((r.tnear, r.tfar), (0.0, f32::INFINITY));
    }
    // none without asking for them
    let accel = build(&mesh);
    let work = Workloads::generate_with(&mesh, &accel, 16, 9, 0);
    assert!(work.random.is_empty());
    assert!(work.sets().iter().all(|s| s.0 != Workload::Random));
}

/// With Embree's own per-pixel `(prim, t, Ng)` (the refdump tool's `primary_hitinfo.bin`), the
/// generator reproduces Embree's shadow and incoherent sets bit for bit. Runs only where
/// `WHITTED_EMBREE_REFSETS` names a folder of those dumps (kitten, subdivide 0).
#[test]
fn embree_hits_give_embrees_exact_sets() {
    let Some(dir) = std::env::var_os("WHITTED_EMBREE_REFSETS") else {
        eprintln!("WHITTED_EMBREE_REFSETS not set: skipped");
        return;
    };
    let dir = std::path::PathBuf::from(dir);
    let info = std::fs::read(dir.join("primary_hitinfo.bin")).unwrap();
    let f = |b: &[u8]| f32::from_le_bytes(b.try_into().unwrap());
    let hits: Vec<Option<bench::SurfaceHit>> = info
        .chunks(20)
        .map(|r| {
            (u32::from_le_bytes(r[0..4].try_into().unwrap()) != u32::MAX).then(|| {
                bench::SurfaceHit {
                    t: f(&r[4..8]),
                    ng: [f(&r[8..12]), f(&r[12..16]), f(&r[16..20])],
                }
            })
        })
        .collect();
    let (mesh, _) = whitted::io::load_mesh(&common::assets().join("meshes/kitten.m")).unwrap();
    let fr = Framing::of(&mesh);
    let primary = bench::primary_rays(&fr, bench::WIDTH, bench::HEIGHT);
    let sec = bench::secondary_rays(&fr, &primary, &hits);
    assert_eq!(bench::ray_hash(&sec.shadow), 0xd3dd657e6f093e1e);
    assert_eq!(bench::ray_hash(&sec.incoherent), 0x26c1eed474d26645);
}

/// rt-bench's output (kitten, 1 thread, `--quality medium`), as captured on the dev machine.
const SAMPLE: &str = r#"mesh /work/shared/meshes/kitten.m subdivide 0: 10219 vertices, 20438 triangles (load 0.04 s)
embree 3.13.5, device config "threads=1", native ray8 1 ray16 0, ROBUST 0
camera canonical: eye (1.6 0.9 4.4) look_at (0 -0.15 0) L1 (5 6 3), 1920x1080 vfov 36
build MEDIUM (threads 1): wall best 8.35 ms, median 9.79 ms | process cpu best 8.36 ms, median 9.80 ms
 primary (1920x1080, 4x4 blocks):
  primary rtcIntersect1          2073600 rays  wall best    15.63 med    15.02 | cpu best    16.29 med    15.50 Mrays/s
  primary rtcIntersect8 (4x2)    2073600 rays  wall best    23.22 med    23.15 | cpu best    23.22 med    23.21 Mrays/s
  primary rtcIntersect16 (4x4)   2073600 rays  wall best    21.30 med    19.54 | cpu best    21.29 med    20.59 Mrays/s
  primary hits 201702 of 2073600 (9.7%); packet-vs-single primID mismatches 0
  primary-hits-only Intersect1    201702 rays  wall best     5.38 med     5.23 | cpu best     5.38 med     5.23 Mrays/s
  primary-hits-only Intersect8    201702 rays  wall best     5.86 med     5.34 | cpu best     5.94 med     5.86 Mrays/s
 shadow rays to L1 from primary hits:
  shadow rtcOccluded1             201702 rays  wall best     6.35 med     6.27 | cpu best     6.36 med     6.30 Mrays/s
  shadow rtcOccluded8             201702 rays  wall best     9.16 med     8.32 | cpu best     9.17 med     8.59 Mrays/s
  shadow rtcOccluded16            201702 rays  wall best     7.75 med     7.60 | cpu best     7.93 med     7.65 Mrays/s
  occluded 61028 of 201702 (30.3%)
 incoherent rays (uniform hemisphere about Ng, seed 1234567):
  incoherent rtcIntersect1        201702 rays  wall best     4.72 med     4.12 | cpu best     4.72 med     4.22 Mrays/s
  incoherent rtcIntersect8        201702 rays  wall best     5.57 med     4.61 | cpu best     5.57 med     4.68 Mrays/s
  incoherent rtcIntersect16       201702 rays  wall best     5.48 med     4.69 | cpu best     5.48 med     4.69 Mrays/s
  incoherent hits 26102 of 201702 (12.9%)
 random rays (origins uniform in the bbox, directions uniform on the sphere, seed 7654321):
  random rtcIntersect1            262144 rays  wall best     5.97 med     5.96 | cpu best     5.97 med     5.96 Mrays/s
  random rtcIntersect8            262144 rays  wall best     6.44 med     6.43 | cpu best     6.44 med     6.43 Mrays/s
  random rtcIntersect16           262144 rays  wall best     6.51 med     6.48 | cpu best     6.51 med     6.48 Mrays/s
  random hits 133563 of 262144 (51.0%)
"#;

#[test]
fn parses_rt_bench_output() {
    let p = bench::parse_peer(SAMPLE).unwrap();
    assert!(p.version.starts_with("embree 3.13.5"));
    assert_eq!(p.triangles, Some(20438));
    assert_eq!(p.camera, "canonical");
    assert_eq!(
        (p.build_best_ms, p.build_median_ms),
        (Some(8.35), Some(9.79))
    );
    assert_eq!(p.kernels.len(), 14);
    assert_eq!(p.kernel(Workload::Random, 16).unwrap().cpu_median, 6.48);
    assert_eq!(p.random_hits, Some(133563));
    let k = p.kernel(Workload::Primary, 8).unwrap();
    assert_eq!(k.rays, 2073600);
    assert_eq!(
        (k.wall_best, k.wall_median, k.cpu_best, k.cpu_median),
        (23.22, 23.15, 23.22, 23.21)
    );
    let k = p.kernel(Workload::PrimaryHits, 1).unwrap();
    assert_eq!((k.rays, k.wall_best, k.cpu_median), (201702, 5.38, 5.23));
    assert!(p.kernel(Workload::PrimaryHits, 16).is_none());
    assert_eq!(p.kernel(Workload::Shadow, 16).unwrap().wall_best, 7.75);
    assert_eq!(p.kernel(Workload::Incoherent, 1).unwrap().cpu_best, 4.72);
    assert_eq!(p.primary_hits, Some(201702));
    assert_eq!(p.mismatches, Some(0));
    assert_eq!(p.occluded, Some(61028));
    assert_eq!(p.incoherent_hits, Some(26102));

    // `--quality both`: only the first quality (MEDIUM) is kept
    let both = format!(
        "{SAMPLE}build HIGH (threads 1): wall best 20.00 ms, median 21.00 ms | process cpu best 1 ms, median 1 ms\n{}",
        SAMPLE
            .lines()
            .skip(4)
            .collect::<Vec<_>>()
            .join("\n")
            .replace("15.63", "99.00")
    );
    let p2 = bench::parse_peer(&both).unwrap();
    assert_eq!(p2, p);

    // not rt-bench output
    assert!(bench::parse_peer("usage: rt-bench MESH ...\n").is_err());
    assert!(bench::parse_peer("  primary rtcIntersect1  12 rays  wall best x med\n").is_err());
}

/// The peer's one-pass runs merge into best and median per kernel and for the build (the
/// median as the peer takes it, `sorted[n / 2]` of the times); runs over different ray sets
/// are refused.
#[test]
fn peer_runs_merge_into_best_and_median() {
    let one = bench::parse_peer(SAMPLE).unwrap();
    // three runs whose shadow x16 rates are 7, 9, 8 and builds 9, 8, 10 ms
    let runs: Vec<_> = [(7.0, 9.0), (9.0, 8.0), (8.0, 10.0)]
        .into_iter()
        .map(|(rate, build)| {
            let mut r = one.clone();
            let k = r
                .kernels
                .iter_mut()
                .find(|k| k.workload == Workload::Shadow && k.width == 16)
                .unwrap();
            (k.wall_best, k.cpu_best) = (rate, rate + 0.5);
            (k.wall_median, k.cpu_median) = (rate, rate + 0.5);
            (r.build_best_ms, r.build_median_ms) = (Some(build), Some(build));
            r
        })
        .collect();
    let m = bench::merge_peer(&runs).unwrap();
    let k = m.kernel(Workload::Shadow, 16).unwrap();
    assert_eq!(
        (k.wall_best, k.wall_median, k.cpu_best, k.cpu_median),
        (9.0, 8.0, 9.5, 8.5)
    );
    assert_eq!((m.build_best_ms, m.build_median_ms), (Some(8.0), Some(9.0)));
    // the other kernels' runs are alike: each run's one pass is its best
    let k = m.kernel(Workload::Primary, 8).unwrap();
    assert_eq!(
        (k.rays, k.wall_best, k.wall_median, k.cpu_best, k.cpu_median),
        (2073600, 23.22, 23.22, 23.22, 23.22)
    );
    // one run merges to itself but for the medians, which become its best passes
    let alone = bench::merge_peer(std::slice::from_ref(&one)).unwrap();
    assert_eq!(
        alone.kernel(Workload::Incoherent, 1).unwrap().cpu_median,
        4.72
    );
    // different ray sets
    let mut other = one.clone();
    other.occluded = Some(1);
    assert!(bench::merge_peer(&[one.clone(), other]).is_err());
    assert!(bench::merge_peer(&[]).is_err());
}

/// A stand-in `rt-bench` in a fresh temporary folder: a shell script that logs its arguments
/// to `calls`, runs `guard` (shell lines that may exit first), then prints `output`. Returns
/// the folder, the script and the log.
#[cfg(unix)]
fn fake_peer(
    name: &str,
    output: &str,
    guard: &str,
) -> (std::path::PathBuf, std::path::PathBuf, std::path::PathBuf) {
    use std::os::unix::fs::PermissionsExt;
    let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (peer, log, out) = (dir.join("rt-bench"), dir.join("calls"), dir.join("out.txt"));
    std::fs::write(&out, output).unwrap();
    std::fs::write(
        &peer,
        format!(
            "#!/bin/sh\necho \"$*\" >> '{}'\n{guard}cat '{}'\n",
            log.display(),
            out.display()
        ),
    )
    .unwrap();
    std::fs::set_permissions(&peer, std::fs::Permissions::from_mode(0o755)).unwrap();
    (dir, peer, log)
}

/// `whitted bench` alternates with the peer: one peer run per round, each of one pass
/// (`--reps 1`), and the report merges them. A stand-in for rt-bench logs its calls and
/// prints the captured output.
#[cfg(unix)]
#[test]
fn bench_alternates_rounds_with_the_peer() {
    use whitted::bench::{Options, bench_mesh};
    let (dir, peer, log) = fake_peer("whitted-fake-peer", SAMPLE, "");
    let cube = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/cube.obj");
    let opts = Options {
        width: 32,
        height: 18,
        reps: 3,
        peer: Some(peer.clone()),
        ..Options::default()
    };
    let r = bench_mesh(&cube, &opts).unwrap();
    let calls = std::fs::read_to_string(&log).unwrap();
    assert_eq!(calls.lines().count(), 3, "{calls}");
    assert!(calls.lines().all(|c| c.contains("--reps 1")), "{calls}");
    assert!(
        calls.lines().all(|c| c.contains("--random 262144")),
        "{calls}"
    );
    let p = r.peer.as_ref().unwrap();
    assert_eq!(p.build_best_ms, Some(8.35));
    let text = bench::format_report(&r);
    assert!(text.contains("rounds 3"), "{text}");
    assert!(
        text.contains("of 3 rounds, one pass each, alternating with the peer's"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An rt-bench older than `--random` refuses the flag (usage, exit 2): the bench runs it
/// without, and reports the random workload for whitted alone.
#[cfg(unix)]
#[test]
fn bench_runs_an_older_peer_without_random() {
    use whitted::bench::{Options, bench_mesh};
    let old: String = SAMPLE
        .lines()
        .take_while(|l| !l.starts_with(" random"))
        .map(|l| format!("{l}\n"))
        .collect();
    let (dir, peer, log) = fake_peer(
        "whitted-old-peer",
        &old,
        "case \"$*\" in *--random*) echo usage >&2; exit 2;; esac\n",
    );
    let cube = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/cube.obj");
    let opts = Options {
        width: 32,
        height: 18,
        reps: 2,
        random: Some(5000),
        peer: Some(peer.clone()),
        ..Options::default()
    };
    let r = bench_mesh(&cube, &opts).unwrap();
    let calls = std::fs::read_to_string(&log).unwrap();
    // round 0: refused with --random, then without; round 1: without
    let lines: Vec<&str> = calls.lines().collect();
    assert_eq!(lines.len(), 3, "{calls}");
    assert!(lines[0].contains("--random 5000") && !lines[1].contains("--random"));
    let p = r.peer.as_ref().unwrap();
    assert!(p.kernel(Workload::Random, 1).is_none());
    assert_eq!(p.random_hits, None);
    let m = r.get(Workload::Random, bench::Engine::Scalar).unwrap();
    assert_eq!(m.rays, 5000);
    let text = bench::format_report(&r);
    let row = text.lines().find(|l| l.starts_with("random ")).unwrap();
    assert!(row.trim_end().ends_with('-'), "{row}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Samples taken in several rounds add up (each round after its own warm-up call), and their
/// best is no more than their median.
#[test]
fn samples_gather_over_rounds() {
    let mut s = bench::Samples::default();
    let mut calls = 0;
    s.take(2, 1, || {}, || calls += 1);
    s.take(3, 1, || {}, || calls += 1);
    assert_eq!((s.len(), calls), (5, 7));
    let t = s.timing();
    assert!(t.wall_best <= t.wall_median);
    if cfg!(target_os = "linux") {
        assert!(t.cpu_best.unwrap() <= t.cpu_median.unwrap());
    }
}

#[test]
fn peer_lookup_prefers_the_explicit_path() {
    let p = std::path::Path::new("/nonexistent/rt-bench");
    assert_eq!(bench::find_peer(Some(p)).as_deref(), Some(p));
}

/// `--width/--height` size the camera workloads (the peer gets the same flags); absurd sizes
/// are refused before anything is allocated.
#[test]
fn bench_size_options() {
    use whitted::bench::{Options, Workload, bench_mesh};
    let opts = Options {
        meshes: vec![],
        width: 64,
        height: 36,
        reps: 1,
        no_peer: true,
        ..Options::default()
    };
    let cube = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/cube.obj");
    let r = bench_mesh(&cube, &opts).unwrap();
    assert_eq!((r.width, r.height), (64, 36));
    let m = r
        .measured
        .iter()
        .find(|m| m.workload == Workload::Primary)
        .unwrap();
    assert_eq!(m.results.tri.len(), 64 * 36);
    // memory: what traversal reads, and the process's peak while the mesh was benchmarked
    assert!(
        r.accel_bytes > r.wide_bytes,
        "{} {}",
        r.accel_bytes,
        r.wide_bytes
    );
    if cfg!(target_os = "linux") {
        let peak = r.peak_resident.expect("VmHWM on Linux");
        assert!(peak >= r.accel_bytes as u64, "{peak} {}", r.accel_bytes);
        // (this machine lets a process reset its peak: the figure is this mesh's)
        assert!(r.peak_reset);
    }
    let huge = Options {
        width: 1 << 20,
        height: 1 << 20,
        ..opts
    };
    let e = bench_mesh(&cube, &huge).unwrap_err().to_string();
    assert!(e.contains("over the cap"), "{e}");
}

/// `--quality` picks the BVH2 builder by name (all give the same hits) and names it in the
/// report; an unknown name is refused with the list.
#[test]
fn bench_quality_names_the_builder() {
    use whitted::bench::{Options, bench_mesh};
    let cube = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/cube.obj");
    let mut hits = vec![];
    for q in ["binned", "fast", "medium", "slow"] {
        let opts = Options {
            width: 32,
            height: 18,
            reps: 1,
            no_peer: true,
            quality: Some(q.into()),
            ..Options::default()
        };
        let r = bench_mesh(&cube, &opts).unwrap();
        assert_eq!(r.builder, q);
        hits.push(r.measured[0].results.clone());
    }
    assert!(hits.windows(2).all(|w| w[0] == w[1]));
    let bad = Options {
        quality: Some("best".into()),
        no_peer: true,
        ..Options::default()
    };
    let e = bench_mesh(&cube, &bad).unwrap_err().to_string();
    assert!(e.contains("binned, fast, medium or slow"), "{e}");
}

/// With no mesh argument, `whitted bench` runs on the kitten whitted ships, found from any
/// folder without `WHITTED_ASSETS` (as renders find it).
#[test]
fn bench_defaults_to_the_shipped_kitten() {
    let dir = std::env::temp_dir().join(format!("whitted-bench-default-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_whitted"))
        .args(["bench", "--no-peer", "--reps", "1", "--threads", "1"])
        .args(["--width", "32", "--height", "18", "--json"])
        .env_remove("WHITTED_ASSETS")
        .current_dir(&dir)
        .output()
        .unwrap();
    std::fs::remove_dir_all(&dir).ok();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mesh = json["whitted_bench"][0]["mesh"]
        .as_str()
        .unwrap_or_default()
        .to_owned();
    assert!(mesh.ends_with("meshes/kitten.m"), "{json}");
    assert_eq!(json["whitted_bench"][0]["triangles"], 20438, "{json}");
    // the kitten's BVH2, SoA columns and wide tree: 100-300 bytes per triangle
    let accel = json["whitted_bench"][0]["accel_bytes"]
        .as_u64()
        .unwrap_or(0);
    assert!((20438 * 100..20438 * 300).contains(&accel), "{json}");
    if cfg!(target_os = "linux") {
        let peak = json["whitted_bench"][0]["peak_resident_bytes"].as_u64();
        assert!(peak.is_some_and(|p| p > accel), "{json}");
        assert_eq!(
            json["whitted_bench"][0]["peak_resident_scope"], "mesh",
            "{json}"
        );
    }
}

/// `VmHWM` is read from `/proc/<pid>/status` in bytes; anything else gives no figure.
#[test]
fn peak_resident_parses_vm_hwm() {
    let status = "Name:\twhitted\nVmPeak:\t  900 kB\nVmHWM:\t    1732 kB\nVmRSS:\t 1700 kB\n";
    assert_eq!(bench::parse_vm_hwm(status), Some(1732 * 1024));
    assert_eq!(bench::parse_vm_hwm("VmRSS:\t 1700 kB\n"), None);
    assert_eq!(bench::parse_vm_hwm("VmHWM:\t 17x2 kB\n"), None);
    assert_eq!(bench::parse_vm_hwm("VmHWM:\t 1732 MB\n"), None);
    if cfg!(target_os = "linux") {
        // with 64 MiB resident the peak is at least that, whatever other tests reset or
        // hold meanwhile (a peak is never below the resident size)
        assert!(bench::reset_peak_resident());
        let v = std::hint::black_box(vec![1u8; 64 << 20]);
        let peak = bench::peak_resident_bytes().unwrap();
        assert!(peak >= 64 << 20, "{peak}");
        assert_eq!(v.iter().map(|&b| b as usize).sum::<usize>(), 64 << 20);
    }
}

/// The `memory:` line says what the peak covers: this mesh after a reset, the whole process
/// where the system refused the reset (a later mesh's figure then includes earlier meshes),
/// and that there is none where the system does not say.
#[test]
fn memory_line_names_what_the_peak_covers() {
    let mesh = bench::memory_line(3 << 20, 1 << 16, Some(300 << 20), true);
    assert!(mesh.contains("3.0 MiB (48.0 bytes/triangle)"), "{mesh}");
    assert!(
        mesh.contains("peak resident 300.0 MiB (this mesh:"),
        "{mesh}"
    );
    let process = bench::memory_line(3 << 20, 1 << 16, Some(300 << 20), false);
    assert!(
        process.contains("300.0 MiB (the process's since it started, earlier meshes included"),
        "{process}"
    );
    assert!(!process.contains("this mesh"), "{process}");
    let none = bench::memory_line(3 << 20, 1 << 16, None, false);
    assert!(none.ends_with("peak resident not available"), "{none}");
}

/// The reported collapse time is the fastest timed build's: never longer than the fastest
/// build it is part of (before, the last build's was reported, and at 1.3M triangles it
/// read up to 802 ms beside a best build of 362).
#[test]
fn build_timing_reports_the_fastest_collapse() {
    let tris = bench::triangles(&small_mesh());
    let (accel, t, collapse) = bench::time_build(&tris, 5, BuildQuality::default(), 1);
    assert!(collapse.as_secs_f64() > 0.0);
    assert!(
        collapse <= accel.collapse_time,
        "{collapse:?} {:?}",
        accel.collapse_time
    );
    assert!(
        collapse.as_secs_f64() <= t.wall_best,
        "collapse {collapse:?} beside a best build of {} s",
        t.wall_best
    );
}

/// The bench's `auto` row with a pilot (a set of at least `PILOT_MIN` rays with two
/// candidates), on the calling thread and on a pool of two, from fresh buffers: the pilot's
/// runs, which the chosen engine does not trace again, hold the reference's results like
/// the rest.
#[test]
fn auto_pass_with_a_pilot_is_exact() {
    use whitted::engine::{self, Choice, Engine};
    let (mesh, _) =
        whitted::io::load_mesh(&common::assets().join("meshes/kitten.m")).expect("the kitten");
    let accel = build(&mesh);
    let work = Workloads::generate_with(&mesh, &accel, 640, 360, 4096);
    for (any_hit, set) in [
        (false, &work.secondary.incoherent),
        (true, &work.secondary.shadow),
    ] {
        let mut rays = set.clone();
        while rays.len() < engine::PILOT_MIN {
            rays.extend_from_within(..rays.len().min(engine::PILOT_MIN - rays.len()));
        }
        assert!(matches!(engine::choices(&accel, &rays), Choice::Try(_)));
        let packets = bench::Packets::new(&rays);
        let want = {
            let mut out = bench::Out::new(&accel, Engine::Scalar, any_hit, &rays);
            bench::pass(&accel, &rays, &packets, &mut out, None);
            out.results(rays.len())
        };
        assert!(want.count() > 0 && want.count() < rays.len());
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .expect("a pool");
        for pool in [None, Some(&pool)] {
            let mut out = bench::Out::new(&accel, Engine::Auto, any_hit, &rays);
            bench::pass(&accel, &rays, &packets, &mut out, pool);
            assert!(out.results(rays.len()) == want, "any hit {any_hit}");
        }
    }
}
