//! The `whitted` binary end to end: render, scene, trace-rays, and errors with exit code 2.

mod common;

use std::path::PathBuf;
use std::process::Command;

fn whitted() -> Command {
    Command::new(env!("CARGO_BIN_EXE_whitted"))
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("whitted-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn renders_the_demo_without_any_files() {
    let out = tmp("demo.png");
    let r = whitted()
        .args(["render", "--width", "64", "--height", "48", "-o"])
        .arg(&out)
        .env_remove("WHITTED_ASSETS")
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert!(
        stderr.contains("64x48") && stderr.contains("Mrays/s"),
        "summary line: {stderr}"
    );
    let img = image::open(&out).unwrap();
    assert_eq!((img.width(), img.height()), (64, 48));
}

/// The tree does not depend on the environment: a build once read a leftover tuning
/// variable `LEAF` and panicked on `LEAF=abc` (and `LEAF=4` changed the tree silently).
#[test]
fn unrelated_environment_variables_change_nothing() {
    let (a, b) = (tmp("env_a.exr"), tmp("env_b.exr"));
    for (out, leaf) in [(&a, None), (&b, Some("abc"))] {
        let mut cmd = whitted();
        cmd.args([
            "render", "phong", "--width", "32", "--height", "24", "-q", "-o",
        ])
        .arg(out);
        if let Some(v) = leaf {
            cmd.env("LEAF", v);
        } else {
            cmd.env_remove("LEAF");
        }
        let r = cmd.output().unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

#[test]
fn both_engines_and_exr_output() {
    for engine in [
        "auto", "packet", "wide", "hybrid", "packet16", "hybrid16", "scalar",
    ] {
        let out = tmp(&format!("demo-{engine}.exr"));
        let r = whitted()
            .args([
                "render", "demo", "--width", "32", "--height", "24", "--spp", "4", "--stats",
                "--engine", engine, "-o",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        let stdout = String::from_utf8_lossy(&r.stdout);
        assert!(
            stdout.contains("BVH build") && stdout.contains("rays"),
            "{stdout}"
        );
        assert!(std::fs::metadata(&out).unwrap().len() > 0);
    }
}

#[test]
fn scene_prints_editable_toml_that_renders() {
    let r = whitted().args(["scene", "demo"]).output().unwrap();
    assert!(r.status.success());
    let file = tmp("demo.toml");
    std::fs::write(&file, &r.stdout).unwrap();
    let out = tmp("demo-from-toml.png");
    let r = whitted()
        .arg("render")
        .arg(&file)
        .args(["--width", "16", "--height", "12", "-q", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
}

#[test]
fn trace_rays_writes_one_record_per_ray_and_engines_agree() {
    let mesh = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes/cube.obj");
    let rays: Vec<whitted::ray::Ray> = (0..37)
        .map(|k| {
            let a = k as f32 * 0.4;
            // Odd rays look away from the cube and miss.
            let s = if k % 2 == 0 { 1.0 } else { -1.0 };
            whitted::ray::Ray::new(
                glam::Vec3::new(a.sin() * 4.0, a.cos() * 4.0, 3.0),
                glam::Vec3::new(-a.sin(), -a.cos(), -0.8) * s,
                0.0,
                f32::INFINITY,
            )
        })
        .collect();
    let input = tmp("rays.bin");
    std::fs::write(&input, whitted::io::rays::encode_rays(&rays)).unwrap();
    let mut outputs = Vec::new();
    // (the 16-ray engines a second time without their AVX-512 kernels, as on a CPU without
    // AVX-512: `WHITTED_NO_AVX512`)
    for (engine, no512) in [
        ("auto", false),
        ("packet", false),
        ("wide", false),
        ("hybrid", false),
        ("packet16", false),
        ("hybrid16", false),
        ("packet16", true),
        ("hybrid16", true),
        ("scalar", false),
    ] {
        let hits = tmp(&format!("hits-{engine}-{no512}.bin"));
        let mut cmd = whitted();
        if no512 {
            cmd.env("WHITTED_NO_AVX512", "1");
        }
        let r = cmd
            .arg("trace-rays")
            .arg(&mesh)
            .arg("--rays")
            .arg(&input)
            .arg("--hits")
            .arg(&hits)
            .args(["--engine", engine])
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
        assert!(String::from_utf8_lossy(&r.stdout).contains("37 rays"));
        let bytes = std::fs::read(&hits).unwrap();
        assert_eq!(bytes.len(), 37 * 16);
        let parsed = whitted::io::rays::parse_hits(&bytes, &hits).unwrap();
        assert!(parsed.iter().any(|h| h.is_some()) && parsed.iter().any(|h| h.is_none()));
        assert!(parsed.iter().flatten().all(|h| h.tri < 12));
        outputs.push(bytes);
    }
    let scalar = outputs.last().unwrap();
    for (k, o) in outputs.iter().enumerate() {
        assert_eq!(
            o, scalar,
            "engine {k}'s hit file equals the scalar reference's"
        );
    }
}

#[test]
fn bad_input_is_one_line_error_with_exit_code_2() {
    let bad = tmp("bad.toml");
    std::fs::write(&bad, "[image]\nwidth = 4\nheight = 3\nbogus = 1\n").unwrap();
    let trap = tmp("trap.toml");
    std::fs::write(&trap, common::TRAP).unwrap();
    let mut cases: Vec<(Vec<String>, &str)> = vec![
        (
            vec!["render".into(), bad.display().to_string(), "-q".into()],
            "bad.toml:4",
        ),
        (
            vec!["render".into(), "nosuchscene".into()],
            "neither a built-in scene",
        ),
        (
            vec![
                "render".into(),
                "demo".into(),
                "--width".into(),
                "100000".into(),
                "--height".into(),
                "100000".into(),
            ],
            "over the cap",
        ),
    ];
    // inside a closed box whose walls both mirror and refract, 64 bounces: every sample's ray
    // tree doubles per bounce (2^65 rays); refused within the budget, by both engines
    for engine in [
        "auto", "packet", "wide", "hybrid", "packet16", "hybrid16", "scalar",
    ] {
        let trap_args = [trap.display().to_string(), "-q".into(), "-o".into()];
        let out = tmp("trap.png").display().to_string();
        cases.push((
            ["render".into()]
                .into_iter()
                .chain(trap_args)
                .chain([out, "--engine".into(), engine.into()])
                .collect(),
            "rays are trapped",
        ));
    }
    cases.extend([
        (
            vec![
                "render".into(),
                "demo".into(),
                "--stage".into(),
                "shiny".into(),
            ],
            "unknown stage",
        ),
        (
            vec!["render".into(), "demo".into(), "-o".into(), "x.jpg".into()],
            "must be .png or .exr",
        ),
        (
            vec![
                "trace-rays".into(),
                "meshes/cube.obj".into(),
                "--rays".into(),
                "Cargo.toml".into(),
                "--hits".into(),
                tmp("h.bin").display().to_string(),
            ],
            "32-byte",
        ),
    ]);
    for (args, want) in cases {
        let r = whitted()
            .args(&args)
            .current_dir(env!("CARGO_MANIFEST_DIR"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(stderr.contains(want), "{args:?}: want {want:?} in {stderr}");
        assert_eq!(
            stderr.trim().lines().count(),
            1,
            "{args:?}: one line: {stderr}"
        );
    }
}

/// Deep recursion is fine where rays escape: the demo's glass ball and mirror at depth 64
/// render (the ray-tree budget only stops trapped rays).
#[test]
fn deep_recursion_renders_where_rays_escape() {
    let out = tmp("deep.png");
    for engine in ["packet", "scalar"] {
        let r = whitted()
            .args([
                "render", "demo", "--depth", "64", "--width", "48", "--height", "36",
            ])
            .args(["--engine", engine, "-q", "-o"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    }
}

/// The built-in scenes find the shipped data from any folder with no environment variable:
/// the search path ends with the project's own data folder.
#[test]
fn canonical_scenes_render_from_another_folder_without_whitted_assets() {
    let dir = tmp("elsewhere");
    std::fs::create_dir_all(&dir).unwrap();
    for name in ["phong", "vertex_color", "texture", "cubemap", "refraction"] {
        let r = whitted()
            .args(["render", name, "--width", "32", "--height", "24", "-q"])
            .current_dir(&dir)
            .env_remove("WHITTED_ASSETS")
            .output()
            .unwrap();
        assert!(
            r.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        let img = image::open(dir.join(format!("{name}.png"))).unwrap();
        assert_eq!((img.width(), img.height()), (32, 24), "{name}");
    }
}

/// An image given where a scene is expected says so and how to make a scene, instead of a
/// TOML error (a mesh is rendered on its own: issue 12); `whitted info` on a type it does not
/// read lists the types it does.
#[test]
fn wrong_file_types_say_what_is_expected() {
    let stl = tmp("x.stl");
    std::fs::write(&stl, "solid x\nendsolid x\n").unwrap();
    let png = tmp("x.png");
    image::RgbImage::new(2, 2).save(&png).unwrap();
    let cases = [
        (
            vec!["render".to_string(), png.display().to_string()],
            vec![
                "x.png: this is an image (.png), but a scene file (.toml) is expected",
                "`whitted scene phong > my.toml`",
                "`whitted render my.toml`",
            ],
        ),
        (
            vec!["info".to_string(), stl.display().to_string()],
            vec![
                "x.stl: not a file type whitted reads; it reads meshes (.m, .obj, .ply), scenes (.toml)",
            ],
        ),
    ];
    for (args, wants) in cases {
        let r = whitted().args(&args).output().unwrap();
        let stderr = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
        for want in wants {
            assert!(stderr.contains(want), "{args:?}: want {want:?} in {stderr}");
        }
    }
}

/// The example, end to end: a scene rendered from its own folder names itself, the
/// line and key of the entry, then the mesh's own file and line.
#[test]
fn error_in_a_mesh_names_scene_key_then_file() {
    let dir = tmp("badmesh");
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::write(
        dir.join("meshes/bad.m"),
        "Vertex 1 0 0 0\nVertex 2 NaN 0 0\n",
    )
    .unwrap();
    let r = whitted().args(["scene", "phong"]).output().unwrap();
    let scene = String::from_utf8(r.stdout)
        .unwrap()
        .replace("meshes/kitten.m", "meshes/bad.m");
    let line = 1 + scene
        .lines()
        .position(|l| l.contains("meshes/bad.m"))
        .unwrap();
    std::fs::write(dir.join("scene.toml"), scene).unwrap();
    let r = whitted()
        .args(["render", "scene.toml", "-q"])
        .current_dir(&dir)
        .env_remove("WHITTED_ASSETS")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(2), "{stderr}");
    assert_eq!(
        stderr.trim(),
        format!(
            "error: scene.toml:{line}: mesh[0].file: meshes/bad.m:2: Vertex 2: 'NaN' is not a finite number"
        )
    );
}
