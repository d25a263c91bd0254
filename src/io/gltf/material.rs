//! A glTF document's `materials` in whitted's terms (the table is in docs/formats.md,
//! "glTF").
//!
//! glTF describes a surface by its base colour `C`, `metallic` `m`, perceptual `roughness`
//! `r` (the GGX width is `a = r^2`), a transmission weight `t` and an index of refraction; it
//! reflects `F0 = mix(F0d, C, m)` at normal incidence (`F0d = ((ior - 1)/(ior + 1))^2`, 0.04
//! for 1.5) and scatters the rest diffusely (dielectrics) or not at all (metals). Whitted has a
//! Phong highlight from the point lights (`ks`, `n`), one mirror ray (`kr`), one refracted ray
//! (`kt`), Lambert (`kd`) and the ambient term (`ka`). The mapping ([`terms`]):
//!
//! - `n = 1/(2 a^2) - 1/2`, clamped to `1..=4096`: Walter et al.'s Blinn-Phong exponent for a
//!   microfacet width `a` (`2/a^2 - 2`), divided by 4 because whitted's lobe is Phong's
//!   `(v . r)^n`, whose angle is twice the half-vector's.
//! - `s = (1 - r)^2`, the share of the reflection that stays sharp. The rest of a metal's
//!   reflection is spread over the hemisphere (the GGX lobe at `a = 1` is nearly Lambert's),
//!   and whitted's Phong term has no cosine, so a broad metal lobe would light the surface
//!   where the light grazes it: that share, tinted by `C` (`Od`), is diffuse instead.
//! - `kd = (1 - m)(1 - t)(1 - F0d) + m (1 - s)`: the dielectric's diffuse share (transmission
//!   takes its part) plus a rough metal's spread reflection; `ka = kd`, the ambient light
//!   scattered the same way (as MTL's `Ka` defaults to `Kd`).
//! - `ks = ((1 - m) F0d + m s C) (n + 2) / 2`: the normalised Phong lobe, so the highlight
//!   reflects its share of the light whatever its width (a rough dielectric a broad dim sheen,
//!   a smooth surface a small bright spot), on the scale where `kd Od` is the diffuse albedo.
//! - `kr = s F0`: the mirror ray for what stays sharp; a rough surface's blurred reflection is
//!   not a mirror image.
//! - `kt = t (1 - m)(1 - F0d) C` and `ior` from `KHR_materials_transmission` and
//!   `KHR_materials_ior`.
//! - `ke = emissiveFactor * emissiveStrength` (`KHR_materials_emissive_strength`), a lamp as
//!   MTL's `Ke`.
//!
//! `Od` is the `baseColorTexture` (with its sampler's wrap modes), else the vertex colours,
//! else `C`; with a texture or vertex colours `C` multiplies `ka` and `kd` instead, so the
//! product is glTF's `C * texture`. Whitted's `ks`, `kr` and `kt` are one value per material,
//! so a metal's are tinted by `C` alone, not by its texture.

use super::image::{Source, reference, source};
use super::{Document, at};
use crate::error::Result;
use crate::io::scene::schema::{Coef, MaterialDesc, default_material};
use crate::texture::Wrap;
use serde::Deserialize;
use std::path::Path;

#[cfg(test)]
mod tests;

/// `materials[i]`.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct MaterialJson {
    name: Option<String>,
    pbr_metallic_roughness: Option<Pbr>,
    emissive_factor: Option<[f32; 3]>,
    emissive_texture: Option<TextureRef>,
    normal_texture: Option<TextureRef>,
    occlusion_texture: Option<TextureRef>,
    #[serde(default)]
    extensions: MaterialExtensions,
}

/// `materials[i].pbrMetallicRoughness`.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Pbr {
    base_color_factor: Option<[f32; 4]>,
    base_color_texture: Option<TextureRef>,
    metallic_factor: Option<f32>,
    roughness_factor: Option<f32>,
    metallic_roughness_texture: Option<TextureRef>,
}

/// The material extensions whitted reads.
#[derive(Debug, Default, Deserialize)]
struct MaterialExtensions {
    #[serde(rename = "KHR_materials_transmission")]
    transmission: Option<Transmission>,
    #[serde(rename = "KHR_materials_ior")]
    ior: Option<Ior>,
    #[serde(rename = "KHR_materials_emissive_strength")]
    emissive_strength: Option<EmissiveStrength>,
}

/// `KHR_materials_transmission`.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct Transmission {
    transmission_factor: Option<f32>,
    transmission_texture: Option<TextureRef>,
}

/// `KHR_materials_ior`.
#[derive(Debug, Deserialize)]
struct Ior {
    ior: Option<f32>,
}

/// `KHR_materials_emissive_strength`.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct EmissiveStrength {
    emissive_strength: Option<f32>,
}

/// A material's reference to `textures[index]`.
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
struct TextureRef {
    index: usize,
    #[serde(default)]
    tex_coord: u32,
}

/// `textures[i]`: an image and how to sample it.
#[derive(Debug, Deserialize)]
pub(super) struct TextureJson {
    source: Option<usize>,
    sampler: Option<usize>,
}

/// `samplers[i]`: the wrap modes (whitted's lookups are bilinear whatever the filters say).
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct SamplerJson {
    wrap_s: Option<u32>,
    wrap_t: Option<u32>,
}

/// Phong exponents beyond this are clamped (a roughness below about 0.1; the lobe is a spike
/// well before), as for MTL's `Ns`.
pub(super) const MAX_N: f32 = 4096.0;

/// glTF's material factors, defaults filled in, for [`terms`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Factors {
    /// `baseColorFactor` (RGB).
    pub base: [f32; 3],
    /// `metallicFactor`.
    pub metallic: f32,
    /// `roughnessFactor`.
    pub roughness: f32,
    /// `KHR_materials_transmission.transmissionFactor`.
    pub transmission: f32,
    /// `KHR_materials_ior.ior` (0: the extension's "infinitely reflective" value).
    pub ior: f32,
}

/// Whitted's terms for [`Factors`] (see the module's documentation): `ka kd ks n kr kt ior`,
/// `ka` and `kd` without the base colour (the caller applies it, as `Od` or as a tint).
pub(super) struct Terms {
    pub ka: f32,
    pub kd: f32,
    pub ks: [f32; 3],
    pub n: f32,
    pub kr: [f32; 3],
    pub kt: [f32; 3],
    pub ior: f32,
}

/// The mapping of the module's documentation.
pub(super) fn terms(f: Factors) -> Terms {
    let f0d = if f.ior == 0.0 {
        1.0
    } else {
        ((f.ior - 1.0) / (f.ior + 1.0)).powi(2)
    };
    let (m, r, t) = (f.metallic, f.roughness, f.transmission);
    let a = r * r;
    let n = if a > 0.0 {
        (0.5 / (a * a) - 0.5).clamp(1.0, MAX_N)
    } else {
        MAX_N
    };
    let f0 = f.base.map(|c| f0d * (1.0 - m) + c * m);
    let sharp = (1.0 - r) * (1.0 - r);
    let kd = (1.0 - m) * (1.0 - t) * (1.0 - f0d) + m * (1.0 - sharp);
    Terms {
        ka: kd,
        kd,
        ks: f
            .base
            .map(|c| (f0d * (1.0 - m) + m * sharp * c) * (n + 2.0) * 0.5),
        n,
        kr: f0.map(|x| x * sharp),
        kt: f.base.map(|c| t * (1.0 - m) * (1.0 - f0d) * c),
        ior: if f.ior >= 1.0 { f.ior } else { 1.5 },
    }
}

/// The glTF wrap mode of `samplers[i].wrapS` or `wrapT` (default `REPEAT`).
fn wrap(code: Option<u32>, key: &str, path: &Path) -> Result<Wrap> {
    match code {
        None | Some(10497) => Ok(Wrap::Repeat),
        Some(33648) => Ok(Wrap::MirroredRepeat),
        Some(33071) => Ok(Wrap::Clamp),
        Some(c) => Err(at(
            path,
            key,
            format!(
                "{c} is not a wrap mode (REPEAT 10497, MIRRORED_REPEAT 33648, CLAMP_TO_EDGE 33071)"
            ),
        )),
    }
}

/// One value per channel as a [`Coef`]: a scalar when the channels agree.
fn coef(c: [f32; 3]) -> Coef {
    if c[0] == c[1] && c[1] == c[2] {
        Coef::Scalar(c[0])
    } else {
        Coef::Rgb(c)
    }
}

/// A factor in `0..=1`, or the error naming it.
fn unit(v: Option<f32>, default: f32, key: &str, path: &Path) -> Result<f32> {
    match v {
        None => Ok(default),
        Some(x) if (0.0..=1.0).contains(&x) => Ok(x),
        Some(x) => Err(at(path, key, format!("{x} is not in [0, 1]"))),
    }
}

/// `materials` in whitted's terms (the module's documentation). `has_uv`: every primitive
/// has `TEXCOORD_0` (else a base colour texture falls back to its factor, with a warning);
/// `vertex_colors`: every primitive has `COLOR_0`, used as `Od` when there is no texture.
/// Textures whitted does not read (metallic-roughness, normal, occlusion, emissive,
/// transmission) are named in one warning.
pub(super) fn materials(
    doc: &Document,
    path: &Path,
    has_uv: bool,
    vertex_colors: bool,
    warnings: &mut Vec<String>,
) -> Result<Vec<MaterialDesc>> {
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut unread = Vec::new();
    let mut out: Vec<MaterialDesc> = Vec::with_capacity(doc.materials.len());
    for (i, m) in doc.materials.iter().enumerate() {
        let key = format!("materials[{i}]");
        let pbr_key = format!("{key}.pbrMetallicRoughness");
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
                &format!("{pbr_key}.baseColorFactor"),
                "components must be finite and >= 0",
            ));
        }
        let base = [factor[0], factor[1], factor[2]];
        let ext = &m.extensions;
        let ext_key = |name: &str, field: &str| format!("{key}.extensions.{name}.{field}");
        let ior = match ext.ior.as_ref().and_then(|x| x.ior) {
            None => 1.5,
            Some(x) if x == 0.0 || (x.is_finite() && x >= 1.0) => x,
            Some(x) => {
                return Err(at(
                    path,
                    &ext_key("KHR_materials_ior", "ior"),
                    format!("{x}: must be >= 1 (or 0)"),
                ));
            }
        };
        let transmission = ext.transmission.as_ref();
        let f = Factors {
            base,
            metallic: unit(
                pbr.and_then(|p| p.metallic_factor),
                1.0,
                &format!("{pbr_key}.metallicFactor"),
                path,
            )?,
            roughness: unit(
                pbr.and_then(|p| p.roughness_factor),
                1.0,
                &format!("{pbr_key}.roughnessFactor"),
                path,
            )?,
            transmission: unit(
                transmission.and_then(|t| t.transmission_factor),
                0.0,
                &ext_key("KHR_materials_transmission", "transmissionFactor"),
                path,
            )?,
            ior,
        };
        // The textures whitted does not read, by their JSON paths.
        for (slot, r) in [
            (
                format!("{pbr_key}.metallicRoughnessTexture"),
                pbr.and_then(|p| p.metallic_roughness_texture.as_ref()),
            ),
            (format!("{key}.normalTexture"), m.normal_texture.as_ref()),
            (
                format!("{key}.occlusionTexture"),
                m.occlusion_texture.as_ref(),
            ),
            (
                format!("{key}.emissiveTexture"),
                m.emissive_texture.as_ref(),
            ),
            (
                ext_key("KHR_materials_transmission", "transmissionTexture"),
                transmission.and_then(|t| t.transmission_texture.as_ref()),
            ),
        ] {
            if let Some(r) = r {
                if r.index >= doc.textures.len() {
                    return Err(at(
                        path,
                        &format!("{slot}.index"),
                        format!("no texture {}", r.index),
                    ));
                }
                unread.push(slot);
            }
        }
        let t = terms(f);
        // Od: the texture, the vertex colours or the base colour; C tints ka and kd when it
        // is not Od.
        let mut od_is_base = !vertex_colors;
        if let Some(r) = pbr.and_then(|p| p.base_color_texture.as_ref()) {
            let tkey = format!("{pbr_key}.baseColorTexture");
            if let Some((texture, wrap)) =
                base_texture(doc, r, &tkey, &dir, path, has_uv, &desc.name, warnings)?
            {
                desc.texture = Some(texture);
                desc.wrap = (wrap != [Wrap::Repeat; 2]).then_some(wrap);
                desc.vertex_color = false;
                od_is_base = false;
            }
        }
        if od_is_base {
            desc.color = Some(base);
            desc.ka = Coef::Scalar(t.ka);
            desc.kd = Coef::Scalar(t.kd);
        } else {
            desc.color = None;
            desc.ka = coef(base.map(|c| c * t.ka));
            desc.kd = coef(base.map(|c| c * t.kd));
        }
        desc.ks = coef(t.ks);
        desc.n = t.n;
        desc.kr = Some(coef(t.kr));
        desc.kt = coef(t.kt);
        desc.ior = t.ior;
        // Emission, as MTL's Ke: shown on the surface, and lighting the scene through point
        // lights of its own (see `scene::emitter_lights`). An emissive texture is not read:
        // its factor alone would light the whole surface, so the material does not emit.
        if let Some(e) = m.emissive_factor {
            if !e.iter().all(|c| c.is_finite() && *c >= 0.0) {
                return Err(at(
                    path,
                    &format!("{key}.emissiveFactor"),
                    "components must be finite and >= 0",
                ));
            }
            let strength = match ext
                .emissive_strength
                .as_ref()
                .and_then(|s| s.emissive_strength)
            {
                None => 1.0,
                Some(s) if s.is_finite() && s >= 0.0 => s,
                Some(s) => {
                    return Err(at(
                        path,
                        &ext_key("KHR_materials_emissive_strength", "emissiveStrength"),
                        format!("{s}: must be finite and >= 0"),
                    ));
                }
            };
            if m.emissive_texture.is_none() {
                desc.ke = coef(e.map(|c| c * strength));
            }
        }
        out.push(desc);
    }
    if !unread.is_empty() {
        warnings.push(format!(
            "{}: glTF textures not read (their materials use their factors; an emissive texture's material does not emit): {}",
            path.display(),
            unread.join(", ")
        ));
    }
    Ok(out)
}

/// The texture name and wrap modes of a `baseColorTexture`, or `None` (with a warning) when
/// whitted cannot use it: a `texCoord` other than 0, a mesh without uv, or a texture whose
/// image comes only through an extension (WebP, KTX2).
#[allow(clippy::too_many_arguments)]
fn base_texture(
    doc: &Document,
    r: &TextureRef,
    tkey: &str,
    dir: &Path,
    path: &Path,
    has_uv: bool,
    material: &str,
    warnings: &mut Vec<String>,
) -> Result<Option<(String, [Wrap; 2])>> {
    let texture = doc.textures.get(r.index).ok_or_else(|| {
        at(
            path,
            &format!("{tkey}.index"),
            format!("no texture {}", r.index),
        )
    })?;
    let wrap = match texture.sampler {
        None => [Wrap::Repeat; 2],
        Some(s) => {
            let sampler = doc.samplers.get(s).ok_or_else(|| {
                at(
                    path,
                    &format!("textures[{}].sampler", r.index),
                    format!("no sampler {s} (the file has {})", doc.samplers.len()),
                )
            })?;
            [
                wrap(sampler.wrap_s, &format!("samplers[{s}].wrapS"), path)?,
                wrap(sampler.wrap_t, &format!("samplers[{s}].wrapT"), path)?,
            ]
        }
    };
    let Some(image) = texture.source else {
        warnings.push(format!(
            "{}: glTF textures[{}] has no source image whitted reads (its image comes through an extension); material '{material}' uses its baseColorFactor",
            path.display(),
            r.index
        ));
        return Ok(None);
    };
    if image >= doc.images.len() {
        return Err(at(
            path,
            &format!("textures[{}].source", r.index),
            format!("no image {image} (the file has {})", doc.images.len()),
        ));
    }
    // Checked even when unused, so a broken file is refused whatever its meshes hold.
    let name = match source(doc, image, path)? {
        Source::File(name) => {
            let f = dir.join(name);
            // Absolute, so a scene finds it whatever folders its search path holds.
            std::path::absolute(&f)
                .unwrap_or(f)
                .to_string_lossy()
                .into_owned()
        }
        Source::Embedded => reference(path, image),
    };
    if r.tex_coord != 0 || !has_uv {
        let why = if r.tex_coord != 0 {
            format!("reads TEXCOORD_{}; only TEXCOORD_0 is read", r.tex_coord)
        } else {
            "needs TEXCOORD_0, which some primitive lacks".into()
        };
        warnings.push(format!(
            "{}: glTF {tkey} {why}; material '{material}' uses its baseColorFactor",
            path.display(),
        ));
        return Ok(None);
    }
    Ok(Some((name, wrap)))
}
