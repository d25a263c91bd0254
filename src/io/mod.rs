//! Reading and writing files: meshes (`.m`, `.obj`, `.ply`, `.stl`, `.gltf`, `.glb`), scenes
//! (TOML), images.

pub mod aov;
pub mod fuzz;
pub mod gltf;
pub mod image;
pub mod merge;
pub mod mesh_scene;
pub mod mfile;
pub mod model;
pub mod mtl;
pub mod obj;
pub mod output;
pub mod ply;
pub mod rays;
pub mod scene;
pub mod stl;

use crate::error::{Error, Result};
use crate::io::model::Model;
use crate::mesh::Mesh;
use std::path::{Path, PathBuf};

/// Largest file any loader reads (mesh, texture, scene): 4 GiB, checked before reading.
pub const MAX_FILE_BYTES: u64 = 1 << 32;

/// Mesh file extensions the loaders read, in lower case (a mesh's format is its extension).
pub const MESH_EXTENSIONS: [&str; 6] = ["m", "obj", "ply", "stl", "gltf", "glb"];

/// Check that `path` is a regular file under [`MAX_FILE_BYTES`], without reading it: folders,
/// devices and FIFOs (`/dev/zero` would never end) are refused.
pub fn check_regular(path: &Path) -> Result<()> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if meta.is_dir() {
        return Err(Error::Usage(format!(
            "{}: is a folder, not a regular file",
            path.display()
        )));
    }
    if !meta.is_file() {
        return Err(Error::Usage(format!(
            "{}: not a regular file (a device, FIFO or socket)",
            path.display()
        )));
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(Error::Usage(format!(
            "{}: {} bytes is over the cap of {MAX_FILE_BYTES}",
            path.display(),
            meta.len()
        )));
    }
    Ok(())
}

/// Read a whole regular file, after [`check_regular`].
pub fn read_regular(path: &Path) -> Result<Vec<u8>> {
    check_regular(path)?;
    std::fs::read(path).map_err(|e| Error::io(path, e))
}

/// Load a mesh with the materials its file brings (OBJ: `mtllib`; glTF: `materials`), by
/// extension.
pub fn load_model(path: &Path) -> Result<(Model, Vec<String>)> {
    match extension(path).as_str() {
        "obj" => obj::load_obj_model(path),
        "gltf" | "glb" => {
            check_regular(path)?;
            gltf::load_gltf_model(path)
        }
        _ => load_mesh(path).map(|(mesh, w)| (Model::plain(mesh), w)),
    }
}

/// Load a mesh by extension (`.m`, `.obj`, `.ply`, `.stl`, `.gltf` or `.glb`); warnings are
/// returned beside it.
pub fn load_mesh(path: &Path) -> Result<(Mesh, Vec<String>)> {
    load_mesh_detail(path).map(|(m, w, _)| (m, w))
}

/// [`load_mesh`], also telling whether the file gave vertex normals (otherwise computed).
pub fn load_mesh_detail(path: &Path) -> Result<(Mesh, Vec<String>, bool)> {
    // A folder or device is named as such before its extension is looked at.
    check_regular(path)?;
    let parse = match extension(path).as_str() {
        "m" => mfile::parse_m_detail,
        "obj" => obj::parse_obj_detail,
        "ply" => ply::parse_ply_detail,
        "stl" => stl::parse_stl_detail,
        "gltf" | "glb" => gltf::parse_gltf_detail,
        _ => return Err(unknown_mesh_type(path)),
    };
    parse(&read_regular(path)?, path)
}

/// A mesh for a scene: [`load_mesh`], also listing the vertices whose `rgb` the file left out
/// where others have one (see [`mfile::MRead::missing_rgb`]); the scene colours them.
pub fn load_scene_mesh(path: &Path) -> Result<(Mesh, Vec<String>, Vec<u32>)> {
    if extension(path) == "m" {
        let r = mfile::read_m(&read_regular(path)?, path)?;
        return Ok((r.mesh, r.warnings, r.missing_rgb));
    }
    load_mesh(path).map(|(m, w)| (m, w, Vec::new()))
}

/// [`load_model`] for a scene: also the vertices a `.m` file left without `rgb` where others
/// have one (see [`load_scene_mesh`]).
pub fn load_scene_model(path: &Path) -> Result<(Model, Vec<String>, Vec<u32>)> {
    match extension(path).as_str() {
        "obj" => obj::load_obj_model(path).map(|(m, w)| (m, w, Vec::new())),
        "gltf" | "glb" => load_model(path).map(|(m, w)| (m, w, Vec::new())),
        "m" => {
            let r = mfile::read_m(&read_regular(path)?, path)?;
            let model = Model {
                file_normals: r.file_normals,
                ..Model::plain(r.mesh)
            };
            Ok((model, r.warnings, r.missing_rgb))
        }
        _ => load_mesh_detail(path).map(|(mesh, w, file_normals)| {
            let model = Model {
                file_normals,
                ..Model::plain(mesh)
            };
            (model, w, Vec::new())
        }),
    }
}

/// The error for a mesh whose extension no loader reads; it lists the ones they do.
pub fn unknown_mesh_type(path: &Path) -> Error {
    let ext = extension(path);
    Error::Format {
        path: path.to_path_buf(),
        msg: format!(
            "{}; mesh files are {}",
            if ext.is_empty() {
                "no extension to tell the mesh format".to_string()
            } else {
                format!("unknown mesh format '.{ext}'")
            },
            list_extensions(&MESH_EXTENSIONS)
        ),
    }
}

/// `.m, .obj`: extensions as a user types them.
pub fn list_extensions(exts: &[&str]) -> String {
    exts.iter()
        .map(|e| format!(".{e}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The number of the file's last line (1 for an empty file; a final newline ends the last
/// line rather than starting one): where an error about what the whole file lacks points,
/// as a compiler points at the end of the file.
pub(crate) fn last_line(bytes: &[u8]) -> usize {
    let newlines = bytes.iter().filter(|&&b| b == b'\n').count();
    if bytes.last().is_none_or(|&b| b == b'\n') {
        newlines.max(1)
    } else {
        newlines + 1
    }
}

/// One line of an OBJ-family text file (OBJ, MTL) as the parsers read it: without its `\r`
/// and its comment (from `#` to the end, which may hold any bytes), trimmed; a NUL byte or
/// invalid UTF-8 outside the comment is an error naming the file and line (`what` names
/// the format in it).
pub(crate) fn text_line<'a>(
    raw: &'a [u8],
    path: &Path,
    line: usize,
    what: &str,
) -> Result<&'a str> {
    let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
    let raw = match raw.iter().position(|&b| b == b'#') {
        Some(h) => &raw[..h],
        None => raw,
    };
    if raw.contains(&0) {
        return Err(Error::parse(
            path,
            line,
            format!("binary data (NUL byte); not {what} text file"),
        ));
    }
    std::str::from_utf8(raw).map(str::trim).map_err(|_| {
        Error::parse(
            path,
            line,
            format!("invalid UTF-8 outside a comment; not {what} text file"),
        )
    })
}

/// What every mesh loader does last: vertex normals where the file gave none (area-weighted)
/// and one warning counting the zero-area faces.
pub(crate) fn finish_mesh(mesh: &mut Mesh, path: &Path, warnings: &mut Vec<String>) {
    mesh.ensure_normals();
    let degenerate = mesh.degenerate_count();
    if degenerate > 0 {
        warnings.push(format!(
            "{}: {degenerate} degenerate (zero-area) faces; they are never hit",
            path.display()
        ));
    }
}

/// `dir/name` if it exists.
pub(crate) fn find_beside(dir: &Path, name: &str) -> Option<PathBuf> {
    let p = dir.join(name);
    p.is_file().then_some(p)
}

/// A folder for messages: `.` for the empty path of a file named without one.
pub(crate) fn display_dir(dir: &Path) -> String {
    if dir.as_os_str().is_empty() {
        ".".into()
    } else {
        dir.display().to_string()
    }
}

/// A file's extension in lower case (`""` when it has none): how every loader picks a format.
pub fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

#[cfg(test)]
mod tests {
    /// The last line's number, with and without a final newline.
    #[test]
    fn last_line_counts_like_an_editor() {
        assert_eq!(super::last_line(b""), 1);
        assert_eq!(super::last_line(b"a"), 1);
        assert_eq!(super::last_line(b"a\n"), 1);
        assert_eq!(super::last_line(b"a\nb"), 2);
        assert_eq!(super::last_line(b"a\nb\n"), 2);
        assert_eq!(super::last_line(b"a\n\n"), 2);
    }
}
