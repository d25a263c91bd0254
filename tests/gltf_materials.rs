//! glTF materials end to end: a GLB whose base colour texture is a PNG in its binary chunk,
//! sampled MIRRORED_REPEAT along u and CLAMP_TO_EDGE along v, becomes a scene texture with
//! those wrap modes and the texels written; its scene prints, reloads and renders; `whitted
//! info` lists its meshes, instances, lights, cameras and materials; the scene key `wrap` is
//! checked as every key is.

mod common;

use common::whitted;
use glam::{Vec2, Vec3};
use serde_json::json;
use std::path::{Path, PathBuf};
use whitted::io::scene::{SceneFile, SearchPath, build_scene};
use whitted::scene::Albedo;
use whitted::texture::Wrap;

fn tmp(name: &str) -> PathBuf {
    common::scratch("gltf-materials", name)
}

/// A 2x2 RGB PNG: red, green (top row), blue, white.
fn png() -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = png::Encoder::new(&mut out, 2, 2);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&[255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255])
        .unwrap();
    w.finish().unwrap();
    out
}

/// A square facing +z with uv from -1 to 2 (so the wrap modes show), material `tex` with
/// [`png`] as its base colour texture in the binary chunk, as a GLB file at `path`.
fn write_glb(path: &Path) {
    let f = |v: &[f32]| v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>();
    let mut bin = f(&[0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.]);
    bin.extend(f(&[-1., 2., 2., 2., 2., -1., -1., -1.]));
    bin.extend([0u16, 1, 2, 0, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    let png = png();
    bin.extend(&png);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "square"}],
        "meshes": [{"name": "square", "primitives": [{
            "attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12},
            {"buffer": 0, "byteOffset": 92, "byteLength": png.len()},
        ],
        "buffers": [{"byteLength": bin.len()}],
        "materials": [{"name": "tex", "pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0}, "metallicFactor": 0, "roughnessFactor": 1}}],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 33648, "wrapT": 33071}],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
    });
    std::fs::write(path, glb_bytes(&doc, &bin)).unwrap();
}

/// A GLB file's bytes: the JSON chunk (`doc`, padded with spaces) and the binary chunk `bin`
/// (a multiple of 4 bytes long).
fn glb_bytes(doc: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(doc).unwrap();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let total = 12 + 8 + text.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    for word in [2, total, text.len()] {
        out.extend((word as u32).to_le_bytes());
    }
    out.extend(b"JSON");
    out.extend(text);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(bin);
    out
}

#[test]
fn an_embedded_texture_keeps_its_texels_and_wrap_modes() {
    let glb = tmp("square.glb");
    write_glb(&glb);
    let (file, warnings) = whitted::io::mesh_scene::scene_for_mesh(&glb, 64, 48).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let search = SearchPath {
        dirs: vec![common::assets()],
    };
    let (scene, _) = build_scene(&file, &glb, &search).unwrap();
    let m = scene.materials.iter().find(|m| m.name == "tex").unwrap();
    let Albedo::Texture(t) = &m.albedo else {
        panic!("not textured: {:?}", m.albedo)
    };
    assert_eq!(t.wrap, [Wrap::MirroredRepeat, Wrap::Clamp]);
    assert_eq!(t.linear_texels(), [Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE]);
    // Texel centres by hand (x = 2u - 0.5, y = 2(1 - v) - 0.5; row 0 is red, green):
    // u = -0.25 is column -1, mirrored to 0 (repeat would read column 1, green).
    assert_eq!(t.sample_uv(Vec2::new(-0.25, 0.75)), Vec3::X);
    // u = 1.25 is column 2, mirrored to 1.
    assert_eq!(t.sample_uv(Vec2::new(1.25, 0.75)), Vec3::Y);
    // v = 1.25 is row -1, clamped to row 0 (repeat would read row 1, blue).
    assert_eq!(t.sample_uv(Vec2::new(0.25, 1.25)), Vec3::X);
    // v = -0.75 is row 3, clamped to row 1.
    assert_eq!(t.sample_uv(Vec2::new(0.75, -0.75)), Vec3::ONE);
    // Rendered, the square shows the texture's red and green.
    let out = tmp("square.png");
    common::render_small(glb.to_str().unwrap(), &out);
    let img = image::open(&out).unwrap().to_rgb8();
    let has = |f: &dyn Fn(&image::Rgb<u8>) -> bool| img.pixels().any(f);
    assert!(has(&|p| p[0] > 100 && p[1] < 40 && p[2] < 40), "red");
    assert!(has(&|p| p[1] > 100 && p[0] < 40 && p[2] < 40), "green");
}

/// `whitted scene` prints the texture as a reference into the GLB with its wrap modes; the
/// printed scene renders; replacing the colour source by `-D` drops the wrap modes with it.
#[test]
fn the_printed_scene_finds_the_embedded_image() {
    let glb = tmp("printed.glb");
    write_glb(&glb);
    let (code, toml, err) = whitted(&["scene", glb.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{err}");
    assert!(toml.contains("printed.glb#images[0]\""), "{toml}");
    assert!(
        toml.contains("wrap = [\"mirrored_repeat\", \"clamp_to_edge\"]"),
        "{toml}"
    );
    let scene = tmp("printed.toml");
    std::fs::write(&scene, &toml).unwrap();
    let out = tmp("printed.png");
    let args = [
        "render",
        scene.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ];
    let (code, _, err) = whitted(&[&args[..], &["--width", "32", "--height", "24"]].concat());
    assert_eq!(code, Some(0), "{err}");
    let (code, _, err) = whitted(
        &[
            &args[..],
            &[
                "--width",
                "32",
                "--height",
                "24",
                "-D",
                "material[0].color=[1, 0, 0]",
            ],
        ]
        .concat(),
    );
    assert_eq!(code, Some(0), "{err}");
}

#[test]
fn info_lists_meshes_instances_lights_cameras_and_materials() {
    let glb = tmp("info.glb");
    write_glb(&glb);
    let (code, out, err) = whitted(&["info", "--json", glb.to_str().unwrap()]);
    assert_eq!(code, Some(0), "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        v["meshes"],
        json!([{"index": 0, "name": "square", "primitives": 1, "triangles": 2, "nodes": [0], "instances": 1}])
    );
    assert_eq!(v["instances"], json!(1));
    assert_eq!(
        (v["lights"].clone(), v["cameras"].clone()),
        (json!([]), json!([]))
    );
    let m = &v["materials"][0];
    assert_eq!(m["name"], "tex");
    assert_eq!(m["wrap"], json!(["mirrored_repeat", "clamp_to_edge"]));
    assert!(
        m["texture"]
            .as_str()
            .unwrap()
            .ends_with("info.glb#images[0]"),
        "{m}"
    );
    // The shipped cube: one material, a rough metal by glTF's defaults (all diffuse).
    let (code, out, err) = whitted(&["info", "meshes/cube.gltf"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(out.contains("instances: 1\n"), "{out}");
    assert!(
        out.contains("\"kd\":1.0") && out.contains("\"ks\":0.0"),
        "{out}"
    );
}

/// `wrap` in a scene file: one mode or `[u, v]`, by glTF's names; anything else, or a wrap
/// with no texture to wrap, is an error naming the key.
#[test]
fn the_wrap_key_is_checked() {
    let scene = |material: &str| {
        format!(
            "[camera]\neye = [0, 0, 3]\nlook_at = [0, 0, 0]\n[[material]]\nname = \"m\"\n{material}\n\
             [[mesh]]\nmaterial = \"m\"\nshape = \"quad\"\n"
        )
    };
    let parse = |m: &str| SceneFile::parse(&scene(m), Path::new("s.toml"));
    let f =
        parse("checker = { squares = 2, a = [0, 0, 0], b = [1, 1, 1] }\nwrap = \"clamp_to_edge\"")
            .unwrap();
    assert_eq!(f.materials[0].wrap, Some([Wrap::Clamp; 2]));
    assert!(f.to_toml().contains("wrap = \"clamp_to_edge\""));
    let f = parse("texture = \"t.png\"\nwrap = [\"repeat\", \"mirrored_repeat\"]").unwrap();
    assert_eq!(
        f.materials[0].wrap,
        Some([Wrap::Repeat, Wrap::MirroredRepeat])
    );
    for (bad, want) in [
        (
            "texture = \"t.png\"\nwrap = \"sideways\"",
            "unknown wrap mode 'sideways'",
        ),
        (
            "texture = \"t.png\"\nwrap = [\"repeat\"]",
            "invalid length 1",
        ),
        (
            "texture = \"t.png\"\nwrap = 3",
            "wrap: expected a mode name or [u, v] mode names",
        ),
    ] {
        let e = parse(bad).unwrap_err().to_string();
        assert!(e.contains("s.toml:") && e.contains(want), "{bad}: {e}");
    }
    let f = parse("color = [1, 0, 0]\nwrap = \"repeat\"").unwrap();
    let search = SearchPath {
        dirs: vec![common::assets()],
    };
    let e = build_scene(&f, Path::new("s.toml"), &search)
        .unwrap_err()
        .to_string();
    assert!(e.contains("wrap: applies to a texture or checker"), "{e}");
}

/// An emissive material no face uses lights nothing, so the model keeps the canonical lights;
/// once a face uses it, its emission lights the model instead.
#[test]
fn only_emitters_in_use_replace_the_canonical_lights() {
    let glb = tmp("unused_lamp.glb");
    write_glb(&glb);
    let bytes = std::fs::read(&glb).unwrap();
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut doc: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let bin = &bytes[20 + json_len + 8..];
    doc["materials"]
        .as_array_mut()
        .unwrap()
        .push(json!({"name": "lamp", "emissiveFactor": [1, 1, 1]}));
    let write = |doc: &serde_json::Value, path: &Path| {
        std::fs::write(path, glb_bytes(doc, bin)).unwrap();
    };
    write(&doc, &glb);
    let (file, _) = whitted::io::mesh_scene::scene_for_mesh(&glb, 64, 48).unwrap();
    assert_eq!(file.lights.len(), 2, "the canonical lights");
    doc["meshes"][0]["primitives"][0]["material"] = json!(1);
    let used = tmp("used_lamp.glb");
    write(&doc, &used);
    let (file, _) = whitted::io::mesh_scene::scene_for_mesh(&used, 64, 48).unwrap();
    assert!(
        file.lights.is_empty(),
        "lit by its emitter: {:?}",
        file.lights
    );
}
