//! Tracing bare ray batches (no shading) with either engine: `whitted trace-rays`, benches.

use crate::accel::{Accel, intersect1, intersect8};
use crate::packet::RayPacket8;
use crate::ray::{Hit, Ray};
use rayon::prelude::*;

/// Which traversal to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Engine {
    /// `intersect8` on packets of 8 consecutive rays.
    Packet,
    /// `intersect1` ray by ray (the reference).
    Scalar,
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
                Engine::Packet => {
                    for group in chunk.chunks(8) {
                        let (packet, active) = RayPacket8::from_fn(|i| group.get(i).copied());
                        let hits = intersect8(accel, &packet, active, cull);
                        out.extend((0..group.len()).map(|i| hits.lane(i)));
                    }
                }
            }
            out
        })
        .collect()
}
