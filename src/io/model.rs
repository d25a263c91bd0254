//! What every mesh loader returns: a mesh with the materials its file brings.
//!
//! The loaders (`.m`, OBJ with MTL, PLY, STL, glTF) fill a [`Model`]; the scene builder
//! ([`crate::io::scene`]), `whitted info` and the scene of a mesh rendered alone read it. It
//! depends on the scene schema only for [`MaterialDesc`], [`CameraDesc`] and [`LightDesc`], so
//! loaders need nothing of the builder.

use crate::error::{Error, Result};
use crate::io::mtl::MtlInfo;
use crate::io::scene::schema::{CameraDesc, LightDesc, MaterialDesc};
use crate::mesh::Mesh;
use glam::{Affine3A, Vec3};
use std::path::Path;

/// A mesh with the materials its file brings.
#[derive(Clone, Debug, Default)]
pub struct Model {
    /// Its triangles.
    pub mesh: Mesh,
    /// Materials of the file (MTL), already mapped onto whitted's terms.
    pub materials: Vec<MaterialDesc>,
    /// What each MTL material said and which textures were found (for `whitted info`).
    pub material_info: Vec<MtlInfo>,
    /// Per triangle, an index into `materials`, or [`NO_MATERIAL`] (`None`: no face has one).
    pub face_materials: Option<Vec<u32>>,
    /// Whether the mesh's normals are the file's own (a scene's `smooth = true` keeps them);
    /// otherwise the loader made them as the format means (flat, smoothing groups, or
    /// averaged for `.m`).
    pub file_normals: bool,
    /// The file's own view (glTF: its first perspective camera), used when the model is
    /// rendered alone instead of framing it.
    pub camera: Option<CameraDesc>,
    /// The file's own point lights (glTF `KHR_lights_punctual`), used when the model is
    /// rendered alone instead of the canonical lights.
    pub lights: Vec<LightDesc>,
    /// Meshes stored once and placed several times (a glTF mesh drawn by several nodes, or
    /// by a node with `EXT_mesh_gpu_instancing`); `mesh` holds the rest, flattened.
    pub shared: Vec<Shared>,
}

/// A mesh of a model stored once, in its own space, and where it is drawn.
#[derive(Clone, Debug, Default)]
pub struct Shared {
    /// Its name in messages and `whitted info` (`model.glb#meshes[2]`, or the file's name
    /// for it).
    pub name: String,
    /// The mesh with its per-face materials (indices into the owning model's `materials`,
    /// which it repeats); its `camera`, `lights` and `shared` are empty.
    pub model: Model,
    /// Object to world, one per copy drawn (finite and invertible: the loader checks).
    pub placements: Vec<Affine3A>,
}

impl Model {
    /// A model of a mesh alone (a file format without materials, or a generated shape), its
    /// normals not the file's.
    pub fn plain(mesh: Mesh) -> Model {
        Model {
            mesh,
            ..Default::default()
        }
    }

    /// The box of everything the model draws: `mesh`, and every placement of each shared
    /// mesh (its box's corners carried through the placement).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let placed = self.shared.iter().flat_map(|s| {
            let b = s.model.mesh.bounds();
            s.placements
                .iter()
                .filter_map(move |m| b.map(|b| placed_box(b, m)))
        });
        self.mesh
            .bounds()
            .into_iter()
            .chain(placed)
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    /// Triangles drawn: `mesh`'s and every placement's.
    pub fn drawn_triangles(&self) -> u64 {
        let shared = self
            .shared
            .iter()
            .map(|s| s.model.mesh.triangles.len() as u64 * s.placements.len() as u64);
        self.mesh.triangles.len() as u64 + shared.sum::<u64>()
    }

    /// The model as one mesh: every placement of the shared meshes copied into `mesh`
    /// (for the callers that want one triangle list). More than `cap` triangles drawn is an
    /// error naming `path`, checked before anything is copied.
    pub fn flattened(mut self, path: &Path, cap: u64) -> Result<Model> {
        let drawn = self.drawn_triangles();
        if drawn > cap {
            return Err(Error::parse(
                path,
                0,
                format!(
                    "its instances draw {drawn} triangles; flattened into one mesh that is over the cap of {cap}"
                ),
            ));
        }
        let own = self.mesh.triangles.len();
        let mut faces = self.face_materials.take();
        for s in std::mem::take(&mut self.shared) {
            for m in &s.placements {
                let n = s.model.mesh.triangles.len();
                if faces.is_some() || s.model.face_materials.is_some() {
                    let f = faces.get_or_insert_with(|| vec![NO_MATERIAL; own]);
                    match &s.model.face_materials {
                        Some(g) => f.extend_from_slice(g),
                        None => f.extend(std::iter::repeat_n(NO_MATERIAL, n)),
                    }
                }
                self.mesh.append(&s.model.mesh.transformed(m));
                self.file_normals &= s.model.file_normals;
            }
        }
        self.face_materials = faces;
        Ok(self)
    }
}

/// The box `(lo, hi)` carried through `m`: the box of its 8 corners.
pub fn placed_box((lo, hi): (Vec3, Vec3), m: &Affine3A) -> (Vec3, Vec3) {
    (0..8)
        .map(|k| {
            m.transform_point3(Vec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ))
        })
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), p| {
            (a.min(p), b.max(p))
        })
}

/// A triangle whose face group named no (known) material.
pub const NO_MATERIAL: u32 = u32::MAX;
