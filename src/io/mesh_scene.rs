//! `whitted render model.obj|.ply|.stl|.gltf|.m`: the scene a mesh file gets when it is
//! rendered alone.
//!
//! The camera (unless the file brings its own: a glTF camera) looks at the centre of the
//! bounding box from the canonical scenes' direction (SCENES.md §5: `eye - look_at = (1.6,
//! 1.05, 4.4)`, to the front, right and above), far enough that the box's bounding sphere fits
//! the narrower field of view with a 10% margin (the canonical kitten view has the same ratio
//! of distance to radius, 3.6). The canonical
//! lights keep their directions and their distances relative to the kitten's bounding sphere
//! (radius 1.333), scaled to the model's; their intensities are the canonical ones. A glTF
//! file's own lights replace them; a model whose materials emit (`Ke`) and has no lights of
//! its own is lit by its emitters instead (`scene::emitter_lights`).
//! Ambient and background are the canonical ones; culling is off (files do not always wind
//! their faces consistently, and refraction must see back faces) and depth is 6.

use crate::error::{Error, Result};
use crate::io::load_model;
use crate::io::scene::{
    BackgroundDesc, CameraDesc, ImageDesc, LightDesc, MeshDesc, RenderDesc, SceneFile,
};
use glam::Vec3;
use std::path::Path;

/// Canonical view direction `eye - look_at` (SCENES.md §5).
const VIEW: Vec3 = Vec3::new(1.6, 1.05, 4.4);
/// The canonical lights relative to `look_at`, with their intensities.
const LIGHTS: [([f32; 3], [f32; 3]); 2] = [
    ([5.0, 6.15, 3.0], [0.9, 0.9, 0.85]),
    ([-5.0, 5.15, 3.0], [0.35, 0.35, 0.45]),
];
/// Radius of the kitten's bounding sphere (half the diagonal of its box), the scale of the
/// canonical light positions.
const KITTEN_RADIUS: f32 = 1.333;
const VFOV: f32 = 36.0;

/// Whether `path` names a mesh file (by extension) rather than a scene.
pub fn is_mesh_file(path: &Path) -> bool {
    crate::io::MESH_EXTENSIONS.contains(&crate::io::extension(path).as_str())
}

/// The scene that renders `path` alone at `width x height`, and the loader's warnings.
/// Paths in it are absolute, so the printed scene works from any folder.
pub fn scene_for_mesh(path: &Path, width: u64, height: u64) -> Result<(SceneFile, Vec<String>)> {
    let (model, warnings) = load_model(path)?;
    let (lo, hi) = model
        .bounds()
        .ok_or_else(|| Error::parse(path, 0, "no vertices"))?;
    let centre = (lo + hi) * 0.5;
    // A flat or point-like model still gets a camera at a finite, non-zero distance.
    let radius = ((hi - lo).length() * 0.5)
        .max(1e-6 * centre.length())
        .max(1e-30);
    let aspect = width as f32 / height.max(1) as f32;
    let half_v = (VFOV * 0.5).to_radians();
    let half_h = (half_v.tan() * aspect).atan();
    let distance = 1.1 * radius / half_v.min(half_h).sin();
    let eye = centre + VIEW.normalize() * distance;
    if !(eye.is_finite() && (eye - centre).length_squared() > 0.0) {
        return Err(Error::parse(
            path,
            0,
            "the bounding box is too large or too small to frame in f32",
        ));
    }
    // Emitters that some face uses: a library's unused lamp material lights nothing, and must
    // not turn the canonical lights off.
    let mut used = vec![false; model.materials.len()];
    let shared = model.shared.iter().map(|s| &s.model.face_materials);
    for &f in std::iter::once(&model.face_materials)
        .chain(shared)
        .flatten()
        .flatten()
    {
        if let Some(u) = used.get_mut(f as usize) {
            *u = true;
        }
    }
    let emits = (model.materials.iter().zip(&used)).any(|(m, &u)| u && m.lamp && !m.ke.is_zero());
    // The file's own lights (glTF), else none beside emitters, else the canonical ones.
    let lights = if !model.lights.is_empty() {
        model.lights
    } else if emits {
        Vec::new()
    } else {
        LIGHTS
            .iter()
            .map(|&(p, intensity)| LightDesc {
                position: (centre + Vec3::from(p) * (radius / KITTEN_RADIUS)).to_array(),
                intensity,
            })
            .collect()
    };
    let file = std::path::absolute(path)
        .unwrap_or_else(|_| path.to_path_buf())
        .to_string_lossy()
        .into_owned();
    let mut materials = model.materials;
    for m in &mut materials {
        if let Some(t) = &mut m.texture
            && let Ok(abs) = std::path::absolute(t.as_str())
        {
            *t = abs.to_string_lossy().into_owned();
        }
    }
    let scene = SceneFile {
        image: ImageDesc { width, height },
        // The file's own camera (glTF), else the framing above.
        camera: model.camera.unwrap_or(CameraDesc {
            eye: eye.to_array(),
            look_at: centre.to_array(),
            up: [0.0, 1.0, 0.0],
            vfov: VFOV,
        }),
        render: RenderDesc {
            depth: 6,
            cull_backfaces: false,
            ambient: [0.15, 0.15, 0.18],
        },
        background: BackgroundDesc {
            color: Some([0.1, 0.12, 0.16]),
            cubemap: None,
        },
        lights,
        materials,
        meshes: vec![MeshDesc {
            name: path.file_name().map(|n| n.to_string_lossy().into_owned()),
            file: Some(file),
            ..Default::default()
        }],
        instances: Vec::new(),
        lines: Default::default(),
    };
    Ok((scene, warnings))
}
