//! A glTF document's `materials` in whitted's terms (the table is in docs/formats.md,
//! "glTF").

use super::{Document, at};
use crate::error::Result;
use crate::io::scene::schema::{Coef, MaterialDesc, default_material};
use std::path::Path;

/// `materials` in whitted's terms: the default material's coefficients with `Od` from
/// `baseColorFactor` (linear RGB, alpha dropped) or a `baseColorTexture` in an image file
/// (the factor is then not applied: a material has one colour source), and `ke` from
/// `emissiveFactor`.
pub(super) fn materials(
    doc: &Document,
    path: &Path,
    has_uv: bool,
    vertex_colors: bool,
    warnings: &mut Vec<String>,
) -> Result<Vec<MaterialDesc>> {
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut out: Vec<MaterialDesc> = Vec::with_capacity(doc.materials.len());
    for (i, m) in doc.materials.iter().enumerate() {
        let key = format!("materials[{i}]");
        let mut desc = default_material(vertex_colors);
        // Names must be unique in a scene: a missing or repeated name gets the index.
        desc.name = match &m.name {
            Some(n) if !n.is_empty() && !out.iter().any(|d| &d.name == n) => n.clone(),
            Some(n) if !n.is_empty() => format!("{n} #{i}"),
            _ => format!("material{i}"),
        };
        let pbr = m.pbr_metallic_roughness.as_ref();
        let factor = pbr.and_then(|p| p.base_color_factor).unwrap_or([1.0; 4]);
        if !factor.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(at(
                path,
                &format!("{key}.pbrMetallicRoughness.baseColorFactor"),
                "components must be finite and >= 0",
            ));
        }
        if !vertex_colors {
            desc.color = Some([factor[0], factor[1], factor[2]]);
        }
        if let Some(t) = pbr.and_then(|p| p.base_color_texture.as_ref()) {
            let tkey = format!("{key}.pbrMetallicRoughness.baseColorTexture");
            let image = doc
                .textures
                .get(t.index)
                .ok_or_else(|| {
                    at(
                        path,
                        &format!("{tkey}.index"),
                        format!("no texture {}", t.index),
                    )
                })?
                .source
                .and_then(|s| doc.images.get(s));
            let file = image
                .and_then(|im| im.uri.as_deref())
                .filter(|u| !u.starts_with("data:"));
            match (file, has_uv && t.tex_coord == 0) {
                (Some(uri), true) => {
                    let name = super::percent_decode(uri).map_err(|e| at(path, &tkey, e))?;
                    let f = dir.join(name);
                    // Absolute, so a scene finds it whatever folders its search path holds.
                    desc.texture = Some(std::path::absolute(&f).unwrap_or(f).to_string_lossy().into_owned());
                    desc.color = None;
                    desc.vertex_color = false;
                }
                _ => warnings.push(format!(
                    "{}: glTF {tkey}: only image files read through TEXCOORD_0 are used (not embedded images); material '{}' uses its baseColorFactor",
                    path.display(),
                    desc.name
                )),
            }
        }
        // Emission, as MTL's Ke: shown on the surface, and lighting the scene through point
        // lights of its own (see `scene::emitter_lights`).
        if let Some(e) = m.emissive_factor {
            if !e.iter().all(|c| c.is_finite() && *c >= 0.0) {
                return Err(at(
                    path,
                    &format!("{key}.emissiveFactor"),
                    "components must be finite and >= 0",
                ));
            }
            desc.ke = Coef::Rgb(e);
        }
        desc.kr = Some(Coef::Scalar(0.0));
        out.push(desc);
    }
    Ok(out)
}
