//! Wavefront OBJ through tobj, after our own validation of every face index.
//!
//! tobj panics (integer overflow) or silently accepts some bad indices, so each `f` line is
//! checked here first: indices are non-zero, positive ones name an existing `v`/`vt`/`vn`,
//! relative (negative) ones do not underflow. Positions must be finite.

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use glam::{Vec2, Vec3};
use std::path::Path;

pub fn load_obj(path: &Path) -> Result<(Mesh, Vec<String>)> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_obj(&bytes, path)
}

/// Validate and load OBJ text. All groups and objects are merged into one mesh.
pub fn parse_obj(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>)> {
    let mut warnings = Vec::new();
    validate(bytes, path, &mut warnings)?;
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = std::io::BufReader::new(bytes);
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
    if all_normals && !normals.is_empty() {
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
    Ok((mesh, warnings))
}

/// Line-by-line check of what tobj trusts: finite `v` coordinates and in-range face indices.
fn validate(bytes: &[u8], path: &Path, warnings: &mut Vec<String>) -> Result<()> {
    let (mut nv, mut nvt, mut nvn) = (0i64, 0i64, 0i64);
    let mut faces = 0usize;
    let mut logical = String::new();
    let mut first_line = 0;
    for (index, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = index + 1;
        let err = |msg: String| Error::parse(path, line_no, msg);
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let trimmed = raw.trim_ascii();
        if trimmed.first() == Some(&b'#') {
            continue;
        }
        if trimmed.contains(&0) {
            return Err(err("binary data (NUL byte); not an OBJ text file".into()));
        }
        let text = std::str::from_utf8(trimmed)
            .map_err(|_| err("invalid UTF-8; not an OBJ text file".into()))?;
        // tobj joins lines ending in '\'.
        if logical.is_empty() {
            first_line = line_no;
        }
        if let Some(cont) = text.strip_suffix('\\') {
            logical.push_str(cont);
            logical.push(' ');
            continue;
        }
        logical.push_str(text);
        let line = std::mem::take(&mut logical);
        let err = |msg: String| Error::parse(path, first_line, msg);
        let mut tok = line.split_whitespace();
        match tok.next() {
            Some("v") => {
                for k in 0..3 {
                    let t = tok.next().ok_or_else(|| err(format!("v: missing coordinate {}", k + 1)))?;
                    let x: f32 = t.parse().map_err(|_| err(format!("v: '{t}' is not a number")))?;
                    if !x.is_finite() {
                        return Err(err(format!("v: '{t}' is not a finite number")));
                    }
                }
                nv += 1;
            }
            Some("vt") => nvt += 1,
            Some("vn") => nvn += 1,
            Some("f") => {
                let mut count = 0;
                for vert in tok {
                    count += 1;
                    let mut parts = vert.split('/');
                    for (slot, (name, n)) in [("v", nv), ("vt", nvt), ("vn", nvn)].into_iter().enumerate() {
                        let Some(p) = parts.next() else { break };
                        if p.is_empty() {
                            if slot == 0 {
                                return Err(err(format!("f: '{vert}' has no position index")));
                            }
                            continue;
                        }
                        let i: i64 = p.parse().map_err(|_| err(format!("f: '{vert}': '{p}' is not an index")))?;
                        let ok = if i > 0 { i <= n } else { i < 0 && n + i >= 0 };
                        if !ok {
                            return Err(err(format!("f: '{vert}': {name} index {i} out of range (1..={n} or -{n}..=-1)")));
                        }
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
            Some("mtllib") => warnings.push(format!(
                "{}:{first_line}: materials from .mtl files are ignored (the scene gives materials)",
                path.display()
            )),
            _ => {}
        }
    }
    if faces == 0 {
        return Err(Error::parse(path, 0, "OBJ: no faces"));
    }
    Ok(())
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
