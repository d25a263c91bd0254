//! Wavefront OBJ through tobj, after our own validation of every line.
//!
//! tobj panics (integer overflow) or silently accepts some bad input (index 0, relative
//! indices that underflow, NaN positions, a `w` of 0), so each line is checked here first and
//! tobj reads a canonical rewrite: finite numbers only, every face index absolute and in range.
//! Accepted: relative indices, n-gons (fan-triangulated), `v x y z w`, `v x y z r g b`,
//! comments with any bytes, `\` continuations, CRLF. `mtllib` is a warning: materials come
//! from the scene, so `.mtl` files are never opened and a missing one cannot break loading.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use glam::{Vec2, Vec3};
use std::path::Path;

/// Read and load an OBJ file ([`parse_obj`] on its bytes).
pub fn load_obj(path: &Path) -> Result<(Mesh, Vec<String>)> {
    let bytes = super::read_regular(path)?;
    parse_obj(&bytes, path)
}

/// Validate and load OBJ text. All groups and objects are merged into one mesh.
pub fn parse_obj(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>)> {
    parse_obj_detail(bytes, path).map(|(m, w, _)| (m, w))
}

/// [`parse_obj`], also telling whether the file gave vertex normals (otherwise computed).
pub fn parse_obj_detail(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>, bool)> {
    let mut warnings = Vec::new();
    let text = canonicalise(bytes, path, &mut warnings)?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = std::io::BufReader::new(text.as_bytes());
    // Materials are not used by whitted (the scene file gives materials), so .mtl files are
    // never opened: a missing .mtl cannot break loading.
    let (models, _) = tobj::load_obj_buf(&mut reader, &options, |_| Ok(Default::default()))
        .map_err(|e| Error::parse(path, 0, format!("OBJ: {e}")))?;

    let mut mesh = Mesh::default();
    let (mut any_normals, mut all_normals, mut all_uvs) = (false, true, true);
    for m in &models {
        let nv = m.mesh.positions.len() / 3;
        any_normals |= m.mesh.normals.len() == nv * 3 && nv > 0;
        all_normals &= m.mesh.normals.len() == nv * 3;
        all_uvs &= m.mesh.texcoords.len() == nv * 2;
    }
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    for m in &models {
        let base = mesh.positions.len() as u32;
        let p = &m.mesh.positions;
        let nv = p.len() / 3;
        mesh.positions
            .extend((0..nv).map(|i| Vec3::new(p[3 * i], p[3 * i + 1], p[3 * i + 2])));
        if all_normals {
            let n = &m.mesh.normals;
            normals.extend((0..nv).map(|i| Vec3::new(n[3 * i], n[3 * i + 1], n[3 * i + 2])));
        }
        if all_uvs {
            let t = &m.mesh.texcoords;
            uvs.extend((0..nv).map(|i| Vec2::new(t[2 * i], t[2 * i + 1])));
        }
        for tri in m.mesh.indices.chunks_exact(3) {
            if tri.iter().any(|&i| i as usize >= nv) {
                return Err(Error::parse(
                    path,
                    0,
                    "OBJ: face index out of range after loading",
                ));
            }
            mesh.triangles
                .push([base + tri[0], base + tri[1], base + tri[2]]);
        }
    }
    if any_normals && !all_normals {
        warnings.push(format!(
            "{}: only some faces have normals; computing all normals",
            path.display()
        ));
    }
    if mesh.triangles.is_empty() {
        return Err(Error::parse(path, 0, "OBJ: no triangles"));
    }
    let file_normals = all_normals && !normals.is_empty();
    if file_normals {
        mesh.normals = Some(normals);
    }
    if all_uvs && !uvs.is_empty() {
        mesh.uvs = Some(uvs);
    }
    mesh.ensure_normals();
    let degenerate = mesh.degenerate_count();
    if degenerate > 0 {
        warnings.push(format!(
            "{}: {degenerate} degenerate (zero-area) faces; they are never hit",
            path.display()
        ));
    }
    Ok((mesh, warnings, file_normals))
}

/// Line-by-line check of everything tobj trusts, producing the text tobj then reads.
///
/// The output holds only `v x y z` (w applied, colours dropped), `vt u v`, `vn x y z` and
/// `f` lines with absolute 1-based indices, one per input line (blank lines elsewhere, so
/// tobj never sees comments, continuations, non-UTF-8 bytes, `l`/`p` records or materials).
/// Every number is finite; every index names an existing `v`/`vt`/`vn`.
fn canonicalise(bytes: &[u8], path: &Path, warnings: &mut Vec<String>) -> Result<String> {
    let (mut nv, mut nvt, mut nvn) = (0u64, 0u64, 0u64);
    let mut faces = 0usize;
    let mut out = String::with_capacity(bytes.len().min(1 << 30) + 16);
    let mut logical = String::new();
    let mut first_line = 0;
    for (index, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = index + 1;
        let err = |msg: String| Error::parse(path, line_no, msg);
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        // A comment runs from '#' to the end of the line and may hold any bytes.
        let raw = match raw.iter().position(|&b| b == b'#') {
            Some(h) => &raw[..h],
            None => raw,
        };
        if raw.contains(&0) {
            return Err(err("binary data (NUL byte); not an OBJ text file".into()));
        }
        let text = std::str::from_utf8(raw)
            .map_err(|_| err("invalid UTF-8 outside a comment; not an OBJ text file".into()))?
            .trim();
        if logical.is_empty() {
            first_line = line_no;
        }
        // A line ending in '\\' continues on the next one.
        if let Some(cont) = text.strip_suffix('\\') {
            logical.push_str(cont);
            logical.push(' ');
            continue;
        }
        logical.push_str(text);
        let line = std::mem::take(&mut logical);
        let err = |msg: String| Error::parse(path, first_line, msg);
        let mut tok = line.split_whitespace();
        let Some(kind) = tok.next() else { continue };
        let nums = |what: &str, tok: std::str::SplitWhitespace| -> Result<Vec<f32>> {
            tok.map(|t| {
                let x: f32 = t
                    .parse()
                    .map_err(|_| err(format!("{what}: '{t}' is not a number")))?;
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(err(format!("{what}: '{t}' is not a finite number")))
                }
            })
            .collect()
        };
        match kind {
            "v" => {
                let c = nums("v", tok)?;
                let p = match c.len() {
                    // x y z, x y z w (homogeneous), x y z r g b (colour, unused here)
                    3 | 6 => [c[0], c[1], c[2]],
                    4 => {
                        if c[3] == 0.0 {
                            return Err(err("v: w must not be 0".into()));
                        }
                        [c[0] / c[3], c[1] / c[3], c[2] / c[3]]
                    }
                    n => {
                        return Err(err(format!(
                            "v: expected x y z [w | r g b], found {n} numbers"
                        )));
                    }
                };
                if !p.iter().all(|x| x.is_finite()) {
                    return Err(err("v: x/w overflows".into()));
                }
                out.push_str(&format!("v {:?} {:?} {:?}", p[0], p[1], p[2]));
                nv += 1;
            }
            "vt" => {
                let c = nums("vt", tok)?;
                if !(1..=3).contains(&c.len()) {
                    return Err(err(format!("vt: expected u [v [w]], found {} numbers", c.len())));
                }
                out.push_str(&format!("vt {:?} {:?}", c[0], c.get(1).copied().unwrap_or(0.0)));
                nvt += 1;
            }
            "vn" => {
                let c = nums("vn", tok)?;
                if c.len() != 3 {
                    return Err(err(format!("vn: expected x y z, found {} numbers", c.len())));
                }
                out.push_str(&format!("vn {:?} {:?} {:?}", c[0], c[1], c[2]));
                nvn += 1;
            }
            "f" => {
                let mut count = 0;
                out.push('f');
                for vert in tok {
                    count += 1;
                    out.push(' ');
                    let mut parts = vert.split('/');
                    for (slot, (name, n)) in [("v", nv), ("vt", nvt), ("vn", nvn)]
                        .into_iter()
                        .enumerate()
                    {
                        let Some(p) = parts.next() else { break };
                        if slot > 0 {
                            out.push('/');
                        }
                        if p.is_empty() {
                            if slot == 0 {
                                return Err(err(format!("f: '{vert}' has no position index")));
                            }
                            continue;
                        }
                        let i: i64 = p
                            .parse()
                            .map_err(|_| err(format!("f: '{vert}': '{p}' is not an index")))?;
                        // 1..=n counts from the start, -n..=-1 back from the latest entry.
                        let abs = match i {
                            1.. if i.unsigned_abs() <= n => i.unsigned_abs(),
                            ..=-1 if i.unsigned_abs() <= n => n - i.unsigned_abs() + 1,
                            _ => {
                                return Err(err(format!(
                                    "f: '{vert}': {name} index {i} out of range (1..={n} or -{n}..=-1)"
                                )));
                            }
                        };
                        out.push_str(&abs.to_string());
                    }
                    if parts.next().is_some() {
                        return Err(err(format!("f: '{vert}' has more than 3 '/' parts")));
                    }
                }
                if count < 3 {
                    return Err(err(format!("f: needs at least 3 vertices, has {count}")));
                }
                faces += 1;
            }
            "mtllib" => warnings.push(format!(
                "{}:{first_line}: materials from .mtl files are ignored (the scene gives materials)",
                path.display()
            )),
            // o, g, s, usemtl, l, p and anything else: not needed (all groups are merged).
            _ => {}
        }
        out.push('\n');
    }
    if faces == 0 {
        return Err(Error::parse(path, 0, "OBJ: no faces"));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<(Mesh, Vec<String>)> {
        parse_obj(s.as_bytes(), Path::new("t.obj"))
    }

    #[test]
    fn loads_ngons_relative_indices_uv_and_normals() {
        let (m, _) = parse(
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\n\
             f -4/-4/1 -3/-3/1 -2/-2/1 -1/-1/1\n",
        )
        .unwrap();
        assert_eq!(m.triangles.len(), 2);
        assert_eq!(m.uvs.as_ref().unwrap().len(), m.positions.len());
        assert!(m.normals.unwrap().iter().all(|n| *n == Vec3::Z));
    }

    #[test]
    fn positions_only_get_area_weighted_normals() {
        let (m, _) = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert!(m.uvs.is_none());
        assert_eq!(m.normals.unwrap()[0], Vec3::Z);
    }

    #[test]
    fn refuses_bad_indices_and_numbers() {
        let cases = [
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", ":4:"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", ":4:"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf -4 1 2\n", ":4:"),
            ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", ":4:"),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1//9223372036854775807 2 3\n",
                ":4:",
            ),
            ("v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", ":1:"),
            ("v 0 0\n", ":1:"),
            ("v 0 0 0\nv 1 0 0\nf 1 2\n", ":3:"),
            ("v 0 0 0\n", ":0:"),
        ];
        for (text, line) in cases {
            let e = parse(text).unwrap_err().to_string();
            assert!(
                e.starts_with("t.obj") && e.contains(line),
                "{text:?} -> {e}"
            );
        }
    }
}
