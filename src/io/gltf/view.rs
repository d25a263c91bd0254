//! What a glTF scene says about its lighting and its view: `KHR_lights_punctual` lights as
//! Whitted's point lights, and a perspective camera as the scene camera.

use super::{Document, at};
use crate::error::Result;
use crate::io::scene::schema::{CameraDesc, LightDesc};
use glam::{Mat4, Vec3};
use std::path::Path;

/// The `KHR_lights_punctual` lights of the scene's nodes as point lights, for a model within
/// `bounds`. glTF lights fall
/// off with the square of the distance and whitted's do not, so each light's `Ip` is its
/// colour times its intensity over its squared distance to the model's centre (directional
/// lights: times their intensity, placed 10 radii from the centre against their direction;
/// spot lights: their cone is not read, with a warning), and all are scaled together so the
/// brightest gives 0.9, the canonical key light's: the lights keep their balance and the model
/// its exposure, whatever units the exporter wrote.
pub(super) fn lights(
    doc: &Document,
    nodes: &[(Mat4, usize)],
    bounds: Option<(Vec3, Vec3)>,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<Vec<LightDesc>> {
    let Some(list) = doc.extensions.as_ref().and_then(|e| e.lights.as_ref()) else {
        return Ok(Vec::new());
    };
    let (lo, hi) = bounds.unwrap_or_default();
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-6);
    let mut out = Vec::with_capacity(nodes.len());
    for &(world, l) in nodes {
        let key = format!("extensions.KHR_lights_punctual.lights[{l}]");
        let light = &list.lights[l];
        let colour = Vec3::from(light.color.unwrap_or([1.0; 3]));
        let intensity = light.intensity.unwrap_or(1.0);
        let valid = colour.is_finite()
            && colour.cmpge(Vec3::ZERO).all()
            && intensity.is_finite()
            && intensity >= 0.0;
        if !valid {
            return Err(at(
                path,
                &key,
                "color and intensity must be finite and >= 0",
            ));
        }
        let (position, ip) = match light.kind.as_str() {
            "directional" => {
                let dir = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
                (centre - dir * 10.0 * radius, colour * intensity)
            }
            kind => {
                if kind == "spot" {
                    warnings.push(format!(
                        "{}: glTF {key}: a spot light is drawn as a point light (its cone is not read)",
                        path.display()
                    ));
                } else if kind != "point" {
                    return Err(at(
                        path,
                        &format!("{key}.type"),
                        format!("unknown light type '{kind}'"),
                    ));
                }
                let p = world.transform_point3(Vec3::ZERO);
                let d2 = p.distance_squared(centre).max((0.01 * radius).powi(2));
                (p, colour * intensity / d2)
            }
        };
        if !position.is_finite() || !ip.is_finite() {
            return Err(at(
                path,
                &key,
                "its node's transform puts it at no finite place",
            ));
        }
        out.push((position, ip));
    }
    let brightest = out
        .iter()
        .map(|(_, ip)| ip.max_element())
        .fold(0.0, f32::max);
    let scale = if brightest > 0.0 {
        0.9 / brightest
    } else {
        0.0
    };
    Ok(out
        .into_iter()
        .map(|(p, ip)| LightDesc {
            position: p.to_array(),
            intensity: (ip * scale).to_array(),
        })
        .collect())
}

/// Camera `c` at `world` as a scene camera: glTF cameras look down their -z with +y up. One
/// that is not perspective, or that its transform makes degenerate, is skipped with a
/// warning (the model is then framed as any mesh is).
pub(super) fn view_of(
    doc: &Document,
    world: Mat4,
    c: usize,
    path: &Path,
    warnings: &mut Vec<String>,
) -> Option<CameraDesc> {
    let cam = &doc.cameras[c];
    let mut skip = |why: &str| {
        warnings.push(format!(
            "{}: glTF cameras[{c}]: {why}; the model is framed instead",
            path.display()
        ));
        None
    };
    let Some(p) = cam
        .perspective
        .as_ref()
        .filter(|_| cam.kind == "perspective")
    else {
        return skip(&format!("a '{}' camera is not read", cam.kind));
    };
    let vfov = p.yfov.to_degrees();
    if !(vfov > 0.0 && vfov < 180.0) {
        return skip(&format!("yfov {} is not in (0, pi)", p.yfov));
    }
    let eye = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y).normalize_or_zero();
    if !eye.is_finite() || forward == Vec3::ZERO || forward.cross(up).length() < 1e-3 {
        return skip("its node's transform leaves no view direction and up");
    }
    Some(CameraDesc {
        eye: eye.to_array(),
        look_at: (eye + forward).to_array(),
        up: up.to_array(),
        vfov,
    })
}
