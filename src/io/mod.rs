//! Reading and writing files: meshes (`.m`, `.obj`), scenes (TOML), images.

pub mod image;
pub mod mfile;
pub mod obj;
pub mod rays;
pub mod scene_file;

use crate::error::{Error, Result};
use crate::mesh::Mesh;
use std::path::Path;

/// Load a mesh by extension (`.m` or `.obj`); warnings are returned beside it.
pub fn load_mesh(path: &Path) -> Result<(Mesh, Vec<String>)> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("m") => mfile::load_m(path),
        Some("obj") => obj::load_obj(path),
        _ => Err(Error::parse(
            path,
            0,
            "unknown mesh format (use .m or .obj)",
        )),
    }
}
