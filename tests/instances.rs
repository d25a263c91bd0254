//! Instanced scenes render as the same scenes flattened, with every engine.

mod common;

/// The field's writer (`cargo run --example kitten_field -- N OUT.glb`).
#[path = "../examples/kitten_field.rs"]
#[allow(dead_code)]
mod kitten_field;

use glam::{Affine3A, Quat, Vec3};
use whitted::render::{Engine, Settings, World, render};
use whitted::scene::{Object, Placement, Scene};

/// A built-in scene with its first object (the kitten) placed three times, and the same
/// scene with the three copies flattened into objects of their own.
fn scenes(name: &str, width: u64, height: u64) -> (Scene, Scene) {
    let w = common::world(name, width, height);
    let scene = w.scene.clone();
    let transforms = [
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.6),
            Quat::from_rotation_y(0.7),
            Vec3::new(-0.9, -0.2, 0.3),
        ),
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(0.5),
            Quat::from_axis_angle(Vec3::new(0.3, 1.0, 0.1).normalize(), -1.2),
            Vec3::new(0.9, -0.3, -0.4),
        ),
        Affine3A::from_translation(Vec3::new(0.0, 0.4, -1.5)),
    ];
    let mut instanced = scene.clone();
    instanced.instances = transforms
        .iter()
        .enumerate()
        .map(|(k, &to_world)| Placement {
            object: 0,
            to_world,
            // the second copy in the scene's last material
            material: (k == 1).then_some(scene.materials.len() - 1),
        })
        .collect();
    let mut flat = scene.clone();
    let kitten = flat.objects.remove(0);
    let copies: Vec<Object> = transforms
        .iter()
        .enumerate()
        .map(|(k, m)| {
            let mut o = kitten.clone();
            let normals = o
                .mesh
                .normals
                .clone()
                .unwrap_or_else(|| o.mesh.area_weighted_normals());
            let nm = m.matrix3.inverse().transpose();
            o.mesh.normals = Some(normals.iter().map(|&n| (nm * n).normalize()).collect());
            for p in &mut o.mesh.positions {
                *p = m.transform_point3(*p);
            }
            if k == 1 {
                o.material = scene.materials.len() - 1;
                o.face_materials = None;
            }
            o
        })
        .collect();
    // the placements come after the objects drawn as they are, in both
    flat.objects.extend(copies);
    (instanced, flat)
}

#[test]
fn instanced_scenes_render_as_the_flattened_scenes_with_every_engine() {
    for name in ["phong", "vertex_color", "refraction"] {
        let (instanced, flat) = scenes(name, 96, 72);
        let (wi, mut wf) = (World::new(instanced), World::new(flat));
        // the same secondary-ray offset in both: the instanced world's box is the union of
        // the placed meshes' boxes, looser than the flattened vertices' box
        wf.eps = wi.eps;
        assert!(wi.instanced.is_some() && wf.instanced.is_none());
        for engine in Engine::ALL {
            let settings = Settings {
                engine,
                ..Settings::default()
            };
            let a = render(&wi, &settings, &|_| ()).0;
            let b = render(&wf, &settings, &|_| ()).0;
            let diffs: Vec<f32> = (a.pixels.iter().zip(&b.pixels))
                .map(|(x, y)| (*x - *y).abs().max_element())
                .collect();
            let off = diffs.iter().filter(|d| **d > 1e-3).count();
            let mean = diffs.iter().sum::<f32>() / diffs.len() as f32;
            println!("{name} {engine:?}: {off} pixels off by > 1e-3, mean {mean:e}");
            // float noise: rays that graze a silhouette or meet an edge may take the other
            // side in one of the two (object-space rays against world-space vertices)
            assert!(
                off <= diffs.len() / 200,
                "{name} {engine:?}: {off} pixels differ"
            );
            assert!(mean < 2e-3, "{name} {engine:?}: mean difference {mean}");
        }
    }
}

const FIELD: &str = r#"
[camera]
eye = [0, 3, 9]
look_at = [0, 0, 0]
vfov = 40
[[light]]
position = [5, 6, 3]
intensity = [1, 1, 1]
[[material]]
name = "orange"
color = [0.9, 0.5, 0.2]
[[material]]
name = "blue"
color = [0.2, 0.3, 0.9]
[[mesh]]
name = "kitten"
file = "meshes/kitten.m"
material = "orange"
[[mesh]]
shape = "quad"
size = [20, 1, 20]
center = [0, -1, 0]
material = "blue"
[[instance]]
mesh = "kitten"
translate = [-2, 0, 0]
rotate = [0, 90, 0]
scale = 0.8
[[instance]]
mesh = "kitten"
material = "blue"
matrix = [[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
"#;

fn build(text: &str) -> whitted::error::Result<Scene> {
    use whitted::io::scene::{SceneFile, SearchPath, build_scene};
    let path = std::path::Path::new("field.toml");
    let file = SceneFile::parse(text, path)?;
    let search = SearchPath {
        dirs: vec![common::assets()],
    };
    build_scene(&file, path, &search).map(|s| s.0)
}

#[test]
fn scene_file_instances_place_meshes_by_name() {
    let scene = build(FIELD).unwrap();
    assert_eq!(scene.instances.len(), 2);
    let kitten = scene.objects[0].mesh.triangles.len();
    // the kitten drawn twice (not at its own place), the floor once
    assert_eq!(scene.triangle_count(), 2 * kitten + 2);
    let p = scene.instances[0];
    assert_eq!(p.object, 0);
    assert_eq!(p.material, None);
    let x = p.to_world.transform_point3(Vec3::X);
    assert!((x - Vec3::new(-2.0, 0.0, -0.8)).length() < 1e-5, "{x}");
    let q = scene.instances[1];
    assert_eq!(q.material, Some(1));
    assert_eq!(
        q.to_world.transform_point3(Vec3::ZERO),
        Vec3::new(2.0, 0.0, 0.0)
    );
    let world = World::new(scene);
    let i = world.instanced.as_ref().unwrap();
    assert_eq!(i.tracer.triangles as usize, 2 * kitten + 2);
    assert_eq!(i.tracer.meshes.len(), 2);
}

#[test]
fn bad_instances_are_refused_with_the_file_and_line() {
    let cases = [
        (
            "mesh = \"kitten\"\nmaterial = \"blue\"",
            "mesh = \"cat\"",
            "no mesh named 'cat'",
        ),
        (
            "matrix = [[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]",
            "matrix = [[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1]]",
            "singular",
        ),
        ("scale = 0.8", "scale = [1, 0, 1]", "singular"),
        (
            "translate = [-2, 0, 0]",
            "translate = [-2, nan, 0]",
            "finite",
        ),
        (
            "matrix = [[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]",
            "matrix = [[1, 0, 0, 2], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]]",
            "last row",
        ),
        (
            "material = \"blue\"\nmatrix",
            "material = \"red\"\nmatrix",
            "no material named 'red'",
        ),
    ];
    for (from, to, want) in cases {
        assert!(FIELD.contains(from), "{from}");
        let text = FIELD.replacen(from, to, 1);
        let line = text[..text.find(to).unwrap()].lines().count() + 1;
        let e = build(&text).err().unwrap().to_string();
        assert!(e.contains(want), "{to}: {e}");
        assert!(e.contains("field.toml"), "{e}");
        // the line of the key
        assert!(e.starts_with(&format!("field.toml:{line}:")), "{e}");
    }
}

/// A field of `n x n` kittens as a scene made in code (the scene file of
/// `examples/kitten_field.rs` without its text): one kitten object, `n * n` placements.
fn field(n: u32) -> Scene {
    let mut scene = build(FIELD).unwrap();
    let half = 1.5 * n as f32;
    scene.width = 1920;
    scene.height = 1080;
    scene.view.eye = Vec3::new(half * 1.1, half * 0.6 + 2.0, half * 1.1);
    scene.view.look_at = Vec3::new(0.0, -1.0, 0.0);
    scene.objects[1].mesh = whitted::scene::shapes::quad(
        Vec3::new(0.0, -1.1, 0.0),
        Vec3::new(0.0, 0.0, half + 2.0),
        Vec3::new(half + 2.0, 0.0, 0.0),
    );
    scene.instances = (0..n * n)
        .map(|k| {
            let (i, j) = ((k / n) as f32, (k % n) as f32);
            Placement {
                object: 0,
                to_world: Affine3A::from_scale_rotation_translation(
                    Vec3::splat(0.8 + 0.4 * ((k * 7919) % 100) as f32 / 100.0),
                    Quat::from_rotation_y(k as f32),
                    Vec3::new(3.0 * i - half + 1.5, 0.0, 3.0 * j - half + 1.5),
                ),
                material: None,
            }
        })
        .collect();
    scene
}

/// The scale targets (README, "Instances"), run with the peak memory measured:
///
///     cargo test --release --test instances -- --ignored --nocapture million
///     /usr/bin/time -v target/release/deps/instances-* --ignored --nocapture million
#[test]
#[ignore = "minutes and up to 2 GB: run by hand"]
fn a_million_kittens_render_at_1080p() {
    for n in [100, 1000] {
        let start = std::time::Instant::now();
        let world = World::new(field(n));
        let built = start.elapsed();
        let i = world.instanced.as_ref().unwrap();
        assert_eq!(i.tracer.instances.len(), (n * n) as usize + 1);
        let (image, stats) = render(&world, &Settings::default(), &|_| ());
        let lit = image.pixels.iter().filter(|p| p.x > p.z).count();
        println!(
            "{} kittens ({} triangles): built in {:.2} s, {} bytes of trees, rendered 1920x1080 in {:.2} s ({} rays); {lit} orange pixels",
            n * n,
            i.tracer.triangles,
            built.as_secs_f64(),
            i.tracer.bytes(),
            stats.time.as_secs_f64(),
            stats.rays.total()
        );
        assert!(lit > 100_000, "{lit} kitten pixels");
    }
}

/// The same targets through one GLB (`examples/kitten_field.rs`: the kitten stored once,
/// drawn by one node's `EXT_mesh_gpu_instancing`), read as `whitted render field.glb`
/// reads it; the peak memory of that command is measured with
///
///     cargo run --release --example kitten_field -- 1000 field.glb
///     /usr/bin/time -v target/release/whitted render field.glb --width 1920 --height 1080
#[test]
#[ignore = "minutes and up to 2 GB: run by hand"]
fn a_million_kittens_from_one_glb_render_at_1080p() {
    use whitted::io::mesh_scene::scene_for_mesh;
    use whitted::io::scene::{SearchPath, build_scene};
    for n in [100, 1000] {
        let path = common::scratch("instances", &format!("field{n}.glb"));
        std::fs::write(&path, kitten_field::glb(n)).unwrap();
        let start = std::time::Instant::now();
        let (file, warnings) = scene_for_mesh(&path, 1920, 1080).unwrap();
        let (scene, more) = build_scene(&file, &path, &SearchPath::for_scene(None)).unwrap();
        assert!(
            warnings.is_empty() && more.is_empty(),
            "{warnings:?} {more:?}"
        );
        assert_eq!(scene.instances.len(), (n * n) as usize);
        assert_eq!(scene.stored_triangle_count(), 20438 + 2);
        let loaded = start.elapsed();
        let world = World::new(scene);
        let i = world.instanced.as_ref().unwrap();
        // the kitten's placements and the floor, drawn as it is
        assert_eq!(i.tracer.instances.len(), (n * n) as usize + 1);
        let (image, stats) = render(&world, &Settings::default(), &|_| ());
        let lit = image.pixels.iter().filter(|p| p.x > 1.3 * p.z).count();
        println!(
            "{} kittens from a GLB ({} triangles): loaded in {:.2} s, BVH {:.2} s, rendered 1920x1080 in {:.2} s ({} rays); {lit} orange pixels",
            n * n,
            i.tracer.triangles,
            loaded.as_secs_f64(),
            i.build_time.as_secs_f64(),
            stats.time.as_secs_f64(),
            stats.rays.total()
        );
        assert!(lit > 100_000, "{lit} kitten pixels");
        std::fs::remove_file(&path).unwrap();
    }
}

#[test]
fn info_lists_instances() {
    let path = common::scratch("instances", "field.toml");
    let dir = common::assets();
    std::fs::write(
        &path,
        FIELD.replace(
            "meshes/kitten.m",
            &dir.join("meshes/kitten.m").to_string_lossy(),
        ),
    )
    .unwrap();
    let json = whitted::info::run(&path, true).unwrap();
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["instances"], 2);
    assert_eq!(v["objects"][0]["instances"], 2);
    assert!(v["objects"][1].get("instances").is_none());
    let list = v["instance_list"].as_array().unwrap();
    assert_eq!(list[1]["mesh"], "kitten");
    assert_eq!(list[1]["material"], "blue");
    assert_eq!(list[1]["matrix"][0][3], 2.0);
    let kitten = v["objects"][0]["triangles"].as_u64().unwrap();
    assert_eq!(v["triangles"].as_u64().unwrap(), 2 * kitten + 2);
    assert_eq!(v["stored_triangles"].as_u64().unwrap(), kitten + 2);
    let text = whitted::info::run(&path, false).unwrap();
    assert!(text.contains("instances: 2\n"), "{text}");
}

/// Lamps placed by `[[instance]]` (turned, scaled, mirrored, one in a material of its
/// own): their lights are those of the scene flattened, and it renders as that scene.
#[test]
fn placed_lamps_light_the_scene_as_the_scene_flattened() {
    let text = format!(
        "{FIELD}{}",
        r#"
[[material]]
name = "lamp"
color = [1, 1, 1]
ke = [6, 5, 4]
[[material]]
name = "lamp2"
color = [1, 1, 1]
ke = [1, 2, 6]
[[mesh]]
name = "lamp"
shape = "quad"
size = [0.5, 1, 0.5]
material = "lamp"
[[instance]]
mesh = "lamp"
translate = [-2, 3, 0]
rotate = [180, 0, 0]
[[instance]]
mesh = "lamp"
material = "lamp2"
translate = [2, 3, 1]
rotate = [180, 0, 0]
scale = [2, 1, 1]
[[instance]]
mesh = "lamp"
matrix = [[1, 0, 0, 0], [0, -1, 0, 3.5], [0, 0, 1, -1], [0, 0, 0, 1]]
"#
    );
    let scene = build(&text).unwrap();
    assert_eq!(scene.instances.len(), 5);
    // the file's light, then one per lamp material facing down
    assert_eq!(scene.lights.len(), 3, "{:?}", scene.lights);
    let mut flat = scene.flattened();
    flat.lights.truncate(1);
    flat.lights.extend(whitted::scene::emitter_lights(
        &flat.objects,
        &flat.materials,
    ));
    assert_eq!(flat.lights.len(), 3);
    for (a, b) in scene.lights.iter().zip(&flat.lights) {
        assert!(
            a.position.distance(b.position) < 1e-3,
            "{a:?} against {b:?}"
        );
        assert!(
            a.intensity.distance(b.intensity) < 1e-5,
            "{a:?} against {b:?}"
        );
    }
    // below the lamps, facing down
    assert!(
        scene.lights[1..]
            .iter()
            .all(|l| l.position.y < 3.0 && l.position.y > 2.9)
    );
    let (mut scene, mut flat) = (scene, flat);
    for s in [&mut scene, &mut flat] {
        (s.width, s.height) = (80, 60);
    }
    let (wi, mut wf) = (World::new(scene), World::new(flat));
    wf.eps = wi.eps;
    let settings = Settings::default();
    let a = render(&wi, &settings, &|_| ()).0;
    let b = render(&wf, &settings, &|_| ()).0;
    let off = (a.pixels.iter().zip(&b.pixels))
        .filter(|(x, y)| (**x - **y).abs().max_element() > 1e-3)
        .count();
    assert!(off <= a.pixels.len() / 200, "{off} pixels differ");
}
