//! Measurements behind two design choices (not assertions; run on demand):
//!
//! ```sh
//! WHITTED_ASSETS=/path/to/course-meshes cargo test --release --test measure -- --ignored --nocapture
//! ```
//!
//! 1. obvhs build preset: build time (kitten, bunny, subdivided kittens) and the packet
//!    engine's primary-ray throughput on the resulting tree.
//! 2. camera packet shape: 4x2 pixel blocks against 8x1 rows.
//! 3. the wavefront issue's speed criterion: `phong` at 3840x2160 on one thread, scalar
//!    and packet engines alternately in the same run, best of 3 each, and their ratio.
//! 4. the 8-wide tree: collapsed from the BVH2 against taken from obvhs's CWBVH.

mod common;

use glam::Vec3;
use std::time::Instant;
use whitted::accel::{Accel, BuildQuality, intersect8};
use whitted::camera::Camera;
use whitted::io::load_mesh;
use whitted::packet::{PacketShape, camera_packet};

fn tris_of(name: &str, subdivide: u32) -> Vec<[Vec3; 3]> {
    let (m, _) = load_mesh(&common::assets().join("meshes").join(name)).unwrap();
    let m = m.subdivide(subdivide);
    m.triangles
        .iter()
        .map(|t| t.map(|i| m.positions[i as usize]))
        .collect()
}

/// Single-threaded primary rays of the canonical camera at 1920x1080, in packets of `shape`.
fn primary_mrays(accel: &Accel, shape: PacketShape) -> (f64, usize) {
    let (w, h) = (1920, 1080);
    let cam = Camera::new(
        Vec3::new(1.6, 0.9, 4.4),
        Vec3::new(0.0, -0.15, 0.0),
        Vec3::Y,
        36.0,
        w,
        h,
    );
    let (pw, ph) = shape.size();
    let mut best = f64::MAX;
    let mut hits = 0;
    for _ in 0..3 {
        let start = Instant::now();
        hits = 0;
        for y in (0..h).step_by(ph as usize) {
            for x in (0..w).step_by(pw as usize) {
                let (p, active) = camera_packet(&cam, shape, x, y, 0.5, 0.5);
                let hp = intersect8(accel, &p, active, false);
                hits += whitted::simd::bitmask(hp.hit_mask()).count_ones() as usize;
            }
        }
        best = best.min(start.elapsed().as_secs_f64());
    }
    ((w * h) as f64 / best / 1e6, hits)
}

#[test]
#[ignore]
fn build_presets() {
    println!("| mesh | triangles | preset | build ms | primary packet Mrays/s (1 thread) |");
    println!("|---|---|---|---|---|");
    for (name, sub) in [
        ("kitten.m", 0),
        ("stanford-bunny.obj", 0),
        ("kitten.m", 1),
        ("kitten.m", 2),
        ("kitten.m", 3),
    ] {
        let tris = tris_of(name, sub);
        for q in BuildQuality::ALL {
            let a = Accel::build(&tris, q);
            let speed = if name == "kitten.m" {
                format!("{:.1}", primary_mrays(&a, PacketShape::Block4x2).0)
            } else {
                "-".into()
            };
            println!(
                "| {name} sub {sub} | {} | {q:?} | {:.1} | {speed} |",
                tris.len(),
                a.build_time.as_secs_f64() * 1e3
            );
        }
    }
}

#[test]
#[ignore]
fn packet_shapes() {
    let a = Accel::build(&tris_of("kitten.m", 0), BuildQuality::Medium);
    for shape in [PacketShape::Block4x2, PacketShape::Row8x1] {
        let (mrays, hits) = primary_mrays(&a, shape);
        println!("{shape:?}: {mrays:.1} Mrays/s ({hits} hits)");
    }
}

#[test]
#[ignore]
fn engine_speed_4k_phong() {
    use whitted::render::{Engine, Settings, render};
    let w = common::world("phong", 3840, 2160);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let mut best = [f64::INFINITY; 2];
    let mut images = Vec::new();
    for _ in 0..3 {
        for (k, engine) in [Engine::Scalar, Engine::Packet].into_iter().enumerate() {
            let s = Settings {
                engine,
                ..Settings::default()
            };
            let (image, stats) = pool.install(|| render(&w, &s, &|_| {}));
            let t = stats.time.as_secs_f64();
            println!("{engine:?}: {t:.3} s, {} rays", stats.rays.total());
            best[k] = best[k].min(t);
            images.push(image);
        }
    }
    let max = images[0]
        .pixels
        .iter()
        .zip(&images[1].pixels)
        .map(|(a, b)| (*a - *b).abs().max_element())
        .fold(0f32, f32::max);
    println!(
        "phong 3840x2160, 1 thread, best of 3: scalar {:.3} s, packet {:.3} s, {:.2}x \
         (max pixel difference {max:e})",
        best[0],
        best[1],
        best[0] / best[1]
    );
}

/// The 8-wide tree collapsed from the BVH2 (`Bvh8::collapse`, what whitted uses) against the
/// one taken from obvhs's CWBVH (`from_cwbvh`): build time of each path and the single-ray
/// engine's throughput on the bench workloads, alternating, best of 3, one thread.
#[test]
#[ignore]
fn wide_tree_collapse_against_cwbvh() {
    use obvhs::{BvhBuildParams, aabb::Aabb, cwbvh::builder::build_cwbvh};
    use whitted::bench::{Engine, Out, Packets, Workloads, pass, subdivide_like_peer, triangles};
    let (kitten, _) = load_mesh(&common::assets().join("meshes/kitten.m")).unwrap();
    for sub in [0, 2, 3] {
        let mesh = subdivide_like_peer(&kitten, sub);
        let tris = triangles(&mesh);
        let aabbs: Vec<Aabb> = tris
            .iter()
            .map(|t| {
                Aabb::new(
                    t[0].min(t[1]).min(t[2]).into(),
                    t[0].max(t[1]).max(t[2]).into(),
                )
            })
            .collect();
        let mut ours = Accel::build(&tris, BuildQuality::Medium);
        let (mut collapse_ms, mut cw_ms) = (f64::MAX, f64::MAX);
        let mut cw_tree = Default::default();
        for _ in 0..3 {
            let t = Instant::now();
            ours.wide = whitted::accel::Bvh8::collapse(&ours);
            collapse_ms = collapse_ms.min(t.elapsed().as_secs_f64() * 1e3);
            let t = Instant::now();
            let cw = build_cwbvh(
                &aabbs,
                BvhBuildParams::medium_build(),
                &mut Default::default(),
            );
            cw_tree = whitted::accel::wide::from_cwbvh(&ours, &cw);
            cw_ms = cw_ms.min(t.elapsed().as_secs_f64() * 1e3);
        }
        let mut theirs = ours.clone();
        theirs.wide = cw_tree;
        println!(
            "kitten sub{sub} ({} triangles): BVH2 {:.1} ms + collapse {collapse_ms:.1} ms, {:.1} B/tri | CWBVH build + conversion {cw_ms:.1} ms, {:.1} B/tri",
            tris.len(),
            ours.build_time.as_secs_f64() * 1e3 - ours.collapse_time.as_secs_f64() * 1e3,
            ours.wide.bytes() as f64 / tris.len() as f64,
            theirs.wide.bytes() as f64 / tris.len() as f64,
        );
        let work = Workloads::generate(&mesh, &ours, 1920, 1080);
        for (w, rays) in work.sets() {
            let packets = Packets::new(rays);
            let mut best = [f64::MAX; 2];
            let mut results = vec![];
            for _ in 0..3 {
                for (k, a) in [&ours, &theirs].into_iter().enumerate() {
                    let mut out = Out::new(&ours, Engine::Wide, w.any_hit(), rays);
                    let t = Instant::now();
                    pass(a, rays, &packets, &mut out, None);
                    best[k] = best[k].min(t.elapsed().as_secs_f64());
                    results.push(out.results(rays.len()));
                }
            }
            assert!(
                results.windows(2).all(|p| p[0] == p[1]),
                "both trees give the same hits"
            );
            let m = |s: f64| rays.len() as f64 / s / 1e6;
            println!(
                "  {:<18} wide1 on collapse {:7.2} Mrays/s | on CWBVH {:7.2} Mrays/s",
                w.name(),
                m(best[0]),
                m(best[1])
            );
        }
    }
}
