//! The scene's materials: each `[[material]]` validated with its texture loaded once per
//! file, and the materials a mesh file brings mapped onto scene materials.

use super::build::{Builder, nonneg, nonneg3, referenced};
use super::schema::{Coef, DEFAULT_COLOR, DEFAULT_MATERIAL, MaterialDesc, default_material};
use crate::error::{Error, Result};
use crate::io::image::load_texture;
use crate::io::model::{Model, NO_MATERIAL};
use crate::scene::{Albedo, Material};
use crate::texture::Texture;
use glam::Vec3;
use std::sync::Arc;

impl Builder<'_> {
    /// Validate one material description and load its texture (one load per file).
    pub(super) fn build_material(
        &mut self,
        m: &MaterialDesc,
        prefix: &str,
        refer: &dyn Fn(Error) -> Error,
    ) -> Result<Material> {
        let (path, search) = (self.path, self.search);
        let key = |k: &str| format!("{prefix}.{k}");
        // `color` beside `vertex_color` colours the vertices a mesh gives no rgb.
        let sources = (m.color.is_some() && !m.vertex_color) as u32
            + m.vertex_color as u32
            + m.texture.is_some() as u32
            + m.checker.is_some() as u32;
        if sources > 1 {
            return Err(Error::scene(
                path,
                format!(
                    "{}: give exactly one of color, vertex_color (with an optional color for vertices without rgb), texture, checker",
                    key("color")
                ),
            ));
        }
        // No source at all: the default material's grey.
        let color = match (m.color, sources) {
            (None, 0) => Some(Vec3::splat(DEFAULT_COLOR)),
            (c, _) => c.map(|c| nonneg3(c, &key("color"), path)).transpose()?,
        };
        if m.wrap.is_some() && m.texture.is_none() && m.checker.is_none() {
            return Err(Error::scene(
                path,
                format!(
                    "{}: applies to a texture or checker, and this material has neither",
                    key("wrap")
                ),
            ));
        }
        let wrap = m.wrap.unwrap_or_default();
        let albedo = if m.vertex_color {
            Albedo::VertexColor
        } else if let Some(col) = color {
            Albedo::Color(col)
        } else if let Some(t) = &m.texture {
            // An image file, or an image inside a glTF file (`model.glb#images[0]`).
            let (found, image) = match crate::io::gltf::image_ref(t) {
                Some((file, i)) => {
                    let found = search.resolve(file).map_err(refer)?;
                    let key = format!("{}#images[{i}]", found.display());
                    (std::path::PathBuf::from(key), Some((found, i)))
                }
                None => (search.resolve(t).map_err(refer)?, None),
            };
            // One load per image and wrap mode.
            match self
                .textures
                .iter()
                .find(|(p, tex)| *p == found && tex.wrap == wrap)
            {
                Some((_, tex)) => Albedo::Texture(tex.clone()),
                None => {
                    let tex = match image {
                        Some((file, i)) => crate::io::gltf::load_image(&file, i),
                        None => load_texture(&found),
                    };
                    let tex = Arc::new(tex.map_err(refer)?.with_wrap(wrap));
                    self.textures.push((found, tex.clone()));
                    Albedo::Texture(tex)
                }
            }
        } else {
            let ch = m.checker.as_ref().expect("one source");
            if !(1..=4096).contains(&ch.squares) {
                return Err(Error::scene(
                    path,
                    format!("{}: squares must be in 1..=4096", key("checker")),
                ));
            }
            let size = (ch.squares as usize * 16).min(4096);
            Albedo::Texture(Arc::new(
                Texture::checker(
                    size,
                    ch.squares as usize,
                    nonneg3(ch.a, &key("checker.a"), path)?,
                    nonneg3(ch.b, &key("checker.b"), path)?,
                )
                .with_wrap(wrap),
            ))
        };
        let ior = m.ior;
        if !(ior.is_finite() && ior > 0.0) {
            return Err(Error::scene(
                path,
                format!("{}: must be a finite number > 0, found {ior}", key("ior")),
            ));
        }
        let coef = |c: Coef, k: &str| match c {
            Coef::Scalar(v) => nonneg(v, &key(k), path).map(Vec3::splat),
            Coef::Rgb(v) => nonneg3(v, &key(k), path),
        };
        let ks = coef(m.ks, "ks")?;
        let ke = coef(m.ke, "ke")?;
        Ok(Material {
            name: m.name.clone(),
            albedo,
            ka: coef(m.ka, "ka")?,
            kd: coef(m.kd, "kd")?,
            ks,
            n: nonneg(m.n, &key("n"), path)?,
            kt: coef(m.kt, "kt")?,
            ior,
            kr: m.kr.map_or(Ok(ks), |c| coef(c, "kr"))?,
            ke,
            lamp: m.lamp && ke.max_element() > 0.0,
        })
    }

    /// Scene materials for a mesh file's own materials: a scene material of the same name if
    /// there is one, else the file's (validated and added to the scene); faces without one get
    /// [`DEFAULT_MATERIAL`] (or its vertex-colour twin when the mesh has colours). Returns the
    /// material of the whole mesh, or a material per triangle.
    pub(super) fn file_materials(
        &mut self,
        model: &Model,
        name: &str,
        i: usize,
    ) -> Result<(usize, Option<Vec<u32>>)> {
        let (file, path) = (self.file, self.path);
        let index_of = |desc: &MaterialDesc, b: &mut Self| -> Result<u32> {
            if let Some(k) = b.materials.iter().position(|m| m.name == desc.name) {
                return Ok(k as u32);
            }
            let prefix = format!("mesh '{name}' material '{}'", desc.name);
            // A texture of the file's materials is named by the mesh entry's file.
            let refer = |e| {
                let toml_key = format!("mesh[{i}].file");
                referenced(file, path, &toml_key, Some(format!("{prefix}.texture")), e)
            };
            let material = b.build_material(desc, &prefix, &refer)?;
            b.materials.push(material);
            Ok(b.materials.len() as u32 - 1)
        };
        let colors = model.mesh.colors.is_some();
        let mut default = default_material(colors);
        if colors {
            default.name = format!("{DEFAULT_MATERIAL}_vertex_color");
        }
        let Some(faces) = &model.face_materials else {
            return Ok((index_of(&default, self)? as usize, None));
        };
        let mut map = Vec::with_capacity(model.materials.len());
        for desc in &model.materials {
            map.push(index_of(desc, self)?);
        }
        let mut fallback = None;
        let mut out = Vec::with_capacity(faces.len());
        for &f in faces {
            out.push(if f == NO_MATERIAL {
                match fallback {
                    Some(k) => k,
                    None => *fallback.insert(index_of(&default, self)?),
                }
            } else {
                map[f as usize]
            });
        }
        Ok((out.first().copied().unwrap_or(0) as usize, Some(out)))
    }
}
