//! The glTF reader: GLB and `.gltf` with data URIs, node transforms flattened, attributes,
//! materials, and every error naming the file and the JSON path.

use super::*;
use crate::io::model::NO_MATERIAL;
use crate::io::scene::schema::Coef;
use glam::{Vec2, Vec3};
use serde_json::{Value, json};

/// Little-endian bytes of `f32`s.
pub(super) fn floats(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A document with one buffer holding `positions` (VEC3 floats, accessor 0) and, when
/// given, u16 `indices` (accessor 1); one mesh of one primitive, one node.
pub(super) fn doc(positions: &[f32], indices: Option<&[u16]>) -> (Value, Vec<u8>) {
    let mut bin = floats(positions);
    let pos_len = bin.len();
    let mut accessors = vec![json!({
        "bufferView": 0, "componentType": 5126, "count": positions.len() / 3, "type": "VEC3"
    })];
    let mut views = vec![json!({"buffer": 0, "byteLength": pos_len})];
    let mut prim = json!({"attributes": {"POSITION": 0}});
    if let Some(ix) = indices {
        let start = bin.len();
        bin.extend(ix.iter().flat_map(|i| i.to_le_bytes()));
        views.push(json!({"buffer": 0, "byteOffset": start, "byteLength": ix.len() * 2}));
        accessors.push(json!({
            "bufferView": 1, "componentType": 5123, "count": ix.len(), "type": "SCALAR"
        }));
        prim["indices"] = json!(1);
    }
    let d = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [prim]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
    });
    (d, bin)
}

/// `d` as a GLB file with `bin` as its binary chunk (buffer 0 has no uri).
pub(super) fn glb(d: &Value, bin: &[u8]) -> Vec<u8> {
    let mut json = serde_json::to_vec(d).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = b"glTF".to_vec();
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(CHUNK_JSON.to_le_bytes());
    out.extend(json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(CHUNK_BIN.to_le_bytes());
    out.extend(bin);
    out
}

/// `d` as `.gltf` text with `bin` in a base64 data URI.
pub(super) fn embedded(mut d: Value, bin: &[u8]) -> Vec<u8> {
    const ABC: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut b64 = String::new();
    for c in bin.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                b64.push(ABC[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                b64.push('=');
            }
        }
    }
    d["buffers"][0]["uri"] = json!(format!("data:application/octet-stream;base64,{b64}"));
    serde_json::to_vec(&d).unwrap()
}

pub(super) fn parse(bytes: &[u8]) -> Result<(Model, Vec<String>)> {
    parse_with(bytes, Path::new("t.gltf"), &mut |name| {
        Err(Error::parse(Path::new(name), 0, "no files in tests"))
    })
}

pub(super) fn err(bytes: &[u8]) -> String {
    parse(bytes).unwrap_err().to_string()
}

const TRI: [f32; 9] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
pub(super) const SQUARE: [f32; 12] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0];

#[test]
fn glb_and_data_uri_read_the_same_flat_mesh() {
    let (d, bin) = doc(&SQUARE, Some(&[0, 1, 2, 0, 2, 3]));
    let (a, _) = parse(&glb(&d, &bin)).unwrap();
    let (b, _) = parse(&embedded(d, &bin)).unwrap();
    assert_eq!(a.mesh, b.mesh);
    assert_eq!(a.mesh.triangles.len(), 2);
    assert!(!a.file_normals);
    assert!(a.mesh.normals.unwrap().iter().all(|&n| n == Vec3::Z));
    assert!(a.face_materials.is_none());
    // Not indexed: every three positions are a triangle.
    let (d, bin) = doc(&TRI, None);
    assert_eq!(parse(&glb(&d, &bin)).unwrap().0.mesh.triangles, [[0, 1, 2]]);
}

/// Two nodes share one mesh: a translated child and a mirrored one (`matrix`, scale -1 in
/// x); flattened, the mirror keeps the triangle facing +z by swapping two corners.
#[test]
fn node_transforms_are_flattened() {
    let (mut d, bin) = doc(&TRI, None);
    d["nodes"] = json!([
        {"children": [1, 2], "translation": [0, 0, 5]},
        {"mesh": 0, "translation": [10, 0, 0], "scale": [2, 2, 2]},
        {"mesh": 0, "matrix": [-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]},
    ]);
    let (m, _) = parse(&glb(&d, &bin)).unwrap();
    // (a mesh drawn twice is stored once: flattened here to look at its copies)
    assert_eq!((m.shared.len(), m.mesh.triangles.len()), (1, 0));
    let m = m.flattened(Path::new("t.gltf"), 2).unwrap();
    let mesh = &m.mesh;
    assert_eq!(mesh.triangles.len(), 2);
    let corners = |t: usize| mesh.triangles[t].map(|v| mesh.positions[v as usize]);
    assert_eq!(corners(0)[1], Vec3::new(12.0, 0.0, 5.0));
    assert!(corners(1).contains(&Vec3::new(-1.0, 0.0, 5.0)));
    for t in 0..2 {
        assert!(mesh.face_cross(t).z > 0.0, "triangle {t} faces +z");
    }
    // A rotation quaternion: 90 degrees about z.
    let (mut d, bin) = doc(&TRI, None);
    let h = std::f32::consts::FRAC_1_SQRT_2;
    d["nodes"] = json!([{"mesh": 0, "rotation": [0, 0, h, h]}]);
    let (m, _) = parse(&glb(&d, &bin)).unwrap();
    assert!(m.mesh.positions.iter().any(|p| p.distance(Vec3::Y) < 1e-6));
}

/// NORMAL, TEXCOORD_0 (v flipped: glTF's v runs down the image) and COLOR_0 (normalised
/// u8, alpha dropped).
#[test]
fn attributes_are_read() {
    let (mut d, mut bin) = doc(&TRI, None);
    let start = bin.len();
    bin.extend(floats(&[0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 0.0, 0.0, 2.0]));
    bin.extend(floats(&[0.0, 0.0, 1.0, 0.25, 0.5, 1.0]));
    bin.extend([255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255]);
    d["bufferViews"] = json!([
        {"buffer": 0, "byteLength": 36},
        {"buffer": 0, "byteOffset": start, "byteLength": 36},
        {"buffer": 0, "byteOffset": start + 36, "byteLength": 24},
        {"buffer": 0, "byteOffset": start + 60, "byteLength": 12},
    ]);
    d["accessors"] = json!([
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
        {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
        {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"},
        {"bufferView": 3, "componentType": 5121, "normalized": true, "count": 3, "type": "VEC4"},
    ]);
    d["meshes"][0]["primitives"][0]["attributes"] =
        json!({"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2, "COLOR_0": 3});
    d["buffers"][0]["byteLength"] = json!(bin.len());
    let (m, _) = parse(&glb(&d, &bin)).unwrap();
    assert!(m.file_normals);
    let mesh = m.mesh;
    assert!(mesh.normals.unwrap().iter().all(|&n| n == Vec3::Z));
    assert_eq!(mesh.uvs.unwrap()[2], Vec2::new(0.5, 0.0));
    assert_eq!(mesh.colors.unwrap()[1], Vec3::Y);
}

/// baseColorFactor is `Od`; faces without a material have none; a texture on a mesh
/// without uv is not read (a warning), the factor is used.
#[test]
fn materials_map_base_colour() {
    let (mut d, bin) = doc(&SQUARE, Some(&[0, 1, 2, 0, 2, 3]));
    let prim = d["meshes"][0]["primitives"][0].clone();
    let mut second = prim.clone();
    second["material"] = json!(0);
    d["meshes"][0]["primitives"] = json!([prim, second]);
    d["materials"] = json!([{"name": "red", "emissiveFactor": [0.5, 0.25, 0], "pbrMetallicRoughness": {
        "baseColorFactor": [1, 0, 0, 1], "baseColorTexture": {"index": 0}}}]);
    d["textures"] = json!([{"source": 0}]);
    d["images"] = json!([{"bufferView": 0, "mimeType": "image/png"}]);
    let (m, w) = parse(&glb(&d, &bin)).unwrap();
    assert_eq!(m.materials.len(), 1);
    assert_eq!(m.materials[0].name, "red");
    assert_eq!(m.materials[0].color, Some([1.0, 0.0, 0.0]));
    assert_eq!(m.materials[0].texture, None);
    assert_eq!(m.materials[0].ke, Coef::Rgb([0.5, 0.25, 0.0]));
    assert_eq!(m.face_materials.unwrap(), [NO_MATERIAL, NO_MATERIAL, 0, 0]);
    assert!(w.iter().any(|w| w.contains("baseColorTexture")), "{w:?}");
}

/// Broken files: each error names the file and the JSON path of its cause.
#[test]
fn errors_name_the_json_path() {
    let (d, bin) = doc(&SQUARE, Some(&[0, 1, 2, 0, 2, 3]));
    let with = |edit: &dyn Fn(&mut Value)| {
        let mut d = d.clone();
        edit(&mut d);
        err(&glb(&d, &bin))
    };
    let cases = [
        (
            with(&|d| d["accessors"][0]["count"] = json!(1_000_000_000u64)),
            "glTF accessors[0].count: 1000000000 elements",
        ),
        (
            with(&|d| d["accessors"][0]["byteOffset"] = json!(40)),
            "glTF accessors[0].count:",
        ),
        (
            with(&|d| d["bufferViews"][0]["byteLength"] = json!(4000)),
            "glTF bufferViews[0].byteLength: bytes 0..4000 are outside buffer 0",
        ),
        (
            with(&|d| d["bufferViews"][0]["byteStride"] = json!(14)),
            "glTF bufferViews[0].byteStride: 14",
        ),
        (
            with(&|d| d["meshes"][0]["primitives"][0]["mode"] = json!(1)),
            "glTF meshes[0].primitives[0].mode: LINES (1) is not read",
        ),
        (
            with(&|d| d["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@@@")),
            "glTF buffers[0].uri: malformed base64",
        ),
        (
            with(&|d| d["buffers"][0]["uri"] = json!("missing.bin")),
            "glTF buffers[0].uri: 'missing.bin'",
        ),
        (
            with(&|d| d["buffers"][0]["uri"] = json!("../secret.bin")),
            "only files beside the model",
        ),
        (
            with(&|d| d["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}])),
            "glTF nodes[0]: reached twice",
        ),
        (
            with(&|d| d["nodes"] = json!([{"mesh": 0, "rotation": [0, 0, 0, 0]}])),
            "glTF nodes[0].rotation: not a unit quaternion",
        ),
        (
            with(&|d| d["extensionsRequired"] = json!(["KHR_draco_mesh_compression"])),
            "glTF extensionsRequired[0]: the model requires extension 'KHR_draco_mesh_compression'",
        ),
        (
            with(&|d| d["asset"]["version"] = json!("1.0")),
            "glTF asset.version: '1.0': only glTF 2.x is read",
        ),
        (
            with(&|d| d["accessors"][1]["componentType"] = json!(5126)),
            "glTF accessors[1].componentType: 5126 is not read as meshes[0].primitives[0].indices",
        ),
        (
            with(&|d| d["accessors"][0]["type"] = json!("VEC2")),
            "glTF accessors[0].type: 'VEC2' as meshes[0].primitives[0].attributes.POSITION",
        ),
        (
            with(&|d| d["meshes"][0]["primitives"][0]["material"] = json!(3)),
            "glTF meshes[0].primitives[0].material: no material 3",
        ),
        (
            with(&|d| d["materials"] = json!([{"emissiveFactor": [0, -1, 0]}])),
            "glTF materials[0].emissiveFactor: components must be finite and >= 0",
        ),
        (
            with(&|d| d["accessors"][1]["sparse"] = json!({})),
            "glTF accessors[1].sparse: sparse accessors are not read",
        ),
    ];
    for (e, want) in cases {
        assert!(
            e.starts_with("t.gltf: ") && e.contains(want),
            "{want:?}: {e}"
        );
    }
    // Meshes are counted before any is copied: 200 meshes (each its own material) drawing
    // one triangle over the same 600,000 vertices would copy 120M vertices, over the cap
    // (3 x 2^25).
    let many = vec![0.0f32; 600_000 * 3];
    let (mut d, bin) = doc(&many, Some(&[0, 1, 2]));
    d["scenes"][0]["nodes"] = json!((0..200).collect::<Vec<_>>());
    d["nodes"] = json!((0..200).map(|k| json!({"mesh": k})).collect::<Vec<_>>());
    d["meshes"] = json!(
        (0..200)
            .map(|k| json!({"primitives": [
                {"attributes": {"POSITION": 0}, "indices": 1, "material": k}
            ]}))
            .collect::<Vec<_>>()
    );
    let e = err(&glb(&d, &bin));
    assert!(
        e.contains("primitives[0]: the scene's meshes add up to over 100663296 vertices"),
        "{e}"
    );
    // Drawn by 200 nodes, the one mesh is stored once.
    d["nodes"] = json!(vec![json!({"mesh": 0}); 200]);
    d["meshes"] = json!([{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}]);
    let (m, _) = parse(&glb(&d, &bin)).unwrap();
    assert_eq!((m.shared.len(), m.shared[0].placements.len()), (1, 200));
    // An index out of range names the accessor and the element.
    let (d, bin) = doc(&SQUARE, Some(&[0, 1, 2, 0, 2, 9]));
    let e = err(&glb(&d, &bin));
    assert!(
        e.contains("glTF accessors[1]: index 9 (element 3) is out of range: 4 vertices"),
        "{e}"
    );
    // JSON syntax: the line.
    let e = err(b"{\n\"asset\": {\"version\": \"2.0\"},\n]");
    assert!(e.starts_with("t.gltf:3: glTF JSON"), "{e}");
    // GLB containers: length and chunks checked.
    let (d, bin) = doc(&TRI, None);
    let g = glb(&d, &bin);
    let e = err(&g[..g.len() - 4]);
    assert!(e.contains("GLB, byte 8: the header says"), "{e}");
    let mut cut = g.clone();
    cut.truncate(30);
    cut[8..12].copy_from_slice(&30u32.to_le_bytes());
    assert!(err(&cut).contains("runs past the end of the file"));
}

/// The first perspective camera in the node trees is the model's view, by its node's
/// transform; an orthographic one is skipped with a warning; a missing one is an error.
#[test]
fn the_first_perspective_camera_is_the_view() {
    let (mut d, bin) = doc(&TRI, None);
    d["cameras"] = json!([
        {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}},
        {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}},
    ]);
    d["scenes"][0]["nodes"] = json!([0, 1]);
    d["nodes"] = json!([
        {"mesh": 0},
        {"translation": [0, 0, 10], "children": [2, 3]},
        {"camera": 1, "rotation": [0, 1, 0, 0]},
        {"camera": 0},
    ]);
    let (m, w) = parse(&glb(&d, &bin)).unwrap();
    let c = m.camera.expect("a camera");
    assert_eq!(c.eye, [0.0, 0.0, 10.0]);
    // Turned half way round about y: it looks down +z.
    assert!(Vec3::from(c.look_at).distance(Vec3::new(0.0, 0.0, 11.0)) < 1e-5);
    assert!(Vec3::from(c.up).distance(Vec3::Y) < 1e-5);
    assert!((c.vfov - 0.5f32.to_degrees()).abs() < 1e-4);
    assert!(w.is_empty(), "{w:?}");
    // Only the orthographic one: skipped, with a warning.
    d["nodes"][1]["children"] = json!([3]);
    let (m, w) = parse(&glb(&d, &bin)).unwrap();
    assert!(m.camera.is_none());
    assert!(
        w.iter()
            .any(|w| w.contains("glTF cameras[0]: a 'orthographic' camera is not read")),
        "{w:?}"
    );
    d["nodes"][3]["camera"] = json!(7);
    assert!(err(&glb(&d, &bin)).contains("glTF nodes[3].camera: no camera 7"));
}

/// `KHR_lights_punctual`: point lights keep their balance at the model (intensity over the
/// squared distance), the brightest scaled to 0.9; a directional light stands 10 radii away
/// against its direction; a spot light is a point light, with a warning.
#[test]
fn punctual_lights_are_point_lights() {
    let (mut d, bin) = doc(&SQUARE, Some(&[0, 1, 2, 0, 2, 3]));
    d["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    d["extensionsRequired"] = json!(["KHR_lights_punctual"]);
    d["extensions"] = json!({"KHR_lights_punctual": {"lights": [
        {"type": "point", "intensity": 50, "color": [1, 0.5, 0]},
        {"type": "point", "intensity": 100},
        {"type": "directional", "intensity": 0.5},
        {"type": "spot", "intensity": 1, "spot": {}},
    ]}});
    d["scenes"][0]["nodes"] = json!([0, 1, 2, 3, 4]);
    let light = |l: usize, t: [f32; 3]| json!({"translation": t, "extensions": {"KHR_lights_punctual": {"light": l}}});
    d["nodes"] = json!([
        {"mesh": 0},
        light(0, [0.5, 0.5, 10.0]),
        light(1, [0.5, 0.5, 20.0]),
        light(2, [0.0, 0.0, 0.0]),
        light(3, [0.5, 0.5, 1.0]),
    ]);
    let (m, w) = parse(&glb(&d, &bin)).unwrap();
    assert_eq!(m.lights.len(), 4);
    let ip = |k: usize| Vec3::from(m.lights[k].intensity);
    // The spot light, 1 from the centre, is the brightest.
    assert!((ip(3).max_element() - 0.9).abs() < 1e-6, "{:?}", m.lights);
    // The first is 10 away with 50 in red: half the spot's (1 at 1); the second, 100 at 20
    // away, a quarter; the directional light's 0.5 is what it gives at the model: half.
    assert!((ip(0).x / ip(3).x - 0.5).abs() < 1e-5 && ip(0).y == ip(0).x * 0.5);
    assert!((ip(1).x / ip(3).x - 0.25).abs() < 1e-5);
    assert!((ip(2).x / ip(3).x - 0.5).abs() < 1e-5);
    // The directional light shines down -z: it stands on the +z side.
    assert!(m.lights[2].position[2] > 1.0);
    assert!(
        w.iter()
            .any(|w| w.contains("a spot light is drawn as a point light")),
        "{w:?}"
    );
    assert!(
        !w.iter().any(|w| w.contains("extensions not read")),
        "{w:?}"
    );
    d["nodes"][1]["extensions"]["KHR_lights_punctual"]["light"] = json!(9);
    assert!(
        err(&glb(&d, &bin))
            .contains("glTF nodes[1].extensions.KHR_lights_punctual.light: no light 9")
    );
}

#[test]
fn base64_decodes_with_and_without_padding() {
    assert_eq!(base64("TWFu").unwrap(), b"Man");
    assert_eq!(base64("TWE=").unwrap(), b"Ma");
    assert_eq!(base64("TQ==").unwrap(), b"M");
    assert_eq!(base64("").unwrap(), b"");
    assert!(base64("T").is_err() && base64("TQ===").is_err() && base64("T!==").is_err());
}
