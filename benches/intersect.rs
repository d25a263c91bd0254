//! Intersection throughput on the kitten: the canonical camera's primary rays (1920x1080, no
//! floor, ~90% miss, as in the Embree peer's `primary` workload), scalar vs packet engine.
//! A checksum of the hits is asserted outside the timed loop. Needs `WHITTED_ASSETS`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::Vec3;
use std::path::PathBuf;
use whitted::accel::{Accel, BuildQuality};
use whitted::camera::Camera;
use whitted::ray::Ray;
use whitted::trace::{Engine, trace_rays};

fn kitten() -> Accel {
    let dir = std::env::var_os("WHITTED_ASSETS")
        .map(|v| std::env::split_paths(&v).next().unwrap())
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    let (mesh, _) =
        whitted::io::load_mesh(&dir.join("meshes/kitten.m")).expect("kitten.m via WHITTED_ASSETS");
    let tris: Vec<[Vec3; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect();
    Accel::build(&tris, BuildQuality::Medium)
}

/// Primary rays in 4x2 pixel blocks (packet lanes are neighbouring pixels).
fn primary_rays(w: u32, h: u32) -> Vec<Ray> {
    let cam = Camera::new(
        Vec3::new(1.6, 0.9, 4.4),
        Vec3::new(0.0, -0.15, 0.0),
        Vec3::Y,
        36.0,
        w,
        h,
    );
    let mut rays = Vec::with_capacity((w * h) as usize);
    for by in (0..h).step_by(2) {
        for bx in (0..w).step_by(4) {
            for k in 0..8 {
                let (x, y) = (bx + k % 4, by + k / 4);
                if x < w && y < h {
                    rays.push(cam.primary_ray(x, y));
                }
            }
        }
    }
    rays
}

fn checksum(hits: &[Option<whitted::ray::Hit>]) -> (usize, u64) {
    let n = hits.iter().flatten().count();
    (n, hits.iter().flatten().map(|h| h.tri as u64).sum())
}

fn bench(c: &mut Criterion) {
    let accel = kitten();
    let rays = primary_rays(1920, 1080);
    let reference = checksum(&trace_rays(&accel, &rays, Engine::Scalar, false));
    assert!(
        reference.0 > 150_000,
        "about 10% of primary rays hit the kitten"
    );
    let mut g = c.benchmark_group("primary");
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.sample_size(10);
    for (name, engine) in [("scalar", Engine::Scalar), ("packet8", Engine::Packet)] {
        assert_eq!(
            checksum(&trace_rays(&accel, &rays, engine, false)),
            reference,
            "{name}"
        );
        g.bench_function(name, |b| {
            b.iter(|| trace_rays(&accel, &rays, engine, false))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
