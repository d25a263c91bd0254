//! The wavefront renderer (packet and wide kernels, chosen per queue): per tile, queues of rays drained stage by
//! stage, one function per stage (pbrt-v4's wavefront integrator reads the same way):
//!
//! generate_camera_rays -> intersect_closest -> handle_escaped_rays -> shade_hits
//!   -> trace_shadow_rays -> (reflection + refraction queue, repacked) -> intersect_closest ...
//!
//! Queues are SoA and tile-local (kept in one `Workspace` per worker thread and reused from
//! tile to tile), so memory does not grow with the image size.

use super::queues::{BinScratch, NO_TWIN, RayQueue, ShadowQueue};
use super::{MAX_SAMPLE_SECONDARY_RAYS, RenderStats, Settings, Terms, World, tile_end};
use crate::accel::{
    Accel, intersect_hybrid8, intersect_hybrid16, intersect_wide8, intersect8, intersect16,
    occluded_hybrid8, occluded_hybrid16, occluded_wide8, occluded8, occluded16,
};
use crate::camera::Camera;
use crate::packet::RayPacket8;
use crate::packet::{HitPacket8, PacketShape, camera_packet};
use crate::scene::Background;
use crate::shade::{Shade8, shade8_in};
use crate::simd::M32x8;
use crate::simd::{self, LANES, Vec3x8};
use crate::trace::Engine;
use crate::world::NOT_INSTANCED;
use glam::Vec3;
use std::sync::atomic::Ordering;
use std::time::Instant;

/// Sort reflection/refraction queues by direction octant and origin octant (about the
/// queue's mean origin) before packing them into packets. Measured on `refraction` 1024x768,
/// 1 thread, three alternating runs each: direction octant alone took the shadow phase from
/// 1.36-1.52 to 0.93-1.13 thread-s and the secondary phase from 1.54-1.74 to 0.97-1.20 (after
/// refraction the rays of a tile point every way; grouped, a packet's lanes share more of
/// the BVH, and so do the shadow rays from their hits); adding the origin octant took another
/// ~8% (shadow 1.02-1.10 -> 0.92-1.00, secondary 1.13-1.20 -> 1.02-1.12); octant x major
/// axis (24 bins) measured the same as the octant alone. On `phong` and `cubemap` the
/// difference is within the noise. On, from the second secondary generation: the first
/// (reflection and refraction rays of camera-ray hits) comes out of camera packets in pixel
/// order and is coherent already; binning it cost `phong` (depth 1) 5-10% for nothing, and
/// skipping it leaves `refraction` where it was (2.61-2.64 s against 2.41-2.70 s).
pub const BIN_SECONDARY: bool = true;

mod kernels;
pub use kernels::{Kernel, Kernels, auto};

/// Queues and buffers of one worker, reused from tile to tile (so a tile allocates nothing
/// once the first few tiles have grown them).
#[derive(Default)]
pub struct Workspace {
    rays: RayQueue,
    next: RayQueue,
    shadows: ShadowQueue,
    binning: BinScratch,
    hits: Vec<HitPacket8>,
    /// Per hit packet, each lane's instance ([`NOT_INSTANCED`] in a flattened world).
    insts: Vec<[u32; LANES]>,
    /// Entries of `rays` traced themselves (not twins), when some are twins.
    unique: Vec<u32>,
    /// Per entry of `rays`, the `next` entries of its reflection and refraction rays (kept
    /// only while the generation has twins).
    children: Vec<[u32; 2]>,
    /// Per entry of `rays` and light (entry-major), its shadow-queue entry (likewise).
    shadow_of: Vec<u32>,
    /// Per shadow-queue entry, whether it is occluded (when some are twins).
    occluded: Vec<bool>,
    shade: Shade8,
    /// Reflection and refraction rays spawned so far per pixel of the tile (the budget).
    tree: Vec<u32>,
    /// The tile's pixels, row-major.
    pub accum: Vec<Vec3>,
}

/// Render the tile with corner `(x0, y0)` into `ws.accum` (pixels row-major within the tile).
pub fn render_tile(
    world: &World,
    settings: &Settings,
    offsets: &[(f32, f32)],
    x0: u32,
    y0: u32,
    stats: &RenderStats,
    ws: &mut Workspace,
) {
    let camera = world.scene.camera();
    let terms = Terms::of(settings.stage);
    let depth = settings.depth(&world.scene);
    let kernels = match (&world.instanced, settings.engine) {
        // Through instances `auto` takes `wide1` for every queue: on the field of 10,000
        // kittens (docs/instances.md) it rendered in 0.6x the time of the packet kernels,
        // whose lanes part at the top level (each kitten covers a few pixels) and whose
        // instance leaves then trace a few lanes at a time.
        (Some(_), Engine::Auto) => Kernels::of(Engine::Wide),
        (_, engine) => Kernels::of(engine),
    };
    let (x1, y1) = tile_end(&camera, x0, y0);
    let Workspace {
        rays,
        next,
        shadows,
        binning,
        hits,
        insts,
        unique,
        children,
        shadow_of,
        occluded,
        shade,
        tree,
        accum,
    } = ws;
    accum.clear();
    accum.resize(((x1 - x0) * (y1 - y0)) as usize, Vec3::ZERO);
    tree.clear();
    tree.resize(accum.len(), 0);
    // per pixel, since the samples of a pixel share its queue entries
    let budget = MAX_SAMPLE_SECONDARY_RAYS.saturating_mul(offsets.len() as u32);
    rays.clear();
    next.clear();
    shadows.clear();
    let mut counts = [0u64; 6];
    let mut phase_ns = [0u64; 4];

    generate_camera_rays(&camera, offsets, (x0, y0, x1, y1), depth, rays);
    counts[0] += rays.len() as u64;
    let mut generation = 0;
    // each phase's end is the next one's start: one clock read per phase
    let mut start = Instant::now();
    let mut lap = |phase: &mut u64| {
        let now = Instant::now();
        *phase += (now - start).as_nanos() as u64;
        start = now;
    };
    while !rays.is_empty() {
        let kernel = match generation {
            0 => kernels.camera,
            1 => kernels.secondary,
            _ => kernels.secondary_later,
        };
        intersect_closest(world, kernel, rays, (hits, insts), unique);
        counts[4] += rays.twins.count() as u64;
        lap(&mut phase_ns[if generation == 0 { 0 } else { 3 }]);

        handle_escaped_rays(world, rays, hits, accum);
        let over = shade_hits(
            world,
            terms,
            rays,
            (hits, insts),
            accum,
            (shadows, shadow_of),
            (next, children),
            &mut counts,
            shade,
            (tree, budget),
        );
        lap(&mut phase_ns[1]);
        if let Some(pixel) = over {
            let tw = x1 - x0;
            stats.set_over_budget(x0 + pixel % tw, y0 + pixel / tw, camera.width);
            break; // the render has failed; the tile's pixels will not be used
        }

        counts[1] += shadows.len() as u64;
        counts[5] += shadows.twins.count() as u64;
        let kernel = if generation == 0 {
            kernels.shadow
        } else {
            kernels.shadow_later
        };
        trace_shadow_rays(world, kernel, shadows, accum, (unique, occluded));
        shadows.clear();
        lap(&mut phase_ns[2]);

        // the repacking of the next generation counts as secondary-ray time
        std::mem::swap(rays, next);
        next.clear();
        // `rays` now holds what this generation's hits spawned; the secondaries of camera-ray
        // hits (generation 0) stay in pixel order
        if BIN_SECONDARY && generation >= 1 {
            rays.bin_by_direction_and_origin(binning);
        }
        lap(&mut phase_ns[3]);
        generation += 1;
    }

    let r = &stats.rays;
    for (a, c) in [
        &r.primary,
        &r.shadow,
        &r.reflection,
        &r.refraction,
        &r.repeated,
        &r.repeated_shadow,
    ]
    .into_iter()
    .zip(counts)
    {
        a.fetch_add(c, Ordering::Relaxed);
    }
    for (a, ns) in stats.phase_ns.iter().zip(phase_ns) {
        a.fetch_add(ns, Ordering::Relaxed);
    }
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
    let weight = Vec3x8::splat([1.0 / offsets.len() as f32; 3]);
    let tw = x1 - x0;
    // Lanes inside the tile (so inside the image) and their tile-local pixels; lanes past
    // the edge get the edge pixel and are left out of the queue.
    let block = |bx: u32, by: u32| -> (u32, [u32; LANES]) {
        let mut inside = 0;
        let pixels = std::array::from_fn(|i| {
            let (dx, dy) = shape.offset(i);
            let (x, y) = (bx + dx, by + dy);
            inside |= ((x < x1 && y < y1) as u32) << i;
            (y.min(y1 - 1) - y0) * tw + (x.min(x1 - 1) - x0)
        });
        (inside, pixels)
    };
    for &(sx, sy) in offsets {
        for by in (y0..y1).step_by(ph as usize) {
            for bx in (x0..x1).step_by(pw as usize) {
                let (packet, _) = camera_packet(camera, shape, bx, by, sx, sy);
                let (inside, pixels) = block(bx, by);
                out.push_lanes(
                    inside,
                    &packet.o,
                    &packet.d,
                    pixels,
                    &weight,
                    [depth; LANES],
                    None,
                );
            }
        }
    }
}

/// Closest hits of every queued ray, 8 consecutive entries per packet; a twin takes its
/// original's hit (the same ray has the same hit: every kernel's result depends on the ray
/// alone), and the other rays are packed 8 at a time without the twins.
fn intersect_closest(
    world: &World,
    kernel: Kernel,
    rays: &RayQueue,
    (out, insts): (&mut Vec<HitPacket8>, &mut Vec<[u32; LANES]>),
    unique: &mut Vec<u32>,
) {
    let cull = world.scene.cull_backfaces;
    out.clear();
    insts.clear();
    let n = rays.len().div_ceil(LANES);
    if rays.twins.count() == 0 {
        let packet = |p: usize| rays.packet(p * LANES);
        kernel.intersect_all(world, n, packet, cull, |_, h, ids| {
            out.push(h);
            insts.push(ids);
        });
        return;
    }
    out.resize(n, HitPacket8::none());
    insts.resize(n, [NOT_INSTANCED; LANES]);
    rays.twins.originals(rays.len(), unique);
    let at = |j: u32| (j as usize / LANES, j as usize % LANES);
    let group = |p: usize| &unique[p * LANES..((p + 1) * LANES).min(unique.len())];
    let packet = |p: usize| RayPacket8::from_fn(|i| group(p).get(i).map(|&j| rays.ray(j as usize)));
    let groups = unique.len().div_ceil(LANES);
    kernel.intersect_all(world, groups, packet, cull, |p, h, ids| {
        for (i, &j) in group(p).iter().enumerate() {
            let (q, lane) = at(j);
            out[q].set_lane(lane, h.lane(i));
            insts[q][lane] = ids[i];
        }
    });
    // (an original comes before its twins, and may be a twin itself)
    for j in 0..rays.len() {
        let t = rays.twins.get(j);
        if t != NO_TWIN {
            let (p, lane) = at(t);
            let h = out[p].lane(lane);
            out[j / LANES].set_lane(j % LANES, h);
            insts[j / LANES][j % LANES] = insts[p][lane];
        }
    }
}

/// Rays that hit nothing take the background, times their weight. A cube map is looked up
/// a packet at a time: the faces and footprints of its eight directions in lanes
/// (`CubeMap::footprint8`), then each escaped lane's four texels.
fn handle_escaped_rays(world: &World, rays: &RayQueue, hits: &[HitPacket8], accum: &mut [Vec3]) {
    let cube = match &world.scene.background {
        Background::CubeMap(m) if m.faces_alike() => Some(&**m),
        _ => None,
    };
    for (p, h) in hits.iter().enumerate() {
        let start = p * LANES;
        let missed = !simd::bitmask(h.hit_mask()) & ((1u32 << (rays.len() - start).min(LANES)) - 1);
        if missed == 0 {
            continue;
        }
        let lanes = (0..LANES).filter(|&i| missed >> i & 1 == 1);
        if let Some(m) = cube {
            let footprint = m.footprint8(Vec3x8::load(&rays.d, start, 1.0));
            for i in lanes {
                let j = start + i;
                accum[rays.pixel[j] as usize] += rays.weight(j) * m.blend(&footprint, i);
            }
        } else {
            for i in lanes {
                let j = start + i;
                accum[rays.pixel[j] as usize] +=
                    rays.weight(j) * world.scene.background.sample(rays.ray(j).dir);
            }
        }
    }
}

/// Whitted's equation at every hit (`shade8`): ambient straight into the pixel, one shadow
/// ray per lit hit and light into the shadow queue, reflection and refraction rays into `next`
/// (each packet's surviving lanes appended densely: the repacking). Returns the tile pixel
/// whose reflection and refraction rays would pass `budget`, if one does.
#[allow(clippy::too_many_arguments)]
fn shade_hits(
    world: &World,
    terms: Terms,
    rays: &RayQueue,
    (hits, insts): (&[HitPacket8], &[[u32; LANES]]),
    accum: &mut [Vec3],
    (shadows, shadow_of): (&mut ShadowQueue, &mut Vec<u32>),
    (next, children): (&mut RayQueue, &mut Vec<[u32; 2]>),
    counts: &mut [u64; 6],
    shaded: &mut Shade8,
    (tree, budget): (&mut [u32], u32),
) -> Option<u32> {
    // (what twins need: per entry its children and its shadow rays, kept only when this
    // generation has twins; a scene without refraction never has any)
    let track = rays.twins.count() > 0;
    let lights = world.scene.lights.len();
    children.clear();
    shadow_of.clear();
    if track {
        children.resize(rays.len(), [NO_TWIN; 2]);
        shadow_of.resize(rays.len() * lights, NO_TWIN);
    }
    // where this packet's reflection rays went (the twins of mirror refraction rays)
    let mut reflected = (0usize, 0u32);
    for (p, h) in hits.iter().enumerate() {
        let start = p * LANES;
        let mask = h.hit_mask();
        let bits = simd::bitmask(mask);
        if bits == 0 {
            continue;
        }
        let pixel = rays.pixel_lanes(start);
        let w = rays.weight_lanes(start);
        if terms.white {
            add_lanes(accum, bits, pixel, &w);
            continue;
        }
        let (packet, _) = rays.packet(start);
        let depth = rays.depth_lanes(start);
        shade8_in(world, terms, &packet, (h, &insts[p]), mask, depth, shaded);
        let s = &*shaded;
        add_lanes(accum, bits, pixel, &w.mul_elem(s.ambient));
        for (li, l) in s.lights.iter().enumerate() {
            let lit = simd::bitmask(l.lit);
            let c = w.mul_elem(l.contribution);
            if terms.shadows {
                // a twin's hit casts its original's shadow rays (the share, and so whether
                // there is a ray, does not depend on the weight)
                let twin = track.then(|| {
                    let mut twin = [NO_TWIN; LANES];
                    for (k, i) in (0..LANES).filter(|&i| lit >> i & 1 == 1).enumerate() {
                        let j = start + i;
                        let t = rays.twins.get(j);
                        if t != NO_TWIN {
                            twin[i] = shadow_of[t as usize * lights + li];
                        }
                        shadow_of[j * lights + li] = (shadows.len() + k) as u32;
                    }
                    twin
                });
                shadows.push_lanes(lit, &l.origin, &l.dir, l.tfar, pixel, &c, twin);
            } else {
                add_lanes(accum, lit, pixel, &c);
            }
        }
        let depth = depth.map(|d| d.saturating_sub(1));
        for (sec, kind) in [(&s.reflection, 2), (&s.refraction, 3)] {
            let b = simd::bitmask(sec.mask);
            for i in (0..LANES).filter(|&i| b >> i & 1 == 1) {
                let t = &mut tree[pixel[i] as usize];
                if *t == budget {
                    return Some(pixel[i]);
                }
                *t += 1;
            }
            counts[kind] += b.count_ones() as u64;
            // twins: what a twin spawns is the twin of what its original spawned (the same
            // ray, hit and depth spawn the same rays), and a mirror refraction ray is the
            // twin of the reflection ray its hit spawned just before
            let mirror = simd::bitmask(sec.mirror);
            let twin = (track || mirror != 0).then(|| {
                let mut twin = [NO_TWIN; LANES];
                for (k, i) in (0..LANES).filter(|&i| b >> i & 1 == 1).enumerate() {
                    let j = start + i;
                    twin[i] = match rays.twins.get(j) {
                        NO_TWIN if mirror >> i & 1 == 1 => {
                            // the reflection ray of lane i: its rank among them
                            let (at, lanes) = reflected;
                            (at + (lanes & ((1 << i) - 1)).count_ones() as usize) as u32
                        }
                        NO_TWIN => NO_TWIN,
                        t => children[t as usize][kind - 2],
                    };
                    if track {
                        children[j][kind - 2] = (next.len() + k) as u32;
                    }
                }
                twin
            });
            if kind == 2 {
                reflected = (next.len(), b);
            }
            next.push_lanes(
                b,
                &sec.origin,
                &sec.dir,
                pixel,
                &w.mul_elem(sec.weight),
                depth,
                twin,
            );
        }
    }
    None
}

/// `accum[pixel[i]] += v[i]` for the lanes of `bits`.
#[inline]
fn add_lanes(accum: &mut [Vec3], bits: u32, pixel: [u32; LANES], v: &Vec3x8) {
    let v = v.to_lanes();
    for i in (0..LANES).filter(|&i| bits >> i & 1 == 1) {
        accum[pixel[i] as usize] += Vec3::new(v[0][i], v[1][i], v[2][i]);
    }
}

/// Any-hit queries for the shadow queue, 8 per packet; visible lights add their contribution.
/// A twin takes its original's answer, and the other rays are packed 8 at a time without the
/// twins; contributions are added in queue order either way.
fn trace_shadow_rays(
    world: &World,
    kernel: Kernel,
    shadows: &ShadowQueue,
    accum: &mut [Vec3],
    (unique, occluded): (&mut Vec<u32>, &mut Vec<bool>),
) {
    let cull = world.scene.cull_backfaces;
    if shadows.twins.count() > 0 {
        occluded.clear();
        occluded.resize(shadows.len(), false);
        shadows.twins.originals(shadows.len(), unique);
        let group = |p: usize| &unique[p * LANES..((p + 1) * LANES).min(unique.len())];
        let packet =
            |p: usize| RayPacket8::from_fn(|i| group(p).get(i).map(|&j| shadows.ray(j as usize)));
        let groups = unique.len().div_ceil(LANES);
        kernel.occluded_all(world, groups, packet, cull, |p, o| {
            let hit = simd::bitmask(o);
            for (i, &j) in group(p).iter().enumerate() {
                occluded[j as usize] = hit >> i & 1 == 1;
            }
        });
        for j in 0..shadows.len() {
            let t = shadows.twins.get(j);
            if t != NO_TWIN {
                occluded[j] = occluded[t as usize];
            }
            if !occluded[j] {
                accum[shadows.pixel[j] as usize] += shadows.contribution(j);
            }
        }
        return;
    }
    let n = shadows.len().div_ceil(LANES);
    let packet = |p: usize| shadows.packet(p * LANES);
    kernel.occluded_all(world, n, packet, cull, |p, occluded| {
        let start = p * LANES;
        let active = (1u32 << (shadows.len() - start).min(LANES)) - 1;
        let visible = active & !simd::bitmask(occluded);
        for i in (0..LANES).filter(|&i| visible >> i & 1 == 1) {
            let j = start + i;
            accum[shadows.pixel[j] as usize] += shadows.contribution(j);
        }
    });
}
