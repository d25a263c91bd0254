//! The scene's meshes: each `[[mesh]]` entry read from its file (once per file), copied from
//! its inline triangles or generated, checked against the scene's triangle caps before it is
//! made.

use super::build::{Builder, finite3, referenced};
use super::schema::{MAX_SCENE_TRIANGLES, MAX_SUBDIVIDE, MAX_SUBDIVIDED_TRIANGLES, MeshDesc};
use crate::error::{Error, Result};
use crate::io::load_scene_model;
use crate::io::model::Model;
use crate::mesh::Mesh;
use crate::scene::shapes;
use glam::Vec3;
use std::path::Path;

/// Segments of a generated `shape = "sphere"` (its triangle count is
/// [`shapes::sphere_triangle_count`] of this).
pub const SPHERE_SEGMENTS: u32 = 48;

/// Triangles an inline or generated mesh entry will have before subdivision, known from its
/// parameters; `None` for files (known once read) and for entries that are not valid (their
/// error comes when they are built).
pub(super) fn planned_triangles(d: &MeshDesc) -> Option<u64> {
    if d.file.is_some() {
        return None;
    }
    match (&d.faces, d.shape.as_deref()) {
        (Some(f), None) => Some(f.len() as u64),
        (None, Some("sphere")) => Some(shapes::sphere_triangle_count(SPHERE_SEGMENTS)),
        (None, Some("cube")) => Some(12),
        (None, Some("quad")) => Some(2),
        _ => None,
    }
}

/// Whether mesh entry `i` with `n` triangles (before its subdivision) fits the caps, given the
/// scene's totals so far; returns the triangles it will make.
pub(super) fn check_caps(
    i: usize,
    d: &MeshDesc,
    n: u64,
    total: u64,
    subdivided: u64,
    path: &Path,
) -> Result<u64> {
    let key = |k: &str| format!("mesh[{i}].{k}");
    if d.subdivide > MAX_SUBDIVIDE {
        return Err(Error::scene(
            path,
            format!(
                "{}: {} is over the cap of {MAX_SUBDIVIDE}",
                key("subdivide"),
                d.subdivide
            ),
        ));
    }
    let made = n.saturating_mul(1 << (2 * d.subdivide));
    if d.subdivide > 0 && subdivided.saturating_add(made) > MAX_SUBDIVIDED_TRIANGLES {
        return Err(Error::scene(
            path,
            format!(
                "{}: {} levels would make {made} triangles, over the scene's cap of {MAX_SUBDIVIDED_TRIANGLES} made by subdivision",
                key("subdivide"),
                d.subdivide
            ),
        ));
    }
    if total.saturating_add(made) > MAX_SCENE_TRIANGLES {
        return Err(Error::scene(
            path,
            format!(
                "mesh[{i}]: the scene's meshes add up to over {MAX_SCENE_TRIANGLES} triangles (the cap) with this one's {made}"
            ),
        ));
    }
    Ok(made)
}

impl Builder<'_> {
    /// Whether entry `i` with `n` triangles (before its subdivision) fits the caps, given
    /// the meshes made so far; called before its mesh is copied or generated.
    pub(super) fn caps(&self, i: usize, d: &MeshDesc, n: u64) -> Result<u64> {
        check_caps(
            i,
            d,
            n,
            self.total_triangles,
            self.subdivided_total,
            self.path,
        )
    }

    /// The mesh of entry `i`, its name and the vertices its file gave no rgb.
    pub(super) fn mesh_of(&mut self, d: &MeshDesc, i: usize) -> Result<(Model, String, Vec<u32>)> {
        let path = self.path;
        let key = |k: &str| format!("mesh[{i}].{k}");
        let sources =
            d.file.is_some() as u32 + d.vertices.is_some() as u32 + d.shape.is_some() as u32;
        if sources != 1 {
            return Err(Error::scene(
                path,
                format!(
                    "{}: give exactly one of file, vertices + faces, shape",
                    key("file")
                ),
            ));
        }
        if d.faces.is_some() && d.vertices.is_none() {
            return Err(Error::scene(
                path,
                format!("{}: faces need inline vertices", key("faces")),
            ));
        }
        if let Some(f) = &d.file {
            let (model, missing) = self.file_mesh(d, i, f)?;
            let name = d.name.clone().unwrap_or_else(|| f.clone());
            return Ok((model, name, missing));
        }
        let name = d.name.clone().unwrap_or_else(|| format!("mesh{i}"));
        let center = finite3(d.center.unwrap_or([0.0; 3]), &key("center"), path)?;
        let mesh = match &d.vertices {
            Some(verts) => self.inline_mesh(d, i, verts)?,
            None => self.shape_mesh(d, i, center)?,
        };
        Ok((Model::plain(mesh), name, Vec::new()))
    }

    /// The model of entry `i`'s file `f` (read on its first use) and the vertices it gave no
    /// rgb.
    fn file_mesh(&mut self, d: &MeshDesc, i: usize, f: &str) -> Result<(Model, Vec<u32>)> {
        let refer = |e| referenced(self.file, self.path, &format!("mesh[{i}].file"), None, e);
        let found = self.search.resolve(f).map_err(refer)?;
        let k = match self.loaded.iter().position(|(p, ..)| *p == found) {
            Some(k) => k,
            None => {
                let (model, w, missing) = load_scene_model(&found).map_err(refer)?;
                self.warnings.extend(w);
                self.loaded.push((found, model, missing));
                self.loaded.len() - 1
            }
        };
        self.caps(i, d, self.loaded[k].1.mesh.triangles.len() as u64)?;
        let (_, model, missing) = &self.loaded[k];
        Ok((model.clone(), missing.clone()))
    }

    /// Entry `i`'s inline `vertices` + `faces`: finite vertices, indices in range.
    fn inline_mesh(&self, d: &MeshDesc, i: usize, verts: &[[f32; 3]]) -> Result<Mesh> {
        let path = self.path;
        let faces = d.faces.as_ref().ok_or_else(|| {
            Error::scene(path, format!("mesh[{i}].faces: inline vertices need faces"))
        })?;
        let positions = verts
            .iter()
            .enumerate()
            .map(|(k, v)| finite3(*v, &format!("mesh[{i}].vertices[{k}]"), path))
            .collect::<Result<Vec<_>>>()?;
        if let Some((k, _)) = faces
            .iter()
            .enumerate()
            .find(|(_, f)| f.iter().any(|&v| v as usize >= positions.len()))
        {
            return Err(Error::scene(
                path,
                format!(
                    "mesh[{i}].faces[{k}]: vertex index out of range (0..{})",
                    positions.len()
                ),
            ));
        }
        if faces.is_empty() {
            return Err(Error::scene(path, format!("mesh[{i}].faces: no faces")));
        }
        self.caps(i, d, faces.len() as u64)?;
        let mut mesh = Mesh {
            positions,
            triangles: faces.clone(),
            ..Default::default()
        };
        mesh.ensure_normals();
        Ok(mesh)
    }

    /// Entry `i`'s generated `shape` at `center`.
    fn shape_mesh(&self, d: &MeshDesc, i: usize, center: Vec3) -> Result<Mesh> {
        let path = self.path;
        let key = |k: &str| format!("mesh[{i}].{k}");
        let shape = d.shape.as_deref().unwrap_or_default();
        let size = finite3(d.size.unwrap_or([1.0; 3]), &key("size"), path)?;
        let radius = d.radius.unwrap_or(1.0);
        if shape == "sphere" && !(radius.is_finite() && radius > 0.0) {
            return Err(Error::scene(
                path,
                format!("{}: must be > 0", key("radius")),
            ));
        }
        let Some(n) = planned_triangles(d) else {
            return Err(Error::scene(
                path,
                format!(
                    "{}: unknown shape '{shape}' (sphere, cube, quad)",
                    key("shape")
                ),
            ));
        };
        self.caps(i, d, n)?;
        let mut mesh = match shape {
            "sphere" => shapes::sphere(center, radius, SPHERE_SEGMENTS),
            "cube" => shapes::cube(center, size * 0.5),
            _ => shapes::quad(center, Vec3::X * size.x * 0.5, Vec3::NEG_Z * size.z * 0.5),
        };
        debug_assert_eq!(mesh.triangles.len() as u64, n, "planned_triangles is exact");
        // A zero size makes the shape's own normals 0/0: fall back to the geometric normals.
        mesh.ensure_normals();
        Ok(mesh)
    }
}
