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
    // (the 16-ray engines and `wide`'s batch walks a second time without their AVX-512
    // kernels, as on a CPU without AVX-512: `WHITTED_NO_AVX512`)
    for (engine, no512) in [
        ("auto", false),
        ("packet", false),
        ("wide", false),
        ("wide", true),
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
    let unknown = tmp("x.3ds");
    std::fs::write(&unknown, "MM").unwrap();
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
            vec!["info".to_string(), unknown.display().to_string()],
            vec![
                "x.3ds: not a file type whitted reads; it reads meshes (.m, .obj, .ply, .stl, .gltf, .glb), scenes (.toml)",
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

/// Runs `whitted ARGS` from the project folder; (exit code, stdout, stderr).
fn run(args: &[&str]) -> (Option<i32>, String, String) {
    common::whitted(args)
}

/// A failure: exit code 2 and one line on stderr holding every `want`.
fn fails_with(args: &[&str], wants: &[&str]) {
    let (code, _, stderr) = run(args);
    assert_eq!(code, Some(2), "{args:?}: {stderr}");
    assert_eq!(
        stderr.trim().lines().count(),
        1,
        "{args:?}: one line: {stderr}"
    );
    assert!(!stderr.contains("panicked"), "{args:?}: {stderr}");
    for want in wants {
        assert!(stderr.contains(want), "{args:?}: want {want:?} in {stderr}");
    }
}

/// A success; its stdout.
fn succeeds(args: &[&str]) -> String {
    let (code, stdout, stderr) = run(args);
    assert_eq!(code, Some(0), "{args:?}: {stderr}");
    stdout
}

/// `-D background.cubemap=...` replaces the colour (and `-D background.color=...` the cube
/// map), as the README's own example does; a whole table can be given inline.
#[test]
fn d_one_background_key_replaces_the_other() {
    let toml = succeeds(&[
        "scene",
        "phong",
        "-D",
        "background.cubemap=textures/cubemap",
    ]);
    assert!(toml.contains("cubemap = \"textures/cubemap\""), "{toml}");
    let background = toml.split("[background]").nth(1).unwrap();
    assert!(
        !background.split("[[").next().unwrap().contains("color"),
        "{toml}"
    );
    let info = succeeds(&[
        "info",
        "cubemap",
        "-D",
        "background.color=[0, 0, 0]",
        "--json",
    ]);
    assert!(
        info.contains("\"background\":{\"color\":[0.0,0.0,0.0]}"),
        "{info}"
    );
    for d in [
        "background.cubemap=textures/cubemap",
        "background={cubemap=\"textures/cubemap\"}",
    ] {
        let out = tmp("bg.png").display().to_string();
        succeeds(&[
            "render", "phong", "-D", d, "--width", "32", "--height", "24", "-q", "-o", &out,
        ]);
    }
    // Both at once is still refused, with the file's line.
    let both = tmp("both.toml");
    let scene = succeeds(&["scene", "phong"]).replace(
        "[background]\n",
        "[background]\ncubemap = \"textures/cubemap\"\n",
    );
    let line = 1 + scene
        .lines()
        .position(|l| l.starts_with("cubemap"))
        .unwrap();
    std::fs::write(&both, scene).unwrap();
    fails_with(
        &["render", both.to_str().unwrap(), "-q"],
        &[&format!(
            "both.toml:{line}: background: give at most one of 'color' or 'cubemap'"
        )],
    );
}

/// Lights (and materials, meshes) are appended with `name[+]={...}`, or key by key at the
/// index one past the end; an entry left incomplete names its `-D`.
#[test]
fn d_appends_lights() {
    let lights = |defs: &[&str]| {
        let mut args = vec!["info", "phong", "--json"];
        for d in defs {
            args.extend(["-D", d]);
        }
        let out = succeeds(&args);
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        v["lights"].as_u64().unwrap()
    };
    assert_eq!(lights(&[]), 2);
    assert_eq!(
        lights(&["light[+]={position=[0, 5, 5], intensity=[1, 1, 1]}"]),
        3
    );
    assert_eq!(
        lights(&[
            "light[2].position=[0, 5, 5]",
            "light[2].intensity=[1, 1, 1]",
            "light[+]={position=[1, 5, 5], intensity=[0.5, 0.5, 0.5]}",
        ]),
        4
    );
    fails_with(
        &["info", "phong", "-D", "light[2].position=[0, 5, 5]"],
        &["-D 'light[2].position=[0, 5, 5]': missing field `intensity`"],
    );
    fails_with(
        &["info", "phong", "-D", "light[5].position=[0, 5, 5]"],
        &["'light' has 2 entries"],
    );
    // A material appended with only a colour gets the documented defaults.
    let toml = succeeds(&[
        "scene",
        "phong",
        "-D",
        "material[+]={name=\"red\", color=[1, 0, 0]}",
        "-D",
        "mesh[0].material=red",
    ]);
    assert!(toml.contains("name = \"red\""), "{toml}");
}

/// `info` and `scene` take built-in names, scene files and `-D`; `-D` on a mesh is refused.
#[test]
fn info_and_scene_take_builtin_names_files_and_d() {
    let text = succeeds(&["info", "phong"]);
    assert!(text.starts_with("kind: scene\n"), "{text}");
    let json = succeeds(&["info", "refraction", "-D", "render.depth=4", "--json"]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(
        (v["kind"].as_str(), v["depth"].as_u64()),
        (Some("scene"), Some(4))
    );
    let file = tmp("scene-file.toml");
    std::fs::write(&file, succeeds(&["scene", "texture"])).unwrap();
    let f = file.to_str().unwrap();
    let printed = succeeds(&["scene", f, "-D", "camera.vfov=30"]);
    assert!(printed.contains("vfov = 30"), "{printed}");
    assert!(succeeds(&["info", f]).contains("kind: scene"));
    let json = succeeds(&["info", f, "-D", "image.width=320", "--json"]);
    assert!(json.contains("\"width\":320"), "{json}");
    fails_with(
        &["info", "phong", "-D", "camera.vfov=200"],
        &[
            "camera.vfov: must be in (0, 180)",
            "(set by -D 'camera.vfov=200')",
        ],
    );
    fails_with(
        &["info", "meshes/cube.obj", "-D", "camera.vfov=30"],
        &["-D applies to scenes"],
    );
    fails_with(&["scene", "nosuch"], &["neither a built-in scene"]);
}

/// A file of a type whitted does not read is refused by its extension, naming the types it
/// reads, instead of being parsed as TOML.
#[test]
fn unknown_extensions_are_named_with_the_known_ones() {
    let unknown = tmp("a.3ds");
    std::fs::write(&unknown, "MM").unwrap();
    let s = unknown.to_str().unwrap();
    fails_with(
        &["render", s],
        &[
            "a.3ds: unknown file type '.3ds'",
            ".toml",
            ".m, .obj, .ply, .stl, .gltf, .glb",
        ],
    );
    fails_with(
        &["scene", s],
        &[
            "unknown file type '.3ds'",
            ".m, .obj, .ply, .stl, .gltf, .glb",
        ],
    );
    fails_with(
        &[
            "trace-rays",
            s,
            "--rays",
            "Cargo.toml",
            "--hits",
            "/dev/null",
        ],
        &[
            "unknown mesh format '.3ds'",
            ".m, .obj, .ply, .stl, .gltf, .glb",
        ],
    );
}

/// Validation errors name the scene file and the line of the key (or of its table); the
/// image size from `--width/--height` names the options.
#[test]
fn validation_errors_name_file_and_line() {
    let scene = succeeds(&["scene", "phong"]);
    let ior = scene.replacen("ior = 1.5", "ior = 0", 1);
    let line = 1 + ior.lines().position(|l| l == "ior = 0").unwrap();
    let p = tmp("p.toml");
    std::fs::write(&p, &ior).unwrap();
    let ps = p.to_str().unwrap();
    fails_with(
        &["render", ps, "-q"],
        &[&format!(
            "p.toml:{line}: material[0] 'kitten'.ior: must be a finite number > 0"
        )],
    );
    let zero = scene.replacen("width = 1024", "width = 0", 1);
    let line = 1 + zero.lines().position(|l| l == "width = 0").unwrap();
    std::fs::write(&p, &zero).unwrap();
    fails_with(
        &["render", ps, "-q"],
        &[&format!("p.toml:{line}: image: image size 0x768")],
    );
    fails_with(&["info", ps], &[&format!("p.toml:{line}: image")]);
    fails_with(
        &["render", "phong", "--width", "0", "-q"],
        &["--width 0: the image size must be > 0 pixels"],
    );
    fails_with(
        &["render", "phong", "-D", "image.width=0", "-q"],
        &["image size 0x768", "(set by -D 'image.width=0')"],
    );
    // A key a table lacks points at the table's first key.
    let vfov = scene.replacen("vfov = 36.0", "vfov = 360.0", 1);
    let line = 1 + vfov.lines().position(|l| l == "vfov = 360.0").unwrap();
    std::fs::write(&p, &vfov).unwrap();
    fails_with(
        &["info", ps],
        &[&format!("p.toml:{line}: camera.vfov: must be in (0, 180)")],
    );
}

/// Only `camera.eye` and `camera.look_at` are required: image size, vfov, `[render]`,
/// `[background]` and a material's coefficients have documented defaults, so a material
/// with only a colour renders, like the default material of a mesh rendered alone.
#[test]
fn a_material_with_only_a_colour_renders() {
    let p = tmp("min.toml");
    std::fs::write(
        &p,
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n\n[[light]]\nposition = [5, 6, 3]\n\
         intensity = [0.9, 0.9, 0.85]\n\n[[material]]\nname = \"red\"\ncolor = [0.8, 0.1, 0.1]\n\n\
         [[mesh]]\nshape = \"sphere\"\nmaterial = \"red\"\n",
    )
    .unwrap();
    let ps = p.to_str().unwrap();
    let json = succeeds(&["info", ps, "--json"]);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(1024), Some(768))
    );
    assert_eq!(v["camera"]["vfov"].as_f64(), Some(36.0));
    assert_eq!(
        v["background"]["color"],
        serde_json::json!([0.1, 0.12, 0.16])
    );
    assert_eq!(v["depth"].as_u64(), Some(1));
    let toml = succeeds(&["scene", ps]);
    let material = toml.split("[[material]]").nth(1).unwrap();
    for want in [
        "ka = 0.3",
        "kd = 0.7",
        "ks = 0.1",
        "n = 40.0",
        "ior = 1.5",
        "kr = 0.0",
    ] {
        assert!(material.contains(want), "{want}: {toml}");
    }
    assert!(toml.contains("ambient = [0.15, 0.15, 0.18]"), "{toml}");
    let out = tmp("min.png");
    succeeds(&[
        "render",
        ps,
        "--width",
        "40",
        "--height",
        "30",
        "-q",
        "-o",
        out.to_str().unwrap(),
    ]);
    let img = image::open(&out).unwrap().to_rgb8();
    let centre = img.get_pixel(20, 15);
    assert!(
        centre[0] > 100 && centre[0] > 2 * centre[1],
        "a lit red sphere: {centre:?}"
    );
    // The mesh alone gets the same material values.
    let alone = succeeds(&["scene", "meshes/tetrahedron.m"]);
    assert!(
        alone.contains("ka = 0.3") || !alone.contains("[[material]]"),
        "{alone}"
    );
}

/// Every option and argument of every subcommand has a help text.
#[test]
fn every_flag_has_help() {
    for sub in ["render", "scene", "info", "trace-rays", "merge", "bench"] {
        let help = succeeds(&[sub, "--help"]);
        let lines: Vec<&str> = help.lines().collect();
        let mut seen = 0;
        for (i, line) in lines.iter().enumerate() {
            let t = line.trim_start();
            let indent = line.len() - t.len();
            let is_arg = (2..=6).contains(&indent)
                && (t.starts_with('-') || t.starts_with('<') || t.starts_with('['));
            if !is_arg {
                continue;
            }
            seen += 1;
            // The long help puts each argument's text on the lines under it, indented more.
            let next = lines.get(i + 1).copied().unwrap_or("");
            let under =
                next.len() - next.trim_start().len() > indent + 2 && !next.trim().is_empty();
            let beside = t
                .split_once("  ")
                .is_some_and(|(_, r)| !r.trim().is_empty());
            let text = under || beside;
            assert!(text, "{sub}: no help on `{line}`\n{help}");
        }
        assert!(seen >= 2, "{sub}: {help}");
    }
    let render = succeeds(&["render", "--help"]);
    assert!(render.contains("Image width in pixels"), "{render}");
    for sub in ["trace-rays", "bench"] {
        let help = succeeds(&[sub, "--help"]);
        assert!(
            help.contains(".m, .obj, .ply, .stl, .gltf or .glb"),
            "{sub}: {help}"
        );
    }
}

/// pbrt's spellings are accepted: `--cropwindow x0 x1 y0 y1`, `--pixelbounds`, `--outfile`,
/// `--nthreads`; the space-separated crop equals the comma form bit for bit.
#[test]
fn pbrt_spellings_are_aliases() {
    let (a, b, c) = (tmp("crop-a.png"), tmp("crop-b.png"), tmp("crop-c.png"));
    let size = ["--width", "64", "--height", "48", "-q"];
    let mut args = vec![
        "render",
        "phong",
        "--crop",
        "0,0.5,0,0.5",
        "-o",
        a.to_str().unwrap(),
    ];
    args.extend(size);
    succeeds(&args);
    let mut args = vec![
        "render",
        "--cropwindow",
        "0",
        "0.5",
        "0",
        "0.5",
        "phong",
        "--nthreads",
        "1",
        "--outfile",
        b.to_str().unwrap(),
    ];
    args.extend(size);
    succeeds(&args);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let mut args = vec![
        "render",
        "phong",
        "--pixelbounds",
        "0",
        "32",
        "0",
        "24",
        "-o",
        c.to_str().unwrap(),
    ];
    args.extend(size);
    succeeds(&args);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&c).unwrap());
    // A comma list is the whole value: the scene after it stays the scene.
    let d = tmp("crop-d.png");
    let mut args = vec![
        "render",
        "--crop",
        "0,0.5,0,0.5",
        "phong",
        "-o",
        d.to_str().unwrap(),
    ];
    args.extend(size);
    succeeds(&args);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&d).unwrap());
    assert!(succeeds(&["trace-rays", "--help"]).contains("nthreads"));
    fails_with(
        &["render", "phong", "--crop", "-0.5,0.5,0,1", "-q"],
        &["--crop -0.5,0.5,0,1: four fractions in [0, 1]"],
    );
}

/// A negative count gets whitted's own message, not clap's "use '-- -1'" hint.
#[test]
fn negative_spp_gets_a_clear_message() {
    for spp in ["-1", "0", "5000"] {
        fails_with(
            &["render", "phong", "--spp", spp, "-q"],
            &[&format!(
                "--spp {spp}: samples per pixel must be in 1..=4096"
            )],
        );
    }
    fails_with(
        &["render", "phong", "--width", "-5", "-q"],
        &["--width -5: the image size must be > 0 pixels"],
    );
}

/// `scene` of a mesh without MTL materials prints no empty material list and no comment
/// about MTL; one with materials says they are mapped from MTL.
#[test]
fn scene_of_a_mesh_without_mtl() {
    let toml = succeeds(&["scene", "meshes/fandisk.m"]);
    assert!(!toml.contains("material = []"), "{toml}");
    assert!(
        !toml.contains("light = []") && !toml.contains("mesh = []"),
        "{toml}"
    );
    assert!(!toml.contains("MTL"), "{toml}");
    assert!(toml.contains("default material"), "{toml}");
    let dir = tmp("mtl");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("t.mtl"), "newmtl red\nKd 1 0 0\n").unwrap();
    std::fs::write(
        dir.join("t.obj"),
        "mtllib t.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl red\nf 1 2 3\n",
    )
    .unwrap();
    let toml = succeeds(&["scene", dir.join("t.obj").to_str().unwrap()]);
    assert!(
        toml.contains("mapped from MTL") && toml.contains("name = \"red\""),
        "{toml}"
    );
}

/// Open edges are counted by position: `spot.obj` splits vertices at its uv seams but is
/// closed.
#[test]
fn info_counts_open_edges_by_position() {
    let text = succeeds(&["info", "meshes/spot.obj"]);
    assert!(text.contains("open_edges: 0\n"), "{text}");
    // An open mesh still has its boundary: a single triangle has 3.
    let tri = tmp("tri.obj");
    std::fs::write(&tri, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let text = succeeds(&["info", tri.to_str().unwrap()]);
    assert!(text.contains("open_edges: 3\n"), "{text}");
}

/// `kr` follows `ks` when `ks` is given, in the file or by `-D`, and is 0 when neither `ks`
/// nor `kr` is given.
#[test]
fn kr_follows_ks_when_ks_is_given() {
    let p = tmp("kr.toml");
    std::fs::write(
        &p,
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[material]]\nname = \"a\"\n\
         [[material]]\nname = \"b\"\nks = 0.5\n[[mesh]]\nshape = \"cube\"\nmaterial = \"a\"\n",
    )
    .unwrap();
    let ps = p.to_str().unwrap();
    let kr = |toml: &str, name: &str| {
        let m = toml
            .split("[[material]]")
            .find(|m| m.contains(&format!("name = \"{name}\"")))
            .unwrap()
            .to_string();
        m.lines()
            .find(|l| l.starts_with("kr = "))
            .map(|l| l.to_string())
    };
    let toml = succeeds(&["scene", ps]);
    assert_eq!(kr(&toml, "a").as_deref(), Some("kr = 0.0"), "{toml}");
    assert_eq!(kr(&toml, "b"), None, "b's kr is its ks: {toml}");
    let toml = succeeds(&["scene", ps, "-D", "material[0].ks=0.7"]);
    assert_eq!(
        kr(&toml, "a"),
        None,
        "a's kr follows the ks set by -D: {toml}"
    );
}
