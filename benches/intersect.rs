//! Intersection throughput on the kitten, on the Embree peer's workloads (`whitted::bench`):
//! primary (1920x1080 in 4x4 pixel blocks, ~90% miss), primary-hits-only, shadow (any hit)
//! and incoherent, for every engine (`whitted::bench::ENGINES`: scalar, packet8, wide1,
//! hybrid8, packet16), single-threaded. The hit count and a checksum of
//! the results are asserted outside the timed loop. Needs `WHITTED_ASSETS` (or `../shared`).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::path::PathBuf;
use std::time::Duration;
use whitted::accel::{Accel, BuildQuality};
use whitted::bench::{Engine, Out, Packets, Workload, Workloads, pass, triangles};

fn assets() -> PathBuf {
    std::env::var_os("WHITTED_ASSETS")
        .map(|v| std::env::split_paths(&v).next().unwrap())
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"))
}

fn bench(c: &mut Criterion) {
    let (mesh, _) = whitted::io::load_mesh(&assets().join("meshes/kitten.m"))
        .expect("kitten.m via WHITTED_ASSETS");
    let accel = Accel::build(&triangles(&mesh), BuildQuality::default());
    let work = Workloads::generate(&mesh, &accel, whitted::bench::WIDTH, whitted::bench::HEIGHT);
    for (workload, rays) in work.sets() {
        let packets = Packets::new(rays);
        let any = workload.any_hit();
        // checksum: every engine gives the same results, with the peer's counts on the kitten
        let mut reference = Out::new(&accel, Engine::Scalar, any, rays);
        pass(&accel, rays, &packets, &mut reference, None);
        let reference = reference.results(rays.len());
        let expect = match workload {
            Workload::Primary | Workload::PrimaryHits => 201702,
            Workload::Shadow => 61028,
            Workload::Incoherent => 26102,
            Workload::Random => 133563,
        };
        assert!(
            reference.count().abs_diff(expect) <= 5,
            "{}: {} hits",
            workload.name(),
            reference.count()
        );
        let mut g = c.benchmark_group(workload.name());
        g.throughput(Throughput::Elements(rays.len() as u64));
        g.sample_size(10);
        g.warm_up_time(Duration::from_millis(500));
        g.measurement_time(Duration::from_secs(2));
        for engine in whitted::bench::ENGINES {
            let mut out = Out::new(&accel, engine, any, rays);
            pass(&accel, rays, &packets, &mut out, None);
            let got = out.results(rays.len());
            assert_eq!(got.checksum(), reference.checksum(), "{}", engine.name());
            g.bench_function(engine.name(), |b| {
                b.iter(|| pass(&accel, rays, &packets, &mut out, None))
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
