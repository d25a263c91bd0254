//! Tests of the scene format: parsing, overrides, validation and the lines errors name.

use super::*;
use crate::error::Result;
use crate::scene::{Albedo, Scene};
use glam::Vec3;
use std::path::Path;

const MINIMAL: &str = r#"
[image]
width = 4
height = 3
[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
vfov = 40
[background]
color = [0.1, 0.2, 0.3]
[[material]]
name = "m"
color = [1, 1, 1]
ka = 0.1
kd = 0.9
ks = 0
n = 1
[[mesh]]
material = "m"
vertices = [[-1, -1, 0], [1, -1, 0], [0, 1, 0]]
faces = [[0, 1, 2]]
"#;

fn build(text: &str) -> Result<Scene> {
    let p = Path::new("s.toml");
    let f = SceneFile::parse(text, p)?;
    build_scene(&f, p, &SearchPath::for_scene(None)).map(|(s, _)| s)
}

#[test]
fn minimal_scene_loads_and_roundtrips() {
    let s = build(MINIMAL).unwrap();
    assert_eq!(
        (s.width, s.height, s.depth, s.cull_backfaces),
        (4, 3, 1, true)
    );
    assert_eq!(s.objects[0].mesh.triangles.len(), 1);
    let f = SceneFile::parse(MINIMAL, Path::new("s")).unwrap();
    assert_eq!(SceneFile::parse(&f.to_toml(), Path::new("s")).unwrap(), f);
}

#[test]
fn overrides_replace_alternatives_and_append_entries() {
    let f = SceneFile::parse(MINIMAL, Path::new("s.toml")).unwrap();
    let d = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let g = f.with_overrides(&d(&["background.cubemap=sky"])).unwrap();
    assert_eq!(g.background.color, None);
    assert_eq!(g.background.cubemap.as_deref(), Some("sky"));
    let g = f
        .with_overrides(&d(&[
            "light[+]={position=[0, 1, 0], intensity=[1, 1, 1]}",
            "light[1].position=[1, 1, 1]",
            "light[1].intensity=[0.5, 0.5, 0.5]",
            "material[0].texture=t.png",
        ]))
        .unwrap();
    assert_eq!(g.lights.len(), 2);
    assert_eq!(g.lights[1].intensity, [0.5; 3]);
    assert_eq!(g.materials[0].color, None);
    let e = f
        .with_overrides(&d(&["light[0].position=[1, 1, 1]"]))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("-D 'light[0].position=[1, 1, 1]': missing field `intensity`"),
        "{e}"
    );
}

#[test]
fn validation_errors_carry_the_key_line_and_defaults_fill_the_rest() {
    let e = build(&MINIMAL.replace("vfov = 40", "vfov = 400"))
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("s.toml:8: camera.vfov"), "{e}");
    // Only the camera's eye and look_at are required.
    let s = build(
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[material]]\nname = \"m\"\n\
         [[mesh]]\nmaterial = \"m\"\nshape = \"cube\"\n",
    )
    .unwrap();
    assert_eq!(
        (s.width, s.height, s.view.vfov, s.depth),
        (1024, 768, 36.0, 1)
    );
    let m = &s.materials[0];
    assert_eq!(
        (m.ka, m.kd, m.ks, m.n),
        (Vec3::splat(0.3), Vec3::splat(0.7), Vec3::splat(0.1), 40.0)
    );
    assert_eq!(m.kr, Vec3::ZERO);
    assert!(matches!(m.albedo, Albedo::Color(c) if c == Vec3::splat(DEFAULT_COLOR)));
}

#[test]
fn key_lines_point_at_keys() {
    let text = "a = 1\n[image]\nwidth = 4\n[background]\ncubemap = \"sky\"\n[[mesh]]\n\
        file = \"a.m\"\n[[mesh]]\n\nfile = \"b.m\"\n";
    let lines = KeyLines::of(text);
    for (key, line) in [
        ("a", 1),
        ("image.width", 3),
        ("background.cubemap", 5),
        ("mesh[0].file", 7),
        ("mesh[1].file", 10),
    ] {
        assert_eq!(lines.line(key), Some(line), "{key}");
    }
    assert_eq!(lines.line("mesh[2].file"), None);
    assert!(KeyLines::of("not toml = = =").line("a").is_none());
}

#[test]
fn errors_name_key_or_line() {
    let cases = [
        (
            MINIMAL.replace("vfov = 40", "vfov = 40\nfov = 3"),
            "s.toml:9: column 1: unknown field `fov`",
        ),
        (MINIMAL.replace("vfov = 40", "vfov = 180"), "camera.vfov"),
        (
            MINIMAL.replace("width = 4", "width = 0"),
            "width and height must be > 0",
        ),
        (
            MINIMAL.replace(
                "width = 4\nheight = 3",
                "width = 4000000000\nheight = 4000000000",
            ),
            "over the cap",
        ),
        (
            MINIMAL.replace("look_at = [0, 0, 0]", "look_at = [0, 0, 0]\nup = [0, 0, 1]"),
            "camera.up",
        ),
        (MINIMAL.replace("kd = 0.9", "kd = nan"), "'m'.kd"),
        (MINIMAL.replace("kd = 0.9", "kd = 0.9\nior = 0"), "ior"),
        (
            MINIMAL.replace("kd = 0.9", "kd = -1"),
            ".kd: must be a finite number >= 0",
        ),
        (
            MINIMAL.replace("material = \"m\"", "material = \"x\""),
            "no material named 'x'",
        ),
        (
            MINIMAL.replace("[[0, 1, 2]]", "[[0, 1, 3]]"),
            "mesh[0].faces[0]",
        ),
        (
            MINIMAL.replace("[[mesh]]", "[render]\ndepth = 1000\n[[mesh]]"),
            "render.depth",
        ),
        (
            MINIMAL.replace("color = [0.1, 0.2, 0.3]", "color = [-1, 0, 0]"),
            "background.color",
        ),
        (
            MINIMAL.replace(
                "vertices = [[-1, -1, 0], [1, -1, 0], [0, 1, 0]]\nfaces = [[0, 1, 2]]",
                "file = \"nope/missing.m\"",
            ),
            "cannot find 'nope/missing.m'; searched:",
        ),
    ];
    for (text, want) in cases {
        let e = build(&text).unwrap_err().to_string();
        assert!(
            e.contains(want) && e.starts_with("s.toml"),
            "want {want:?}, got {e}"
        );
    }
}

use crate::mesh::shading::is_flat;

/// A scene of one mesh entry with `keys` added to it.
fn one_mesh(entry: &str) -> Result<Scene> {
    build(&format!(
        "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[material]]\nname = \"m\"\n\
         [[mesh]]\nmaterial = \"m\"\n{entry}\n"
    ))
}

/// `smooth` and `crease` override the normals a format means: the cube OBJ (flat without
/// them) becomes a pillow with `smooth = true` and stays flat at `crease = 60`; the kitten
/// (the file's normals) becomes flat with `smooth = false` and keeps its normals with
/// `smooth = true`; a generated cube is rounded by `smooth = true`.
#[test]
fn smooth_and_crease_keys_override_the_format() {
    let mesh = |entry: &str| one_mesh(entry).unwrap().objects.remove(0).mesh;
    let cube = "file = \"meshes/cube.obj\"";
    assert!(is_flat(&mesh(cube)));
    assert!(!is_flat(&mesh(&format!("{cube}\nsmooth = true"))));
    // One normal per point (the flat file's split vertices stay split, with equal normals).
    let smooth = mesh(&format!("{cube}\nsmooth = true"));
    let n = smooth.normals.as_ref().unwrap();
    for (a, b) in smooth.positions.iter().zip(n) {
        for (c, d) in smooth.positions.iter().zip(n) {
            assert!(a != c || b == d, "{a}: {b} and {d}");
        }
    }
    assert!(is_flat(&mesh(&format!("{cube}\ncrease = 60"))));
    assert!(!is_flat(&mesh(&format!("{cube}\ncrease = 120"))));
    assert!(is_flat(&mesh(&format!(
        "{cube}\nsmooth = true\ncrease = 89"
    ))));

    let kitten = "file = \"meshes/kitten.m\"";
    let own = mesh(kitten);
    assert!(!is_flat(&own));
    assert_eq!(mesh(&format!("{kitten}\nsmooth = true")), own);
    let flat = mesh(&format!("{kitten}\nsmooth = false"));
    assert!(is_flat(&flat));
    assert_eq!(flat.triangles.len(), own.triangles.len());

    assert!(is_flat(&mesh("shape = \"cube\"")));
    assert!(!is_flat(&mesh("shape = \"cube\"\nsmooth = true")));
    // Subdivision comes after the override and keeps a flat mesh flat.
    assert!(is_flat(&mesh(&format!("{cube}\nsubdivide = 1"))));
}

#[test]
fn bad_crease_keys_name_the_key_and_line() {
    let cube = "file = \"meshes/cube.obj\"";
    for (keys, want) in [
        (
            "crease = 200",
            "s.toml:9: mesh[0].crease: must be an angle in 0..=180 degrees, found 200",
        ),
        ("crease = nan", "mesh[0].crease: must be an angle"),
        (
            "smooth = false\ncrease = 30",
            "mesh[0].crease: a crease angle smooths the flatter edges",
        ),
    ] {
        let e = one_mesh(&format!("{cube}\n{keys}"))
            .unwrap_err()
            .to_string();
        assert!(e.contains(want), "{keys}: {e}");
    }
}

/// `[[instance]]` tables are read one at a time (`instance_text.rs`): the same scene as the
/// TOML parser reads whole, the same lines for their keys, errors on the right line; a
/// multi-line matrix whose rows begin lines is no table header.
#[test]
fn instance_tables_read_alone_are_the_whole_parse() {
    let text = format!(
        "{MINIMAL}name = \"tri\"\n\n[[instance]] # the first\nmesh = \"tri\"\ntranslate = [1, 2, 3]\n\
         [render]\ndepth = 2\n  [[ instance ]]\nmesh = \"tri\"\nmatrix = [\n[1, 0, 0, 0],\n  [0, 1, 0, 0],\n\
         [0, 0, 1, 0], [0, 0, 0, 1]]\n[[light]]\nposition = [0, 5, 5]\nintensity = [1, 1, 1]\n\
         [[instance]]\nmesh = \"tri\"\nscale = [1, 2, 1]\nmaterial = \"m\"\n"
    );
    let path = Path::new("s.toml");
    let file = SceneFile::parse(&text, path).unwrap();
    let whole: SceneFile = toml::from_str(&text).unwrap();
    assert_eq!(file.instances.len(), 3);
    assert_eq!(file.instances, whole.instances);
    assert_eq!(file.render, whole.render);
    assert_eq!(file.lights, whole.lights);
    assert_eq!(file.meshes, whole.meshes);
    let line = |key: &str| {
        let at = text.find(key).unwrap();
        text[..at].matches('\n').count() + 1
    };
    assert_eq!(
        file.lines.line("instance[0].translate"),
        Some(line("translate"))
    );
    assert_eq!(file.lines.line("instance[1].matrix"), Some(line("matrix")));
    assert_eq!(
        file.lines.line("instance[2].scale"),
        Some(line("scale = [1, 2"))
    );
    assert_eq!(file.lines.line("render.depth"), Some(line("depth = 2")));
    assert_eq!(file.lines.line("light[0].position"), Some(line("position")));
    // an error in a table names its line and column
    let bad = text.replace("scale = [1, 2, 1]", "scale = [1, 2, 1]\nshear = 3");
    let e = SceneFile::parse(&bad, path).unwrap_err().to_string();
    let want = format!(
        "s.toml:{}: column 1: unknown field `shear`",
        line("scale = [1, 2") + 1
    );
    assert!(e.starts_with(&want), "{e}");
    // an array and tables of instances together are refused, as the parser refuses them
    let both = format!("instance = [{{ mesh = \"tri\" }}]\n{text}");
    let e = SceneFile::parse(&both, path).unwrap_err().to_string();
    assert!(
        e.contains("both as an array and as [[instance]] tables"),
        "{e}"
    );
}
