//! AOV layers over a rectangle of the image (the streamed writer's bands, and the whole image
//! for [`crate::aov::capture`]): 4x2 camera packets on the image's grid through `intersect8`,
//! then the scalar `surface` per hit lane, so every pixel is the same, bit for bit, whatever
//! rectangle it is captured in.

use crate::accel::intersect8;
use crate::aov::{Aov, AovImages};
use crate::image::PixelBounds;
use crate::packet::{PacketShape, camera_packet};
use crate::shade::surface_in;
use crate::simd::{self, LANES};
use crate::world::{NOT_INSTANCED, World};
use glam::Vec3;
use rayon::prelude::*;

/// Capture `aovs` over `part` of the world's camera image (pairs of rows in parallel), into
/// images of the part's size.
pub fn capture_part(world: &World, aovs: &[Aov], part: PixelBounds) -> AovImages {
    let cam = world.scene.camera();
    let (w, h) = (part.width() as usize, part.height() as usize);
    let cull = world.scene.cull_backfaces;
    #[derive(Clone, Copy)]
    struct Px {
        albedo: Vec3,
        normal: Vec3,
        depth: f32,
        id: u32,
    }
    let miss = Px {
        albedo: Vec3::ZERO,
        normal: Vec3::ZERO,
        depth: f32::INFINITY,
        id: u32::MAX,
    };
    let mut pixels = vec![miss; w * h];
    // the pairs of image rows (from an even row) and the 4-pixel columns that meet the part
    let (py0, px0) = (part.y0 & !1, part.x0 & !3);
    let first_pair = (part.y0 - py0) as usize; // part rows in the first pair's upper row: 0 or 1
    let mut chunks: Vec<(u32, &mut [Px])> = Vec::new();
    let mut rest = pixels.as_mut_slice();
    let mut y = py0;
    while !rest.is_empty() {
        let rows = if y == py0 { 2 - first_pair } else { 2 };
        let n = (rows * w).min(rest.len());
        let (head, tail) = rest.split_at_mut(n);
        chunks.push((y, head));
        rest = tail;
        y += 2;
    }
    chunks.into_par_iter().for_each(|(y0, rows)| {
        for x0 in (px0..part.x1).step_by(4) {
            let (packet, active) = camera_packet(&cam, PacketShape::Block4x2, x0, y0, 0.5, 0.5);
            let (hits, insts) = match &world.instanced {
                None => (
                    intersect8(&world.accel, &packet, active, cull),
                    [NOT_INSTANCED; LANES],
                ),
                Some(i) => (i.tracer).intersect_packet8(&packet, active, cull, Some(intersect8)),
            };
            for i in (0..LANES).filter(|&i| simd::lane_set(active, i)) {
                let (dx, dy) = PacketShape::Block4x2.offset(i);
                let (x, y) = (x0 + dx, y0 + dy);
                if !(part.x0..part.x1).contains(&x) || !(part.y0..part.y1).contains(&y) {
                    continue;
                }
                let Some(hit) = hits.lane(i) else { continue };
                let ray = packet.lane(i);
                let s = surface_in(world, &ray, &hit, insts[i]);
                let m = &world.scene.materials[s.material as usize];
                // row of `y` within this chunk (the chunk starts at part row max(y0, part.y0))
                let r = (y - y0.max(part.y0)) as usize;
                rows[r * w + (x - part.x0) as usize] = Px {
                    albedo: s.od * m.kd,
                    normal: s.n,
                    depth: hit.t * ray.dir.length(),
                    id: world.global_id(hit.tri, insts[i]),
                };
            }
        }
    });
    let want = |a: Aov| aovs.contains(&a);
    AovImages {
        width: w,
        height: h,
        albedo: want(Aov::Albedo).then(|| pixels.iter().map(|p| p.albedo).collect()),
        normal: want(Aov::Normal).then(|| pixels.iter().map(|p| p.normal).collect()),
        depth: want(Aov::Depth).then(|| pixels.iter().map(|p| p.depth).collect()),
        id: want(Aov::Id).then(|| pixels.iter().map(|p| p.id).collect()),
    }
}
