//! The STL reader: both encodings, welding, flat normals, and every error path with its
//! line or byte offset.

use super::*;

/// A binary STL of `tris` (zero normals, zero attributes), with an 80-byte `header`.
pub(crate) fn binary(header: &[u8], tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut b = header.to_vec();
    b.resize(80, b' ');
    b.extend((tris.len() as u32).to_le_bytes());
    for t in tris {
        b.extend([0u8; 12]);
        for v in t {
            for c in v {
                b.extend(c.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

/// Two triangles of a unit square in z = 0, sharing an edge.
const SQUARE: [[[f32; 3]; 3]; 2] = [
    [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
    [[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
];

const ASCII: &str = "solid square\n\
  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 0 0\n      vertex 1 1 0\n    endloop\n  endfacet\n\
  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n      vertex 1 1 0\n      vertex 0 1 0\n    endloop\n  endfacet\n\
endsolid square\n";

fn parse(b: &[u8]) -> Result<Mesh> {
    parse_stl(b, Path::new("t.stl")).map(|(m, _)| m)
}

fn err(b: &[u8]) -> String {
    parse(b).unwrap_err().to_string()
}

#[test]
fn ascii_and_binary_read_the_same_welded_flat_mesh() {
    let a = parse(ASCII.as_bytes()).unwrap();
    let b = parse(&binary(b"binary", &SQUARE)).unwrap();
    assert_eq!(a, b);
    assert_eq!(a.triangles.len(), 2);
    // Welded: 4 corners of the square, not 6; flat: both faces' normal is +z.
    assert_eq!(a.positions.len(), 4);
    assert!(a.normals.unwrap().iter().all(|&n| n == Vec3::Z));
    // CRLF, upper-case keywords, a BOM, blank lines and two solids are read too.
    let loose = format!(
        "\u{feff}{}\r\n\r\n{}",
        ASCII
            .replace('\n', "\r\n")
            .replace("facet normal", "FACET NORMAL"),
        ASCII
    );
    assert_eq!(parse(loose.as_bytes()).unwrap().triangles.len(), 4);
}

#[test]
fn binary_header_may_start_with_solid() {
    let m = parse(&binary(b"solid exported by a CAD tool", &SQUARE)).unwrap();
    assert_eq!(m.triangles.len(), 2);
}

#[test]
fn minus_zero_welds_with_zero() {
    let mut t = SQUARE;
    t[1][0] = [-0.0, -0.0, 0.0];
    assert_eq!(parse(&binary(b"", &t)).unwrap().positions.len(), 4);
}

#[test]
fn flat_faces_of_a_fold_keep_their_own_normals() {
    // Two faces folded 90 degrees along the x axis: each keeps its geometric normal.
    let t = [
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]],
        [[1.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
    ];
    let m = parse(&binary(b"", &t)).unwrap();
    let n = m.normals.as_ref().unwrap();
    for (k, want) in [(0, Vec3::Z), (1, Vec3::Y)] {
        for &v in &m.triangles[k] {
            assert!(
                n[v as usize].distance(want) < 1e-6,
                "{k}: {}",
                n[v as usize]
            );
        }
    }
}

#[test]
fn binary_errors_name_the_byte_offset() {
    let good = binary(b"", &SQUARE);
    let nan_at = |k: usize, v: f32| {
        let mut b = good.clone();
        b[k..k + 4].copy_from_slice(&v.to_le_bytes());
        err(&b)
    };
    // Facet 1, vertex 2, y: 84 + 50 + 12 + 12 + 4.
    let e = nan_at(84 + 50 + 28, f32::NAN);
    assert!(
        e.starts_with("t.stl: binary STL, byte 162: facet 1 vertex 2 y: NaN"),
        "{e}"
    );
    let e = nan_at(84 + 12, f32::INFINITY);
    assert!(e.contains("byte 96: facet 0 vertex 1 x: inf"), "{e}");
    // A normal is not used: NaN there is accepted.
    assert!(
        parse(&{
            let mut b = good.clone();
            b[84..88].copy_from_slice(&f32::NAN.to_le_bytes());
            b
        })
        .is_ok()
    );

    let cases: Vec<(Vec<u8>, &str)> = vec![
        (
            good[..good.len() - 1].to_vec(),
            "byte 80: the header counts 2 facets",
        ),
        (
            good[..100].to_vec(),
            "truncated, or a wrong count (0 whole facets)",
        ),
        (
            [good.clone(), vec![0; 7]].concat(),
            "7 bytes of trailing data",
        ),
        (
            {
                let mut b = good.clone();
                b[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
                b
            },
            "counts 4294967295 facets",
        ),
        (binary(b"", &[]), "byte 80: the header counts 0 facets"),
        (b"abc".to_vec(), "byte 3: truncated"),
        (Vec::new(), "byte 0: truncated"),
    ];
    for (b, want) in cases {
        let e = err(&b);
        assert!(
            e.starts_with("t.stl: binary STL") && e.contains(want),
            "{want:?}: {e}"
        );
    }
}

#[test]
fn ascii_errors_name_the_line() {
    let bad = |from: &str, to: &str| err(ASCII.replacen(from, to, 1).as_bytes());
    let cases = [
        (
            bad("vertex 1 0 0", "vertex 1 nan 0"),
            ":5: ASCII STL: vertex: (1, NaN, 0) is not finite",
        ),
        (
            bad("vertex 1 0 0", "vertex 1 inf 0"),
            ":5: ASCII STL: vertex: (1, inf, 0)",
        ),
        (
            bad("vertex 1 0 0", "vertex 1 0"),
            ":5: ASCII STL: vertex: expected 3 numbers, found 2",
        ),
        (
            bad("vertex 1 0 0", "vertex 1 0 0 0"),
            ":5: ASCII STL: vertex: expected 3 numbers, found more",
        ),
        (
            bad("vertex 1 0 0", "vertex 1 x 0"),
            ":5: ASCII STL: vertex: 'x' is not a number",
        ),
        (
            bad("facet normal 0 0 1", "facet 0 0 1"),
            ":2: ASCII STL: expected 'facet normal",
        ),
        (
            bad("facet normal 0 0 1", "facet normal 0 0"),
            ":2: ASCII STL: facet normal: expected 3",
        ),
        (
            bad("outer loop", "outer"),
            ":3: ASCII STL: expected 'outer loop'",
        ),
        (
            bad("outer loop", "loop"),
            ":3: ASCII STL: expected 'outer loop', found 'loop'",
        ),
        (
            bad("      vertex 1 1 0\n    endloop", "    endloop"),
            ":6: ASCII STL: expected 'vertex x y z', found 'endloop'",
        ),
        (
            bad("endloop", "vertex 2 2 2"),
            ":7: ASCII STL: expected 'endloop' (a facet has exactly 3 vertices)",
        ),
        (
            bad("endfacet", "endfacet x"),
            ":8: ASCII STL: 'endfacet' followed by 'x'",
        ),
        (
            bad("endloop", "endloop x"),
            ":7: ASCII STL: 'endloop' followed by 'x'",
        ),
        (
            bad("  endfacet\n", ""),
            ":8: ASCII STL: expected 'endfacet', found 'facet normal 0 0 1'",
        ),
        (
            bad("endsolid square\n", ""),
            ":15: ASCII STL: the file ends where 'facet normal nx ny nz' or 'endsolid' is expected",
        ),
        (
            err(&ASCII.as_bytes()[..60]),
            ":4: ASCII STL: vertex: expected 3 numbers, found 0",
        ),
        (
            err(ASCII
                .lines()
                .take(4)
                .collect::<Vec<_>>()
                .join("\n")
                .as_bytes()),
            ":4: ASCII STL: the file ends where 'vertex x y z' is expected",
        ),
        (
            err(b"solid empty\nendsolid empty\n"),
            ":2: ASCII STL: no facets by the end of the file",
        ),
        (
            err(b"solid x\nfacet normal 0 0 1\n\xff\n"),
            ":3: ASCII STL: invalid UTF-8",
        ),
        (
            err(format!("{ASCII}garbage\n").as_bytes()),
            ":17: ASCII STL: expected 'solid', found 'garbage'",
        ),
    ];
    for (e, want) in cases {
        assert!(e.starts_with("t.stl") && e.contains(want), "{want:?}: {e}");
    }
}

#[test]
fn degenerate_facets_warn() {
    let mut t = SQUARE;
    t[1][2] = t[1][1];
    let (m, w) = parse_stl(&binary(b"", &t), Path::new("t.stl")).unwrap();
    assert_eq!(m.triangles.len(), 2);
    assert!(w[0].contains("1 degenerate"), "{w:?}");
}
