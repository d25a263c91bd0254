//! Reading and writing files: meshes (`.m`, `.obj`), scenes (TOML), images.

pub mod aov;
pub mod fuzz;
pub mod image;
pub mod mesh_scene;
pub mod mfile;
pub mod mtl;
pub mod obj;
pub mod ply;
pub mod rays;
pub mod scene_file;

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use std::path::Path;

/// Largest file any loader reads (mesh, texture, scene): 4 GiB, checked before reading.
pub const MAX_FILE_BYTES: u64 = 1 << 32;

/// Read a whole regular file. Devices, FIFOs and folders are refused before anything is read
/// (`/dev/zero` would never end), and so is a file over [`MAX_FILE_BYTES`].
pub fn read_regular(path: &Path) -> Result<Vec<u8>> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        return Err(Error::Usage(format!(
            "{}: not a regular file",
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
    std::fs::read(path).map_err(|e| Error::io(path, e))
}

/// Load a mesh with the materials its file brings (OBJ: `mtllib`), by extension.
pub fn load_model(path: &Path) -> Result<(obj::Model, Vec<String>)> {
    match extension(path).as_str() {
        "obj" => obj::load_obj_model(path),
        _ => load_mesh(path).map(|(mesh, w)| {
            (
                obj::Model {
                    mesh,
                    ..Default::default()
                },
                w,
            )
        }),
    }
}

/// The mesh formats [`load_mesh`] reads, by extension.
pub const MESH_EXTENSIONS: [&str; 3] = ["m", "obj", "ply"];

/// Load a mesh by extension (`.m`, `.obj` or `.ply`); warnings are returned beside it.
pub fn load_mesh(path: &Path) -> Result<(Mesh, Vec<String>)> {
    load_mesh_detail(path).map(|(m, w, _)| (m, w))
}

/// [`load_mesh`], also telling whether the file gave vertex normals (otherwise computed).
pub fn load_mesh_detail(path: &Path) -> Result<(Mesh, Vec<String>, bool)> {
    let parse = match extension(path).as_str() {
        "m" => mfile::parse_m_detail,
        "obj" => obj::parse_obj_detail,
        "ply" => ply::parse_ply_detail,
        _ => {
            return Err(Error::parse(
                path,
                0,
                "unknown mesh format (use .m, .obj or .ply)",
            ));
        }
    };
    parse(&read_regular(path)?, path)
}

/// A file's extension in lower case (`""` when it has none): how every loader picks a format.
pub fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}
