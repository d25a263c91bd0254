//! glTF 2.0 models (`.gltf` with its buffers, and `.glb`), read strictly: the scene's node
//! trees flattened into one mesh.
//!
//! Read: the default scene (`scene`, else the first of `scenes`, else every node that is no
//! node's child) and its node trees, each node's `matrix` or `translation`/`rotation`/`scale`
//! applied to its meshes; triangle primitives (mode 4), indexed (u8, u16, u32) or not;
//! `POSITION`, `NORMAL`, `TEXCOORD_0` and `COLOR_0` (floats, or normalised u8/u16 for uv and
//! colour); buffers in the GLB `BIN` chunk, in `data:` URIs (base64) or in files beside the
//! model; materials' metallic-roughness factors, `baseColorTexture` (an image file, a data URI
//! or a buffer view, with its sampler's wrap modes), `emissiveFactor` and the
//! `KHR_materials_transmission`, `KHR_materials_ior` and `KHR_materials_emissive_strength`
//! extensions, in Whitted's terms (`gltf/material.rs`); the first perspective camera met in
//! the node trees; `KHR_lights_punctual` lights as point lights. Skins, morph targets and
//! animations are not read; other primitive modes, sparse accessors and any other
//! `extensionsRequired` are refused by name. Every count and offset is checked against the bytes its buffer holds before
//! anything is allocated; errors name the file and the JSON path (`accessors[3].count: ...`).
//! The table of what maps to what is in docs/formats.md ("glTF").

mod accessor;
mod image;
mod instancing;
#[cfg(test)]
mod instancing_tests;
mod listing;
mod material;
mod mesh;
#[cfg(test)]
mod tests;
mod view;

pub use image::{image_ref, load_image};
pub use listing::listing;

use crate::error::{Error, Result};
use crate::io::model::Model;
use serde::Deserialize;
use std::path::Path;

/// The parts of a glTF document whitted reads (the rest, `extras` and `extensions` included,
/// is ignored by serde).
#[derive(Debug, Default, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Document {
    asset: Asset,
    scene: Option<usize>,
    #[serde(default)]
    scenes: Vec<SceneJson>,
    #[serde(default)]
    nodes: Vec<Node>,
    #[serde(default)]
    meshes: Vec<MeshJson>,
    #[serde(default)]
    accessors: Vec<Accessor>,
    #[serde(default)]
    buffer_views: Vec<BufferView>,
    #[serde(default)]
    buffers: Vec<Buffer>,
    #[serde(default)]
    materials: Vec<material::MaterialJson>,
    #[serde(default)]
    textures: Vec<material::TextureJson>,
    #[serde(default)]
    samplers: Vec<material::SamplerJson>,
    #[serde(default)]
    images: Vec<image::ImageJson>,
    #[serde(default)]
    cameras: Vec<CameraJson>,
    #[serde(default)]
    extensions_used: Vec<String>,
    #[serde(default)]
    extensions_required: Vec<String>,
    extensions: Option<RootExtensions>,
}

/// The extensions whitted reads; any other in `extensionsRequired` is refused.
const READ_EXTENSIONS: [&str; 5] = [
    "EXT_mesh_gpu_instancing",
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_materials_ior",
    "KHR_materials_transmission",
];

/// The document's `extensions`: the lights of `KHR_lights_punctual`.
#[derive(Debug, Default, Deserialize)]
struct RootExtensions {
    #[serde(rename = "KHR_lights_punctual")]
    lights: Option<LightList>,
}

/// `extensions.KHR_lights_punctual`.
#[derive(Debug, Default, Deserialize)]
struct LightList {
    #[serde(default)]
    lights: Vec<LightJson>,
}

/// `extensions.KHR_lights_punctual.lights[i]`.
#[derive(Debug, Deserialize)]
struct LightJson {
    #[serde(rename = "type")]
    kind: String,
    color: Option<[f32; 3]>,
    intensity: Option<f32>,
}

/// A node's `extensions`: its `KHR_lights_punctual` light and its
/// `EXT_mesh_gpu_instancing` copies of its mesh.
#[derive(Debug, Default, Deserialize)]
struct NodeExtensions {
    #[serde(rename = "KHR_lights_punctual")]
    light: Option<NodeLight>,
    #[serde(rename = "EXT_mesh_gpu_instancing")]
    gpu_instancing: Option<instancing::GpuInstancing>,
}

/// `nodes[i].extensions.KHR_lights_punctual`.
#[derive(Debug, Deserialize)]
struct NodeLight {
    light: usize,
}

/// `asset`: only the version is checked.
#[derive(Debug, Default, Deserialize)]
struct Asset {
    version: String,
}

/// `scenes[i]`: its root nodes.
#[derive(Debug, Deserialize)]
struct SceneJson {
    #[serde(default)]
    nodes: Vec<usize>,
}

/// `nodes[i]`: a transform, children and a mesh.
#[derive(Debug, Deserialize)]
struct Node {
    #[serde(default)]
    children: Vec<usize>,
    mesh: Option<usize>,
    camera: Option<usize>,
    extensions: Option<NodeExtensions>,
    matrix: Option<[f32; 16]>,
    translation: Option<[f32; 3]>,
    rotation: Option<[f32; 4]>,
    scale: Option<[f32; 3]>,
}

/// `cameras[i]`: only perspective cameras are used.
#[derive(Debug, Deserialize)]
struct CameraJson {
    #[serde(rename = "type")]
    kind: String,
    perspective: Option<Perspective>,
}

/// `cameras[i].perspective`: its vertical field of view (the aspect ratio is the image's).
#[derive(Debug, Deserialize)]
struct Perspective {
    yfov: f32,
}

/// `meshes[i]`.
#[derive(Debug, Deserialize)]
struct MeshJson {
    primitives: Vec<Primitive>,
}

/// `meshes[i].primitives[j]` (equal primitives draw the same triangles: meshes whose
/// primitives are all equal are stored once).
#[derive(Debug, Deserialize, PartialEq, Eq, Hash)]
struct Primitive {
    attributes: std::collections::BTreeMap<String, usize>,
    indices: Option<usize>,
    material: Option<usize>,
    #[serde(default = "triangles")]
    mode: u32,
}

/// glTF's default primitive mode, `TRIANGLES`.
fn triangles() -> u32 {
    4
}

/// `accessors[i]`: typed elements in a buffer view.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Accessor {
    buffer_view: Option<usize>,
    #[serde(default)]
    byte_offset: u64,
    component_type: u32,
    #[serde(default)]
    normalized: bool,
    count: u64,
    #[serde(rename = "type")]
    kind: String,
    sparse: Option<serde_json::Value>,
}

/// `bufferViews[i]`: a byte range of a buffer.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct BufferView {
    buffer: usize,
    #[serde(default)]
    byte_offset: u64,
    byte_length: u64,
    byte_stride: Option<u64>,
}

/// `buffers[i]`: bytes in the GLB chunk (no `uri`), a `data:` URI or a file.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Buffer {
    uri: Option<String>,
    byte_length: u64,
}

/// The GLB header's magic, `glTF`.
const GLB_MAGIC: &[u8; 4] = b"glTF";
/// A GLB chunk type: the JSON document.
const CHUNK_JSON: u32 = 0x4E4F_534A;
/// A GLB chunk type: the binary buffer.
const CHUNK_BIN: u32 = 0x004E_4942;

/// The error for the glTF value at `json_path`.
fn at(path: &Path, json_path: &str, msg: impl std::fmt::Display) -> Error {
    Error::parse(path, 0, format!("glTF {json_path}: {msg}"))
}

/// Read and load a glTF or GLB file with its materials ([`parse_gltf_model`]).
pub fn load_gltf_model(path: &Path) -> Result<(Model, Vec<String>)> {
    let bytes = super::read_regular(path)?;
    parse_gltf_model(&bytes, path)
}

/// Parse glTF JSON or GLB bytes into one mesh with its materials; buffers and images named by
/// file are found beside `path`.
pub fn parse_gltf_model(bytes: &[u8], path: &Path) -> Result<(Model, Vec<String>)> {
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    parse_with(bytes, path, &mut |name| {
        let file = dir.join(name);
        super::read_regular(&file)
    })
}

/// [`parse_gltf_model`] as one mesh (every copy of a shared mesh flattened into it, up to
/// the scene's triangle cap), and whether its normals are the file's.
pub fn parse_gltf_detail(
    bytes: &[u8],
    path: &Path,
) -> Result<(crate::mesh::Mesh, Vec<String>, bool)> {
    let (model, w) = parse_gltf_model(bytes, path)?;
    let model = model.flattened(path, crate::io::scene::schema::MAX_SCENE_TRIANGLES)?;
    Ok((model.mesh, w, model.file_normals))
}

/// Reads the file a buffer's `uri` names (relative to the model).
pub type FileReader<'a> = dyn FnMut(&str) -> Result<Vec<u8>> + 'a;

/// [`parse_gltf_model`] with `read_file` reading the files buffers name (the fuzz target
/// gives one that reads nothing).
pub fn parse_with(
    bytes: &[u8],
    path: &Path,
    read_file: &mut FileReader,
) -> Result<(Model, Vec<String>)> {
    let (doc, bin) = document(bytes, path)?;
    let mut warnings = Vec::new();
    if !doc.asset.version.starts_with("2.") {
        return Err(at(
            path,
            "asset.version",
            format!("'{}': only glTF 2.x is read", doc.asset.version),
        ));
    }
    if let Some((i, name)) = doc
        .extensions_required
        .iter()
        .enumerate()
        .find(|(_, e)| !READ_EXTENSIONS.contains(&e.as_str()))
    {
        return Err(at(
            path,
            &format!("extensionsRequired[{i}]"),
            format!("the model requires extension '{name}', which whitted does not read"),
        ));
    }
    let unread: Vec<&str> = doc
        .extensions_used
        .iter()
        .map(String::as_str)
        .filter(|e| !READ_EXTENSIONS.contains(e))
        .collect();
    if !unread.is_empty() {
        warnings.push(format!(
            "{}: glTF extensions not read (the model is drawn without them): {}",
            path.display(),
            unread.join(", ")
        ));
    }
    let buffers = load_buffers(&doc, bin, path, read_file)?;
    let model = mesh::build(&doc, &buffers, path, &mut warnings)?;
    Ok((model, warnings))
}

/// The glTF JSON of a `.gltf` or `.glb` file's bytes, and a GLB's binary chunk.
fn document<'a>(bytes: &'a [u8], path: &Path) -> Result<(Document, Option<&'a [u8]>)> {
    let (json, bin) = if bytes.starts_with(GLB_MAGIC) {
        glb_chunks(bytes, path)?
    } else {
        (bytes, None)
    };
    let doc: Document = serde_json::from_slice(json).map_err(|e| {
        Error::parse(
            path,
            e.line(),
            format!("glTF JSON, column {}: {e}", e.column()),
        )
    })?;
    Ok((doc, bin))
}

/// The JSON and `BIN` chunks of a GLB file, checked against its length.
fn glb_chunks<'a>(bytes: &'a [u8], path: &Path) -> Result<(&'a [u8], Option<&'a [u8]>)> {
    let err = |at: usize, msg: String| Error::parse(path, 0, format!("GLB, byte {at}: {msg}"));
    let u32_at = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes(b.try_into().expect("4 bytes")))
    };
    let version = u32_at(4).ok_or_else(|| err(4, "truncated header (12 bytes)".into()))?;
    if version != 2 {
        return Err(err(4, format!("version {version}; only GLB 2 is read")));
    }
    let length = u32_at(8).ok_or_else(|| err(8, "truncated header (12 bytes)".into()))? as usize;
    if length != bytes.len() {
        return Err(err(
            8,
            format!(
                "the header says {length} bytes, the file has {}",
                bytes.len()
            ),
        ));
    }
    let mut chunks = Vec::new();
    let mut pos = 12;
    while pos < bytes.len() {
        let (Some(len), Some(kind)) = (u32_at(pos), u32_at(pos + 4)) else {
            return Err(err(pos, "truncated chunk header (8 bytes)".into()));
        };
        let start = pos + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                err(
                    pos,
                    format!("chunk of {len} bytes runs past the end of the file"),
                )
            })?;
        chunks.push((kind, &bytes[start..end]));
        pos = end;
    }
    let Some(&(CHUNK_JSON, json)) = chunks.first() else {
        return Err(err(12, "the first chunk is not JSON".into()));
    };
    let bin = chunks.get(1).filter(|c| c.0 == CHUNK_BIN).map(|c| c.1);
    Ok((json, bin))
}

/// Every buffer's bytes, at least `byteLength` of them.
fn load_buffers<'a>(
    doc: &Document,
    bin: Option<&'a [u8]>,
    path: &Path,
    read_file: &mut FileReader,
) -> Result<Vec<std::borrow::Cow<'a, [u8]>>> {
    let mut out = Vec::with_capacity(doc.buffers.len());
    for (i, b) in doc.buffers.iter().enumerate() {
        let key = format!("buffers[{i}]");
        let data: std::borrow::Cow<[u8]> = match &b.uri {
            None => match (i, bin) {
                (0, Some(bin)) => bin.into(),
                _ => {
                    return Err(at(
                        path,
                        &key,
                        "no uri, and not the GLB binary chunk (only buffers[0] of a .glb may be)",
                    ));
                }
            },
            Some(uri) if uri.starts_with("data:") => decode_data_uri(uri)
                .map_err(|m| at(path, &format!("{key}.uri"), m))?
                .into(),
            Some(uri) => {
                let name = percent_decode(uri).map_err(|m| at(path, &format!("{key}.uri"), m))?;
                read_file(&name)
                    .map_err(|e| at(path, &format!("{key}.uri"), format!("'{uri}': {e}")))?
                    .into()
            }
        };
        if (data.len() as u64) < b.byte_length {
            return Err(at(
                path,
                &format!("{key}.byteLength"),
                format!(
                    "{} bytes, but the buffer holds {}",
                    b.byte_length,
                    data.len()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The bytes of a base64 `data:` URI.
fn decode_data_uri(uri: &str) -> std::result::Result<Vec<u8>, String> {
    let (head, data) = uri
        .split_once(',')
        .ok_or("a data URI needs a ',' before its data")?;
    if !head.ends_with(";base64") {
        return Err("only base64 data URIs are read".into());
    }
    base64(data.trim())
}

/// Standard base64 (`A-Z a-z 0-9 + /`, `=` padding), strictly.
fn base64(text: &str) -> std::result::Result<Vec<u8>, String> {
    let digit = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let body = text.trim_end_matches('=');
    if text.len() - body.len() > 2 || body.len() % 4 == 1 {
        return Err("malformed base64 (bad length or padding)".into());
    }
    let mut out = Vec::with_capacity(body.len() / 4 * 3 + 2);
    for (k, chunk) in body.as_bytes().chunks(4).enumerate() {
        let mut acc = 0u32;
        for (j, &c) in chunk.iter().enumerate() {
            let d = digit(c)
                .ok_or_else(|| format!("malformed base64: '{}' at {}", c as char, k * 4 + j))?;
            acc |= d << (18 - 6 * j);
        }
        let bytes = acc.to_be_bytes();
        out.extend_from_slice(&bytes[1..chunk.len()]);
    }
    Ok(out)
}

/// A relative URI's `%XX` escapes decoded (`my%20model.bin`); absolute and parent paths are
/// refused, so a model reads only files beside it and under its folder.
fn percent_decode(uri: &str) -> std::result::Result<String, String> {
    let mut out = Vec::with_capacity(uri.len());
    let b = uri.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = uri
                .get(i + 1..i + 3)
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("'{uri}': malformed %-escape"))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    let name = String::from_utf8(out).map_err(|_| format!("'{uri}': not UTF-8"))?;
    let p = Path::new(&name);
    if p.is_absolute() || name.contains(':') || p.components().any(|c| c.as_os_str() == "..") {
        return Err(format!(
            "'{uri}': only files beside the model or below its folder are read"
        ));
    }
    Ok(name)
}
