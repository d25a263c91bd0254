//! Meshes drawn more than once are stored once: nodes sharing a mesh, meshes sharing their
//! primitives, `EXT_mesh_gpu_instancing`; placed, they render as the model flattened.

use super::tests::{doc, embedded, err, floats, glb, parse};
use glam::{Affine3A, Quat, Vec3};
use serde_json::{Value, json};

/// A tetrahedron (4 vertices, 4 triangles facing out), indexed by u16.
const TET: [f32; 12] = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
const TET_FACES: [u16; 12] = [0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3];

/// The tetrahedron drawn by three nodes under a parent: two draw mesh 0, the third mesh 1,
/// whose primitives are mesh 0's (the same accessors); one node mirrors it.
fn three_nodes() -> (Value, Vec<u8>) {
    let (mut d, bin) = doc(&TET, Some(&TET_FACES));
    d["meshes"] = json!([d["meshes"][0].clone(), d["meshes"][0].clone()]);
    d["nodes"] = json!([
        {"children": [1, 2, 3], "translation": [0, 0.5, 0]},
        {"mesh": 0, "translation": [-2, 0, 0], "scale": [0.5, 1, 0.8]},
        {"mesh": 0, "rotation": [0, 0.38268343, 0, 0.9238795]},
        {"mesh": 1, "matrix": [-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 2, 0, 0, 1]},
    ]);
    (d, bin)
}

#[test]
fn a_mesh_drawn_by_three_nodes_is_stored_once() {
    let (d, bin) = three_nodes();
    let (m, w) = parse(&glb(&d, &bin)).unwrap();
    assert!(w.is_empty(), "{w:?}");
    assert!(m.mesh.triangles.is_empty(), "nothing left to flatten");
    assert_eq!(m.shared.len(), 1);
    let s = &m.shared[0];
    assert_eq!(s.name, "meshes[0]");
    // (no NORMAL: flat, three vertices per triangle)
    assert_eq!(s.model.mesh.positions.len(), 12);
    assert_eq!(s.model.mesh.triangles.len(), 4);
    assert_eq!(s.placements.len(), 3);
    let up = Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0));
    let want = [
        up * Affine3A::from_scale_rotation_translation(
            Vec3::new(0.5, 1.0, 0.8),
            Quat::IDENTITY,
            Vec3::new(-2.0, 0.0, 0.0),
        ),
        up * Affine3A::from_quat(Quat::from_rotation_y(std::f32::consts::FRAC_PI_4)),
        up * Affine3A::from_cols_array(&[
            -1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 2.0, 0.0, 0.0,
        ]),
    ];
    for (got, want) in s.placements.iter().zip(want) {
        assert!(got.abs_diff_eq(want, 1e-6), "{got} against {want}");
    }
    // Flattened: 12 triangles, every one facing out of its copy (the mirrored copy turned).
    assert_eq!(m.drawn_triangles(), 12);
    let flat = m.clone().flattened("t.gltf".as_ref(), 100).unwrap();
    assert_eq!(flat.mesh.triangles.len(), 12);
    for t in 0..12 {
        let c = flat.mesh.triangles[t].map(|v| flat.mesh.positions[v as usize]);
        let centre = (c[0] + c[1] + c[2]) / 3.0;
        let copy = &s.placements[t / 4];
        let inside = copy.transform_point3(Vec3::splat(0.2));
        assert!(
            flat.mesh.face_cross(t).dot(centre - inside) > 0.0,
            "triangle {t}"
        );
    }
    assert!(
        m.flattened("t.gltf".as_ref(), 11)
            .unwrap_err()
            .to_string()
            .contains("draw 12 triangles")
    );
    // The same mesh drawn once more, by a fourth node: still one stored mesh.
    let (mut d, bin) = three_nodes();
    d["nodes"][0]["children"] = json!([1, 2, 3, 4]);
    d["nodes"].as_array_mut().unwrap().push(json!({"mesh": 1}));
    let (m, _) = parse(&glb(&d, &bin)).unwrap();
    assert_eq!((m.shared.len(), m.shared[0].placements.len()), (1, 4));
    // A shared mesh without primitives draws nothing, and a model of nothing else is refused.
    let (mut d, bin) = three_nodes();
    d["meshes"] = json!([{"primitives": []}, {"primitives": []}]);
    assert!(err(&glb(&d, &bin)).contains("glTF scenes: no triangles in the scene's nodes"));
    // A mesh drawn once is flattened as before.
    let (d, bin) = doc(&TET, Some(&TET_FACES));
    let (m, _) = parse(&glb(&d, &bin)).unwrap();
    assert!(m.shared.is_empty() && m.mesh.triangles.len() == 4);
}

/// The three-node model rendered alone (`whitted render model.gltf`): through the two-level
/// BVH, as its scene flattened, with every engine.
#[test]
fn three_nodes_render_as_the_model_flattened() {
    use crate::io::mesh_scene::scene_for_mesh;
    use crate::io::scene::{SearchPath, build_scene};
    use crate::render::{Engine, Settings, World, render};
    let (d, bin) = three_nodes();
    let dir = std::env::temp_dir().join(format!("whitted-gltf-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("three.gltf");
    std::fs::write(&path, embedded(d, &bin)).unwrap();
    let (file, _) = scene_for_mesh(&path, 64, 48).unwrap();
    let (scene, _) = build_scene(&file, &path, &SearchPath::for_scene(None)).unwrap();
    // `whitted info`: what is stored, what is drawn, the copies per mesh
    let info = crate::info::info(&path).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(info.get("triangles"), Some(&json!(4)));
    assert_eq!(info.get("drawn_triangles"), Some(&json!(12)));
    assert_eq!(info.get("instances"), Some(&json!(3)));
    let meshes = info.get("meshes").unwrap();
    assert_eq!(
        (
            meshes[0]["instances"].clone(),
            meshes[1]["instances"].clone()
        ),
        (json!(2), json!(1))
    );
    assert_eq!(scene.instances.len(), 3);
    assert_eq!(scene.stored_triangle_count(), 4);
    assert_eq!(scene.triangle_count(), 12);
    let flat = scene.flattened();
    let (wi, mut wf) = (World::new(scene), World::new(flat));
    wf.eps = wi.eps;
    assert!(wi.instanced.is_some() && wf.instanced.is_none());
    for engine in Engine::ALL {
        let settings = Settings {
            engine,
            ..Settings::default()
        };
        let a = render(&wi, &settings, &|_| ()).0;
        let b = render(&wf, &settings, &|_| ()).0;
        let lit = a.pixels.iter().filter(|p| p.max_element() > 0.3).count();
        assert!(lit > 30, "{engine:?}: {lit} lit pixels");
        let off = (a.pixels.iter().zip(&b.pixels))
            .filter(|(x, y)| (**x - **y).abs().max_element() > 1e-3)
            .count();
        assert!(off <= 3, "{engine:?}: {off} pixels differ");
    }
}

/// How the document of [`gpu`] writes its rotations.
#[derive(Clone, Copy)]
enum Rotations {
    Float,
    NormalizedShort,
}

/// The tetrahedron drawn by one node (translated by 10 in z) with
/// `EXT_mesh_gpu_instancing`: three copies, translated, turned about y and scaled.
fn gpu(rotations: Rotations) -> (Value, Vec<u8>) {
    let (mut d, mut bin) = doc(&TET, Some(&TET_FACES));
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let h = std::f32::consts::FRAC_1_SQRT_2;
    let t = floats(&[1.0, 0.0, 0.0, 0.0, 2.0, 0.0, -3.0, 0.0, 1.0]);
    let r = [0.0, 0.0, 0.0, 1.0, 0.0, h, 0.0, h, 0.0, 1.0, 0.0, 0.0];
    let s = floats(&[1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 0.5, 1.0, 3.0]);
    let (r, component) = match rotations {
        Rotations::Float => (floats(&r), 5126),
        Rotations::NormalizedShort => (
            r.iter()
                .flat_map(|x| ((x * 32767.0).round() as i16).to_le_bytes())
                .collect(),
            5122,
        ),
    };
    let mut views = d["bufferViews"].as_array().unwrap().clone();
    let mut accessors = d["accessors"].as_array().unwrap().clone();
    for (data, kind, component) in [(t, "VEC3", 5126), (r, "VEC4", component), (s, "VEC3", 5126)] {
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": data.len()}));
        accessors.push(json!({
            "bufferView": views.len() - 1, "componentType": component, "count": 3, "type": kind,
            "normalized": component != 5126,
        }));
        bin.extend(data);
    }
    d["bufferViews"] = json!(views);
    d["accessors"] = json!(accessors);
    d["buffers"][0]["byteLength"] = json!(bin.len());
    d["extensionsUsed"] = json!(["EXT_mesh_gpu_instancing"]);
    d["extensionsRequired"] = json!(["EXT_mesh_gpu_instancing"]);
    d["nodes"] = json!([{"mesh": 0, "translation": [0, 0, 10], "extensions": {
        "EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": 2, "ROTATION": 3, "SCALE": 4}}
    }}]);
    (d, bin)
}

#[test]
fn gpu_instancing_places_each_copy_at_the_node_times_trs() {
    let node = Affine3A::from_translation(Vec3::new(0.0, 0.0, 10.0));
    let want = [
        node * Affine3A::from_translation(Vec3::X),
        node * Affine3A::from_scale_rotation_translation(
            Vec3::splat(2.0),
            Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
            Vec3::new(0.0, 2.0, 0.0),
        ),
        node * Affine3A::from_scale_rotation_translation(
            Vec3::new(0.5, 1.0, 3.0),
            Quat::from_rotation_y(std::f32::consts::PI),
            Vec3::new(-3.0, 0.0, 1.0),
        ),
    ];
    for (rotations, tolerance) in [(Rotations::Float, 1e-6), (Rotations::NormalizedShort, 1e-4)] {
        let (d, bin) = gpu(rotations);
        let (m, w) = parse(&glb(&d, &bin)).unwrap();
        // read, so neither the warning of unknown extensions nor the error of required ones
        assert!(w.is_empty(), "{w:?}");
        assert!(m.mesh.triangles.is_empty());
        let placements = &m.shared[0].placements;
        assert_eq!(placements.len(), 3);
        for (got, want) in placements.iter().zip(want) {
            assert!(got.abs_diff_eq(want, tolerance), "{got} against {want}");
        }
        assert_eq!(m.drawn_triangles(), 12);
    }
    // A zero scale draws nothing: the copy is left out, with a warning.
    let (d, mut bin) = gpu(Rotations::Float);
    let scale = d["bufferViews"][4]["byteOffset"].as_u64().unwrap() as usize;
    bin[scale..scale + 12].copy_from_slice(&floats(&[0.0; 3]));
    let (m, w) = parse(&glb(&d, &bin)).unwrap();
    assert_eq!(m.shared[0].placements.len(), 2);
    assert!(
        w.iter()
            .any(|w| w.contains("1 copies of meshes have a singular transform")),
        "{w:?}"
    );
}

#[test]
fn bad_gpu_instancing_names_the_file_and_json_path() {
    let key = "t.gltf: glTF nodes[0].extensions.EXT_mesh_gpu_instancing.attributes";
    let bad = |edit: &dyn Fn(&mut Value, &mut Vec<u8>)| {
        let (mut d, mut bin) = gpu(Rotations::Float);
        edit(&mut d, &mut bin);
        err(&glb(&d, &bin))
    };
    let at = |d: &Value, accessor: usize, element: usize, component: usize| {
        let start = d["bufferViews"][accessor]["byteOffset"].as_u64().unwrap() as usize;
        let width = if accessor == 3 { 4 } else { 3 };
        start + 4 * (element * width + component)
    };
    let cases = [
        (
            bad(&|d, _| d["accessors"][4]["count"] = json!(2)),
            format!("{key}.SCALE: 2 copies, but TRANSLATION has 3"),
        ),
        (
            bad(&|d, bin| {
                let k = at(d, 3, 1, 2);
                bin[k..k + 4].copy_from_slice(&f32::NAN.to_le_bytes());
            }),
            format!("{key}.ROTATION: element 1 is not a unit quaternion"),
        ),
        (
            bad(&|d, bin| {
                let k = at(d, 2, 2, 0);
                bin[k..k + 4].copy_from_slice(&f32::INFINITY.to_le_bytes());
            }),
            format!("{key}.TRANSLATION: element 2 is not finite"),
        ),
        (
            bad(&|d, bin| {
                let k = at(d, 4, 0, 1);
                bin[k..k + 4].copy_from_slice(&f32::NAN.to_le_bytes());
            }),
            format!("{key}.SCALE: element 0 is not finite"),
        ),
        (
            // every attribute claims 5 copies; the buffer views hold 3
            bad(&|d, _| {
                for a in 2..5 {
                    d["accessors"][a]["count"] = json!(5);
                }
            }),
            "t.gltf: glTF accessors[2].count: 5 elements of 12 bytes".to_string(),
        ),
        (
            bad(&|d, _| {
                for a in 2..5 {
                    d["accessors"][a]["count"] = json!(1_000_000_000u64);
                }
            }),
            "t.gltf: glTF nodes[0]: the scene's nodes place over 4194304 copies".to_string(),
        ),
        (
            bad(&|d, _| {
                d["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["ROTATION"] =
                    json!(9)
            }),
            format!("{key}.ROTATION: no accessor 9"),
        ),
        (
            bad(&|d, _| d["accessors"][3]["type"] = json!("VEC3")),
            format!("glTF accessors[3].type: 'VEC3' as {}.ROTATION", &key[13..]),
        ),
        (
            bad(&|d, _| {
                d["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = json!({})
            }),
            format!("{key}: none of TRANSLATION, ROTATION or SCALE"),
        ),
    ];
    for (e, want) in cases {
        assert!(e.contains(&want), "{want:?}: {e}");
    }
    // integer rotations must be normalized
    let (mut d, bin) = gpu(Rotations::NormalizedShort);
    d["accessors"][3]["normalized"] = json!(false);
    let e = err(&glb(&d, &bin));
    assert!(
        e.contains(&format!(
            "{key}.ROTATION: accessors[3] holds integers that are not normalized"
        )),
        "{e}"
    );
}
