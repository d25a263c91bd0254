//! Render time of each canonical scene (SCENES.md §5) at 160x120 with the default engine, on
//! rayon's default pool. A checksum of the image (sum of the linear pixels) is computed outside
//! the timed loop and asserted equal on every render. Needs `WHITTED_ASSETS` (or `../shared`).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::path::PathBuf;
use std::time::Duration;
use whitted::io::scene::{SearchPath, build_scene};
use whitted::render::{Settings, World, render};
use whitted::scenes;

const SIZE: (u64, u64) = (160, 120);
const CANONICAL: [&str; 5] = ["phong", "vertex_color", "texture", "cubemap", "refraction"];

fn assets() -> PathBuf {
    std::env::var_os("WHITTED_ASSETS")
        .map(|v| std::env::split_paths(&v).next().unwrap())
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"))
}

fn world(name: &str) -> World {
    let mut file = scenes::builtin(name).unwrap();
    (file.image.width, file.image.height) = SIZE;
    let search = SearchPath {
        dirs: vec![assets()],
    };
    let (scene, _) = build_scene(&file, name.as_ref(), &search).expect("scene via WHITTED_ASSETS");
    World::new(scene)
}

fn checksum(world: &World, settings: &Settings) -> f64 {
    let (image, _) = render(world, settings, &|_| {});
    image.pixels.iter().map(|p| (p.x + p.y + p.z) as f64).sum()
}

fn bench(c: &mut Criterion) {
    let settings = Settings::default();
    let mut g = c.benchmark_group("render_160x120");
    g.sample_size(10);
    g.warm_up_time(Duration::from_millis(300));
    g.measurement_time(Duration::from_secs(2));
    g.throughput(Throughput::Elements(SIZE.0 * SIZE.1));
    for name in CANONICAL {
        let w = world(name);
        let sum = checksum(&w, &settings);
        assert!(sum.is_finite() && sum > 0.0, "{name}: {sum}");
        assert_eq!(checksum(&w, &settings), sum, "{name}: deterministic");
        g.bench_function(name, |b| b.iter(|| render(&w, &settings, &|_| {})));
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
