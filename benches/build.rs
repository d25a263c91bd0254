//! BVH build time (whitted's default quality, one thread, the BVH2 and its 8-wide collapse) for the kitten (20k triangles), the
//! Stanford bunny and the kitten subdivided 1, 2 and 3 times (82k, 327k, 1.3M triangles, the
//! Embree peer's subdivision). The tree's node count and depth are asserted outside the timed
//! loop. Needs `WHITTED_ASSETS` (or `../shared`).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use std::path::PathBuf;
use std::time::Duration;
use whitted::accel::{Accel, BuildQuality};
use whitted::bench::{subdivide_like_peer, triangles};

fn assets() -> PathBuf {
    std::env::var_os("WHITTED_ASSETS")
        .map(|v| std::env::split_paths(&v).next().unwrap())
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"))
}

fn bench(c: &mut Criterion) {
    let load = |name: &str| {
        whitted::io::load_mesh(&assets().join("meshes").join(name))
            .expect("meshes via WHITTED_ASSETS")
            .0
    };
    let kitten = load("kitten.m");
    let cases = [
        ("kitten", subdivide_like_peer(&kitten, 0)),
        ("bunny", subdivide_like_peer(&load("stanford-bunny.obj"), 0)),
        ("kitten-sub1", subdivide_like_peer(&kitten, 1)),
        ("kitten-sub2", subdivide_like_peer(&kitten, 2)),
        ("kitten-sub3", subdivide_like_peer(&kitten, 3)),
    ];
    let mut g = c.benchmark_group("bvh_build");
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(200));
    g.measurement_time(Duration::from_secs(2));
    for (name, mesh) in &cases {
        let tris = triangles(mesh);
        // checksum: every triangle in exactly one leaf, a sane depth
        let a = Accel::build(&tris, BuildQuality::default());
        assert_eq!(a.tris.len(), tris.len(), "{name}");
        let mut prims = a.tris.prim.clone();
        prims.sort_unstable();
        assert!(
            prims.iter().enumerate().all(|(i, &p)| p == i as u32),
            "{name}"
        );
        assert!(a.depth > 8 && a.depth < 64, "{name}: depth {}", a.depth);
        let leaf_tris: usize = a.wide.blocks.iter().map(|b| b.triangles()).sum();
        assert_eq!(
            leaf_tris,
            tris.len(),
            "{name}: every triangle in one wide leaf"
        );
        g.throughput(Throughput::Elements(tris.len() as u64));
        g.bench_with_input(BenchmarkId::from_parameter(name), &tris, |b, t| {
            b.iter(|| Accel::build(t, BuildQuality::default()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
