//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;
use whitted::io::scene::{SearchPath, build_scene};
use whitted::render::{Settings, Stage, World};
use whitted::scenes;

/// The project's own data folder (the shipped `meshes/` and `textures/`): the tests need no
/// `WHITTED_ASSETS` and nothing beside the repository.
pub fn assets() -> PathBuf {
    let dir = PathBuf::from(whitted::io::scene::PROJECT_DATA);
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

/// A camera inside a closed cube whose walls both reflect and refract (`ks = kt = 0.5`),
/// culling off, depth 64: every sample's ray tree passes the budget.
pub const TRAP: &str = r#"
[image]
width = 32
height = 24
[camera]
eye = [0, 0, 0]
look_at = [0, 0, -1]
vfov = 60
[render]
depth = 64
cull_backfaces = false
[background]
color = [0.1, 0.2, 0.3]
[[light]]
position = [0.2, 0.3, 0.1]
intensity = [1, 1, 1]
[[material]]
name = "glassmirror"
color = [0.8, 0.8, 0.8]
ka = 0.1
kd = 0.2
ks = 0.5
kt = 0.5
ior = 1.5
n = 20
[[mesh]]
material = "glassmirror"
shape = "cube"
"#;

/// Run the `whitted` binary from the repository's folder, without `WHITTED_ASSETS`: its exit
/// code, standard output and standard error.
pub fn whitted(args: &[&str]) -> (Option<i32>, String, String) {
    let r = Command::new(env!("CARGO_BIN_EXE_whitted"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("WHITTED_ASSETS")
        .output()
        .unwrap();
    (
        r.status.code(),
        String::from_utf8_lossy(&r.stdout).into_owned(),
        String::from_utf8_lossy(&r.stderr).into_owned(),
    )
}

/// `name` in this test process's scratch folder for `what` (made if missing).
pub fn scratch(what: &str, name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("whitted-{what}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// `whitted render MESH` at 64x48 into `out`, which must succeed.
pub fn render_small(mesh: &str, out: &Path) {
    let (code, _, stderr) = whitted(&[
        "render",
        mesh,
        "--width",
        "64",
        "--height",
        "48",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{mesh}: {stderr}");
}
