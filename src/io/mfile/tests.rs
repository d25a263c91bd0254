//! Tests of the `.m` reader.

use super::*;

fn parse(s: &str) -> Result<(Mesh, Vec<String>)> {
    parse_m(s.as_bytes(), Path::new("t.m"))
}

fn err_of(s: &str) -> String {
    parse(s).unwrap_err().to_string()
}

const QUAD: &str = "# a quad\nVertex 1 0 0 0 {uv=(0 0) rgb=(1 0 0)}\nVertex 2 1 0 0 {uv=(1 0) rgb=(0 1 0)}\n\
    Vertex 5 1 1 0 {uv=(1 1) rgb=(0 0 1)}\nVertex 7 0 1 0 {uv=(0 1) rgb=(1 1 1) wid=3 father=(2)}\n\
    Face 1 1 2 5\nFace 2 1 5 7\n";

#[test]
fn reads_vertices_faces_and_attributes() {
    let (m, w) = parse(QUAD).unwrap();
    assert!(w.is_empty());
    assert_eq!(m.positions.len(), 4);
    assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
    assert_eq!(m.uvs.as_ref().unwrap()[2], Vec2::new(1.0, 1.0));
    assert_eq!(m.colors.as_ref().unwrap()[1], Vec3::Y);
    // No normals in the file: area-weighted, facing +z.
    assert!(
        m.normals
            .unwrap()
            .iter()
            .all(|n| (*n - Vec3::Z).length() < 1e-6)
    );
}

#[test]
fn accepts_crlf_bom_enotation_comments_and_polygons() {
    let text = "\u{feff}#      VERTICES\r\nVertex   10   1.0E+00  0.0e0 -0.0\r\nVertex 3 0 1E0 0 {normal=(0 0 1)}\r\n\
        Face 1 10 3 99 4\r\nVertex 99 -1 0 0\r\nVertex 4 0 -1 0 # trailing\r\nEdge 1 2 {sharp}\r\n";
    let mut bytes = text.as_bytes().to_vec();
    bytes.extend_from_slice(b"# latin-1 comment \xE9\xE8\n");
    let (m, w) = parse_m(&bytes, Path::new("t.m")).unwrap();
    assert_eq!(m.triangles.len(), 2, "quad fan-triangulated");
    assert_eq!(m.positions[0], Vec3::new(1.0, 0.0, 0.0));
    assert_eq!(m.triangles[0], [0, 1, 2]);
    assert!(w.iter().any(|w| w.contains("no normal")));
}

#[test]
fn very_large_ids_use_a_map() {
    let (m, _) = parse("Vertex 18446744073709551615 0 0 0\nVertex 2 1 0 0\nVertex 3 0 1 0\nFace 1 18446744073709551615 2 3\n").unwrap();
    assert_eq!(m.triangles, vec![[0, 1, 2]]);
}

#[test]
fn refuses_bad_input_with_line() {
    let cases = [
        ("Vertex 1 0 0\nFace 1 1 1 1\n", ":1:", "missing z"),
        ("Vertex 1 0 0 0 4\n", ":1:", "extra value"),
        ("Vertex 1 0 nan 0\n", ":1:", "not a finite"),
        ("Vertex 1 0 1e39 0\n", ":1:", "out of range"),
        (
            "Vertex 1 0 0 0\nVertex 1 1 0 0\n",
            ":2:",
            "duplicate vertex id 1",
        ),
        ("Vertex 0 0 0 0\n", ":1:", "must be >= 1"),
        ("Vertex -3 0 0 0\n", ":1:", "positive integer"),
        (
            "Vertex 1 0 0 0 {normal=(1 2)}\n",
            ":1:",
            "expected 3 numbers",
        ),
        ("Vertex 1 0 0 0 {normal=(1 2 3}\n", ":1:", "missing ')'"),
        ("Vertex 1 0 0 0 {uv=(1 2)\n", ":1:", "unbalanced braces"),
        ("Vertex 1 0 0 0 uv=(1 2)}\n", ":1:", "unbalanced braces"),
        (
            "Vertex 1 0 0 0\nVertex 2 1 0 0\nVertex 3 0 1 0\nFace 1 1 2 4\n",
            ":4:",
            "undefined vertex 4",
        ),
        ("Vertex 1 0 0 0\nFace 1 1 1\n", ":2:", "at least 3"),
        ("Vertex 1 0 0 0\n", ":1:", "no faces by the end of the file"),
        ("\u{0}\u{1}binary", ":1:", "binary"),
    ];
    for (text, line, what) in cases {
        let e = err_of(text);
        assert!(
            e.starts_with("t.m") && e.contains(line) && e.contains(what),
            "{text:?} -> {e}"
        );
    }
    let e = parse_m(b"Vertex 1 \xff\xfe 0 0\n", Path::new("t.m"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("UTF-8"), "{e}");
}

/// Only some vertices carry uv, rgb or normal: the file loads, the gaps are filled (uv
/// (0, 0), rgb white and listed in `missing_rgb`, normal area-weighted) and one warning
/// counts each.
#[test]
fn partial_attributes_are_filled_with_one_warning() {
    let text = "Vertex 1 0 0 0 {uv=(0.5 0.5) rgb=(1 0 0) normal=(1 0 0)}\nVertex 2 1 0 0 {rgb=(0 1 0)}\n\
        Vertex 3 0 1 0\nVertex 4 1 1 0 {uv=(1 1)}\nFace 1 1 2 3\nFace 2 2 4 3\n";
    let r = read_m(text.as_bytes(), Path::new("t.m")).unwrap();
    assert_eq!(r.warnings.len(), 1, "{:?}", r.warnings);
    let w = &r.warnings[0];
    for want in [
        "t.m:",
        "2 of 4 have no uv (set to (0, 0))",
        "2 of 4 have no rgb (the material's colour)",
        "3 of 4 have no normal (area-weighted)",
    ] {
        assert!(w.contains(want), "want {want:?} in {w}");
    }
    let m = &r.mesh;
    assert_eq!(
        m.uvs.as_deref().unwrap(),
        [Vec2::splat(0.5), Vec2::ZERO, Vec2::ZERO, Vec2::ONE]
    );
    assert_eq!(m.colors.as_ref().unwrap()[2], Vec3::ONE);
    assert_eq!(r.missing_rgb, vec![2, 3]);
    let normals = m.normals.as_ref().unwrap();
    assert_eq!(normals[0], Vec3::X, "the file's normal is kept");
    assert!(normals[1..].iter().all(|n| (*n - Vec3::Z).length() < 1e-6));
    assert!(r.file_normals);
    // Complete files have no gaps and no warning.
    let r = read_m(QUAD.as_bytes(), Path::new("t.m")).unwrap();
    assert!(r.warnings.is_empty() && r.missing_rgb.is_empty());
}

/// A face id given twice: a warning with the file, the line, the id and the first line;
/// every face is kept.
#[test]
fn duplicate_face_ids_warn_with_file_line_and_id() {
    let (m, w) = parse(&QUAD.replace("Face 2 1 5 7", "Face 1 1 5 7")).unwrap();
    assert_eq!(m.triangles.len(), 2);
    assert_eq!(
        w,
        ["t.m:7: duplicate face id 1 (first at line 6); both faces are kept"]
    );
    let (_, w) = parse(&format!("{QUAD}Face 2 2 5 7\nFace 1 1 2 7\n")).unwrap();
    assert_eq!(
        w,
        [
            "t.m:8: duplicate face id 2 (first at line 7); both faces are kept \
             (1 more faces repeat an id)"
        ]
    );
    assert!(parse(QUAD).unwrap().1.is_empty());
}

/// The fast path's numbers are `str::parse`'s, bit for bit, and it leaves every other
/// form to it.
#[test]
fn plain_decimals_parse_as_the_standard_library_does() {
    for tok in [
        "0",
        "-0",
        "+0",
        "-0.474563",
        "0.1",
        "0.3",
        "1.",
        ".5",
        "-.5",
        "123456789012345",
        "0.000000000000001",
        "9.99999999999999",
        "-0.0844681",
        "1e-7",
    ] {
        let want: f64 = tok.parse().unwrap();
        let got = plain_decimal(tok).unwrap_or(want);
        assert_eq!(got.to_bits(), want.to_bits(), "{tok}");
    }
    for tok in [
        "",
        ".",
        "-",
        "+",
        "--1",
        "1.2.3",
        "1e5",
        "1E5",
        "nan",
        "inf",
        "0x10",
        "1,5",
        "1234567890123456",
        "1 2",
        "123456789012345678901234567890",
    ] {
        assert_eq!(plain_decimal(tok), None, "{tok}");
    }
    use proptest::prelude::*;
    proptest!(|(m in 0u64..1_000_000_000_000_000, point in 0usize..17, neg: bool)| {
        let digits = m.to_string();
        let point = point.min(digits.len());
        let tok = format!("{}{}.{}", if neg { "-" } else { "" }, &digits[..digits.len() - point], &digits[digits.len() - point..]);
        let want: f64 = tok.parse().unwrap();
        match plain_decimal(&tok) {
            Some(got) => prop_assert_eq!(got.to_bits(), want.to_bits(), "{}", tok),
            None => prop_assert!(digits.len() > 15, "{}", tok),
        }
    });
}

#[test]
fn degenerate_faces_warn() {
    let (m, w) =
        parse("Vertex 1 0 0 0\nVertex 2 1 0 0\nVertex 3 0 1 0\nFace 1 1 2 3\nFace 2 1 1 2\n")
            .unwrap();
    assert_eq!(m.degenerate_count(), 1);
    assert!(w[0].contains("1 degenerate"));
}

/// A file cut into pieces parsed on their own and merged gives what one pass gives: the same
/// mesh and warnings, or the same first error (its line and message), whatever the cuts.
#[test]
fn pieces_parse_as_the_whole_file() {
    let show = |r: Result<MRead>| match r {
        Ok(r) => format!(
            "{:?} {:?} {} {:?}",
            r.mesh, r.warnings, r.file_normals, r.missing_rgb
        ),
        Err(e) => e.to_string(),
    };
    let bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/meshes/fandisk.m"))
        .expect("meshes/fandisk.m");
    let good = [
        QUAD,
        &QUAD.replace("Face 2 1 5 7", "Face 1 1 5 7\nFace 1 2 5 7\nFace 2 1 5 7"),
        "\u{feff}#      VERTICES\r\nVertex   10   1.0E+00  0.0e0 -0.0\r\nVertex 3 0 1E0 0 {normal=(0 0 1)}\r\n\
         Face 1 10 3 99 4\r\nVertex 99 -1 0 0\r\nVertex 4 0 -1 0 # trailing\r\nEdge 1 2 {sharp}",
        "Vertex 1 0 0 0 {uv=(0.5 0.5) rgb=(1 0 0)}\nVertex 2 1 0 0 {rgb=(0 1 0)}\n\n\n\
         Vertex 3 0 1 0\nVertex 4 1 1 0 {uv=(1 1)}\nFace 1 1 2 3\nFace 2 2 4 3\n",
    ];
    let bad = [
        // a duplicate vertex before a later line's error, and after an earlier one
        "Vertex 1 0 0 0\nVertex 2 0 0 0\nVertex 1 1 0 0\nFace 1 1 2\nVertex 3 0 nan 0\n",
        "Vertex 1 0 0 0\nVertex 2 0 0 0\nVertex 3 0 nan 0\nFace 1 1 2 3\nVertex 1 1 0 0\n",
        "Vertex 1 0 0 0\nVertex 2 1 0 0\nVertex 3 0 1 0\nFace 1 1 2 4\n#\n\n",
        "Vertex 1 0 0 0 {uv=(1 2)\nVertex 2 0 0 0\n",
        "Vertex 1 0 0 0\n# \u{e9}\nVertex 2 \u{0} 0 0\n",
        "Vertex 1 0 0 0\nVertex 2 1 0 0\n",
    ];
    for text in good.iter().chain(&bad) {
        let whole = show(read_m_in(text.as_bytes(), Path::new("t.m"), usize::MAX));
        for piece in [1, 2, 7, 30, 64] {
            let cut = show(read_m_in(text.as_bytes(), Path::new("t.m"), piece));
            assert_eq!(cut, whole, "{text:?} in pieces of {piece}");
        }
    }
    for text in &bad {
        assert!(read_m_in(text.as_bytes(), Path::new("t.m"), 1).is_err());
    }
    let whole = read_m_in(&bytes, Path::new("f.m"), usize::MAX);
    assert!(whole.is_ok(), "fandisk.m reads");
    let whole = show(whole);
    for piece in [1000, 65536] {
        assert_eq!(show(read_m_in(&bytes, Path::new("f.m"), piece)), whole);
    }
}

/// The brace and comment rule of a record line, written out one search at a time.
fn split_braces_reference(text: &str) -> std::result::Result<(&str, Option<&str>), String> {
    let text = match text.find('#') {
        Some(h) if !text[..h].contains('{') || text[..h].contains('}') => &text[..h],
        _ => text,
    };
    match text.find('{') {
        None if text.contains('}') => Err("unbalanced braces: '}' without '{'".into()),
        None => Ok((text, None)),
        Some(open) => {
            let rest = text[open + 1..].trim_end();
            let body = rest.strip_suffix('}').ok_or_else(|| {
                "unbalanced braces: '{' without closing '}' at the end of the line".to_string()
            })?;
            if body.contains('{') || body.contains('}') {
                return Err("unbalanced or nested braces".into());
            }
            Ok((&text[..open], Some(body)))
        }
    }
}

#[test]
fn braces_split_as_the_rule_says() {
    use proptest::prelude::*;
    let line = proptest::collection::vec(
        prop_oneof![
            Just('#'),
            Just('{'),
            Just('}'),
            Just(' '),
            Just('\t'),
            Just('a'),
            Just('\u{a0}'),
            Just('\u{e9}')
        ],
        0..16,
    );
    proptest!(ProptestConfig::with_cases(20_000), |(chars in line)| {
        let text: String = chars.into_iter().collect();
        prop_assert_eq!(split_braces(&text), split_braces_reference(&text), "{:?}", text);
    });
}

/// Random files of good and bad lines parse the same in pieces as in one pass.
#[test]
fn random_files_parse_the_same_in_pieces() {
    use proptest::prelude::*;
    let line = prop_oneof![
        (1u64..6, -2i32..3, -2i32..3).prop_map(|(id, x, y)| format!("Vertex {id} {x} {y} 0")),
        (1u64..6, 0u8..3).prop_map(|(id, k)| format!(
            "Vertex {id} 1 2 3 {{{}}}",
            ["uv=(0.5 0.5)", "rgb=(1 0 0) normal=(0 0 1)", "uv=(1 2"][k as usize]
        )),
        (1u64..4, 1u64..7, 1u64..7, 1u64..7)
            .prop_map(|(f, a, b, c)| format!("Face {f} {a} {b} {c}")),
        Just("# comment {".to_string()),
        Just(String::new()),
        Just("Edge 1 2 {sharp}".to_string()),
        Just("Vertex 9 nan 0 0".to_string()),
        Just("Face 8 1 2".to_string()),
        Just("Vertex 7 0 0 0 } {".to_string()),
    ];
    let file = proptest::collection::vec(line, 0..24);
    proptest!(ProptestConfig::with_cases(2_000), |(lines in file, piece in 1usize..80, crlf: bool)| {
        let text = lines.join(if crlf { "\r\n" } else { "\n" });
        let show = |r: Result<MRead>| match r {
            Ok(r) => format!("{:?} {:?} {} {:?}", r.mesh, r.warnings, r.file_normals, r.missing_rgb),
            Err(e) => e.to_string(),
        };
        let whole = show(read_m_in(text.as_bytes(), Path::new("t.m"), usize::MAX));
        let cut = show(read_m_in(text.as_bytes(), Path::new("t.m"), piece));
        prop_assert_eq!(cut, whole, "{:?} in pieces of {}", text, piece);
    });
}
