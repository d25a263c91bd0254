//! STL end to end: the shipped ASCII and binary cubes render, trace and inspect alike (and
//! like the flat-shaded `cube.obj`), and a broken STL is one error line naming the file and
//! where, with exit code 2.

mod common;

use common::whitted;
use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    common::scratch("stl", name)
}

fn render(mesh: &str, out: &Path) {
    common::render_small(mesh, out)
}

/// `whitted render x.stl` frames the mesh and renders it; the two encodings of one cube
/// give the same image, and the cube is in it (not only background).
#[test]
fn ascii_and_binary_cubes_render_the_same_image() {
    let (a, b) = (tmp("ascii.png"), tmp("binary.png"));
    render("meshes/cube.stl", &a);
    render("meshes/cube_binary.stl", &b);
    let (ia, ib) = (image::open(&a).unwrap(), image::open(&b).unwrap());
    assert_eq!(ia.as_bytes(), ib.as_bytes());
    let px = ia.to_rgb8();
    let corner = *px.get_pixel(0, 0);
    assert!(
        px.pixels().filter(|&&p| p != corner).count() > 500,
        "the cube covers part of the frame"
    );
}

/// `info` reads STL as a mesh: 12 triangles welded to 8 corners (24 vertices once each
/// face has its own normal), closed.
#[test]
fn info_reads_stl() {
    for mesh in ["meshes/cube.stl", "meshes/cube_binary.stl"] {
        let (code, out, err) = whitted(&["info", mesh]);
        assert_eq!(code, Some(0), "{err}");
        assert!(out.contains("triangles: 12\n"), "{out}");
        assert!(out.contains("open_edges: 0\n"), "{out}");
    }
}

/// A scene's `[[mesh]] file` may be an STL, and `trace-rays` takes one.
#[test]
fn scene_meshes_and_trace_rays_take_stl() {
    let (code, _, err) = whitted(&[
        "render",
        "-D",
        "mesh[0].file=meshes/cube_binary.stl",
        "-D",
        "image.width=32",
        "-D",
        "image.height=24",
        "-o",
        tmp("scene.png").to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let rays = [whitted::ray::Ray::new(
        glam::Vec3::new(0.0, 0.0, 5.0),
        glam::Vec3::NEG_Z,
        0.0,
        f32::INFINITY,
    )];
    let input = tmp("rays.bin");
    std::fs::write(&input, whitted::io::rays::encode_rays(&rays)).unwrap();
    let hits = tmp("hits.bin");
    let (code, _, err) = whitted(&[
        "trace-rays",
        "meshes/cube.stl",
        "--rays",
        input.to_str().unwrap(),
        "--hits",
        hits.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let hit = whitted::io::rays::parse_hits(&std::fs::read(&hits).unwrap(), &hits).unwrap();
    let h = hit[0].expect("the ray down the z axis hits the cube");
    assert!((h.t - 4.0).abs() < 1e-5, "{}", h.t);
}

/// A truncated binary STL and a bad ASCII vertex: one line each, with the byte offset or
/// the line, exit code 2, no panic.
#[test]
fn broken_stl_is_one_error_line() {
    let bin = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/cube_binary.stl"))
        .unwrap();
    let cut = tmp("cut.stl");
    std::fs::write(&cut, &bin[..bin.len() - 10]).unwrap();
    let ascii =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/cube.stl"))
            .unwrap();
    let nan = tmp("nan.stl");
    std::fs::write(
        &nan,
        ascii.replacen("vertex -1 -1 -1", "vertex -1 nan -1", 1),
    )
    .unwrap();
    for (file, want) in [
        (&cut, "binary STL, byte 80: the header counts 12 facets"),
        (
            &nan,
            "nan.stl:4: ASCII STL: vertex: (-1, NaN, -1) is not finite",
        ),
    ] {
        let (code, _, err) = whitted(&["render", file.to_str().unwrap()]);
        assert_eq!(code, Some(2), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
        assert!(
            err.contains(want) && !err.contains("panicked"),
            "{want:?}: {err}"
        );
    }
}

/// Flat shading as the formats mean it: `cube.obj` (no `vn`, no smoothing groups) renders
/// exactly as the STL cube, six flat faces; `smooth = true` rounds it into another image.
#[test]
fn cube_obj_is_flat_like_the_stl_cube() {
    let (obj, stl, smooth) = (tmp("cube_obj.png"), tmp("cube_stl.png"), tmp("smooth.png"));
    render("meshes/cube.obj", &obj);
    render("meshes/cube.stl", &stl);
    let (code, _, err) = whitted(&[
        "render",
        "meshes/cube.obj",
        "--width",
        "64",
        "--height",
        "48",
        "-D",
        "mesh[0].smooth=true",
        "-o",
        smooth.to_str().unwrap(),
    ]);
    assert_eq!(code, Some(0), "{err}");
    let bytes = |p: &Path| image::open(p).unwrap().into_bytes();
    assert_eq!(bytes(&obj), bytes(&stl));
    assert_ne!(bytes(&obj), bytes(&smooth));
    let (_, out, _) = whitted(&["info", "meshes/cube.obj"]);
    assert!(
        out.contains("vertices: 24\n"),
        "a vertex per face corner: {out}"
    );
}
