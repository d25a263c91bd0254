//! Every mesh shipped in `meshes/` loads, the course meshes with their expected counts.

mod common;

use std::path::PathBuf;
use whitted::io::load_mesh;

#[test]
fn every_shipped_mesh_loads() {
    let dir = common::assets().join("meshes");
    let expect = [
        ("kitten.m", 20_438, true, true, false),
        ("kitten_rgb.m", 20_438, true, true, true),
        ("fandisk.m", 12_946, true, false, false),
        ("stanford-bunny.obj", 69_451, true, false, false),
        ("spot.obj", 5_856, true, true, false),
        ("teapot.obj", 6_320, true, false, false),
    ];
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if !whitted::io::MESH_EXTENSIONS.contains(&whitted::io::extension(&path).as_str()) {
            continue; // the README
        }
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        let (mesh, _warnings) = load_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
        assert!(!mesh.triangles.is_empty());
        let normals = mesh.normals.as_ref().expect("normals are always filled in");
        assert!(
            normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-3),
            "{name}: unit normals"
        );
        if let Some(&(_, tris, _, uv, rgb)) = expect.iter().find(|e| e.0 == name) {
            assert_eq!(mesh.triangles.len(), tris, "{name}");
            assert_eq!(mesh.uvs.is_some(), uv, "{name} uv");
            assert_eq!(mesh.colors.is_some(), rgb, "{name} rgb");
            seen += 1;
        }
    }
    assert_eq!(seen, expect.len(), "all expected meshes present");
}

#[test]
fn kitten_is_closed_and_sits_on_y_minus_1() {
    let (m, _) = load_mesh(&common::assets().join("meshes/kitten.m")).unwrap();
    assert_eq!(m.open_edges(), 0);
    let (lo, _hi) = m.bounds().unwrap();
    assert!((lo.y + 1.0).abs() < 1e-3, "{lo}");
}

#[test]
fn project_meshes_load() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes");
    let (t, _) = load_mesh(&dir.join("tetrahedron.m")).unwrap();
    assert_eq!((t.triangles.len(), t.open_edges()), (4, 0));
    let (q, _) = load_mesh(&dir.join("quad_uv_rgb.m")).unwrap();
    assert!(q.uvs.is_some() && q.colors.is_some());
    // The cube is shaded flat (no `vn`): its corners are split per face, so it is closed by
    // position, not by vertex index.
    let (c, _) = load_mesh(&dir.join("cube.obj")).unwrap();
    assert_eq!(
        (c.triangles.len(), whitted::info::open_edges_by_position(&c)),
        (12, 0)
    );
    for t in 0..c.triangles.len() {
        let centroid: glam::Vec3 = c.triangles[t]
            .iter()
            .map(|&i| c.positions[i as usize])
            .sum();
        assert!(
            c.face_cross(t).dot(centroid) > 0.0,
            "cube face {t} points outwards"
        );
    }
    let (p, _) = load_mesh(&dir.join("prism.m")).unwrap();
    assert_eq!((p.triangles.len(), p.open_edges()), (8, 0));
}
