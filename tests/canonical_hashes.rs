//! The canonical scenes render bit for bit as they did before RGB coefficients, emission and
//! per-triangle materials: a hash of every pixel's f32 bits, for each scene and stage and
//! both engines, against the values the code computed before that change (commit a2208ca).
//!
//! To print the current values: `cargo test --release --test canonical_hashes -- --nocapture`.

mod common;

use common::world;
use whitted::render::{Engine, Settings, Stage, render};

/// FNV-1a over the bits of every channel of every pixel, row-major.
fn hash(pixels: &[glam::Vec3]) -> u64 {
    let mut h = 0xcbf29ce484222325u64;
    for p in pixels {
        for c in p.to_array() {
            for b in c.to_bits().to_le_bytes() {
                h = (h ^ b as u64).wrapping_mul(0x100000001b3);
            }
        }
    }
    h
}

fn cases() -> Vec<(&'static str, Option<Stage>, Engine, u32)> {
    let mut v = Vec::new();
    for name in whitted::scenes::NAMES {
        for engine in [Engine::Packet, Engine::Scalar] {
            v.push((name, None, engine, 2));
        }
    }
    for stage in Stage::ALL {
        v.push(("phong", Some(stage), Engine::Packet, 1));
    }
    v
}

/// Computed by the code before the change, in the order of `cases()`.
const EXPECTED: &[u64] = &[
    0x5d90498b36fb5afe,
    0x87d7291564abc971,
    0x05316adcd33c1eb3,
    0x15a1d433252862ce,
    0xa2fc5900ad1678f8,
    0x8737d633281618c7,
    0x5b1a8e6fc968a4ca,
    0x94bbc16100ad52a2,
    0x7e10a8e465b4c388,
    0x89ffb97727b3adac,
    0x6176808f5aad86e1,
    0x77a9c510a982c920,
    0xc10b632b692ab483,
    0xf8e2e6aeeecb1a2e,
    0x63b90c561809f3b2,
    0xdaf5eca0eec30ae2,
    0x30f7443bb242937f,
];

#[test]
fn canonical_scenes_render_bit_for_bit_as_before() {
    let mut got = Vec::new();
    for (name, stage, engine, spp) in cases() {
        let w = world(name, 96, 72);
        let settings = Settings {
            stage,
            spp,
            engine,
            ..Settings::default()
        };
        let (image, _) = render(&w, &settings, &|_| {});
        let h = hash(&image.pixels);
        println!("{name} {stage:?} {engine:?}: {h:#018x}");
        got.push(h);
    }
    assert_eq!(got, EXPECTED);
}
