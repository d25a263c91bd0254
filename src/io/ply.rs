//! PLY meshes (Stanford polygon files): ASCII and binary, little and big endian, read strictly.
//!
//! Vertices: `x y z` (required), `nx ny nz`, `u v` / `s t` / `texture_u texture_v`,
//! `red green blue` (integer types are 8-bit sRGB, decoded to linear as 8-bit textures are;
//! float types are linear). Faces: a list property `vertex_indices` or `vertex_index`,
//! polygons fan-triangulated. Other elements and properties are read past and ignored.
//! Element counts are checked against what the rest of the file can hold before anything
//! is allocated; every number must be finite, every index in range. Errors name the file and
//! the line (header, ASCII body) or the byte offset (binary body).

use crate::error::{Error, Result};
use crate::io::scene::schema::MAX_SCENE_TRIANGLES;
use crate::mesh::Mesh;
use glam::{Vec2, Vec3};
use std::path::Path;

/// Longest header accepted (bytes up to `end_header`).
const MAX_HEADER_BYTES: usize = 1 << 16;
/// Most vertices a face may list.
const MAX_FACE_VERTICES: u64 = 1 << 16;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Ascii,
    Le,
    Be,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }
    fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    /// `Some(count type)` for a list property.
    list: Option<Scalar>,
    ty: Scalar,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

/// Reads values of the body, ASCII (token by token, tracking lines) or binary.
struct Body<'a> {
    data: &'a [u8],
    pos: usize,
    format: Format,
    /// Current line (ASCII) for messages.
    line: usize,
    path: &'a Path,
}

impl Body<'_> {
    fn err(&self, msg: impl Into<String>) -> Error {
        match self.format {
            Format::Ascii => Error::parse(self.path, self.line, msg),
            _ => Error::scene(
                self.path,
                format!("binary body at byte {}: {}", self.pos, msg.into()),
            ),
        }
    }

    /// The next ASCII token on the current line (`None` at the end of the line).
    fn token(&mut self) -> Option<&str> {
        let d = self.data;
        while self.pos < d.len()
            && (d[self.pos] == b' ' || d[self.pos] == b'\t' || d[self.pos] == b'\r')
        {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < d.len() && !d[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return None;
        }
        std::str::from_utf8(&d[start..self.pos]).ok()
    }

    /// Move to the next ASCII line; anything left on this one is an error.
    fn end_line(&mut self, what: &str) -> Result<()> {
        if let Some(t) = self.token() {
            let t = t.to_string();
            return Err(self.err(format!("{what}: unexpected '{t}' after the last property")));
        }
        if self.pos < self.data.len() {
            // at '\n'
            self.pos += 1;
        }
        self.line += 1;
        // Skip blank lines.
        while self.pos < self.data.len() {
            let save = (self.pos, self.line);
            if self.token().is_some() {
                (self.pos, self.line) = save;
                break;
            }
            if self.pos < self.data.len() {
                self.pos += 1;
                self.line += 1;
            } else {
                break;
            }
        }
        Ok(())
    }

    fn value(&mut self, ty: Scalar, what: &str) -> Result<f64> {
        match self.format {
            Format::Ascii => {
                let Some(t) = self.token() else {
                    return Err(self.err(format!("{what}: missing value")));
                };
                let t = t.to_string();
                let v = if ty.is_int() {
                    t.parse::<i64>().ok().map(|v| v as f64)
                } else {
                    t.parse::<f64>().ok()
                };
                let v = v.ok_or_else(|| self.err(format!("{what}: '{t}' is not a number")))?;
                if !v.is_finite() {
                    return Err(self.err(format!("{what}: '{t}' is not a finite number")));
                }
                let ok = match ty {
                    Scalar::I8 => (-128.0..=127.0).contains(&v),
                    Scalar::U8 => (0.0..=255.0).contains(&v),
                    Scalar::I16 => (-32768.0..=32767.0).contains(&v),
                    Scalar::U16 => (0.0..=65535.0).contains(&v),
                    Scalar::I32 => (i32::MIN as f64..=i32::MAX as f64).contains(&v),
                    Scalar::U32 => (0.0..=u32::MAX as f64).contains(&v),
                    Scalar::F32 | Scalar::F64 => v.is_finite(),
                };
                if !ok {
                    return Err(self.err(format!("{what}: '{t}' is out of range for its type")));
                }
                Ok(v)
            }
            f => {
                let n = ty.size();
                let Some(b) = self.data.get(self.pos..self.pos + n) else {
                    return Err(self.err(format!("{what}: the file ends early")));
                };
                let mut a = [0u8; 8];
                a[..n].copy_from_slice(b);
                if f == Format::Be {
                    a[..n].reverse();
                }
                self.pos += n;
                let v = match ty {
                    Scalar::I8 => a[0] as i8 as f64,
                    Scalar::U8 => a[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([a[0], a[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([a[0], a[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([a[0], a[1], a[2], a[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(a),
                };
                if !v.is_finite() {
                    self.pos -= n;
                    return Err(self.err(format!("{what}: not a finite number")));
                }
                Ok(v)
            }
        }
    }
}

fn header(bytes: &[u8], path: &Path) -> Result<(Format, Vec<Element>, usize, usize)> {
    if !(bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")) {
        return Err(Error::parse(
            path,
            1,
            "not a PLY file (the first line must be 'ply')",
        ));
    }
    let end = bytes
        .windows(10)
        .take(MAX_HEADER_BYTES)
        .position(|w| w == b"end_header")
        .ok_or_else(|| {
            Error::parse(
                path,
                1,
                format!("PLY: no 'end_header' in the first {MAX_HEADER_BYTES} bytes"),
            )
        })?;
    // The body starts after the end of the end_header line.
    let mut body = end + 10;
    if bytes.get(body) == Some(&b'\r') {
        body += 1;
    }
    if bytes.get(body) == Some(&b'\n') {
        body += 1;
    }
    let text = std::str::from_utf8(&bytes[..end])
        .map_err(|_| Error::parse(path, 1, "PLY: the header is not ASCII text"))?;
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim()));
    match lines.next() {
        Some((_, "ply")) => {}
        _ => {
            return Err(Error::parse(
                path,
                1,
                "not a PLY file (the first line must be 'ply')",
            ));
        }
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    for (n, line) in lines {
        let err = |m: String| Error::parse(path, n, format!("PLY header: {m}"));
        let w: Vec<&str> = line.split_whitespace().collect();
        match w.as_slice() {
            [] | ["comment", ..] | ["obj_info", ..] => {}
            ["format", f, version] => {
                if *version != "1.0" {
                    return Err(err(format!("version '{version}' (only 1.0)")));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Le,
                    "binary_big_endian" => Format::Be,
                    other => return Err(err(format!("unknown format '{other}'"))),
                });
            }
            ["element", name, count] => {
                let count: u64 = count
                    .parse()
                    .map_err(|_| err(format!("element {name}: '{count}' is not a count")))?;
                if elements.iter().any(|e| e.name == *name) {
                    return Err(err(format!("element {name} is declared twice")));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", "list", ct, it, name] => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| err("property before any element".into()))?;
                let ct = Scalar::parse(ct).filter(|t| t.is_int()).ok_or_else(|| {
                    err(format!(
                        "list {name}: count type '{ct}' is not an integer type"
                    ))
                })?;
                let ty = Scalar::parse(it)
                    .ok_or_else(|| err(format!("list {name}: unknown type '{it}'")))?;
                e.props.push(Property {
                    name: name.to_string(),
                    list: Some(ct),
                    ty,
                });
            }
            ["property", ty, name] => {
                let e = elements
                    .last_mut()
                    .ok_or_else(|| err("property before any element".into()))?;
                let ty = Scalar::parse(ty)
                    .ok_or_else(|| err(format!("property {name}: unknown type '{ty}'")))?;
                if e.props.iter().any(|p| p.name == *name) {
                    return Err(err(format!("property {name} is declared twice")));
                }
                e.props.push(Property {
                    name: name.to_string(),
                    list: None,
                    ty,
                });
            }
            _ => return Err(err(format!("cannot read '{line}'"))),
        }
    }
    let format = format.ok_or_else(|| Error::parse(path, 2, "PLY header: no format line"))?;
    let header_lines = text.lines().count() + 1;
    Ok((format, elements, body, header_lines))
}

/// Parse PLY bytes into a mesh; warnings are returned beside it.
pub fn parse_ply(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>)> {
    parse_ply_detail(bytes, path).map(|(m, w, _)| (m, w))
}

/// [`parse_ply`], also telling whether the file gave vertex normals.
pub fn parse_ply_detail(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>, bool)> {
    let mut warnings = Vec::new();
    let (format, elements, body_start, header_lines) = header(bytes, path)?;
    let vertex = elements
        .iter()
        .find(|e| e.name == "vertex")
        .ok_or_else(|| Error::parse(path, 1, "PLY header: no 'element vertex'"))?;
    let face = elements.iter().find(|e| e.name == "face").ok_or_else(|| {
        Error::parse(
            path,
            1,
            "PLY header: no 'element face' (point clouds are not rendered)",
        )
    })?;
    let find = |names: &[&str]| {
        names.iter().find_map(|n| {
            vertex
                .props
                .iter()
                .position(|p| p.name == *n && p.list.is_none())
        })
    };
    let pos = [find(&["x"]), find(&["y"]), find(&["z"])];
    let [Some(px), Some(py), Some(pz)] = pos else {
        return Err(Error::parse(
            path,
            1,
            "PLY header: vertex needs properties x, y and z",
        ));
    };
    let normal = match [find(&["nx"]), find(&["ny"]), find(&["nz"])] {
        [Some(a), Some(b), Some(c)] => Some([a, b, c]),
        _ => None,
    };
    let uv = match [
        find(&["u", "s", "texture_u", "texture_s"]),
        find(&["v", "t", "texture_v", "texture_t"]),
    ] {
        [Some(a), Some(b)] => Some([a, b]),
        _ => None,
    };
    let color = match [
        find(&["red", "r"]),
        find(&["green", "g"]),
        find(&["blue", "b"]),
    ] {
        [Some(a), Some(b), Some(c)] => Some([a, b, c]),
        _ => None,
    };
    let index_prop = face
        .props
        .iter()
        .position(|p| (p.name == "vertex_indices" || p.name == "vertex_index") && p.list.is_some())
        .ok_or_else(|| {
            Error::parse(
                path,
                1,
                "PLY header: face needs a list property vertex_indices or vertex_index",
            )
        })?;
    if !face.props[index_prop].ty.is_int() {
        return Err(Error::parse(
            path,
            1,
            "PLY header: face vertex indices must have an integer type",
        ));
    }

    // Caps before allocating: every element takes at least one byte per property (binary) or
    // one line (ASCII, at least 2 bytes: a digit and a newline).
    let remaining = (bytes.len() - body_start) as u64;
    for e in &elements {
        let min = match format {
            Format::Ascii => 2,
            _ => e
                .props
                .iter()
                .map(|p| p.list.map_or(p.ty.size(), |c| c.size()) as u64)
                .sum::<u64>()
                .max(1),
        };
        if e.count.saturating_mul(min) > remaining {
            return Err(Error::parse(
                path,
                1,
                format!(
                    "PLY header: element {} claims {} entries, more than the file's remaining {remaining} bytes can hold",
                    e.name, e.count
                ),
            ));
        }
    }
    if vertex.count > u32::MAX as u64 {
        return Err(Error::parse(path, 1, "PLY header: over 2^32 vertices"));
    }

    let mut body = Body {
        data: bytes,
        pos: body_start,
        format,
        line: header_lines + 1,
        path,
    };
    let nv = vertex.count as usize;
    let mut mesh = Mesh::default();
    mesh.positions.reserve(nv);
    let mut normals = Vec::with_capacity(if normal.is_some() { nv } else { 0 });
    let mut uvs = Vec::with_capacity(if uv.is_some() { nv } else { 0 });
    let mut colors = Vec::with_capacity(if color.is_some() { nv } else { 0 });
    let mut values = Vec::new();
    let srgb = |v: f64| {
        let c = (v / 255.0) as f32;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    for e in &elements {
        if format == Format::Ascii && e.count > 0 {
            // Start at the first non-blank line.
            body.end_line_start();
        }
        for k in 0..e.count {
            let what = |p: &str| format!("{} {k} {p}", e.name);
            if e.name == "vertex" {
                values.clear();
                for p in &e.props {
                    if p.list.is_some() {
                        skip_list(&mut body, p, &what(&p.name))?;
                        values.push(0.0);
                    } else {
                        values.push(body.value(p.ty, &what(&p.name))?);
                    }
                }
                let v = |i: usize| values[i] as f32;
                let q = Vec3::new(v(px), v(py), v(pz));
                if !q.is_finite() {
                    return Err(body.err(format!("{}: position overflows f32", what("x y z"))));
                }
                mesh.positions.push(q);
                if let Some([a, b, c]) = normal {
                    normals.push(Vec3::new(v(a), v(b), v(c)));
                }
                if let Some([a, b]) = uv {
                    uvs.push(Vec2::new(v(a), v(b)));
                }
                if let Some(ch) = color {
                    let c = ch.map(|i| {
                        if e.props[i].ty.is_int() {
                            srgb(values[i].clamp(0.0, 255.0))
                        } else {
                            values[i] as f32
                        }
                    });
                    if c.iter().any(|&x| !(x >= 0.0 && x.is_finite())) {
                        return Err(body.err(format!(
                            "{}: colour must be finite and >= 0",
                            what("red green blue")
                        )));
                    }
                    colors.push(Vec3::from(c));
                }
            } else if e.name == "face" {
                for (pi, p) in e.props.iter().enumerate() {
                    if pi != index_prop {
                        match p.list {
                            Some(_) => skip_list(&mut body, p, &what(&p.name))?,
                            None => {
                                body.value(p.ty, &what(&p.name))?;
                            }
                        }
                        continue;
                    }
                    let ct = p.list.expect("list");
                    let n = body.value(ct, &what(&p.name))?;
                    if !(3.0..=MAX_FACE_VERTICES as f64).contains(&n) {
                        return Err(body.err(format!(
                            "{}: a face needs 3 to {MAX_FACE_VERTICES} vertices, has {n}",
                            what(&p.name)
                        )));
                    }
                    let n = n as usize;
                    if (mesh.triangles.len() + n - 2) as u64 > MAX_SCENE_TRIANGLES {
                        return Err(
                            body.err(format!("over {MAX_SCENE_TRIANGLES} triangles (the cap)"))
                        );
                    }
                    let mut first = 0;
                    let mut prev = 0;
                    for j in 0..n {
                        let i = body.value(p.ty, &what(&p.name))?;
                        if !(i >= 0.0 && i < nv as f64) {
                            return Err(body.err(format!(
                                "{}: vertex index {i} out of range (0..{nv})",
                                what(&p.name)
                            )));
                        }
                        let i = i as u32;
                        match j {
                            0 => first = i,
                            1 => {}
                            _ => mesh.triangles.push([first, prev, i]),
                        }
                        prev = i;
                    }
                }
            } else {
                for p in &e.props {
                    match p.list {
                        Some(_) => skip_list(&mut body, p, &what(&p.name))?,
                        None => {
                            body.value(p.ty, &what(&p.name))?;
                        }
                    }
                }
            }
            if format == Format::Ascii {
                body.end_line(&e.name)?;
            }
        }
    }
    if mesh.positions.len() != nv {
        return Err(body.err("vertex element not read"));
    }
    if mesh.triangles.is_empty() {
        return Err(Error::parse(path, 1, "PLY: no faces"));
    }
    if format != Format::Ascii && body.pos < bytes.len() {
        warnings.push(format!(
            "{}: {} bytes after the last element are ignored",
            path.display(),
            bytes.len() - body.pos
        ));
    }
    let file_normals = normal.is_some();
    if file_normals {
        mesh.normals = Some(normals);
    }
    if uv.is_some() {
        mesh.uvs = Some(uvs);
    }
    if color.is_some() {
        mesh.colors = Some(colors);
    }
    super::finish_mesh(&mut mesh, path, &mut warnings);
    // Without `nx ny nz` a PLY mesh is shaded flat, as the format means it.
    let mesh = if file_normals {
        mesh
    } else {
        mesh.flat_shaded()
    };
    Ok((mesh, warnings, file_normals))
}

fn skip_list(body: &mut Body, p: &Property, what: &str) -> Result<()> {
    let n = body.value(p.list.expect("list"), what)?;
    if n < 0.0 {
        return Err(body.err(format!("{what}: negative list length")));
    }
    for _ in 0..n as u64 {
        body.value(p.ty, what)?;
    }
    Ok(())
}

impl Body<'_> {
    /// Skip blank lines before the first element (ASCII).
    fn end_line_start(&mut self) {
        while self.pos < self.data.len() {
            let save = (self.pos, self.line);
            if self.token().is_some() {
                (self.pos, self.line) = save;
                return;
            }
            if self.pos < self.data.len() {
                self.pos += 1;
                self.line += 1;
            }
        }
    }
}

/// Read and parse a `.ply` file (see [`parse_ply`]).
pub fn load_ply(path: &Path) -> Result<(Mesh, Vec<String>)> {
    parse_ply(&super::read_regular(path)?, path)
}

#[cfg(test)]
mod tests;
