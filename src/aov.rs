//! AOVs ("arbitrary output variables"): first-hit quantities written beside the beauty image.
//!
//! They are captured in a pass of their own over the camera rays through pixel centres
//! (4x2 camera packets through `intersect8`, then the scalar `surface` per hit: the same hit
//! and shading normal the renderers compute; `render::aov::capture_part`, over the whole image
//! or a part of it), so neither engine's loop changes; with `--spp > 1` the beauty image is averaged
//! but the AOVs stay one sample at the pixel centre (an averaged triangle id means nothing).

use crate::world::World;
use glam::Vec3;

/// One kind of AOV.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Aov {
    /// `Od * kd` at the first hit (the diffuse reflectance; 0 on misses).
    Albedo,
    /// Shading normal `N` at the first hit, world space, facing the camera (0 on misses).
    Normal,
    /// Distance from the eye to the first hit along the ray (`+inf` on misses).
    Depth,
    /// Index of the hit triangle in the scene (objects in order, then faces in file order;
    /// `0xFFFFFFFF` on misses), as an unsigned 32-bit channel.
    Id,
}

impl Aov {
    /// Every AOV, in the order of their names.
    pub const ALL: [Aov; 4] = [Aov::Albedo, Aov::Normal, Aov::Depth, Aov::Id];

    /// Its name on the command line and in the EXR's channel names.
    pub fn name(self) -> &'static str {
        ["albedo", "normal", "depth", "id"][self as usize]
    }

    /// Parse a comma-separated list (`albedo,normal,depth,id`); duplicates are dropped.
    pub fn parse_list(s: &str) -> Result<Vec<Aov>, String> {
        let mut out = Vec::new();
        for name in s.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            let a = Aov::ALL
                .into_iter()
                .find(|a| a.name() == name)
                .ok_or_else(|| format!("unknown AOV '{name}' (albedo, normal, depth, id)"))?;
            if !out.contains(&a) {
                out.push(a);
            }
        }
        if out.is_empty() {
            return Err("no AOV named (albedo, normal, depth, id)".into());
        }
        Ok(out)
    }
}

/// The captured layers, row-major, one entry per pixel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AovImages {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// `Od * kd` at the first hit (0 on misses), if asked for.
    pub albedo: Option<Vec<Vec3>>,
    /// The shading normal at the first hit, world space, facing the camera (0 on misses).
    pub normal: Option<Vec<Vec3>>,
    /// Distance from the eye along the camera ray (`+inf` on misses).
    pub depth: Option<Vec<f32>>,
    /// Index of the hit triangle in the scene (`0xFFFFFFFF` on misses).
    pub id: Option<Vec<u32>>,
}

/// Capture `aovs` for every pixel of the world's camera: [`crate::render::aov::capture_part`]
/// over the whole image.
pub fn capture(world: &World, aovs: &[Aov]) -> AovImages {
    let cam = world.scene.camera();
    crate::render::aov::capture_part(
        world,
        aovs,
        crate::image::PixelBounds::full(cam.width, cam.height),
    )
}
