//! The PLY reader: the three encodings, attributes, flat shading without normals, and
//! one-line errors.

use super::*;

const ASCII: &str = "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 4\n\
    property float x\nproperty float y\nproperty float z\nproperty float s\nproperty float t\n\
    property uchar red\nproperty uchar green\nproperty uchar blue\n\
    element face 1\nproperty list uchar int vertex_indices\nend_header\n\
    0 0 0 0 0 255 0 0\n1 0 0 1 0 0 255 0\n1 1 0 1 1 0 0 255\n0 1 0 0 1 255 255 255\n4 0 1 2 3\n";

fn parse(b: &[u8]) -> Result<Mesh> {
    parse_ply(b, Path::new("t.ply")).map(|(m, _)| m)
}

/// The same quad as binary, with normals, in either byte order.
fn binary(be: bool) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_{}_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\nproperty float nx\nproperty float ny\nproperty float nz\n\
         property double u\nproperty double v\nelement face 1\n\
         property list uchar uint vertex_index\nend_header\n",
        if be { "big" } else { "little" }
    )
    .into_bytes();
    let f = |b: &mut Vec<u8>, x: f32| b.extend(if be { x.to_be_bytes() } else { x.to_le_bytes() });
    for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        for v in [x, y, 0.0, 0.0, 0.0, 1.0] {
            f(&mut b, v);
        }
        for v in [x as f64, y as f64] {
            b.extend(if be { v.to_be_bytes() } else { v.to_le_bytes() });
        }
    }
    b.push(4);
    for i in 0u32..4 {
        b.extend(if be { i.to_be_bytes() } else { i.to_le_bytes() });
    }
    b
}

#[test]
fn ascii_with_uv_and_colours() {
    let m = parse(ASCII.as_bytes()).unwrap();
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(m.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
    let c = m.colors.unwrap();
    assert_eq!((c[0], c[3]), (Vec3::X, Vec3::ONE));
}

/// Without `nx ny nz` a fold keeps its two flat faces; with them, the file's normals.
#[test]
fn without_normals_faces_are_flat() {
    let fold = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
        property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n\
        0 0 0\n1 0 0\n1 1 0\n0 0 1\n3 0 1 2\n3 1 0 3\n";
    let m = parse(fold.as_bytes()).unwrap();
    let n = m.normals.as_ref().unwrap();
    for (t, want) in [(0, Vec3::Z), (1, Vec3::Y)] {
        for &v in &m.triangles[t] {
            assert_eq!(n[v as usize], want, "triangle {t}");
        }
    }
    assert_eq!(
        m.positions.len(),
        6,
        "the fold's two shared corners are split"
    );
}

#[test]
fn binary_both_byte_orders() {
    for be in [false, true] {
        let m = parse(&binary(be)).unwrap();
        assert_eq!(m.triangles.len(), 2);
        assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert!(m.normals.unwrap().iter().all(|n| *n == Vec3::Z));
        assert_eq!(m.uvs.unwrap()[1], Vec2::new(1.0, 0.0));
    }
}

#[test]
fn malformed_files_give_one_line_errors() {
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (b"plx\n".to_vec(), "t.ply:1: not a PLY file"),
        (
            ASCII.replace("end_header", "end_headr").into_bytes(),
            "no 'end_header'",
        ),
        (
            ASCII.replace("vertex 4", "vertex 4000000000").into_bytes(),
            "claims 4000000000",
        ),
        (
            ASCII.replace("4 0 1 2 3", "4 0 1 2 9").into_bytes(),
            "t.ply:20: face 0 vertex_indices: vertex index 9 out of range",
        ),
        (
            ASCII.replace("1 1 0 1 1", "1 nan 0 1 1").into_bytes(),
            "t.ply:18: vertex 2 y: 'nan' is not a finite number",
        ),
        (
            ASCII.replace("1 1 0 1 1", "1 1e39 0 1 1").into_bytes(),
            "t.ply:18: vertex 2 x y z: position overflows",
        ),
        (
            ASCII.replace("255 255 255", "255 256 255").into_bytes(),
            "t.ply:19: vertex 3 green",
        ),
        (
            ASCII.replace("4 0 1 2 3", "2 0 1").into_bytes(),
            "a face needs 3",
        ),
        (
            ASCII.replace("property float x\n", "").into_bytes(),
            "needs properties x, y and z",
        ),
        (
            ASCII.replace("format ascii", "format binary").into_bytes(),
            "unknown format",
        ),
        (
            {
                let b = binary(true);
                b[..b.len() - 10].to_vec()
            },
            "t.ply: binary body at byte",
        ),
    ];
    for (b, want) in cases {
        let e = parse(&b).unwrap_err().to_string();
        assert!(
            e.contains(want) && !e.contains('\n'),
            "want {want:?}, got {e}"
        );
    }
    let mut nan = binary(false);
    let at = nan.len() - 17 - 4 * 40 + 4;
    nan[at..at + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    let e = parse(&nan).unwrap_err().to_string();
    assert!(e.contains("not a finite number"), "{e}");
}
