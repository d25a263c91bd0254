//! Rendering: the world (scene + geometry + BVH), stages, tiles, statistics.

pub mod aov;
pub mod part;
pub mod queues;
pub mod recursive;
pub mod report;
pub mod wavefront;

pub use crate::trace::Engine;
pub use crate::world::{Stage, Terms, World};

use crate::camera::sample_offsets;
use crate::error::Result;
use crate::image::{Image, PixelBounds};
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
    /// The wavefront renderer with the fastest kernel per queue (`Auto`, default), with one
    /// kernel for every queue (`Packet`, `Wide`), or the scalar recursive reference.
    pub engine: Engine,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            stage: None,
            depth: None,
            spp: 1,
            engine: Engine::Auto,
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
    /// Reflection and refraction rays (counted above too) that repeat another ray of the
    /// same generation bit for bit and take its hit instead of a traversal of their own
    /// (wavefront engines: total internal reflection, where the refraction ray is the
    /// reflection ray, and what such pairs spawn).
    pub repeated: AtomicU64,
    /// Shadow rays (counted above too) that repeat another shadow ray bit for bit (those of
    /// a repeated ray's hit) and take its answer instead of a traversal of their own.
    pub repeated_shadow: AtomicU64,
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

/// Bytes of f32 pixels a batch of bands aims at (at least one band of [`TILE`] rows): 4 MB
/// is one band of a 16384-wide image (1,024 tiles, plenty to keep every thread busy up to
/// the batch's end), 22 bands of a 3840-wide one. Against 16 MB batches (2026-12-07, AMD
/// EPYC Zen 3, 2 vCPUs, `phong`, default EXR output, medians of alternating runs, the same
/// files): peak memory 24 against 47 MiB at 1920x1080 on one thread and 31 against 60 MiB
/// at 3840x2160 on two, whole-process CPU time 0.95x and wall time 0.98x.
pub const BATCH_BYTES: usize = 4 << 20;

/// Bands in the next batch, `left` of the part's `total` bands still to render: a full
/// batch (`full` bands), but where the part spans several batches, the last ones taper,
/// each about half of what is left and no fewer than `least` bands (four tiles per thread).
/// The sink's work on a batch (EXR compression) runs while the next batch renders, so what
/// is left of it when the last tile is done is serial time; batches that shrink toward the
/// end leave little. 4K `phong` on two threads, default output (2026-12-07, AMD EPYC Zen
/// 3, 2 vCPUs): the wall time after the last band went from 45-48 ms to 9-30 ms, the whole
/// process's wall time 0.98x, and two threads against one 1.85x (1.81x before); one
/// thread's CPU time is level.
fn batch_bands(left: u32, total: u32, full: u32, least: u32) -> u32 {
    if total <= full {
        return left;
    }
    let most = full.min(left);
    left.div_ceil(2).clamp(least.min(most), most)
}

/// Render `world` over tiles in parallel with the engine of `settings`: the wavefront
/// renderer on packets, or the scalar reference (`recursive::trace1` per sample).
/// `progress(pixels)` is called as tiles finish.
pub fn render(
    world: &World,
    settings: &Settings,
    progress: &(dyn Fn(u64) + Sync),
) -> (Image, RenderStats) {
    let full = PixelBounds::full(world.scene.width, world.scene.height);
    render_part(world, settings, full, progress)
}

/// [`render`] of the pixels of `part` only, into an image of the part's size: each pixel
/// equal, bit for bit, to the same pixel of the full render.
pub fn render_part(
    world: &World,
    settings: &Settings,
    part: PixelBounds,
    progress: &(dyn Fn(u64) + Sync),
) -> (Image, RenderStats) {
    let (w, h) = (part.width() as usize, part.height() as usize);
    let mut image = Image::new(w, h);
    let stats = render_rows(world, settings, part, progress, &mut |y, rows| {
        let start = (y - part.y0) as usize * w;
        image.pixels[start..start + rows.len()].copy_from_slice(rows);
        Ok(())
    })
    .expect("the image sink does not fail");
    (image, stats)
}

/// Render the pixels of `part` and hand them to `sink` in batches of whole rows, top to
/// bottom: `sink(y, rows)` gets rows `y..` of the part, `part.width()` pixels each, row-major.
/// A sink's error stops the render and is returned. Memory is one batch (about
/// [`BATCH_BYTES`], twice: tiles, then rows) plus one tile's queues per thread, whatever the
/// image size.
///
/// The tiles are the full render's: the grid of [`TILE`]-pixel squares from the image's
/// corner, clipped to the image. A tile that `part` cuts is still traced whole, so every
/// packet (and every pixel) is the full render's, and the pixels outside the part are
/// dropped; a part on the tile grid (as `--tile` makes) wastes nothing.
///
/// When a sample passes [`MAX_SAMPLE_SECONDARY_RAYS`] the render stops after the batch in
/// flight and returns with [`RenderStats::over_budget`] set; what was handed to the sink must
/// then be thrown away.
pub fn render_rows(
    world: &World,
    settings: &Settings,
    part: PixelBounds,
    progress: &(dyn Fn(u64) + Sync),
    sink: &mut dyn FnMut(u32, &[Vec3]) -> Result<()>,
) -> Result<RenderStats> {
    let start = Instant::now();
    let full = PixelBounds::full(world.scene.width, world.scene.height);
    assert!(
        full.contains(&part),
        "part {part} outside the {}x{} image",
        full.x1,
        full.y1
    );
    let stats = RenderStats::default();
    let offsets = sample_offsets(settings.spp);
    let pw = part.width() as usize;
    // tile rows and columns that meet the part
    let (tx0, tx1) = (part.x0 / TILE, part.x1.div_ceil(TILE));
    let (ty0, ty1) = (part.y0 / TILE, part.y1.div_ceil(TILE));
    let band_bytes = TILE as usize * pw.max(1) * std::mem::size_of::<Vec3>();
    let bands_per_batch = (BATCH_BYTES / band_bytes).max(1) as u32;
    let tiles_per_band = (tx1 - tx0).max(1);
    let least = (4 * rayon::current_num_threads() as u32).div_ceil(tiles_per_band);
    let mut rows = Vec::new();
    let mut batch_ty1 = ty0;
    while batch_ty1 < ty1 {
        let batch_ty = batch_ty1;
        batch_ty1 += batch_bands(ty1 - batch_ty, ty1 - ty0, bands_per_batch, least);
        let tiles: Vec<(u32, u32)> = (batch_ty..batch_ty1)
            .flat_map(|ty| (tx0..tx1).map(move |tx| (tx * TILE, ty * TILE)))
            .collect();
        let rendered: Vec<Vec<Vec3>> = tiles
            .par_iter()
            .map_init(wavefront::Workspace::default, |ws, &(x0, y0)| {
                if stats.over_budget.load(Ordering::Relaxed) != 0 {
                    return Vec::new(); // the render has failed; stop tracing
                }
                let pixels = match settings.engine {
                    Engine::Auto
                    | Engine::Packet
                    | Engine::Wide
                    | Engine::Hybrid
                    | Engine::Packet16
                    | Engine::Hybrid16 => {
                        wavefront::render_tile(world, settings, &offsets, x0, y0, &stats, ws);
                        std::mem::take(&mut ws.accum)
                    }
                    Engine::Scalar => {
                        recursive::render_tile(world, settings, &offsets, x0, y0, &stats)
                    }
                };
                let (x1, y1) = ((x0 + TILE).min(full.x1), (y0 + TILE).min(full.y1));
                let inside = part.intersect(&PixelBounds { x0, x1, y0, y1 });
                progress(inside.area());
                pixels
            })
            .collect();
        if stats.over_budget.load(Ordering::Relaxed) != 0 {
            break;
        }
        // the batch's rows of the part, from its tiles: one band of tile rows per task
        let (ry0, ry1) = (
            (batch_ty * TILE).max(part.y0),
            (batch_ty1 * TILE).min(part.y1),
        );
        // every pixel is written below: a batch reuses the last one's buffer as it is (only
        // growth is zeroed), where clearing it cost a serial memset of the whole batch
        rows.resize((ry1 - ry0) as usize * pw, Vec3::ZERO);
        let per_band = (tx1 - tx0) as usize;
        let mut bands = Vec::with_capacity((batch_ty1 - batch_ty) as usize);
        let mut rest = rows.as_mut_slice();
        for ty in batch_ty..batch_ty1 {
            let (y0, y1) = ((ty * TILE).max(ry0), ((ty + 1) * TILE).min(ry1));
            let (band, tail) = rest.split_at_mut((y1 - y0) as usize * pw);
            bands.push((y0, band));
            rest = tail;
        }
        bands
            .into_par_iter()
            .zip(
                tiles
                    .par_chunks(per_band)
                    .zip(rendered.par_chunks(per_band)),
            )
            .for_each(|((band_y0, band), (tiles, rendered))| {
                for (&(x0, y0), pixels) in tiles.iter().zip(rendered) {
                    let tw = (TILE.min(full.x1 - x0)) as usize;
                    let (x1, y1) = (x0 + tw as u32, (y0 + TILE).min(full.y1));
                    let inside = part.intersect(&PixelBounds { x0, x1, y0, y1 });
                    for y in inside.y0..inside.y1 {
                        let src = (y - y0) as usize * tw + (inside.x0 - x0) as usize;
                        let dst = (y - band_y0) as usize * pw + (inside.x0 - part.x0) as usize;
                        let n = inside.width() as usize;
                        band[dst..dst + n].copy_from_slice(&pixels[src..src + n]);
                    }
                }
            });
        drop(rendered);
        sink(ry0, &rows)?;
    }
    Ok(RenderStats {
        time: start.elapsed(),
        ..stats
    })
}

#[cfg(test)]
mod tests {
    use super::batch_bands;

    /// The batches of `total` bands, in order.
    fn batches(total: u32, full: u32, least: u32) -> Vec<u32> {
        let (mut left, mut out) = (total, Vec::new());
        while left > 0 {
            let b = batch_bands(left, total, full, least);
            assert!(b >= 1 && b <= left, "{b} of {left}");
            out.push(b);
            left -= b;
        }
        out
    }

    #[test]
    fn batches_cover_the_part_and_taper_at_its_end() {
        // a part within one batch: one batch
        assert_eq!(batches(32, 42, 1), vec![32]);
        // 4K: 135 bands, 22 a batch
        assert_eq!(
            batches(135, 22, 1),
            vec![22, 22, 22, 22, 22, 13, 6, 3, 2, 1]
        );
        // never under `least` bands (but the last), never over a full batch
        assert_eq!(batches(100, 30, 4), vec![30, 30, 20, 10, 5, 4, 1]);
        // `least` above a full batch: full batches
        assert_eq!(batches(10, 3, 8), vec![3, 3, 3, 1]);
        for (total, full, least) in [(1, 1, 1), (7, 2, 1), (1000, 7, 3), (64, 8, 100)] {
            let b = batches(total, full, least);
            assert_eq!(b.iter().sum::<u32>(), total);
            assert!(b.windows(2).all(|w| w[1] <= w[0]), "{b:?}");
            assert!(b.iter().all(|&n| n <= full), "{b:?}");
        }
    }
}
