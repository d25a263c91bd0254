//! Wavefront OBJ, read and checked line by line by our own reader, with its MTL materials.
//!
//! Every number must be finite, every face index (absolute or relative) must name an existing
//! `v`/`vt`/`vn`, and errors name the file and line. Accepted: n-gons (fan-triangulated),
//! `v x y z w`, `v x y z r g b` (vertex colours), comments with any bytes, `\` continuations,
//! CRLF, `usemtl` per face group, several `mtllib` statements and file names with spaces,
//! smoothing groups (`s N`, `s off`). Without `vn` a mesh is flat but for its smoothing
//! groups (see [`Mesh::group_shaded`]).
//! (The reader was tobj until materials and vertex colours were needed: tobj's single-index
//! mode cannot map colours back when only some vertices have them, it panics on `Kd 0.5` in
//! an MTL file, and it had to be fed a validated rewrite of the file anyway.)

use crate::error::{Error, Result};
use crate::io::model::{Model, NO_MATERIAL};
use crate::io::mtl;
use crate::mesh::Mesh;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Read and load an OBJ file ([`parse_obj`] on its bytes).
pub fn load_obj(path: &Path) -> Result<(Mesh, Vec<String>)> {
    let bytes = super::read_regular(path)?;
    parse_obj(&bytes, path)
}

/// Validate and load OBJ text (materials are not read). All groups are merged into one mesh.
pub fn parse_obj(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>)> {
    parse_obj_detail(bytes, path).map(|(m, w, _)| (m, w))
}

/// [`parse_obj`], also telling whether the file gave vertex normals (otherwise computed).
pub fn parse_obj_detail(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>, bool)> {
    let mut warnings = Vec::new();
    let parsed = parse_lines(bytes, path, &mut warnings)?;
    let (mesh, file_normals, _) = assemble(&parsed, path, &mut warnings)?;
    Ok((mesh, warnings, file_normals))
}

/// Load an OBJ file with its `mtllib` materials (resolved beside the OBJ file). A missing
/// `.mtl` or texture is a warning; a malformed `.mtl` is an error naming its file and line.
pub fn load_obj_model(path: &Path) -> Result<(Model, Vec<String>)> {
    let bytes = super::read_regular(path)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_obj_model(&bytes, path, &mut |line, entry, warnings| {
        // `mtllib a.mtl b.mtl` names two files, `mtllib my materials.mtl` one with a space:
        // the whole entry when such a file exists, else each word.
        let names: Vec<&str> = if super::find_beside(&dir, entry).is_some() {
            vec![entry]
        } else {
            entry.split_whitespace().collect()
        };
        let mut out = Vec::new();
        for name in names {
            match super::find_beside(&dir, name) {
                Some(file) => out.extend(mtl::parse_mtl(&super::read_regular(&file)?, &file)?),
                None => warnings.push(format!(
                    "{}:{line}: mtllib '{name}' not found in {}; its materials fall back to the default",
                    path.display(),
                    super::display_dir(&dir)
                )),
            }
        }
        Ok(out)
    })
}

/// Reads the materials of one `mtllib` statement: `(line, rest of the line, warnings)`.
pub type MtlReader<'a> =
    dyn FnMut(usize, &str, &mut Vec<String>) -> Result<Vec<mtl::MtlMaterial>> + 'a;

/// [`load_obj_model`] on bytes, with `read_mtl` reading each `mtllib` entry.
pub fn parse_obj_model(
    bytes: &[u8],
    path: &Path,
    read_mtl: &mut MtlReader,
) -> Result<(Model, Vec<String>)> {
    let mut warnings = Vec::new();
    let parsed = parse_lines(bytes, path, &mut warnings)?;
    // Every mtllib entry, in order; the first definition of a name wins.
    let mut mtls: Vec<mtl::MtlMaterial> = Vec::new();
    for (line, entry) in &parsed.mtllibs {
        for m in read_mtl(*line, entry, &mut warnings)? {
            if mtls.iter().any(|x| x.name == m.name) {
                warnings.push(format!(
                    "{}:{line}: material '{}' is defined twice; the first definition is used",
                    path.display(),
                    m.name
                ));
            } else {
                mtls.push(m);
            }
        }
    }
    let (mesh, file_normals, face_groups) = assemble(&parsed, path, &mut warnings)?;
    // Map the usemtl names of the face groups onto the MTL materials.
    let mut group_material = Vec::with_capacity(parsed.usemtl.len());
    for (line, name) in &parsed.usemtl {
        let found = mtls.iter().position(|m| &m.name == name);
        if found.is_none() {
            warnings.push(format!(
                "{}:{line}: usemtl '{name}': no such material in the mtllib files; the default material is used",
                path.display()
            ));
        }
        group_material.push(found.map_or(NO_MATERIAL, |i| i as u32));
    }
    let face_materials = (!parsed.usemtl.is_empty()).then(|| {
        face_groups
            .iter()
            .map(|&g| {
                if g == NO_MATERIAL {
                    NO_MATERIAL
                } else {
                    group_material[g as usize]
                }
            })
            .collect::<Vec<u32>>()
    });
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let has_uv = mesh.uvs.is_some();
    let has_colors = mesh.colors.is_some();
    let mut materials = Vec::new();
    let mut material_info = Vec::new();
    for m in &mtls {
        let (desc, info) = mtl::to_material(m, &dir, has_uv, has_colors, &mut warnings);
        materials.push(desc);
        material_info.push(info);
    }
    Ok((
        Model {
            mesh,
            materials,
            material_info,
            face_materials,
            file_normals,
            ..Default::default()
        },
        warnings,
    ))
}

/// What the line pass collects: attributes, faces as `(v, vt, vn)` corners (0-based,
/// `u32::MAX` = absent) and the face group (`usemtl` index) of every face.
#[derive(Default)]
struct Parsed {
    positions: Vec<Vec3>,
    colors: Vec<Option<Vec3>>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    /// Corners of all faces, one after the other; `faces[k]` = (first corner, count, group,
    /// smoothing group: 0 = `s off`).
    corners: Vec<[u32; 3]>,
    faces: Vec<(u32, u32, u32, u32)>,
    /// `(line, rest of the line)` of each `mtllib`.
    mtllibs: Vec<(usize, String)>,
    /// `(line, name)` of each `usemtl` (a face group).
    usemtl: Vec<(usize, String)>,
}

const ABSENT: u32 = u32::MAX;

/// Most corners (face vertices) a file may have: far beyond the scene's triangle cap, checked
/// as faces are read so that the corner list never grows without bound.
const MAX_CORNERS: usize = 1 << 28;

fn parse_lines(bytes: &[u8], path: &Path, warnings: &mut Vec<String>) -> Result<Parsed> {
    let mut p = Parsed::default();
    let mut group = NO_MATERIAL;
    // The smoothing group of the faces that follow (`s N`; `s off` and `s 0` are 0, flat).
    let mut smoothing = 0u32;
    let mut logical = String::new();
    let mut first_line = 0;
    for (index, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = index + 1;
        let text = super::text_line(raw, path, line_no, "an OBJ")?;
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
        let line = line.trim();
        let (kind, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let rest = rest.trim();
        let tok = rest.split_whitespace();
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
            "" => {}
            "v" => {
                let c = nums("v", tok)?;
                let (q, color) = match c.len() {
                    3 => ([c[0], c[1], c[2]], None),
                    // x y z r g b: a vertex colour
                    6 => ([c[0], c[1], c[2]], Some(Vec3::new(c[3], c[4], c[5]))),
                    4 => {
                        if c[3] == 0.0 {
                            return Err(err("v: w must not be 0".into()));
                        }
                        ([c[0] / c[3], c[1] / c[3], c[2] / c[3]], None)
                    }
                    n => {
                        return Err(err(format!(
                            "v: expected x y z [w | r g b], found {n} numbers"
                        )));
                    }
                };
                if !q.iter().all(|x| x.is_finite()) {
                    return Err(err("v: x/w overflows".into()));
                }
                if let Some(c) = color
                    && c.cmplt(Vec3::ZERO).any()
                {
                    return Err(err("v: colour components must be >= 0".into()));
                }
                p.positions.push(Vec3::from(q));
                p.colors.push(color);
            }
            "vt" => {
                let c = nums("vt", tok)?;
                if !(1..=3).contains(&c.len()) {
                    return Err(err(format!(
                        "vt: expected u [v [w]], found {} numbers",
                        c.len()
                    )));
                }
                p.uvs
                    .push(Vec2::new(c[0], c.get(1).copied().unwrap_or(0.0)));
            }
            "vn" => {
                let c = nums("vn", tok)?;
                if c.len() != 3 {
                    return Err(err(format!(
                        "vn: expected x y z, found {} numbers",
                        c.len()
                    )));
                }
                p.normals.push(Vec3::new(c[0], c[1], c[2]));
            }
            "f" => {
                let first = p.corners.len() as u32;
                let counts = [p.positions.len(), p.uvs.len(), p.normals.len()];
                for vert in tok {
                    let mut corner = [ABSENT; 3];
                    let mut parts = vert.split('/');
                    for (slot, name) in ["v", "vt", "vn"].into_iter().enumerate() {
                        let Some(s) = parts.next() else { break };
                        if s.is_empty() {
                            if slot == 0 {
                                return Err(err(format!("f: '{vert}' has no position index")));
                            }
                            continue;
                        }
                        let n = counts[slot] as u64;
                        let i: i64 = s
                            .parse()
                            .map_err(|_| err(format!("f: '{vert}': '{s}' is not an index")))?;
                        // 1..=n counts from the start, -n..=-1 back from the most recent entry.
                        let abs = match i {
                            1.. if i.unsigned_abs() <= n => i.unsigned_abs() - 1,
                            ..=-1 if i.unsigned_abs() <= n => n - i.unsigned_abs(),
                            _ => {
                                return Err(err(format!(
                                    "f: '{vert}': {name} index {i} out of range (1..={n} or -{n}..=-1)"
                                )));
                            }
                        };
                        corner[slot] = abs as u32;
                    }
                    if parts.next().is_some() {
                        return Err(err(format!("f: '{vert}' has more than 3 '/' parts")));
                    }
                    if p.corners.len() >= MAX_CORNERS {
                        return Err(err(format!(
                            "f: over {MAX_CORNERS} face vertices in the file (the cap)"
                        )));
                    }
                    p.corners.push(corner);
                }
                let count = p.corners.len() as u32 - first;
                if count < 3 {
                    return Err(err(format!("f: needs at least 3 vertices, has {count}")));
                }
                p.faces.push((first, count, group, smoothing));
            }
            "mtllib" => {
                if rest.is_empty() {
                    return Err(err("mtllib: no file name".into()));
                }
                p.mtllibs.push((first_line, rest.to_string()));
            }
            "usemtl" => {
                if rest.is_empty() {
                    return Err(err("usemtl: no material name".into()));
                }
                group = p.usemtl.len() as u32;
                p.usemtl.push((first_line, rest.to_string()));
            }
            "s" => {
                smoothing = match rest {
                    "off" => 0,
                    n => n.parse().map_err(|_| {
                        err(format!(
                            "s: expected a smoothing group number or 'off', found '{n}'"
                        ))
                    })?,
                };
            }
            // o, g, l, p and anything else: not needed (all groups are merged).
            _ => {}
        }
    }
    if p.faces.is_empty() {
        return Err(Error::parse(
            path,
            super::last_line(bytes),
            "OBJ: no faces by the end of the file",
        ));
    }
    let coloured = p.colors.iter().filter(|c| c.is_some()).count();
    if coloured > 0 && coloured < p.colors.len() {
        warnings.push(format!(
            "{}: only {coloured} of {} vertices have a colour (v x y z r g b); colours are ignored",
            path.display(),
            p.colors.len()
        ));
    }
    Ok(p)
}

/// One vertex per distinct `(v, vt, vn)` corner, faces fan-triangulated in file order, with
/// the file's normals, else flat or smoothing-group normals (see
/// [`Mesh::group_shaded`]). Returns the mesh, whether normals came from the file, and each
/// triangle's face group.
fn assemble(p: &Parsed, path: &Path, warnings: &mut Vec<String>) -> Result<(Mesh, bool, Vec<u32>)> {
    let corners = &p.corners;
    let all_uv = corners.iter().all(|c| c[1] != ABSENT);
    let any_n = corners.iter().any(|c| c[2] != ABSENT);
    let all_n = corners.iter().all(|c| c[2] != ABSENT);
    let all_colors = p.colors.iter().all(Option::is_some);
    if any_n && !all_n {
        warnings.push(format!(
            "{}: only some faces have normals; they are ignored (shaded as a file without vn)",
            path.display()
        ));
    }
    let key = |c: &[u32; 3]| {
        [
            c[0],
            if all_uv { c[1] } else { 0 },
            if all_n { c[2] } else { 0 },
        ]
    };
    let mut index: HashMap<[u32; 3], u32> = HashMap::new();
    let mut mesh = Mesh::default();
    let (mut uvs, mut normals, mut colors) = (Vec::new(), Vec::new(), Vec::new());
    let mut vertex = Vec::with_capacity(corners.len());
    for c in corners {
        let next = mesh.positions.len() as u32;
        let v = *index.entry(key(c)).or_insert_with(|| {
            mesh.positions.push(p.positions[c[0] as usize]);
            if all_uv {
                uvs.push(p.uvs[c[1] as usize]);
            }
            if all_n {
                normals.push(p.normals[c[2] as usize]);
            }
            if all_colors {
                colors.push(p.colors[c[0] as usize].unwrap_or(Vec3::ONE));
            }
            next
        });
        vertex.push(v);
    }
    let mut groups = Vec::new();
    let mut smoothing = Vec::new();
    for &(first, count, group, s) in &p.faces {
        let f = &vertex[first as usize..(first + count) as usize];
        for k in 1..f.len() - 1 {
            mesh.triangles.push([f[0], f[k], f[k + 1]]);
            groups.push(group);
            smoothing.push(s);
        }
    }
    if all_uv {
        mesh.uvs = Some(uvs);
    }
    if all_colors {
        mesh.colors = Some(colors);
    }
    if all_n {
        mesh.normals = Some(normals);
    }
    super::finish_mesh(&mut mesh, path, warnings);
    // Normals as OBJ means them: the file's `vn`; without them, smooth within each smoothing
    // group and flat elsewhere (no `s`, `s off`, `s 0`).
    let mesh = if all_n {
        mesh
    } else if smoothing.iter().any(|&s| s != 0) {
        mesh.group_shaded(&smoothing)
    } else {
        mesh.flat_shaded()
    };
    Ok((mesh, all_n, groups))
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
    fn positions_only_get_flat_normals() {
        let (m, _) = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        assert!(m.uvs.is_none());
        assert_eq!(m.normals.unwrap()[0], Vec3::Z);
    }

    use crate::mesh::shading::is_flat;

    const CUBE: &str =
        "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n";
    const CUBE_FACES: [&str; 6] = [
        "f 1 4 3 2\n",
        "f 5 6 7 8\n",
        "f 1 2 6 5\n",
        "f 4 8 7 3\n",
        "f 1 5 8 4\n",
        "f 2 3 7 6\n",
    ];

    /// No `vn`, no `s`: flat, 4 vertices per face of the cube (its two triangles share a
    /// normal); `s off` and `s 0` are flat too.
    #[test]
    fn without_vn_faces_are_flat() {
        for s in ["", "s off\n", "s 0\n"] {
            let (m, _) = parse(&format!("{CUBE}{s}{}", CUBE_FACES.concat())).unwrap();
            assert!(is_flat(&m), "{s:?}");
            assert_eq!(m.positions.len(), 24, "{s:?}");
        }
    }

    /// One smoothing group: one normal per corner of the cube, pointing out of it (area
    /// weighted per triangle, so not exactly the diagonal: a quad's two triangles meet at two
    /// of its corners); two groups:
    /// smooth within each, apart across them; `s off` in between ends a group.
    #[test]
    fn smoothing_groups_smooth_within_each_group() {
        let (m, _) = parse(&format!("{CUBE}s 1\n{}", CUBE_FACES.concat())).unwrap();
        assert_eq!(m.positions.len(), 8);
        let n = m.normals.as_ref().unwrap();
        for (p, n) in m.positions.iter().zip(n) {
            assert!(n.dot(p.normalize()) > 0.9, "{p} {n}");
        }
        // Faces 0-2 in group 1, 3-5 in group 2: a corner where both groups meet has two
        // normals, and no face is flat.
        let text = format!(
            "{CUBE}s 1\n{}s 2\n{}",
            CUBE_FACES[..3].concat(),
            CUBE_FACES[3..].concat()
        );
        let (m, _) = parse(&text).unwrap();
        assert!(m.positions.len() > 8 && m.positions.len() < 24);
        assert!(!is_flat(&m));
        // Group 1, then `s off`: the later faces are flat.
        let text = format!(
            "{CUBE}s 1\n{}s off\n{}",
            CUBE_FACES[..3].concat(),
            CUBE_FACES[3..].concat()
        );
        let (m, _) = parse(&text).unwrap();
        let flat_tail = Mesh {
            triangles: m.triangles[6..].to_vec(),
            ..m.clone()
        };
        assert!(is_flat(&flat_tail));
        assert!(!is_flat(&m));
        let e = parse(&format!("{CUBE}s one\n{}", CUBE_FACES.concat()))
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("t.obj:9: s: expected a smoothing group number or 'off'"),
            "{e}"
        );
    }

    /// `vn` in the file: its normals are used as they are, smoothing groups or not.
    #[test]
    fn file_normals_win_over_smoothing_groups() {
        let (m, _) =
            parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0.6 0.8\ns off\nf 1//1 2//1 3//1\n").unwrap();
        assert!(
            m.normals
                .unwrap()
                .iter()
                .all(|n| *n == Vec3::new(0.0, 0.6, 0.8))
        );
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
            (
                "v 0 0 0\nv 1 0 0\n",
                ":2: OBJ: no faces by the end of the file",
            ),
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
