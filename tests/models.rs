//! Models rendered in one command, from small files these tests write themselves: OBJ with
//! MTL (colours, a texture, glass, an emitting lamp), PLY, `.m`; `whitted scene model.obj`;
//! `-D` overrides; AOV layers in the EXR, read back with the exr crate.

mod common;

use glam::Vec3;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use whitted::image::Image;
use whitted::io::image::load_exr_image;

fn whitted() -> Command {
    Command::new(env!("CARGO_BIN_EXE_whitted"))
}

/// A fresh folder per test (the name may hold spaces).
fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("whitted-models-{}/{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run(args: &[&str], files: &[&Path]) -> Output {
    let mut c = whitted();
    c.args(args);
    for f in files {
        c.arg(f);
    }
    c.output().unwrap()
}

fn ok(r: &Output) -> String {
    let err = String::from_utf8_lossy(&r.stderr).into_owned();
    assert!(r.status.success(), "failed: {err}");
    err
}

/// Render `model` alone to an EXR of 64x48 with extra arguments; returns the image and stderr.
/// The image goes to this run's temporary folder, never beside the model (shared data is
/// read-only).
fn render(model: &Path, extra: &[&str]) -> (Image, String) {
    static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = N.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let out = dir("renders").join(format!("{n}.exr"));
    let mut c = whitted();
    c.arg("render")
        .arg(model)
        .args(["--width", "64", "--height", "48", "-q", "-o"])
        .arg(&out)
        .args(extra);
    let err = ok(&c.output().unwrap());
    (load_exr_image(&out).unwrap(), err)
}

fn px(img: &Image, x: usize, y: usize) -> Vec3 {
    img.get(x, y)
}

/// A quad as OBJ text: corners in order, with `vt` when `uv`.
fn quad(c: [[f32; 3]; 4], first: usize, uv: bool) -> String {
    let mut s = String::new();
    for p in c {
        s += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    if uv {
        s += "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n";
    }
    let i = |k: usize| {
        if uv {
            format!("{0}/{0}", first + k)
        } else {
            (first + k).to_string()
        }
    };
    s + &format!("f {} {} {} {}\n", i(0), i(1), i(2), i(3))
}

/// The Cornell box: a closed 2 x 2 x 2 room (red left wall, green right wall, white floor,
/// ceiling, back and front) with a small lamp just below the ceiling, facing down.
fn cornell(d: &Path, ke: &str) -> PathBuf {
    let mut obj = String::from("# Cornell box\nmtllib cornell box.mtl\n");
    let walls: [(&str, [[f32; 3]; 4]); 7] = [
        (
            "white",
            [[-1., 0., -1.], [-1., 0., 1.], [1., 0., 1.], [1., 0., -1.]],
        ),
        (
            "white",
            [[-1., 2., -1.], [1., 2., -1.], [1., 2., 1.], [-1., 2., 1.]],
        ),
        (
            "white",
            [[-1., 0., -1.], [1., 0., -1.], [1., 2., -1.], [-1., 2., -1.]],
        ),
        (
            "white",
            [[-1., 0., 1.], [-1., 2., 1.], [1., 2., 1.], [1., 0., 1.]],
        ),
        (
            "red",
            [[-1., 0., -1.], [-1., 2., -1.], [-1., 2., 1.], [-1., 0., 1.]],
        ),
        (
            "green",
            [[1., 0., -1.], [1., 0., 1.], [1., 2., 1.], [1., 2., -1.]],
        ),
        (
            "lamp",
            [
                [-0.3, 1.98, -0.3],
                [0.3, 1.98, -0.3],
                [0.3, 1.98, 0.3],
                [-0.3, 1.98, 0.3],
            ],
        ),
    ];
    for (k, (m, c)) in walls.iter().enumerate() {
        obj += &format!("g wall{k}\nusemtl {m}\n");
        obj += &quad(*c, 4 * k + 1, false);
    }
    std::fs::write(d.join("cornell box.obj"), obj).unwrap();
    std::fs::write(
        d.join("cornell box.mtl"),
        format!(
            "newmtl white\nKd 0.75 0.75 0.75\nKa 0 0 0\nillum 1\n\
             newmtl red\nKd 0.75 0.1 0.1\nKa 0 0 0\nillum 1\n\
             newmtl green\nKd 0.1 0.75 0.1\nKa 0 0 0\nillum 1\n\
             newmtl lamp\nKd 0.8 0.8 0.8\nKa 0 0 0\nKe {ke}\nillum 1\n"
        ),
    )
    .unwrap();
    d.join("cornell box.obj")
}

#[test]
fn closed_cornell_box_is_lit_by_its_ceiling_lamp() {
    let d = dir("cornell");
    // The camera inside the closed box, looking at the back wall.
    let inside = [
        "-D",
        "camera.eye=[0, 1, 0.95]",
        "-D",
        "camera.look_at=[0, 1, 0]",
        "-D",
        "camera.vfov=90",
    ];
    let (lit, _) = render(&cornell(&d, "17 12 4"), &inside);
    let (left, right, floor, back) = (
        px(&lit, 2, 24),
        px(&lit, 61, 24),
        px(&lit, 32, 46),
        px(&lit, 32, 24),
    );
    assert!(left.x > 3.0 * left.y && left.x > 0.1, "red wall {left}");
    assert!(
        right.y > 3.0 * right.x && right.y > 0.1,
        "green wall {right}"
    );
    // Lit in the lamp's colour (Ke 17 12 4: warm).
    assert!(
        floor.x > 0.3 && floor.x > floor.y && floor.y > floor.z,
        "floor under the lamp {floor}"
    );
    assert!(back.min_element() > 0.1, "back wall {back}");
    // The lamp itself shows its colour, Ke as given (HDR in the EXR).
    let lamp = px(&lit, 32, 1);
    assert!(lamp.x > 10.0 && lamp.y > 8.0, "lamp {lamp}");
    // Without the emitter the default lights stand outside the closed box: ambient only.
    let d2 = dir("cornell-off");
    let (dark, _) = render(&cornell(&d2, "0 0 0"), &inside);
    let f = px(&dark, 32, 46);
    assert!(
        floor.min_element() > 5.0 * f.max_element(),
        "lit {floor} vs no lamp {f}"
    );
}

/// A UV sphere (the library's) as OBJ with normals, material `glass`, and a backdrop: two
/// quads behind it, red on the left (x < 0) and blue on the right.
fn glass_scene(d: &Path, ni: f32) -> PathBuf {
    let s = whitted::scene::shapes::sphere(Vec3::ZERO, 1.0, 32);
    let mut obj = String::from("mtllib glass.mtl\n");
    for p in &s.positions {
        obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for n in s.normals.as_ref().unwrap() {
        obj += &format!("vn {} {} {}\n", n.x, n.y, n.z);
    }
    obj += "usemtl glass\n";
    for t in &s.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        obj += &format!("f {a}//{a} {b}//{b} {c}//{c}\n");
    }
    let nv = s.positions.len();
    obj += "usemtl red\n";
    obj += &quad(
        [
            [-4., -3., -2.],
            [0., -3., -2.],
            [0., 3., -2.],
            [-4., 3., -2.],
        ],
        nv + 1,
        false,
    );
    obj += "usemtl blue\n";
    obj += &quad(
        [[0., -3., -2.], [4., -3., -2.], [4., 3., -2.], [0., 3., -2.]],
        nv + 5,
        false,
    );
    std::fs::write(d.join("glass.obj"), obj).unwrap();
    std::fs::write(
        d.join("glass.mtl"),
        format!(
            "newmtl glass\nKd 0 0 0\nKa 0 0 0\nKs 0 0 0\nTf 1 1 1\nNi {ni}\nillum 7\n\
             newmtl red\nKd 0.9 0.05 0.05\nillum 1\nnewmtl blue\nKd 0.05 0.05 0.9\nillum 1\n"
        ),
    )
    .unwrap();
    d.join("glass.obj")
}

#[test]
fn glass_sphere_refracts() {
    let view = [
        "-D",
        "camera.eye=[0, 0, 8]",
        "-D",
        "camera.look_at=[0, 0, 0]",
        "-D",
        "camera.vfov=30",
    ];
    // A pixel left of the centre, inside the sphere's silhouette.
    let (x, y) = (26, 24);
    let (straight, _) = render(&glass_scene(&dir("glass-1"), 1.0), &view);
    let (glass, _) = render(&glass_scene(&dir("glass-15"), 1.5), &view);
    let (s, g) = (px(&straight, x, y), px(&glass, x, y));
    // Ni = 1 sees straight through to the red half; the lens of Ni = 1.5 turns the view
    // over, so the same pixel sees the blue half behind the other side.
    assert!(s.x > 2.0 * s.z, "Ni 1: {s}");
    assert!(g.z > 2.0 * g.x, "Ni 1.5: {g}");
    // Outside the sphere both see the backdrop unchanged.
    assert_eq!(px(&straight, 2, 24), px(&glass, 2, 24));
}

#[test]
fn map_kd_texture_shows_and_a_missing_one_falls_back_to_kd() {
    let d = dir("textured model");
    // 8 x 1 texels: four red, four green (sRGB 8-bit).
    let mut img = image::RgbImage::new(8, 1);
    for x in 0..8 {
        img.put_pixel(
            x,
            0,
            image::Rgb(if x < 4 { [255, 0, 0] } else { [0, 255, 0] }),
        );
    }
    img.save(d.join("my tex.png")).unwrap();
    let obj = "mtllib tex.mtl\nusemtl tex\n".to_string()
        + &quad(
            [[-1., -1., 0.], [1., -1., 0.], [1., 1., 0.], [-1., 1., 0.]],
            1,
            true,
        );
    std::fs::write(d.join("quad.obj"), obj).unwrap();
    let view = [
        "-D",
        "camera.eye=[0, 0, 3]",
        "-D",
        "camera.look_at=[0, 0, 0]",
    ];
    std::fs::write(
        d.join("tex.mtl"),
        "newmtl tex\nKa 0 0 0\nKd 1 1 1\nmap_Kd -bm 1 my tex.png\n",
    )
    .unwrap();
    let (tex, _) = render(&d.join("quad.obj"), &view);
    let (l, r) = (px(&tex, 17, 24), px(&tex, 47, 24));
    assert!(l.x > 0.2 && l.x > 5.0 * l.y, "left of the quad {l}");
    assert!(r.y > 0.2 && r.y > 5.0 * r.x, "right of the quad {r}");
    std::fs::write(
        d.join("tex.mtl"),
        "newmtl tex\nKa 0 0 0\nKd 0 0 1\nmap_Kd gone.png\n",
    )
    .unwrap();
    let (blue, err) = render(&d.join("quad.obj"), &view);
    assert!(
        err.contains("warning:") && err.contains("gone.png") && err.contains("using Kd"),
        "{err}"
    );
    let b = px(&blue, 32, 24);
    assert!(b.z > 0.2 && b.x == 0.0 && b.y == 0.0, "Kd blue {b}");
}

#[test]
fn ply_obj_vertex_colours_and_m_files_render_in_one_command() {
    let d = dir("kinds");
    let ply = d.join("quad.ply");
    std::fs::write(
        &ply,
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face 1\nproperty list uchar int vertex_index\nend_header\n\
         -1 -1 0 255 0 0\n1 -1 0 255 0 0\n1 1 0 255 0 0\n-1 1 0 255 0 0\n4 0 1 2 3\n",
    )
    .unwrap();
    let obj = d.join("rgb.obj");
    std::fs::write(
        &obj,
        "v -1 -1 0 0 1 0\nv 1 -1 0 0 1 0\nv 1 1 0 0 1 0\nv -1 1 0 0 1 0\nf 1 2 3 4\n",
    )
    .unwrap();
    for (file, channel) in [(&ply, 0), (&obj, 1)] {
        let (img, _) = render(file, &[]);
        let c = px(&img, 32, 24);
        // Vertex colours are the default material's Od: one channel dominates.
        assert!(
            c[channel] > 0.3 && c[channel] > 5.0 * c[1 - channel],
            "{}: {c}",
            file.display()
        );
    }
    let kitten = common::assets().join("meshes/kitten.m");
    let (img, _) = render(&kitten, &[]);
    let bg = px(&img, 0, 0);
    assert_ne!(
        px(&img, 32, 24),
        bg,
        "the kitten is in the middle of its frame"
    );
}

#[test]
fn printed_scene_renders_what_the_one_command_render_gives() {
    let d = dir("printed");
    let model = cornell(&d, "1 1 1");
    let r = run(&["scene"], &[&model]);
    ok(&r);
    let toml = String::from_utf8(r.stdout).unwrap();
    assert!(
        toml.contains("[[material]]") && toml.contains("name = \"red\""),
        "{toml}"
    );
    assert!(
        toml.contains("ke = 1.0") && !toml.contains("[[light]]"),
        "emitters, no lights: {toml}"
    );
    // Written elsewhere, it still finds the model (absolute paths).
    let scene = dir("printed/elsewhere").join("s.toml");
    std::fs::write(&scene, toml).unwrap();
    let out = scene.with_extension("exr");
    ok(&run(
        &["render", "--width", "64", "--height", "48", "-q", "-o"],
        &[&out, &scene],
    ));
    let (direct, _) = render(&model, &[]);
    assert_eq!(load_exr_image(&out).unwrap().pixels, direct.pixels);
}

#[test]
fn info_json_lists_materials_with_textures_found_or_missing() {
    let d = dir("info");
    std::fs::write(d.join("t.png"), []).unwrap();
    std::fs::write(
        d.join("a.obj"),
        "mtllib a.mtl b.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nusemtl m1\nf 1/1 2/1 3/1\n",
    )
    .unwrap();
    std::fs::write(
        d.join("a.mtl"),
        "newmtl m1\nKd 0.5 0.25 1\nillum 2\nmap_Kd t.png\n",
    )
    .unwrap();
    std::fs::write(d.join("b.mtl"), "newmtl m2\nKe 1 1 1\nmap_Kd nope.png\n").unwrap();
    let r = run(&["info", "--json"], &[&d.join("a.obj")]);
    ok(&r);
    let v: serde_json::Value = serde_json::from_slice(&r.stdout).unwrap();
    let m = v["materials"].as_array().unwrap();
    assert_eq!(m.len(), 2);
    assert_eq!(m[0]["name"], "m1");
    assert_eq!(m[0]["illum"], 2);
    assert_eq!(m[0]["kd"], serde_json::json!([0.5, 0.25, 1.0]));
    assert_eq!(m[0]["map_kd_found"], true);
    assert_eq!(m[1]["ke"], serde_json::json!([1.0, 1.0, 1.0]));
    assert_eq!(m[1]["map_kd_found"], false);
    assert!(v["warnings"].to_string().contains("nope.png"));
}

#[test]
fn defines_override_scene_values_and_name_themselves_in_errors() {
    let out = dir("defines").join("d.exr");
    let base = [
        "render", "phong", "--width", "32", "--height", "24", "-q", "-o",
    ];
    let r = |extra: &[&str]| {
        let mut c = whitted();
        c.args(base)
            .arg(&out)
            .args(extra)
            .env("WHITTED_ASSETS", common::assets());
        c.output().unwrap()
    };
    ok(&r(&[]));
    let plain = load_exr_image(&out).unwrap();
    ok(&r(&[
        "-D",
        "light[0].intensity=[0, 0, 0]",
        "-D",
        "light[1].intensity=[0,0,0]",
    ]));
    let unlit = load_exr_image(&out).unwrap();
    let sum = |i: &Image| i.pixels.iter().map(|p| p.element_sum()).sum::<f32>();
    assert!(sum(&unlit) < 0.7 * sum(&plain));
    for (arg, want) in [
        (
            "camera.vfov=200",
            "camera.vfov: must be in (0, 180) degrees, found 200 (set by -D 'camera.vfov=200')",
        ),
        ("camera.fov=3", "-D 'camera.fov=3': unknown field `fov`"),
        ("render.depth=deep", "-D 'render.depth=deep': invalid type"),
        (
            "light[7].intensity=[1,1,1]",
            "-D 'light[7].intensity=[1,1,1]': 'light' has 2 entries",
        ),
        ("vfov", "-D 'vfov': expected key=value"),
    ] {
        let o = r(&["-D", arg]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{arg}: {err}");
        assert!(
            err.contains(want) && err.lines().count() == 1,
            "{arg}: {err}"
        );
    }
}

#[test]
fn aov_layers_are_named_exr_channels_read_back_by_the_exr_crate() {
    use exr::prelude::*;
    let d = dir("aov");
    let model = cornell(&d, "0 0 0");
    let out = d.join("aov.exr");
    let r = run(
        &[
            "render",
            "--width",
            "40",
            "--height",
            "30",
            "-q",
            "--aov",
            "albedo,normal,depth,id",
            "-o",
        ],
        &[&out, &model],
    );
    ok(&r);
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(&out)
        .unwrap();
    let chans = &img.layer_data.channel_data.list;
    let names: Vec<String> = chans.iter().map(|c| c.name.to_string()).collect();
    for n in [
        "R", "G", "B", "albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z",
        "depth.Z", "id.id",
    ] {
        assert!(names.iter().any(|x| x == n), "{n} missing in {names:?}");
    }
    let get = |n: &str| {
        &chans
            .iter()
            .find(|c| c.name.to_string() == n)
            .unwrap()
            .sample_data
    };
    let (w, h) = (40usize, 30usize);
    let (corner, centre) = (0usize, (h / 2) * w + w / 2);
    let FlatSamples::U32(id) = get("id.id") else {
        panic!("id is not u32")
    };
    let FlatSamples::F32(depth) = get("depth.Z") else {
        panic!("depth is not f32")
    };
    assert_eq!(id[corner], u32::MAX, "background id");
    assert!(depth[corner].is_infinite());
    assert!((id[centre] as usize) < 14 && depth[centre] > 0.0 && depth[centre].is_finite());
    let f = |n: &str| match get(n) {
        FlatSamples::F32(v) => v[centre],
        _ => panic!("{n}"),
    };
    let normal = Vec3::new(f("normal.X"), f("normal.Y"), f("normal.Z"));
    assert!((normal.length() - 1.0).abs() < 1e-5, "{normal}");
    // The box's materials are plain colours: albedo = Kd of the wall seen.
    let albedo = Vec3::new(f("albedo.R"), f("albedo.G"), f("albedo.B"));
    assert!(
        [
            Vec3::splat(0.75),
            Vec3::new(0.75, 0.1, 0.1),
            Vec3::new(0.1, 0.75, 0.1)
        ]
        .iter()
        .any(|k| (*k - albedo).length() < 1e-6),
        "{albedo}"
    );
    // The beauty image is the same with or without AOVs.
    let plain = d.join("plain.exr");
    ok(&run(
        &["render", "--width", "40", "--height", "30", "-q", "-o"],
        &[&plain, &model],
    ));
    assert_eq!(
        load_exr_image(&plain).unwrap().pixels,
        load_exr_image(&out).unwrap().pixels
    );
    // PNG output is refused with a clear message.
    let r = run(
        &["render", "-q", "--aov", "depth", "-o"],
        &[&d.join("x.png"), &model],
    );
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2));
    assert!(
        err.contains("--aov depth") && err.contains("not .exr"),
        "{err}"
    );
    let r = run(&["render", "-q", "--aov", "colour", "-o"], &[&out, &model]);
    assert!(String::from_utf8_lossy(&r.stderr).contains("unknown AOV 'colour'"));
}

#[test]
fn malformed_model_files_give_one_line_errors_and_exit_code_2() {
    let d = dir("bad files");
    let cases: [(&str, &[u8], &str); 5] = [
        ("a.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "a.ply:13: face 0 vertex_indices: vertex index 7 out of range (0..3)"),
        ("b.ply", b"ply\nformat binary_big_endian 1.0\nelement vertex 99999999\nproperty float x\nproperty float y\nproperty float z\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n", "claims 99999999 entries"),
        ("c.ply", b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n", "c.ply:11: vertex 1 y: 'inf' is not a finite number"),
        ("d.obj", b"mtllib d.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "d.mtl:2: Kd: expected r [g b]"),
        ("e.obj", b"v 0 0 0\nv 1 0 0\nf 1 2 3\n", "e.obj:3: f: '3': v index 3 out of range"),
    ];
    std::fs::write(d.join("d.mtl"), "newmtl m\nKd 1 1\n").unwrap();
    for (name, bytes, want) in cases {
        let f = d.join(name);
        std::fs::write(&f, bytes).unwrap();
        let r = run(&["render", "-q", "-o"], &[&d.join("x.png"), &f]);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{name}: {err}");
        assert!(
            err.contains(want) && err.trim().lines().count() == 1,
            "{name}: {err}"
        );
    }
}
