//! STL meshes (stereolithography), ASCII and binary, read strictly.
//!
//! Binary: an 80-byte header, a little-endian `u32` facet count, then 50 bytes per facet
//! (normal, three vertices, a `u16` attribute). A file is binary when its size is exactly
//! `84 + 50 * count`, whatever its header says (some exporters begin binary headers with
//! `solid`); otherwise a file that begins with `solid` and holds no NUL byte is ASCII, and
//! anything else is a binary file whose count disagrees with its size (an error). ASCII:
//! `solid [name]`, then per facet `facet normal nx ny nz`, `outer loop`, three
//! `vertex x y z`, `endloop`, `endfacet`, and `endsolid [name]` (several solids in one file
//! are merged; keywords in any case, one statement per line).
//!
//! The facet normals are not trusted (exporters write zeros, stale or unnormalised ones) and
//! not read beyond their syntax; the attribute bytes are ignored. Vertices are welded by
//! exact position (`-0` = `0`), so the mesh is connected as the model was; shading is
//! flat, each facet's normal its geometric one (a scene's `smooth` key can ask otherwise).
//! Every coordinate must be finite. Errors name the file and the line (ASCII) or the byte
//! offset (binary); the facet count is checked against the file size and the triangle cap
//! before anything is allocated.

use crate::error::{Error, Result};
use crate::io::scene::schema::MAX_SCENE_TRIANGLES;
use crate::mesh::Mesh;
use glam::Vec3;
use std::collections::HashMap;
use std::path::Path;

/// Bytes before the first binary facet: the header and the count.
const BINARY_HEADER: usize = 84;
/// Bytes of one binary facet: normal, three vertices (12 `f32`) and the attribute `u16`.
const BINARY_FACET: usize = 50;

/// Read and load an STL file ([`parse_stl`] on its bytes).
pub fn load_stl(path: &Path) -> Result<(Mesh, Vec<String>)> {
    let bytes = super::read_regular(path)?;
    parse_stl(&bytes, path)
}

/// Parse STL bytes (ASCII or binary, told apart as the module doc says) into a mesh with flat
/// normals; warnings are returned beside it.
pub fn parse_stl(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>)> {
    parse_stl_detail(bytes, path).map(|(m, w, _)| (m, w))
}

/// [`parse_stl`], also telling whether the file gave vertex normals (never: STL's facet
/// normals are not used).
pub fn parse_stl_detail(bytes: &[u8], path: &Path) -> Result<(Mesh, Vec<String>, bool)> {
    let triangles = if is_binary(bytes) {
        read_binary(bytes, path)?
    } else {
        read_ascii(bytes, path)?
    };
    let mut warnings = Vec::new();
    let mut mesh = weld(&triangles);
    super::finish_mesh(&mut mesh, path, &mut warnings);
    Ok((mesh.flat_shaded(), warnings, false))
}

/// Whether `bytes` are read as binary STL: the size matches the count, or the file does not
/// look like ASCII STL (no `solid` at the start, or a NUL byte anywhere).
fn is_binary(bytes: &[u8]) -> bool {
    if bytes.len() >= BINARY_HEADER {
        let count = u32::from_le_bytes(bytes[80..84].try_into().expect("4 bytes")) as u64;
        if (BINARY_HEADER as u64) + (BINARY_FACET as u64) * count == bytes.len() as u64 {
            return true;
        }
    }
    let text = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let starts_solid = text
        .trim_ascii_start()
        .get(..5)
        .is_some_and(|w| w.eq_ignore_ascii_case(b"solid"));
    !starts_solid || bytes.contains(&0)
}

/// The triangles of a binary STL file; the count must match the size exactly.
fn read_binary(bytes: &[u8], path: &Path) -> Result<Vec<[Vec3; 3]>> {
    let err = |offset: usize, msg: String| {
        Error::parse(path, 0, format!("binary STL, byte {offset}: {msg}"))
    };
    if bytes.len() < BINARY_HEADER {
        return Err(err(
            bytes.len(),
            format!(
                "truncated: a binary STL file starts with an 80-byte header and a 4-byte facet \
                 count, but the file has {} bytes (and does not begin with 'solid' as ASCII STL does)",
                bytes.len()
            ),
        ));
    }
    let count = u32::from_le_bytes(bytes[80..84].try_into().expect("4 bytes")) as u64;
    let body = (bytes.len() - BINARY_HEADER) as u64;
    let want = count * BINARY_FACET as u64;
    if want != body {
        let whole = body / BINARY_FACET as u64;
        let msg = if want > body {
            format!(
                "the header counts {count} facets ({want} bytes after the header) but the file \
                 has {body} bytes after it: truncated, or a wrong count ({whole} whole facets)"
            )
        } else {
            format!(
                "the header counts {count} facets ({want} bytes after the header) but the file \
                 has {body} bytes after it: {} bytes of trailing data, or a wrong count",
                body - want
            )
        };
        return Err(err(80, msg));
    }
    if count == 0 {
        return Err(err(80, "the header counts 0 facets: no triangles".into()));
    }
    if count > MAX_SCENE_TRIANGLES {
        return Err(err(
            80,
            format!("{count} facets is over the cap of {MAX_SCENE_TRIANGLES} triangles"),
        ));
    }
    let mut triangles = Vec::with_capacity(count as usize);
    for (f, facet) in bytes[BINARY_HEADER..]
        .chunks_exact(BINARY_FACET)
        .enumerate()
    {
        let at = BINARY_HEADER + f * BINARY_FACET;
        let mut tri = [Vec3::ZERO; 3];
        for (k, v) in tri.iter_mut().enumerate() {
            for c in 0..3 {
                // Vertex k's coordinate c, after the 12-byte normal.
                let o = 12 + 12 * k + 4 * c;
                let x = f32::from_le_bytes(facet[o..o + 4].try_into().expect("4 bytes"));
                if !x.is_finite() {
                    return Err(err(
                        at + o,
                        format!(
                            "facet {f} vertex {} {}: {x} is not a finite number",
                            k + 1,
                            ["x", "y", "z"][c]
                        ),
                    ));
                }
                v[c] = x;
            }
        }
        triangles.push(tri);
    }
    Ok(triangles)
}

/// What an ASCII STL file may say next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Expect {
    /// `solid` (the start, or after an `endsolid`: another solid or the end).
    Solid,
    /// `facet normal` or `endsolid`.
    Facet,
    /// `outer loop`.
    Loop,
    /// `vertex`, the n-th of the facet (0, 1, 2).
    Vertex(usize),
    /// `endloop`.
    EndLoop,
    /// `endfacet`.
    EndFacet,
}

impl Expect {
    /// What a user would write there, for messages.
    fn what(self) -> &'static str {
        match self {
            Expect::Solid => "'solid'",
            Expect::Facet => "'facet normal nx ny nz' or 'endsolid'",
            Expect::Loop => "'outer loop'",
            Expect::Vertex(_) => "'vertex x y z'",
            Expect::EndLoop => "'endloop' (a facet has exactly 3 vertices)",
            Expect::EndFacet => "'endfacet'",
        }
    }
}

/// The triangles of an ASCII STL file, read line by line.
fn read_ascii(bytes: &[u8], path: &Path) -> Result<Vec<[Vec3; 3]>> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let mut triangles = Vec::new();
    let mut tri = [Vec3::ZERO; 3];
    let mut expect = Expect::Solid;
    let mut solids = 0usize;
    for (index, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = index + 1;
        let err = |msg: String| Error::parse(path, line_no, format!("ASCII STL: {msg}"));
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let text = std::str::from_utf8(raw)
            .map_err(|_| err("invalid UTF-8; not an STL text file".into()))?
            .trim();
        if text.is_empty() {
            continue;
        }
        let mut tok = text.split_ascii_whitespace();
        let word = tok.next().unwrap_or_default().to_ascii_lowercase();
        let unexpected = |expect: Expect| {
            err(format!(
                "expected {}, found '{}'",
                expect.what(),
                text.chars().take(40).collect::<String>()
            ))
        };
        expect = match (expect, word.as_str()) {
            // The name after `solid` and `endsolid` is free text.
            (Expect::Solid, "solid") => {
                solids += 1;
                Expect::Facet
            }
            (Expect::Facet, "endsolid") => Expect::Solid,
            (Expect::Facet, "facet") => {
                let normal = tok.next().map(str::to_ascii_lowercase);
                if normal.as_deref() != Some("normal") {
                    return Err(err("expected 'facet normal nx ny nz'".into()));
                }
                // The normal must be numbers, but its value is not used (see the module doc).
                three(&mut tok, "facet normal", &err)?;
                if triangles.len() as u64 >= MAX_SCENE_TRIANGLES {
                    return Err(err(format!("over {MAX_SCENE_TRIANGLES} facets (the cap)")));
                }
                Expect::Loop
            }
            (Expect::Loop, "outer") => {
                let rest: Vec<&str> = tok.collect();
                if rest.len() != 1 || !rest[0].eq_ignore_ascii_case("loop") {
                    return Err(err("expected 'outer loop'".into()));
                }
                Expect::Vertex(0)
            }
            (Expect::Vertex(k), "vertex") => {
                let v = three(&mut tok, "vertex", &err)?;
                if !v.is_finite() {
                    return Err(err(format!(
                        "vertex: ({}, {}, {}) is not finite",
                        v.x, v.y, v.z
                    )));
                }
                tri[k] = v;
                if k == 2 {
                    Expect::EndLoop
                } else {
                    Expect::Vertex(k + 1)
                }
            }
            (Expect::EndLoop, "endloop") => Expect::EndFacet,
            (Expect::EndFacet, "endfacet") => {
                triangles.push(tri);
                Expect::Facet
            }
            (e, _) => return Err(unexpected(e)),
        };
        // Keywords stand alone on their lines (only `solid`/`endsolid` take a name).
        if matches!(word.as_str(), "endloop" | "endfacet")
            && let Some(t) = text.split_ascii_whitespace().nth(1)
        {
            return Err(err(format!("'{word}' followed by '{t}'")));
        }
    }
    let last = super::last_line(bytes);
    if expect != Expect::Solid {
        let msg = if solids == 0 {
            "no 'solid' line".to_string()
        } else {
            format!(
                "the file ends where {} is expected (truncated?)",
                expect.what()
            )
        };
        return Err(Error::parse(path, last, format!("ASCII STL: {msg}")));
    }
    if triangles.is_empty() {
        return Err(Error::parse(
            path,
            last,
            "ASCII STL: no facets by the end of the file",
        ));
    }
    Ok(triangles)
}

/// The three numbers ending a `facet normal` or `vertex` line (no more, no fewer).
fn three(
    tok: &mut std::str::SplitAsciiWhitespace,
    what: &str,
    err: &dyn Fn(String) -> Error,
) -> Result<Vec3> {
    let mut v = [0f32; 3];
    for (c, x) in v.iter_mut().enumerate() {
        let t = tok
            .next()
            .ok_or_else(|| err(format!("{what}: expected 3 numbers, found {c}")))?;
        *x = t
            .parse()
            .map_err(|_| err(format!("{what}: '{t}' is not a number")))?;
    }
    if let Some(t) = tok.next() {
        return Err(err(format!(
            "{what}: expected 3 numbers, found more ('{t}')"
        )));
    }
    Ok(Vec3::from(v))
}

/// One vertex per distinct position (`-0` and `0` are one), triangles in file order.
fn weld(triangles: &[[Vec3; 3]]) -> Mesh {
    let mut index: HashMap<[u32; 3], u32> = HashMap::with_capacity(triangles.len() / 2);
    let mut mesh = Mesh {
        triangles: Vec::with_capacity(triangles.len()),
        ..Default::default()
    };
    for tri in triangles {
        let corners = tri.map(|p| {
            // Adding 0 turns -0 into +0, so the two spellings of zero weld.
            let p = p + Vec3::ZERO;
            let next = mesh.positions.len() as u32;
            *index
                .entry(p.to_array().map(f32::to_bits))
                .or_insert_with(|| {
                    mesh.positions.push(p);
                    next
                })
        });
        mesh.triangles.push(corners);
    }
    mesh
}

#[cfg(test)]
mod tests;
