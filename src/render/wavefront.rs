//! The wavefront renderer on the packet engine: per tile, queues of rays drained stage by
//! stage, one function per stage (pbrt-v4's wavefront integrator reads the same way):
//!
//! generate_camera_rays -> intersect_closest -> handle_escaped_rays -> shade_hits
//!   -> trace_shadow_rays -> (reflection + refraction queue, repacked) -> intersect_closest ...
//!
//! Queues are SoA and tile-local, so memory does not grow with the image size.

use super::queues::{RayQueue, ShadowQueue};
use super::{RenderStats, Settings, TILE, Terms, World};
use crate::accel::{intersect8, occluded8};
use crate::camera::Camera;
use crate::packet::{HitPacket8, PacketShape};
use crate::shade::{SecondaryKind, shade8};
use crate::simd::{self, LANES};
use glam::Vec3;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Sort reflection/refraction queues by direction octant before packing them into packets.
/// Measured on `refraction` at 1024x768: see the README ("Wavefront renderer").
pub const BIN_SECONDARY: bool = true;

/// Render the tile with corner `(x0, y0)`; pixels row-major within the tile.
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
    let (x1, y1) = (
        (x0 + TILE).min(camera.width),
        (y0 + TILE).min(camera.height),
    );
    let mut accum = vec![Vec3::ZERO; ((x1 - x0) * (y1 - y0)) as usize];
    let (mut rays, mut next, mut shadows) = (
        RayQueue::default(),
        RayQueue::default(),
        ShadowQueue::default(),
    );
    let mut counts = [0u64; 4];
    let mut phase_ns = [0u64; 4];

    generate_camera_rays(&camera, offsets, (x0, y0, x1, y1), depth, &mut rays);
    counts[0] += rays.len() as u64;
    let mut generation = 0;
    while !rays.is_empty() {
        let start = Instant::now();
        let hits = intersect_closest(world, &rays);
        phase_ns[if generation == 0 { 0 } else { 3 }] += start.elapsed().as_nanos() as u64;

        let start = Instant::now();
        handle_escaped_rays(world, &rays, &hits, &mut accum);
        shade_hits(
            world,
            terms,
            &rays,
            &hits,
            &mut accum,
            &mut shadows,
            &mut next,
            &mut counts,
        );
        phase_ns[1] += start.elapsed().as_nanos() as u64;

        let start = Instant::now();
        counts[1] += shadows.len() as u64;
        trace_shadow_rays(world, &shadows, &mut accum);
        shadows.clear();
        phase_ns[2] += start.elapsed().as_nanos() as u64;

        std::mem::swap(&mut rays, &mut next);
        next.clear();
        if BIN_SECONDARY {
            rays.bin_by_octant();
        }
        generation += 1;
    }

    let r = &stats.rays;
    for (a, c) in [&r.primary, &r.shadow, &r.reflection, &r.refraction]
        .into_iter()
        .zip(counts)
    {
        a.fetch_add(c, Ordering::Relaxed);
    }
    for (a, ns) in stats.phase_ns.iter().zip(phase_ns) {
        a.fetch_add(ns, Ordering::Relaxed);
    }
    accum
}

/// Camera rays of the tile `(x0, y0, x1, y1)` for every sample offset, in 4x2 pixel blocks so
/// that each packet of 8 consecutive entries is a camera packet of neighbouring pixels.
fn generate_camera_rays(
    camera: &Camera,
    offsets: &[(f32, f32)],
    (x0, y0, x1, y1): (u32, u32, u32, u32),
    depth: u32,
    out: &mut RayQueue,
) {
    let shape = PacketShape::Block4x2;
    let (pw, ph) = shape.size();
    let weight = Vec3::splat(1.0 / offsets.len() as f32);
    let tw = x1 - x0;
    for &(sx, sy) in offsets {
        for by in (y0..y1).step_by(ph as usize) {
            for bx in (x0..x1).step_by(pw as usize) {
                for i in 0..LANES {
                    let (dx, dy) = shape.offset(i);
                    let (x, y) = (bx + dx, by + dy);
                    if x < x1 && y < y1 {
                        let pixel = (y - y0) * tw + (x - x0);
                        out.push(
                            &camera.ray_at(x as f32 + sx, y as f32 + sy),
                            pixel,
                            weight,
                            depth,
                        );
                    }
                }
            }
        }
    }
}

/// Closest hits of every queued ray, 8 consecutive entries per packet.
fn intersect_closest(world: &World, rays: &RayQueue) -> Vec<HitPacket8> {
    (0..rays.len())
        .step_by(LANES)
        .map(|start| {
            let (packet, active) = rays.packet(start);
            intersect8(&world.accel, &packet, active, world.scene.cull_backfaces)
        })
        .collect()
}

/// Rays that hit nothing take the background, times their weight.
fn handle_escaped_rays(world: &World, rays: &RayQueue, hits: &[HitPacket8], accum: &mut [Vec3]) {
    for (p, h) in hits.iter().enumerate() {
        for i in 0..LANES {
            let j = p * LANES + i;
            if j < rays.len() && h.lane(i).is_none() {
                accum[rays.pixel[j] as usize] +=
                    rays.weight(j) * world.scene.background.sample(rays.ray(j).dir);
            }
        }
    }
}

/// Whitted's equation at every hit (`shade8`): ambient straight into the pixel, one shadow
/// ray per lit hit and light into the shadow queue, reflection and refraction rays into `next`.
#[allow(clippy::too_many_arguments)]
fn shade_hits(
    world: &World,
    terms: Terms,
    rays: &RayQueue,
    hits: &[HitPacket8],
    accum: &mut [Vec3],
    shadows: &mut ShadowQueue,
    next: &mut RayQueue,
    counts: &mut [u64; 4],
) {
    for (p, h) in hits.iter().enumerate() {
        let start = p * LANES;
        let mask = h.hit_mask();
        if simd::none(mask) {
            continue;
        }
        let lanes: Vec<usize> = (0..LANES).filter(|&i| simd::lane_set(mask, i)).collect();
        if terms.white {
            for &i in &lanes {
                accum[rays.pixel[start + i] as usize] += rays.weight(start + i);
            }
            continue;
        }
        let (packet, _) = rays.packet(start);
        let depth = std::array::from_fn(|i| rays.depth.get(start + i).copied().unwrap_or(0));
        let s = shade8(world, terms, &packet, h, mask, depth);
        for &i in &lanes {
            let j = start + i;
            let (pixel, w) = (rays.pixel[j], rays.weight(j));
            accum[pixel as usize] += w * Vec3::from(s.ambient.lane(i));
            for l in &s.lights {
                if !simd::lane_set(l.lit, i) {
                    continue;
                }
                let c = w * Vec3::from(l.contribution.lane(i));
                if terms.shadows {
                    shadows.push(
                        l.origin.lane(i),
                        l.dir.lane(i),
                        simd::lanes(l.tfar)[i],
                        pixel,
                        c.to_array(),
                    );
                } else {
                    accum[pixel as usize] += c;
                }
            }
            for sec in s.secondaries[i].iter().flatten() {
                counts[2 + (sec.kind == SecondaryKind::Refraction) as usize] += 1;
                next.push(&sec.ray, pixel, w * sec.weight, depth[i] - 1);
            }
        }
    }
}

/// Any-hit queries for the shadow queue, 8 per packet; visible lights add their contribution.
fn trace_shadow_rays(world: &World, shadows: &ShadowQueue, accum: &mut [Vec3]) {
    for start in (0..shadows.len()).step_by(LANES) {
        let (packet, active) = shadows.packet(start);
        let occluded = occluded8(&world.accel, &packet, active, world.scene.cull_backfaces);
        for i in 0..LANES {
            let j = start + i;
            if j < shadows.len() && !simd::lane_set(occluded, i) {
                let c = Vec3::new(
                    shadows.contribution[0][j],
                    shadows.contribution[1][j],
                    shadows.contribution[2][j],
                );
                accum[shadows.pixel[j] as usize] += c;
            }
        }
    }
}
