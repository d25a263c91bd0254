//! Writes an `n x n` field of kittens (`meshes/kitten.m`), each turned and scaled a little
//! at random, on a floor, seen from above one corner: as a scene file of `[[instance]]`
//! entries (`OUT.toml`), or as one GLB (`OUT.glb`) holding the kitten once, drawn by one
//! node with `EXT_mesh_gpu_instancing`, with its lights (`KHR_lights_punctual`) and camera.
//! The scale test of instancing (README, "Instances"; docs/instances.md):
//!
//!     cargo run --release --example kitten_field -- 100 field.glb
//!     /usr/bin/time -v whitted render field.glb --width 1920 --height 1080 -o field.png

use glam::{Mat3, Quat, Vec3};
use serde_json::json;
use std::fmt::Write;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(n), Some(out)) = (args.get(1).and_then(|n| n.parse::<u32>().ok()), args.get(2))
    else {
        eprintln!(
            "usage: kitten_field N OUT.toml|OUT.glb  (an N x N field of kittens: a scene file, or one GLB)"
        );
        std::process::exit(2);
    };
    let bytes = if out.ends_with(".glb") {
        glb(n)
    } else {
        toml(n).into_bytes()
    };
    std::fs::write(out, bytes).unwrap();
    eprintln!("{out}: {} kittens", n as u64 * n as u64);
}

/// The kitten mesh file.
fn kitten_path() -> std::path::PathBuf {
    std::path::absolute(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/kitten.m"))
        .unwrap()
}

/// The field's layout: half its width, the camera's eye and the two lights (position,
/// colour), shared by both formats. The kitten is about 2 units across: 3 apart, the field
/// centred on the origin.
struct Layout {
    half: f32,
    eye: Vec3,
    look_at: Vec3,
    lights: [(Vec3, [f32; 3]); 2],
}

fn layout(n: u32) -> Layout {
    let half = 1.5 * n as f32;
    let e = half * 1.1;
    let h2 = half + 5.0;
    Layout {
        half,
        eye: Vec3::new(e, half * 0.6 + 2.0, e),
        look_at: Vec3::new(0.0, -1.0, 0.0),
        lights: [
            (Vec3::new(half * 0.8, h2, half * 0.3), [0.9, 0.9, 0.85]),
            (Vec3::new(-half * 0.8, h2, half * 0.8), [0.35, 0.35, 0.45]),
        ],
    }
}

/// Every kitten's (translation, rotation about y in degrees, uniform scale), the same field
/// every time (xorshift).
fn kittens(n: u32) -> impl Iterator<Item = (Vec3, f32, f32)> {
    let half = 1.5 * n as f32;
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32
    };
    (0..n)
        .flat_map(move |i| (0..n).map(move |j| (i, j)))
        .map(move |(i, j)| {
            let x = 3.0 * i as f32 - half + 1.5;
            let z = 3.0 * j as f32 - half + 1.5;
            let degrees = (3600.0 * rnd()).round() / 10.0;
            let scale = (1000.0 * (0.8 + 0.4 * rnd())).round() / 1000.0;
            (Vec3::new(x, 0.0, z), degrees, scale)
        })
}

/// The field as a scene file: one `[[instance]]` per kitten.
pub fn toml(n: u32) -> String {
    let l = layout(n);
    let kitten = kitten_path().display().to_string().replace('\\', "/");
    let [(p0, c0), (p1, c1)] = l.lights;
    let mut s = format!(
        r#"[image]
width = 1920
height = 1080
[camera]
eye = {:?}
look_at = {:?}
vfov = 50
[render]
depth = 2
[[light]]
position = {:?}
intensity = {c0:?}
[[light]]
position = {:?}
intensity = {c1:?}
[[material]]
name = "fur"
color = [0.95, 0.6, 0.3]
ks = 0.3
n = 40
[[material]]
name = "floor"
color = [0.5, 0.55, 0.6]
ks = 0.2
n = 10
[[mesh]]
name = "kitten"
file = "{kitten}"
material = "fur"
[[mesh]]
shape = "quad"
center = [0, -1.1, 0]
size = [{floor}, 1, {floor}]
material = "floor"
"#,
        l.eye.to_array(),
        l.look_at.to_array(),
        p0.to_array(),
        p1.to_array(),
        floor = 2.0 * l.half + 4.0,
    );
    for (t, degrees, scale) in kittens(n) {
        writeln!(
            s,
            "[[instance]]\nmesh = \"kitten\"\ntranslate = [{}, 0, {}]\nrotate = [0, {degrees}, 0]\nscale = {scale}",
            t.x, t.z
        )
        .unwrap();
    }
    s
}

/// The field as one GLB: the kitten (positions, normals, u32 indices) and the floor stored
/// once each; node 0 draws the kitten at every TRANSLATION/ROTATION/SCALE of its
/// `EXT_mesh_gpu_instancing`; a camera node and two point lights (`KHR_lights_punctual`,
/// each intensity its squared distance to the field's centre times the scene file's
/// light, since whitted reads glTF lights relative to the model's centre).
pub fn glb(n: u32) -> Vec<u8> {
    let l = layout(n);
    let (kitten, _) = whitted::io::load_mesh(&kitten_path()).unwrap();
    let normals = kitten.normals.clone().unwrap();
    let a = l.half + 2.0;
    let floor: [Vec3; 4] = [
        Vec3::new(-a, -1.1, -a),
        Vec3::new(-a, -1.1, a),
        Vec3::new(a, -1.1, a),
        Vec3::new(a, -1.1, -a),
    ];
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    // one buffer view and accessor per array (every element 4-byte aligned)
    let mut push = |bytes: Vec<u8>, component: u32, kind: &str, count: usize| {
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len()}));
        bin.extend(bytes);
        accessors.push(json!({
            "bufferView": views.len() - 1, "componentType": component, "count": count, "type": kind,
        }));
        accessors.len() - 1
    };
    let floats = |v: &[Vec3]| -> Vec<u8> {
        v.iter()
            .flat_map(|p| p.to_array())
            .flat_map(f32::to_le_bytes)
            .collect()
    };
    let ints =
        |v: &[[u32; 3]]| -> Vec<u8> { v.iter().flatten().flat_map(|i| i.to_le_bytes()).collect() };
    let np = kitten.positions.len();
    let positions = push(floats(&kitten.positions), 5126, "VEC3", np);
    push(floats(&normals), 5126, "VEC3", np);
    push(
        ints(&kitten.triangles),
        5125,
        "SCALAR",
        3 * kitten.triangles.len(),
    );
    let floor_positions = push(floats(&floor), 5126, "VEC3", 4);
    push(floats(&[Vec3::Y; 4]), 5126, "VEC3", 4);
    push(ints(&[[0, 1, 2], [0, 2, 3]]), 5125, "SCALAR", 6);
    let (mut t, mut r, mut s) = (Vec::new(), Vec::new(), Vec::new());
    for (pos, degrees, scale) in kittens(n) {
        t.extend(pos.to_array());
        r.extend(Quat::from_rotation_y(degrees.to_radians()).to_array());
        s.extend([scale; 3]);
    }
    let copies = n as usize * n as usize;
    let bytes = |v: Vec<f32>| {
        v.into_iter()
            .flat_map(f32::to_le_bytes)
            .collect::<Vec<u8>>()
    };
    push(bytes(t), 5126, "VEC3", copies);
    push(bytes(r), 5126, "VEC4", copies);
    push(bytes(s), 5126, "VEC3", copies);
    // POSITION accessors carry their bounds, as the spec asks
    for (k, points) in [
        (positions, &kitten.positions[..]),
        (floor_positions, &floor[..]),
    ] {
        let lo = points.iter().fold(Vec3::INFINITY, |m, p| m.min(*p));
        let hi = points.iter().fold(Vec3::NEG_INFINITY, |m, p| m.max(*p));
        accessors[k]["min"] = json!(lo.to_array());
        accessors[k]["max"] = json!(hi.to_array());
    }
    // the camera looks down its -z with +y up
    let f = (l.look_at - l.eye).normalize();
    let right = f.cross(Vec3::Y).normalize();
    let up = right.cross(f);
    let camera_rotation = Quat::from_mat3(&Mat3::from_cols(right, up, -f));
    let centre = Vec3::new(0.0, 0.0, 0.0);
    let light = |k: usize| {
        let (p, c) = l.lights[k];
        json!({
            "type": "point",
            "color": c.map(|x| x / 0.9),
            "intensity": 0.9 * p.distance_squared(centre),
        })
    };
    let light_node = |k: usize| json!({"translation": l.lights[k].0.to_array(), "extensions": {"KHR_lights_punctual": {"light": k}}});
    let material = |name: &str, c: [f32; 3]| {
        json!({"name": name, "pbrMetallicRoughness": {
            "baseColorFactor": [c[0], c[1], c[2], 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0
        }})
    };
    let doc = json!({
        "asset": {"version": "2.0", "generator": "whitted examples/kitten_field.rs"},
        "extensionsUsed": ["EXT_mesh_gpu_instancing", "KHR_lights_punctual"],
        "extensionsRequired": ["EXT_mesh_gpu_instancing"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3, 4]}],
        "nodes": [
            {"name": "kittens", "mesh": 0, "extensions": {"EXT_mesh_gpu_instancing": {
                "attributes": {"TRANSLATION": 6, "ROTATION": 7, "SCALE": 8}
            }}},
            {"name": "floor", "mesh": 1},
            {"name": "camera", "camera": 0, "translation": l.eye.to_array(),
             "rotation": camera_rotation.to_array()},
            light_node(0),
            light_node(1),
        ],
        "cameras": [{"type": "perspective", "perspective": {
            "yfov": 50f32.to_radians(), "znear": 0.1, "aspectRatio": 16.0 / 9.0
        }}],
        "meshes": [
            {"name": "kitten", "primitives": [
                {"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}
            ]},
            {"name": "floor", "primitives": [
                {"attributes": {"POSITION": 3, "NORMAL": 4}, "indices": 5, "material": 1}
            ]},
        ],
        "materials": [material("fur", [0.95, 0.6, 0.3]), material("floor", [0.5, 0.55, 0.6])],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
        "extensions": {"KHR_lights_punctual": {"lights": [light(0), light(1)]}},
    });
    container(&serde_json::to_vec(&doc).unwrap(), bin)
}

/// A GLB container of `json` and the binary chunk `bin`, each padded to 4 bytes.
fn container(json: &[u8], mut bin: Vec<u8>) -> Vec<u8> {
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(0x4E4F_534Au32.to_le_bytes());
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(0x004E_4942u32.to_le_bytes());
    out.extend(bin);
    out
}
