//! MeshLib `.m` reader, hand-written and strict: `Vertex id x y z {attrs}`, `Face id a b c ...`.
//!
//! Accepted: `#` comments (any bytes inside them), CRLF, a UTF-8 BOM, E-notation, 1-based and
//! non-contiguous ids of any size (a map, not an array), faces before the vertices they name,
//! unknown attribute keys and record types (skipped), polygons (fan-triangulated).
//! Refused with file and line: missing or extra coordinates, NaN / inf / out-of-range numbers,
//! undefined or duplicate vertex ids, ids <= 0, malformed attribute tuples, unbalanced braces,
//! binary data, no faces. A face id given twice is a warning naming both lines (both faces
//! are kept: the id names nothing else).
//!
//! Files where only some vertices carry `uv=`, `rgb=` or `normal=` exist in the wild: they load,
//! with one warning that counts the gaps. A missing uv is (0, 0); a missing normal is the
//! area-weighted one; a missing rgb is the material's colour, filled in by the scene (see
//! [`MRead::missing_rgb`]; white when the mesh is loaded on its own).

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Attributes a vertex line may carry; `None` when absent.
#[derive(Default)]
struct VertexAttrs {
    normal: Option<Vec3>,
    uv: Option<Vec2>,
    rgb: Option<Vec3>,
}

/// A parsed `.m` file and what it left out.
#[derive(Clone, Debug)]
pub struct MRead {
    /// The mesh; attributes some vertices lacked are filled in (see the module doc).
    pub mesh: Mesh,
    /// Gaps in the attributes, degenerate faces, ...
    pub warnings: Vec<String>,
    /// Whether the file gave (some) vertex normals; otherwise they were all computed.
    pub file_normals: bool,
    /// Vertices with no `rgb=` in a file where others have one (their colour is white here;
    /// a scene gives them the material's colour). Empty when every vertex or none has rgb.
    pub missing_rgb: Vec<u32>,
}

/// Read and parse a `.m` file. Warnings (degenerate faces, ...) are returned beside the mesh.
pub fn load_m(path: &Path) -> Result<(Mesh, Vec<String>)> {
    let bytes = super::read_regular(path)?;
    parse_m(&bytes, path)
}

/// Parse `.m` text; `path` is only used in messages.
pub fn parse_m(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>)> {
    parse_m_detail(bytes, path).map(|(m, w, _)| (m, w))
}

/// [`parse_m`], also telling whether the file gave vertex normals (otherwise they were computed).
pub fn parse_m_detail(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>, bool)> {
    read_m(bytes, path).map(|r| (r.mesh, r.warnings, r.file_normals))
}

/// Parse `.m` text into an [`MRead`]; `path` is only used in messages.
pub fn read_m(bytes: &[u8], path: &Path) -> Result<MRead> {
    // a few pieces a thread, so that the vertex lines (the slow ones, usually first) spread;
    // one thread parses the file as one piece
    let piece = match rayon::current_num_threads() {
        1 => usize::MAX,
        n => PIECE_BYTES.max(bytes.len() / (4 * n)),
    };
    read_m_in(bytes, path, piece)
}

/// The fewest bytes of text one task parses: a larger file is cut at line ends into pieces,
/// parsed on rayon's pool and merged in order (the same mesh, warnings and first error as
/// one pass over the file).
const PIECE_BYTES: usize = 1 << 18;

/// [`read_m`] with the file cut into pieces of about `piece` bytes.
fn read_m_in(bytes: &[u8], path: &Path, piece: usize) -> Result<MRead> {
    use rayon::prelude::*;
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let err = |line: usize, msg: String| Error::parse(path, line, msg);

    let pieces = cut_at_lines(bytes, piece);
    let parsed: Vec<Records> = pieces.par_iter().map(|p| Records::parse(p)).collect();

    let mut ids = IdMap::new(bytes.len());
    let mut positions = Vec::new();
    let mut attrs: Vec<(VertexAttrs, usize)> = Vec::new();
    // Each face's line and its vertex ids (a run of `face_verts`), resolved once every
    // vertex is known.
    let mut faces: Vec<(usize, std::ops::Range<usize>)> = Vec::new();
    let mut face_verts: Vec<u64> = Vec::new();
    // The face of each face id, and the first id given twice (`(line, id, first line)`) with
    // how many more were: duplicate faces are kept, with a warning.
    let mut face_ids = IdMap::new(bytes.len());
    let mut duplicate_face: Option<(usize, u64, usize)> = None;
    let mut more_duplicates = 0usize;

    // the merged vectors sized once (a piece's vectors are freed as it is merged)
    let total = |n: fn(&Records) -> usize| parsed.iter().map(n).sum::<usize>();
    let sizes = (
        total(|r| r.positions.len()),
        total(|r| r.faces.len()),
        total(|r| r.face_verts.len()),
    );
    // the lines before the piece
    let mut before = 0;
    for mut r in parsed {
        // a duplicate vertex id comes before the piece's own error, which ends its records
        for (j, &id) in r.vertex_ids.iter().enumerate() {
            if ids.insert_new(id, (positions.len() + j) as u32).is_some() {
                let line = before + r.attrs[j].1;
                return Err(err(line, format!("duplicate vertex id {id}")));
            }
        }
        let (shift, base) = (face_verts.len(), faces.len());
        for k in 0..r.faces.len() {
            let (line, verts) = &mut r.faces[k];
            *line += before;
            *verts = verts.start + shift..verts.end + shift;
            let (id, line) = (r.face_ids[k], *line);
            if let Some(first) = face_ids.insert_new(id, (base + k) as u32) {
                let first = match first as usize {
                    f if f < base => faces[f].0,
                    f => r.faces[f - base].0,
                };
                match duplicate_face {
                    None => duplicate_face = Some((line, id, first)),
                    Some(_) => more_duplicates += 1,
                }
            }
        }
        if let Some((line, msg)) = r.error {
            return Err(err(before + line, msg));
        }
        for a in &mut r.attrs {
            a.1 += before;
        }
        take_or_extend(&mut positions, r.positions, sizes.0);
        take_or_extend(&mut attrs, r.attrs, sizes.0);
        take_or_extend(&mut faces, r.faces, sizes.1);
        take_or_extend(&mut face_verts, r.face_verts, sizes.2);
        before += r.newlines;
    }

    if faces.is_empty() {
        return Err(err(
            super::last_line(bytes),
            "no faces by the end of the file".into(),
        ));
    }
    let mut triangles = Vec::with_capacity(faces.len());
    let mut idx = Vec::new();
    for (line_no, verts) in &faces {
        idx.clear();
        for &v in &face_verts[verts.clone()] {
            idx.push(
                ids.get(v)
                    .ok_or_else(|| err(*line_no, format!("face names undefined vertex {v}")))?,
            );
        }
        for k in 1..idx.len() - 1 {
            triangles.push([idx[0], idx[k], idx[k + 1]]);
        }
    }

    let mut warnings = Vec::new();
    if let Some((line, id, first)) = duplicate_face {
        let more = match more_duplicates {
            0 => String::new(),
            n => format!(" ({n} more faces repeat an id)"),
        };
        warnings.push(format!(
            "{}:{line}: duplicate face id {id} (first at line {first}); both faces are kept{more}",
            path.display()
        ));
    }
    // An attribute on some vertices only: the others get `fill` (and are counted).
    let n = attrs.len();
    let mut gaps = Vec::new();
    let uvs = partial(
        &attrs,
        |a| a.uv,
        Vec2::ZERO,
        "uv (set to (0, 0))",
        &mut gaps,
    );
    let colors = partial(
        &attrs,
        |a| a.rgb,
        Vec3::ONE,
        "rgb (the material's colour)",
        &mut gaps,
    );
    // A zero normal is replaced by the area-weighted one in `ensure_normals` below.
    let normals = partial(
        &attrs,
        |a| a.normal,
        Vec3::ZERO,
        "normal (area-weighted)",
        &mut gaps,
    );
    if !gaps.is_empty() {
        warnings.push(format!(
            "{}: some vertices lack attributes others have: {}",
            path.display(),
            gaps.join(", ")
        ));
    }
    let missing_rgb: Vec<u32> = match colors {
        Some(_) => (0..n as u32)
            .filter(|&i| attrs[i as usize].0.rgb.is_none())
            .collect(),
        None => Vec::new(),
    };
    let file_normals = normals.is_some();
    let mut mesh = Mesh {
        positions,
        triangles,
        normals,
        uvs,
        colors,
    };
    super::finish_mesh(&mut mesh, path, &mut warnings);
    Ok(MRead {
        mesh,
        warnings,
        file_normals,
        missing_rgb,
    })
}

/// `bytes` cut after a newline every `size` bytes or so (one piece when it is no longer).
fn cut_at_lines(bytes: &[u8], size: usize) -> Vec<&[u8]> {
    let mut pieces = Vec::new();
    let mut rest = bytes;
    while rest.len() > size {
        let Some(k) = memchr::memchr(b'\n', &rest[size..]) else {
            break;
        };
        let (piece, tail) = rest.split_at(size + k + 1);
        pieces.push(piece);
        rest = tail;
    }
    pieces.push(rest);
    pieces
}

/// The records of a piece of a `.m` file, lines numbered from 1 at the piece's start.
#[derive(Default)]
struct Records {
    /// Newlines in the piece: the lines of the pieces after it start this much later.
    newlines: usize,
    /// Each vertex's id, position, and attributes with its line.
    vertex_ids: Vec<u64>,
    positions: Vec<Vec3>,
    attrs: Vec<(VertexAttrs, usize)>,
    /// Each face's id, and its line with its run of `face_verts`.
    face_ids: Vec<u64>,
    faces: Vec<(usize, std::ops::Range<usize>)>,
    face_verts: Vec<u64>,
    /// The first line that does not parse, and why: the records stop before it.
    error: Option<(usize, String)>,
}

/// `items` appended to `to`, or taken as it is when `to` is empty (a file of one piece
/// is not copied), with room for `total` items in all.
fn take_or_extend<T>(to: &mut Vec<T>, items: Vec<T>, total: usize) {
    if to.is_empty() {
        *to = items;
    } else {
        to.extend(items);
    }
    to.reserve_exact(total.saturating_sub(to.len()));
}

impl Records {
    fn parse(piece: &[u8]) -> Records {
        let mut r = Records {
            newlines: memchr::memchr_iter(b'\n', piece).count(),
            ..Records::default()
        };
        for (line_no, line) in lines(piece) {
            if let Err(msg) = r.record(line_no, line) {
                r.error = Some((line_no, msg));
                break;
            }
        }
        r
    }

    /// Record line `line_no` (its text, or why it is not text).
    fn record(
        &mut self,
        line_no: usize,
        line: std::result::Result<&str, &'static str>,
    ) -> std::result::Result<(), String> {
        let text = line?;
        let (head, body) = split_braces(text)?;
        let mut tokens = head.split_ascii_whitespace();
        match tokens.next() {
            Some("Vertex") => {
                let id = parse_id(tokens.next(), "vertex id")?;
                let mut xyz = [0f32; 3];
                for (k, c) in xyz.iter_mut().enumerate() {
                    let tok = tokens.next().ok_or_else(|| {
                        format!("Vertex {id}: missing {} coordinate", ["x", "y", "z"][k])
                    })?;
                    *c = parse_f32(tok).map_err(|m| format!("Vertex {id}: {m}"))?;
                }
                if let Some(extra) = tokens.next() {
                    return Err(format!("Vertex {id}: unexpected extra value '{extra}'"));
                }
                let a = parse_attrs(body.unwrap_or("")).map_err(|m| format!("Vertex {id}: {m}"))?;
                self.vertex_ids.push(id);
                self.positions.push(Vec3::from(xyz));
                self.attrs.push((a, line_no));
            }
            Some("Face") => {
                let id = parse_id(tokens.next(), "face id")?;
                let start = self.face_verts.len();
                for t in tokens {
                    let v =
                        parse_id(Some(t), "vertex id").map_err(|m| format!("Face {id}: {m}"))?;
                    self.face_verts.push(v);
                }
                let count = self.face_verts.len() - start;
                if count < 3 {
                    return Err(format!("Face {id}: needs at least 3 vertices, has {count}"));
                }
                if let Some(b) = body {
                    parse_attrs(b).map_err(|m| format!("Face {id}: {m}"))?;
                }
                self.face_ids.push(id);
                self.faces.push((line_no, start..self.face_verts.len()));
            }
            // Edge, Corner and any other record type: not needed for rendering.
            _ => {}
        }
        Ok(())
    }
}

/// The lines of a `.m` file that hold a record (not blank, not a comment), numbered from 1,
/// without their CR and leading blanks: the text, or why the line is not text (comments may
/// hold any bytes). Usually the whole file is UTF-8 without NUL bytes, checked once;
/// otherwise each record line is checked.
fn lines(bytes: &[u8]) -> impl Iterator<Item = (usize, Result<&str, &'static str>)> {
    let whole = match bytes.contains(&0) {
        true => None,
        false => std::str::from_utf8(bytes).ok(),
    };
    let base = bytes.as_ptr() as usize;
    let mut start = 0;
    memchr::memchr_iter(b'\n', bytes)
        .map(Some)
        .chain([None])
        .map(move |end| {
            let end = end.unwrap_or(bytes.len());
            let line = &bytes[start..end];
            start = end + 1;
            line
        })
        .enumerate()
        .filter_map(move |(index, raw)| {
            let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
            let trimmed = raw.trim_ascii_start();
            if trimmed.is_empty() || trimmed[0] == b'#' {
                return None;
            }
            let text = match whole {
                // (a line of the checked text: it starts and ends at an ASCII byte, so on
                // character boundaries)
                Some(whole) => {
                    let at = trimmed.as_ptr() as usize - base;
                    Ok(&whole[at..at + trimmed.len()])
                }
                None if trimmed.contains(&0) => Err("binary data (NUL byte); not a .m text file"),
                None => std::str::from_utf8(trimmed)
                    .map_err(|_| "invalid UTF-8 outside a comment; not a .m text file"),
            };
            Some((index + 1, text))
        })
}

/// Record ids to indices. Ids are usually `1..=n`, so ids below a bound set by the file's
/// size (an eighth of its bytes: at most half its size in memory) index a vector; larger
/// ones go to a map, as ids may be any positive `u64`. A hash per id was a third of the
/// kitten's parse.
struct IdMap {
    dense: Vec<u32>,
    limit: u64,
    sparse: HashMap<u64, u32>,
}

impl IdMap {
    /// Absent in `dense`.
    const NONE: u32 = u32::MAX;

    fn new(file_len: usize) -> IdMap {
        IdMap {
            dense: Vec::new(),
            limit: (file_len / 8) as u64 + 1024,
            sparse: HashMap::new(),
        }
    }

    fn get(&self, id: u64) -> Option<u32> {
        if id < self.limit {
            self.dense
                .get(id as usize)
                .copied()
                .filter(|&v| v != Self::NONE)
        } else {
            self.sparse.get(&id).copied()
        }
    }

    /// Map `id` to `v` unless it is mapped already: then its index, unchanged.
    fn insert_new(&mut self, id: u64, v: u32) -> Option<u32> {
        if id < self.limit {
            let i = id as usize;
            if i >= self.dense.len() {
                self.dense.resize(i + 1, Self::NONE);
            }
            match self.dense[i] {
                Self::NONE => {
                    self.dense[i] = v;
                    None
                }
                old => Some(old),
            }
        } else {
            match self.sparse.entry(id) {
                std::collections::hash_map::Entry::Occupied(e) => Some(*e.get()),
                std::collections::hash_map::Entry::Vacant(e) => {
                    e.insert(v);
                    None
                }
            }
        }
    }
}

/// One attribute per vertex when any vertex has it (`None` when none does): the vertices
/// without it get `fill`, and a gap note (`2 of 5 have no uv ...`) is added to `gaps`.
fn partial<T: Copy>(
    attrs: &[(VertexAttrs, usize)],
    get: impl Fn(&VertexAttrs) -> Option<T>,
    fill: T,
    what: &str,
    gaps: &mut Vec<String>,
) -> Option<Vec<T>> {
    let given = attrs.iter().filter(|(a, _)| get(a).is_some()).count();
    if given == 0 {
        return None;
    }
    if given < attrs.len() {
        gaps.push(format!(
            "{} of {} have no {what}",
            attrs.len() - given,
            attrs.len()
        ));
    }
    Some(attrs.iter().map(|(a, _)| get(a).unwrap_or(fill)).collect())
}

/// Split `head {body}` into its parts; the body must be the last thing on the line. A `#`
/// starts a comment unless it lies inside braces opened before it and not closed. (One
/// pass finds the first `#`, `{` and `}`; `split_braces_reference` in the tests is the rule
/// written out.)
fn split_braces(text: &str) -> Result<(&str, Option<&str>), String> {
    let b = text.as_bytes();
    let (mut hash, mut open, mut close) = (None, None, None);
    for at in memchr::memchr3_iter(b'#', b'{', b'}', b) {
        let first = match b[at] {
            b'#' => &mut hash,
            b'{' => &mut open,
            _ => &mut close,
        };
        first.get_or_insert(at);
        if hash.is_some() && open.is_some() && close.is_some() {
            break;
        }
    }
    let text = match hash {
        // a trailing comment after the record (outside any braces)
        Some(h) if open.is_none_or(|o| o > h) || close.is_some_and(|c| c < h) => &text[..h],
        _ => text,
    };
    let (open, close) = (
        open.filter(|&o| o < text.len()),
        close.filter(|&c| c < text.len()),
    );
    match open {
        None if close.is_some() => Err("unbalanced braces: '}' without '{'".into()),
        None => Ok((text, None)),
        Some(open) => {
            let rest = text[open + 1..].trim_end();
            let body = rest.strip_suffix('}').ok_or_else(|| {
                "unbalanced braces: '{' without closing '}' at the end of the line".to_string()
            })?;
            if memchr::memchr2(b'{', b'}', body.as_bytes()).is_some() {
                return Err("unbalanced or nested braces".into());
            }
            Ok((&text[..open], Some(body)))
        }
    }
}

/// Parse `key=(a b c) key=value bare` attribute lists; keep `normal`, `uv` and `rgb`.
fn parse_attrs(body: &str) -> Result<VertexAttrs, String> {
    let mut out = VertexAttrs::default();
    let mut rest = body.trim_start();
    while !rest.is_empty() {
        // (a byte search: '=' and ASCII blanks are single bytes, so their positions are
        // character boundaries)
        let key_end = rest
            .bytes()
            .position(|b| b == b'=' || b.is_ascii_whitespace())
            .unwrap_or(rest.len());
        let key = &rest[..key_end];
        rest = &rest[key_end..];
        if let Some(after) = rest.strip_prefix('=') {
            if let Some(tuple) = after.strip_prefix('(') {
                let close = tuple
                    .find(')')
                    .ok_or_else(|| format!("{key}=(...: missing ')'"))?;
                let inner = &tuple[..close];
                if inner.contains('(') {
                    return Err(format!("{key}=(...: unbalanced parentheses"));
                }
                rest = &tuple[close + 1..];
                let want = match key {
                    "normal" | "rgb" => 3,
                    "uv" => 2,
                    _ => 0,
                };
                if want > 0 {
                    // every number parsed (the first bad one is the error), then counted
                    let mut nums = [0f32; 3];
                    let mut found = 0;
                    for tok in inner.split_ascii_whitespace() {
                        let v = parse_f32(tok).map_err(|m| format!("{key}=({inner}): {m}"))?;
                        if let Some(slot) = nums.get_mut(found) {
                            *slot = v;
                        }
                        found += 1;
                    }
                    if found != want {
                        return Err(format!(
                            "{key}=({inner}): expected {want} numbers, found {found}"
                        ));
                    }
                    match key {
                        "normal" => out.normal = Some(Vec3::from_array(nums)),
                        "uv" => out.uv = Some(Vec2::new(nums[0], nums[1])),
                        _ => out.rgb = Some(Vec3::from_array(nums)),
                    }
                }
            } else {
                if matches!(key, "normal" | "uv" | "rgb") {
                    return Err(format!("{key}= must be followed by a tuple '(...)'"));
                }
                let end = after
                    .bytes()
                    .position(|b| b.is_ascii_whitespace())
                    .unwrap_or(after.len());
                rest = &after[end..];
            }
        } else if key.is_empty() {
            return Err("attribute list: unexpected character".into());
        }
        rest = rest.trim_start();
    }
    Ok(out)
}

fn parse_id(tok: Option<&str>, what: &str) -> Result<u64, String> {
    let tok = tok.ok_or_else(|| format!("missing {what}"))?;
    match tok.parse::<u64>() {
        Ok(0) => Err(format!("{what} must be >= 1, found 0")),
        Ok(v) => Ok(v),
        Err(_) => Err(format!("{what} must be a positive integer, found '{tok}'")),
    }
}

/// A finite number that fits in f32 (E-notation allowed; `nan`, `inf` refused): the f64
/// nearest the decimal, rounded to f32.
fn parse_f32(tok: &str) -> Result<f32, String> {
    let v: f64 = match plain_decimal(tok) {
        Some(v) => v,
        None => tok
            .parse()
            .map_err(|_| format!("'{tok}' is not a number"))?,
    };
    if !v.is_finite() {
        return Err(format!("'{tok}' is not a finite number"));
    }
    if v.abs() > f32::MAX as f64 {
        return Err(format!("'{tok}' is out of range for f32"));
    }
    Ok(v as f32)
}

/// Exact powers of ten in f64 (`10^k` for `k <= 22` has at most 53 significant bits).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// The f64 nearest a plain decimal (`-0.474563`: a sign, at most 15 digits, a point, no
/// exponent), as `str::parse` gives it but in a few instructions: the digits as an integer
/// below 2^53 and a power of ten up to 10^22 are both exact in f64, so their quotient is
/// rounded once, to the nearest f64 (Clinger's fast path). `None` for anything else, which
/// `str::parse` then reads. Coordinates in text meshes are nearly all of this form; their
/// parse was two thirds of the kitten's load.
fn plain_decimal(tok: &str) -> Option<f64> {
    let b = tok.as_bytes();
    let (negative, digits) = match b.first()? {
        b'-' => (true, &b[1..]),
        b'+' => (false, &b[1..]),
        _ => (false, b),
    };
    let mut mantissa = 0u64;
    let (mut count, mut fraction) = (0usize, None);
    for (i, &c) in digits.iter().enumerate() {
        match c {
            // (at most 15 digits, so the mantissa stays below 10^15)
            b'0'..=b'9' if count < 15 => {
                mantissa = mantissa * 10 + u64::from(c - b'0');
                count += 1;
            }
            b'.' if fraction.is_none() => fraction = Some(digits.len() - i - 1),
            _ => return None,
        }
    }
    if count == 0 {
        return None;
    }
    let v = mantissa as f64 / POW10[fraction.unwrap_or(0)];
    Some(if negative { -v } else { v })
}

#[cfg(test)]
mod tests;
