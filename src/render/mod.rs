//! Rendering: the world (scene + geometry + BVH), stages, tiles, statistics.

pub mod queues;
pub mod recursive;
pub mod wavefront;

pub use crate::trace::Engine;
pub use crate::world::{Stage, Terms, World};

use crate::camera::sample_offsets;
use crate::image::Image;
use crate::scene::Scene;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Options of one render.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Settings {
    /// One stage of the assignment, or `None` for the full scene.
    pub stage: Option<Stage>,
    /// Recursion depth; `None` uses the stage's (0 below `reflection`) or the scene's.
    pub depth: Option<u32>,
    /// Samples per pixel (stratified, deterministic).
    pub spp: u32,
    /// Wavefront on packets (default) or the scalar recursive reference.
    pub engine: Engine,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            stage: None,
            depth: None,
            spp: 1,
            engine: Engine::Packet,
        }
    }
}

impl Settings {
    /// The recursion depth this render uses for `scene`.
    pub fn depth(&self, scene: &Scene) -> u32 {
        match (self.depth, self.stage) {
            (Some(d), _) => d,
            (
                None,
                Some(Stage::Intersection | Stage::Diffuse | Stage::Specular | Stage::Shadow),
            ) => 0,
            (None, _) => scene.depth,
        }
    }
}

/// The most reflection and refraction rays one camera sample's ray tree may spawn. A tree
/// only grows exponentially where rays are trapped (say, mirror-and-glass walls around the
/// camera at `depth = 64`: 2^65 rays per sample); real scenes need far fewer (`refraction`
/// at most 126, a glass sphere at depth 64 about 130). Past it, both engines stop and the
/// render fails with [`RenderStats::over_budget`] set instead of running for days.
pub const MAX_SAMPLE_SECONDARY_RAYS: u32 = 1 << 14;

/// Rays traced, by kind.
#[derive(Debug, Default)]
pub struct RayCounts {
    /// Camera rays.
    pub primary: AtomicU64,
    /// Shadow rays.
    pub shadow: AtomicU64,
    /// Reflection rays.
    pub reflection: AtomicU64,
    /// Refraction rays.
    pub refraction: AtomicU64,
}

impl RayCounts {
    /// All rays of every kind.
    pub fn total(&self) -> u64 {
        [
            &self.primary,
            &self.shadow,
            &self.reflection,
            &self.refraction,
        ]
        .iter()
        .map(|c| c.load(Ordering::Relaxed))
        .sum()
    }
}

/// What a render measured.
#[derive(Debug, Default)]
pub struct RenderStats {
    /// Rays traced, by kind.
    pub rays: RayCounts,
    /// Wall time of the render.
    pub time: Duration,
    /// Summed thread time (ns) per phase: primary intersection, shading, shadow rays,
    /// secondary intersection (wavefront engine only).
    pub phase_ns: [AtomicU64; 4],
    /// `y * width + x + 1` of a pixel whose sample passed [`MAX_SAMPLE_SECONDARY_RAYS`]
    /// (0: none). Once set, the render stops early and its image must not be used.
    pub over_budget: AtomicU64,
}

impl RenderStats {
    /// The pixel whose ray tree passed the budget, if any.
    pub fn over_budget_pixel(&self, width: u32) -> Option<(u32, u32)> {
        match self.over_budget.load(Ordering::Relaxed) {
            0 => None,
            k => Some((
                ((k - 1) % width as u64) as u32,
                ((k - 1) / width as u64) as u32,
            )),
        }
    }

    /// Record that the sample at `(x, y)` passed the budget (the first report wins).
    pub fn set_over_budget(&self, x: u32, y: u32, width: u32) {
        let k = y as u64 * width as u64 + x as u64 + 1;
        let _ = self
            .over_budget
            .compare_exchange(0, k, Ordering::Relaxed, Ordering::Relaxed);
    }
}

impl RenderStats {
    /// Names of the phases of `phase_ns`, in order.
    pub const PHASES: [&'static str; 4] = ["primary", "shade", "shadow", "secondary"];
}

/// Exclusive end `(x1, y1)` of the tile starting at `(x0, y0)`, clipped to the image.
pub fn tile_end(camera: &crate::camera::Camera, x0: u32, y0: u32) -> (u32, u32) {
    (
        (x0 + TILE).min(camera.width),
        (y0 + TILE).min(camera.height),
    )
}

/// Tile edge in pixels: small enough to balance threads, big enough for coherent packets.
pub const TILE: u32 = 16;

/// Render `world` over tiles in parallel with the engine of `settings`: the wavefront
/// renderer on packets, or the scalar reference (`recursive::trace1` per sample).
/// `progress(pixels)` is called as tiles finish.
pub fn render(
    world: &World,
    settings: &Settings,
    progress: &(dyn Fn(u64) + Sync),
) -> (Image, RenderStats) {
    let start = Instant::now();
    let (w, h) = (world.scene.width, world.scene.height);
    let stats = RenderStats::default();
    let offsets = sample_offsets(settings.spp);
    let mut image = Image::new(w as usize, h as usize);
    // Bands of TILE rows in parallel, tiles written straight into the image: memory is the
    // image plus one tile's queues per thread, whatever the resolution.
    let band_len = TILE as usize * w as usize;
    image
        .pixels
        .par_chunks_mut(band_len)
        .enumerate()
        .for_each_init(wavefront::Workspace::default, |ws, (band, rows)| {
            let y0 = band as u32 * TILE;
            for x0 in (0..w).step_by(TILE as usize) {
                if stats.over_budget.load(Ordering::Relaxed) != 0 {
                    return; // the render has failed; stop tracing
                }
                let scalar;
                let pixels: &[Vec3] = match settings.engine {
                    Engine::Packet => {
                        wavefront::render_tile(world, settings, &offsets, x0, y0, &stats, ws);
                        &ws.accum
                    }
                    Engine::Scalar => {
                        scalar = recursive::render_tile(world, settings, &offsets, x0, y0, &stats);
                        &scalar
                    }
                };
                let tw = TILE.min(w - x0) as usize;
                for (k, p) in pixels.iter().enumerate() {
                    rows[(k / tw) * w as usize + x0 as usize + k % tw] = *p;
                }
                progress(pixels.len() as u64);
            }
        });
    let stats = RenderStats {
        time: start.elapsed(),
        ..stats
    };
    (image, stats)
}
