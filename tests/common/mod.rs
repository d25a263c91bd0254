//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;
use whitted::io::scene_file::{SearchPath, build_scene};
use whitted::render::{Settings, Stage, World};
use whitted::scenes;

/// The shared data folder: `WHITTED_ASSETS` when set (as `.ci/run` does), else `../shared`
/// beside the project. Panics (fails the test) when the data is missing.
pub fn assets() -> PathBuf {
    let dir = std::env::var_os("WHITTED_ASSETS")
        .map(|v| std::env::split_paths(&v).next().unwrap())
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../shared"));
    assert!(
        dir.join("meshes/kitten.m").is_file(),
        "shared data not found at {} (set WHITTED_ASSETS)",
        dir.display()
    );
    dir
}

/// A built-in scene at a small size, ready to render.
pub fn world(name: &str, width: u64, height: u64) -> World {
    let mut file = scenes::builtin(name).unwrap();
    file.image.width = width;
    file.image.height = height;
    let search = SearchPath {
        dirs: vec![assets()],
    };
    let (scene, _) = build_scene(&file, name.as_ref(), &search).unwrap();
    World::new(scene)
}

pub fn settings(stage: Option<Stage>) -> Settings {
    Settings {
        stage,
        ..Settings::default()
    }
}
