//! The batch and packet entries of [`Instances`]: rays in runs, 8 and 16 at a time, by engine.

use super::*;

impl Instances {
    /// Closest hits of `rays` with `engine` on the calling thread, into `out` (the same
    /// length): [`crate::trace::intersect_into`] through instances. `auto` takes the rule's
    /// first candidate for these rays ([`crate::engine::candidates`]; no pilot).
    ///
    /// # Panics
    /// If `out` is shorter than `rays`.
    pub fn intersect_into(
        &self,
        rays: &[Ray],
        engine: Engine,
        cull: bool,
        out: &mut [Option<InstHit>],
    ) {
        let engine = self.concrete(engine, rays);
        let out = &mut out[..rays.len()];
        match engine {
            Engine::Scalar | Engine::Wide => {
                let f = if engine == Engine::Scalar {
                    intersect1
                } else {
                    intersect_wide1
                };
                let mut stack = Vec::with_capacity(2 * self.depth + 2);
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = self.walk1::<false>(r, &mut stack, |a, r| f(a, r, cull));
                }
            }
            Engine::Packet16 | Engine::Hybrid16 => {
                let f = if engine == Engine::Hybrid16 {
                    intersect_hybrid16
                } else {
                    intersect16
                };
                let mut stack = Vec::new();
                for (group, o) in rays.chunks(16).zip(out.chunks_mut(16)) {
                    let active = (1u32 << group.len()) - 1;
                    self.intersect_group(group, active, &mut stack, o, |a, object| {
                        let [(p0, m0), (p1, m1)] = packets(object);
                        let h = f(a, [&p0, &p1], [m0, m1], cull);
                        std::array::from_fn(|k| h[k / 8].lane(k % 8))
                    });
                }
            }
            // (`concrete` resolved `auto`)
            Engine::Auto | Engine::Packet | Engine::Hybrid => {
                let f = if engine == Engine::Hybrid {
                    intersect_hybrid8
                } else {
                    intersect8
                };
                let mut stack = Vec::new();
                for (group, o) in rays.chunks(8).zip(out.chunks_mut(8)) {
                    let active = (1u32 << group.len()) - 1;
                    self.intersect_group(group, active, &mut stack, o, |a, object| {
                        let [(p, m), _] = packets(object);
                        let h = f(a, &p, m, cull);
                        std::array::from_fn(|k| if k < 8 { h.lane(k) } else { None })
                    });
                }
            }
        }
    }

    /// Whether each of `rays` is blocked (any hit), with `engine` on the calling thread, into
    /// `out` (the same length): [`Instances::intersect_into`]'s twin.
    ///
    /// # Panics
    /// If `out` is shorter than `rays`.
    pub fn occluded_into(&self, rays: &[Ray], engine: Engine, cull: bool, out: &mut [bool]) {
        let engine = self.concrete(engine, rays);
        let out = &mut out[..rays.len()];
        match engine {
            Engine::Scalar | Engine::Wide => {
                let f = if engine == Engine::Scalar {
                    occluded1
                } else {
                    occluded_wide1
                };
                let mut stack = Vec::with_capacity(2 * self.depth + 2);
                for (o, r) in out.iter_mut().zip(rays) {
                    *o = self
                        .walk1::<true>(r, &mut stack, |a, r| {
                            f(a, r, cull).then_some(Hit {
                                tri: 0,
                                t: 0.0,
                                b1: 0.0,
                                b2: 0.0,
                            })
                        })
                        .is_some();
                }
            }
            Engine::Packet16 | Engine::Hybrid16 => {
                let f = if engine == Engine::Hybrid16 {
                    occluded_hybrid16
                } else {
                    occluded16
                };
                let mut stack = Vec::new();
                for (group, o) in rays.chunks(16).zip(out.chunks_mut(16)) {
                    let active = (1u32 << group.len()) - 1;
                    let m = self.occluded_group(group, active, &mut stack, |a, object| {
                        let [(p0, m0), (p1, m1)] = packets(object);
                        let [b0, b1] = f(a, [&p0, &p1], [m0, m1], cull).map(simd::bitmask);
                        b0 | b1 << 8
                    });
                    for (i, o) in o.iter_mut().enumerate() {
                        *o = m >> i & 1 == 1;
                    }
                }
            }
            Engine::Auto | Engine::Packet | Engine::Hybrid => {
                let f = if engine == Engine::Hybrid {
                    occluded_hybrid8
                } else {
                    occluded8
                };
                let mut stack = Vec::new();
                for (group, o) in rays.chunks(8).zip(out.chunks_mut(8)) {
                    let active = (1u32 << group.len()) - 1;
                    let m = self.occluded_group(group, active, &mut stack, |a, object| {
                        let [(p, m), _] = packets(object);
                        simd::bitmask(f(a, &p, m, cull))
                    });
                    for (i, o) in o.iter_mut().enumerate() {
                        *o = m >> i & 1 == 1;
                    }
                }
            }
        }
    }

    /// Closest hits of `rays`, in parallel, in input order ([`crate::trace::trace_rays`]
    /// through instances).
    pub fn trace_rays(&self, rays: &[Ray], engine: Engine, cull: bool) -> Vec<Option<InstHit>> {
        let engine = self.concrete(engine, rays);
        let mut out = vec![None; rays.len()];
        out.par_chunks_mut(CHUNK)
            .zip(rays.par_chunks(CHUNK))
            .for_each(|(o, r)| self.intersect_into(r, engine, cull, o));
        out
    }

    /// Whether each of `rays` is blocked, in parallel, in input order.
    pub fn occluded_rays(&self, rays: &[Ray], engine: Engine, cull: bool) -> Vec<bool> {
        let engine = self.concrete(engine, rays);
        let mut out = vec![false; rays.len()];
        out.par_chunks_mut(CHUNK)
            .zip(rays.par_chunks(CHUNK))
            .for_each(|(o, r)| self.occluded_into(r, engine, cull, o));
        out
    }

    /// Closest hits of one packet of 8 (the renderer's queues): the hits with the mesh's own
    /// triangle ids, and the instance of each lane that hit. `bottom` is the 8-ray entry
    /// point (`intersect8`, `intersect_hybrid8`), or `None` for `wide1` lane by lane.
    pub fn intersect_packet8(
        &self,
        rays: &RayPacket8,
        active: M32x8,
        cull: bool,
        bottom: Option<Bottom8>,
    ) -> (HitPacket8, [u32; 8]) {
        let group: [Ray; 8] = std::array::from_fn(|i| rays.lane(i));
        let bits = simd::bitmask(active);
        let mut out = [None; 8];
        let mut stack = Vec::new();
        match bottom {
            Some(f) => self.intersect_group(&group, bits, &mut stack, &mut out, |a, object| {
                let [(p, m), _] = packets(object);
                let h = f(a, &p, m, cull);
                std::array::from_fn(|k| if k < 8 { h.lane(k) } else { None })
            }),
            None => {
                let mut s = Vec::new();
                for i in (0..8).filter(|&i| bits >> i & 1 == 1) {
                    out[i] =
                        self.walk1::<false>(&group[i], &mut s, |a, r| intersect_wide1(a, r, cull));
                }
            }
        }
        let mut hits = HitPacket8::none();
        let mut insts = [u32::MAX; 8];
        for (i, h) in out.iter().enumerate() {
            if let Some(h) = h {
                hits.set_lane(i, Some(h.hit));
                insts[i] = h.inst;
            }
        }
        (hits, insts)
    }

    /// Occluded lanes of one packet of 8 ([`Instances::intersect_packet8`]'s twin).
    pub fn occluded_packet8(
        &self,
        rays: &RayPacket8,
        active: M32x8,
        cull: bool,
        bottom: Option<Occluded8>,
    ) -> M32x8 {
        let group: [Ray; 8] = std::array::from_fn(|i| rays.lane(i));
        let bits = simd::bitmask(active);
        let mut stack = Vec::new();
        let blocked = match bottom {
            Some(f) => self.occluded_group(&group, bits, &mut stack, |a, object| {
                let [(p, m), _] = packets(object);
                simd::bitmask(f(a, &p, m, cull))
            }),
            None => {
                let mut s = Vec::new();
                let mut b = 0;
                for i in (0..8).filter(|&i| bits >> i & 1 == 1) {
                    let hit = self.walk1::<true>(&group[i], &mut s, |a, r| {
                        occluded_wide1(a, r, cull).then_some(Hit {
                            tri: 0,
                            t: 0.0,
                            b1: 0.0,
                            b2: 0.0,
                        })
                    });
                    b |= (hit.is_some() as u32) << i;
                }
                b
            }
        };
        simd::mask_from_bits(blocked)
    }

    /// Closest hits of two packets of 8 as one group of 16, through a 16-ray entry point
    /// (`intersect16`, `intersect_hybrid16`).
    pub fn intersect_pair16(
        &self,
        rays: [&RayPacket8; 2],
        active: [M32x8; 2],
        cull: bool,
        bottom: Bottom16,
    ) -> [(HitPacket8, [u32; 8]); 2] {
        let group: [Ray; 16] = std::array::from_fn(|i| rays[i / 8].lane(i % 8));
        let bits = simd::bitmask(active[0]) | simd::bitmask(active[1]) << 8;
        let mut out = [None; 16];
        self.intersect_group(&group, bits, &mut Vec::new(), &mut out, |a, object| {
            let [(p0, m0), (p1, m1)] = packets(object);
            let h = bottom(a, [&p0, &p1], [m0, m1], cull);
            std::array::from_fn(|k| h[k / 8].lane(k % 8))
        });
        std::array::from_fn(|half| {
            let mut hits = HitPacket8::none();
            let mut insts = [u32::MAX; 8];
            for i in 0..8 {
                if let Some(h) = out[8 * half + i] {
                    hits.set_lane(i, Some(h.hit));
                    insts[i] = h.inst;
                }
            }
            (hits, insts)
        })
    }

    /// Occluded lanes of two packets of 8 as one group of 16 ([`Instances::intersect_pair16`]'s
    /// twin).
    pub fn occluded_pair16(
        &self,
        rays: [&RayPacket8; 2],
        active: [M32x8; 2],
        cull: bool,
        bottom: Occluded16,
    ) -> [M32x8; 2] {
        let group: [Ray; 16] = std::array::from_fn(|i| rays[i / 8].lane(i % 8));
        let bits = simd::bitmask(active[0]) | simd::bitmask(active[1]) << 8;
        let m = self.occluded_group(&group, bits, &mut Vec::new(), |a, object| {
            let [(p0, m0), (p1, m1)] = packets(object);
            let [b0, b1] = bottom(a, [&p0, &p1], [m0, m1], cull).map(simd::bitmask);
            b0 | b1 << 8
        });
        [simd::mask_from_bits(m & 0xff), simd::mask_from_bits(m >> 8)]
    }

    /// `engine`, or for `auto` the rule's first candidate for `rays` over the scene's box.
    fn concrete(&self, engine: Engine, rays: &[Ray]) -> Engine {
        if engine != Engine::Auto {
            return engine;
        }
        let diagonal = self.bounds().map_or(0.0, |(lo, hi)| (hi - lo).length());
        crate::engine::candidates(
            crate::engine::spread(rays, diagonal),
            crate::accel::packet16::available(),
        )
        .first()
    }
}

/// An 8-ray closest-hit entry point (`intersect8`, `intersect_hybrid8`).
pub type Bottom8 = fn(&Accel, &RayPacket8, M32x8, bool) -> HitPacket8;
/// An 8-ray any-hit entry point (`occluded8`, `occluded_hybrid8`).
pub type Occluded8 = fn(&Accel, &RayPacket8, M32x8, bool) -> M32x8;
/// A 16-ray closest-hit entry point (`intersect16`, `intersect_hybrid16`).
pub type Bottom16 = fn(&Accel, [&RayPacket8; 2], [M32x8; 2], bool) -> [HitPacket8; 2];
/// A 16-ray any-hit entry point (`occluded16`, `occluded_hybrid16`).
pub type Occluded16 = fn(&Accel, [&RayPacket8; 2], [M32x8; 2], bool) -> [M32x8; 2];

/// Rays per parallel work item (a multiple of 16).
const CHUNK: usize = 4096;

/// Up to 16 object-space rays as two packets of 8 (missing lanes inactive).
#[inline(always)]
fn packets(object: &[Option<Ray>; 16]) -> [(RayPacket8, M32x8); 2] {
    std::array::from_fn(|h| RayPacket8::from_fn(|i| object[8 * h + i]))
}
