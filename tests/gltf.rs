//! glTF end to end: the shipped cube as GLB renders exactly as the STL cube does (flat, no
//! NORMAL), the `.gltf` cube brings its material into the scene, and a broken file is one
//! error line naming the JSON path, with exit code 2.

mod common;

use common::whitted;
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    common::scratch("gltf", name)
}

fn render(mesh: &str, out: &Path) {
    common::render_small(mesh, out)
}

#[test]
fn glb_cube_renders_as_the_stl_cube() {
    let (glb, stl) = (tmp("glb.png"), tmp("stl.png"));
    render("meshes/cube.glb", &glb);
    render("meshes/cube.stl", &stl);
    let bytes = |p: &Path| image::open(p).unwrap().into_bytes();
    assert_eq!(bytes(&glb), bytes(&stl));
}

#[test]
fn gltf_materials_come_into_the_scene() {
    let (code, toml, err) = whitted(&["scene", "meshes/cube.gltf"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(toml.contains("name = \"red\""), "{toml}");
    let out = tmp("red.png");
    render("meshes/cube.gltf", &out);
    let px = image::open(&out).unwrap().to_rgb8();
    assert!(
        px.pixels().any(|p| p[0] > 2 * p[1].max(p[2]) && p[0] > 60),
        "a red cube"
    );
    let (code, out, err) = whitted(&["info", "meshes/cube.gltf"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        out.contains("triangles: 12\n") && out.contains("open_edges: 0\n"),
        "{out}"
    );
    assert!(out.contains("materials:") && out.contains("red"), "{out}");
}

#[test]
fn broken_gltf_is_one_error_line_with_the_json_path() {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/cube.gltf"))
            .unwrap();
    let bad = tmp("bad.gltf");
    std::fs::write(
        &bad,
        text.replacen("\"count\": 36", "\"count\": 3600000000", 1),
    )
    .unwrap();
    let (code, _, err) = whitted(&["render", bad.to_str().unwrap()]);
    assert_eq!(code, Some(2), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains("bad.gltf: glTF accessors[1].count: 3600000000 elements"),
        "{err}"
    );
}

/// A glTF camera is the view of the model rendered alone, and its lights light it
/// (`whitted scene` prints both).
#[test]
fn a_gltf_camera_and_lights_make_the_scene() {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/cube.gltf"))
            .unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    doc["cameras"] =
        serde_json::json!([{"type": "perspective", "perspective": {"yfov": 0.6, "znear": 0.1}}]);
    doc["nodes"][0]["children"] = serde_json::json!([1]);
    doc["nodes"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"camera": 0, "translation": [0, 0, 6]}));
    doc["extensions"] = serde_json::json!({"KHR_lights_punctual": {"lights": [{"type": "point"}]}});
    doc["scenes"][0]["nodes"] = serde_json::json!([0, 2]);
    doc["nodes"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({
            "translation": [3, 4, 5], "extensions": {"KHR_lights_punctual": {"light": 0}}
        }));
    let file = tmp("camera.gltf");
    std::fs::write(&file, serde_json::to_string(&doc).unwrap()).unwrap();
    let (code, toml, err) = whitted(&["scene", file.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{err}");
    assert!(toml.contains("eye = [0.0, 0.0, 6.0]"), "{toml}");
    assert!(toml.contains("look_at = [0.0, 0.0, 5.0]"), "{toml}");
    // Its one light, alone, at 0.9.
    assert!(
        toml.contains("position = [3.0, 4.0, 5.0]") && toml.contains("intensity = [0.9, 0.9, 0.9]"),
        "{toml}"
    );
    assert_eq!(toml.matches("[[light]]").count(), 1, "{toml}");
    render(file.to_str().unwrap(), &tmp("camera.png"));
}
