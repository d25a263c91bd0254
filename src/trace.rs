//! Tracing bare ray batches (no shading) with either engine: `whitted trace-rays`, benches.

use crate::accel::{
    Accel, intersect_hybrid8, intersect_hybrid16, intersect_wide1, intersect1, intersect8,
    intersect16,
};
use crate::packet::RayPacket8;
use crate::ray::{Hit, Ray};
use rayon::prelude::*;

/// Which traversal to use. Every engine returns the same hits bit for bit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Engine {
    /// The fastest kernel per kind of ray, chosen by measurement: in the renderer per queue
    /// (`render::wavefront::auto`), for bare ray batches `packet`.
    #[default]
    Auto,
    /// `intersect8` on packets of 8 consecutive rays over the binary tree.
    Packet,
    /// `intersect_wide1` ray by ray over the 8-wide tree.
    Wide,
    /// `intersect_hybrid8`: packets of 8 over the binary tree that hand their last few
    /// lanes to single-ray traversal of the 8-wide tree.
    Hybrid,
    /// `intersect16` on packets of 16 consecutive rays over the binary tree (AVX-512; two
    /// `intersect8` calls on a CPU without it).
    Packet16,
    /// `intersect_hybrid16`: 16-ray packets down the 8-wide tree together when their lanes
    /// share a direction octant, else down the binary tree, each lane alone down the 8-wide
    /// tree once few remain (AVX-512; two `intersect_hybrid8` calls without it).
    Hybrid16,
    /// `intersect1` ray by ray over the binary tree (the reference).
    Scalar,
}

impl Engine {
    /// Every engine, by name.
    pub const ALL: [Engine; 7] = [
        Engine::Auto,
        Engine::Packet,
        Engine::Wide,
        Engine::Hybrid,
        Engine::Packet16,
        Engine::Hybrid16,
        Engine::Scalar,
    ];

    /// The engine's name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Engine::Auto => "auto",
            Engine::Packet => "packet",
            Engine::Wide => "wide",
            Engine::Hybrid => "hybrid",
            Engine::Packet16 => "packet16",
            Engine::Hybrid16 => "hybrid16",
            Engine::Scalar => "scalar",
        }
    }

    /// The engine called `name`.
    pub fn from_name(name: &str) -> Option<Engine> {
        Engine::ALL.into_iter().find(|e| e.name() == name)
    }
}

/// Rays per parallel work item (a multiple of 8).
const CHUNK: usize = 4096;

/// Closest hits of `rays`, in parallel, in input order.
pub fn trace_rays(accel: &Accel, rays: &[Ray], engine: Engine, cull: bool) -> Vec<Option<Hit>> {
    rays.par_chunks(CHUNK)
        .flat_map_iter(|chunk| {
            let mut out = Vec::with_capacity(chunk.len());
            match engine {
                Engine::Scalar => out.extend(chunk.iter().map(|r| intersect1(accel, r, cull))),
                Engine::Wide => {
                    out.extend(chunk.iter().map(|r| intersect_wide1(accel, r, cull)));
                }
                Engine::Packet16 | Engine::Hybrid16 => {
                    let f = if engine == Engine::Hybrid16 {
                        intersect_hybrid16
                    } else {
                        intersect16
                    };
                    for group in chunk.chunks(16) {
                        let (lo, hi) = group.split_at(group.len().min(8));
                        let (p0, a0) = RayPacket8::from_fn(|i| lo.get(i).copied());
                        let (p1, a1) = RayPacket8::from_fn(|i| hi.get(i).copied());
                        let hits = f(accel, [&p0, &p1], [a0, a1], cull);
                        out.extend((0..group.len()).map(|i| hits[i / 8].lane(i % 8)));
                    }
                }
                Engine::Auto | Engine::Packet | Engine::Hybrid => {
                    let f = if engine == Engine::Hybrid {
                        intersect_hybrid8
                    } else {
                        intersect8
                    };
                    for group in chunk.chunks(8) {
                        let (packet, active) = RayPacket8::from_fn(|i| group.get(i).copied());
                        let hits = f(accel, &packet, active, cull);
                        out.extend((0..group.len()).map(|i| hits.lane(i)));
                    }
                }
            }
            out
        })
        .collect()
}
