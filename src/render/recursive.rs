//! The scalar reference renderer: `trace1(ray, depth)` recursion over `intersect1` / `occluded1`
//! (through instances when the scene has them: `World::intersect1`).

use super::{MAX_SAMPLE_SECONDARY_RAYS, RenderStats, Settings, Terms, World, tile_end};
use crate::ray::Ray;
use crate::shade::{SecondaryKind, shade1};
use glam::Vec3;
use std::sync::atomic::Ordering;

/// Colour seen along `ray` with `depth` bounces left. `budget` is what the camera sample may
/// still spawn in reflection and refraction rays; when a ray would pass it, the sample is
/// abandoned (`budget` becomes `None`) and so is the render (`MAX_SAMPLE_SECONDARY_RAYS`).
pub fn trace1(
    world: &World,
    terms: Terms,
    ray: &Ray,
    depth: u32,
    counts: &mut [u64; 4],
    budget: &mut Option<u32>,
) -> Vec3 {
    let Some((hit, inst)) = world.intersect1(ray) else {
        return world.scene.background.sample(ray.dir);
    };
    if terms.white {
        return Vec3::ONE;
    }
    let (mut color, secondaries) = shade1(world, terms, ray, (&hit, inst), depth, &mut counts[1]);
    for s in secondaries.into_iter().flatten() {
        match budget {
            Some(0) | None => {
                *budget = None;
                return color;
            }
            Some(b) => *b -= 1,
        }
        counts[2 + (s.kind == SecondaryKind::Refraction) as usize] += 1;
        color += s.weight * trace1(world, terms, &s.ray, depth - 1, counts, budget);
    }
    color
}

/// Render the tile with top-left corner `(x0, y0)`; pixels row-major within the tile.
pub fn render_tile(
    world: &World,
    settings: &Settings,
    offsets: &[(f32, f32)],
    x0: u32,
    y0: u32,
    stats: &RenderStats,
) -> Vec<Vec3> {
    let camera = world.scene.camera();
    let terms = Terms::of(settings.stage);
    let depth = settings.depth(&world.scene);
    let (x1, y1) = tile_end(&camera, x0, y0);
    let mut counts = [0u64; 4];
    let mut out = Vec::with_capacity(((x1 - x0) * (y1 - y0)) as usize);
    let scale = 1.0 / offsets.len() as f32;
    for j in y0..y1 {
        for i in x0..x1 {
            let mut c = Vec3::ZERO;
            for &(dx, dy) in offsets {
                let ray = camera.ray_at(i as f32 + dx, j as f32 + dy);
                counts[0] += 1;
                let mut budget = Some(MAX_SAMPLE_SECONDARY_RAYS);
                c += trace1(world, terms, &ray, depth, &mut counts, &mut budget);
                if budget.is_none() {
                    stats.set_over_budget(i, j, camera.width);
                }
            }
            out.push(c * scale);
        }
    }
    let rays = &stats.rays;
    for (a, c) in [
        &rays.primary,
        &rays.shadow,
        &rays.reflection,
        &rays.refraction,
    ]
    .into_iter()
    .zip(counts)
    {
        a.fetch_add(c, Ordering::Relaxed);
    }
    out
}
