//! What every mesh loader returns: a mesh with the materials its file brings.
//!
//! The loaders (`.m`, OBJ with MTL, PLY, STL, glTF) fill a [`Model`]; the scene builder
//! ([`crate::io::scene`]), `whitted info` and the scene of a mesh rendered alone read it. It
//! depends on the scene schema only for [`MaterialDesc`], [`CameraDesc`] and [`LightDesc`], so
//! loaders need nothing of the builder.

use crate::io::mtl::MtlInfo;
use crate::io::scene::schema::{CameraDesc, LightDesc, MaterialDesc};
use crate::mesh::Mesh;

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
}

/// A triangle whose face group named no (known) material.
pub const NO_MATERIAL: u32 = u32::MAX;
