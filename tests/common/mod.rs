//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;
use whitted::io::scene_file::{SearchPath, build_scene};
use whitted::render::{Settings, Stage, World};
use whitted::scenes;

/// The project's own data folder (the shipped `meshes/` and `textures/`): the tests need no
/// `WHITTED_ASSETS` and nothing beside the repository.
pub fn assets() -> PathBuf {
    let dir = PathBuf::from(whitted::io::scene_file::PROJECT_DATA);
    assert!(
        dir.join("meshes/kitten.m").is_file(),
        "the shipped data is missing from {}",
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
