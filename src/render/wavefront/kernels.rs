//! Which kernel traces each of the wavefront's queues: the engines as packet kernels
//! (`Kernel`), a choice per queue (`Kernels`), and `auto`'s choices.

use super::*;

/// How a queue's packets are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kernel {
    /// `intersect8` / `occluded8`: the 8 rays together down the binary tree.
    Packet,
    /// `intersect_wide1` / `occluded_wide1` lane by lane down the 8-wide tree.
    Wide,
    /// `intersect_hybrid8` / `occluded_hybrid8`: together while the lanes agree, then alone.
    Hybrid,
    /// `intersect16` / `occluded16`: two packets as one of 16 rays (AVX-512; else two
    /// packet calls).
    Packet16,
    /// `intersect_hybrid16` / `occluded_hybrid16`: two packets as one hybrid packet of 16
    /// (down the wide tree together when they share an octant, as binned queues mostly do).
    Hybrid16,
}

impl Kernel {
    #[inline]
    fn intersect(self, accel: &Accel, p: &RayPacket8, active: M32x8, cull: bool) -> HitPacket8 {
        match self {
            Kernel::Packet | Kernel::Packet16 => intersect8(accel, p, active, cull),
            Kernel::Wide => intersect_wide8(accel, p, active, cull),
            Kernel::Hybrid | Kernel::Hybrid16 => intersect_hybrid8(accel, p, active, cull),
        }
    }
    #[inline]
    fn occluded(self, accel: &Accel, p: &RayPacket8, active: M32x8, cull: bool) -> M32x8 {
        match self {
            Kernel::Packet | Kernel::Packet16 => occluded8(accel, p, active, cull),
            Kernel::Wide => occluded_wide8(accel, p, active, cull),
            Kernel::Hybrid | Kernel::Hybrid16 => occluded_hybrid8(accel, p, active, cull),
        }
    }
    /// Closest hits of packets `0..n` (`packet(p)` builds the `p`-th), handed to
    /// `out(p, hits, instances)` in order: the 16-ray kernels take two packets at a time, the
    /// others one (their loop as before the 16-ray kernels: a loop over pairs cost `phong`'s
    /// camera phase 9% and its shadow phase 4%). Through instances when the world has them
    /// (each lane's instance, else [`NOT_INSTANCED`]). Kept out of line: inlined into the
    /// tile loop it cost `refraction`'s shade phase 20% (code of the shading fell out of
    /// line).
    #[inline(never)]
    pub(super) fn intersect_all(
        self,
        world: &World,
        n: usize,
        packet: impl Fn(usize) -> (RayPacket8, M32x8),
        cull: bool,
        mut out: impl FnMut(usize, HitPacket8, [u32; LANES]),
    ) {
        let accel = &world.accel;
        let two: Option<Pair16<HitPacket8>> = match self {
            Kernel::Packet16 => Some(intersect16),
            Kernel::Hybrid16 => Some(intersect_hybrid16),
            _ => None,
        };
        if let Some(i) = &world.instanced {
            let t = &i.tracer;
            let one = |q: &RayPacket8, m| t.intersect_packet8(q, m, cull, self.bottom8());
            let Some(two) = two else {
                for p in 0..n {
                    let (q, m) = packet(p);
                    let (h, ids) = one(&q, m);
                    out(p, h, ids);
                }
                return;
            };
            for p in (0..n).step_by(2) {
                let a = packet(p);
                if p + 1 < n {
                    let b = packet(p + 1);
                    let [(h0, i0), (h1, i1)] =
                        t.intersect_pair16([&a.0, &b.0], [a.1, b.1], cull, two);
                    out(p, h0, i0);
                    out(p + 1, h1, i1);
                } else {
                    let (h, ids) = one(&a.0, a.1);
                    out(p, h, ids);
                }
            }
            return;
        }
        let one = |q: &RayPacket8, m| self.intersect(accel, q, m, cull);
        each_packet(accel, cull, n, packet, one, two, |p, h| {
            out(p, h, [NOT_INSTANCED; LANES])
        });
    }
    /// Occluded lanes of packets `0..n`, handed to `out(p, occluded)` in order (as
    /// [`Kernel::intersect_all`]).
    #[inline(never)]
    pub(super) fn occluded_all(
        self,
        world: &World,
        n: usize,
        packet: impl Fn(usize) -> (RayPacket8, M32x8),
        cull: bool,
        out: impl FnMut(usize, M32x8),
    ) {
        let accel = &world.accel;
        let two: Option<Pair16<M32x8>> = match self {
            Kernel::Packet16 => Some(occluded16),
            Kernel::Hybrid16 => Some(occluded_hybrid16),
            _ => None,
        };
        if let Some(i) = &world.instanced {
            let t = &i.tracer;
            let one = |q: &RayPacket8, m| t.occluded_packet8(q, m, cull, self.occluded8());
            let mut out = out;
            for p in (0..n).step_by(if two.is_some() { 2 } else { 1 }) {
                let a = packet(p);
                match two {
                    Some(f) if p + 1 < n => {
                        let b = packet(p + 1);
                        let [r0, r1] = t.occluded_pair16([&a.0, &b.0], [a.1, b.1], cull, f);
                        out(p, r0);
                        out(p + 1, r1);
                    }
                    _ => out(p, one(&a.0, a.1)),
                }
            }
            return;
        }
        let one = |q: &RayPacket8, m| self.occluded(accel, q, m, cull);
        each_packet(accel, cull, n, packet, one, two, out);
    }
    /// The 8-ray closest-hit entry point each instance's lanes go through (`None`: `wide1`
    /// lane by lane).
    fn bottom8(self) -> Option<crate::instance::Bottom8> {
        match self {
            Kernel::Packet | Kernel::Packet16 => Some(intersect8),
            Kernel::Wide => None,
            Kernel::Hybrid | Kernel::Hybrid16 => Some(intersect_hybrid8),
        }
    }
    /// [`Kernel::bottom8`]'s any-hit twin.
    fn occluded8(self) -> Option<crate::instance::Occluded8> {
        match self {
            Kernel::Packet | Kernel::Packet16 => Some(occluded8),
            Kernel::Wide => None,
            Kernel::Hybrid | Kernel::Hybrid16 => Some(occluded_hybrid8),
        }
    }
}

/// A 16-ray kernel on two packets of 8 (`intersect16`, `occluded_hybrid16`, ...).
type Pair16<T> = fn(&Accel, [&RayPacket8; 2], [M32x8; 2], bool) -> [T; 2];

/// Packets `0..n` (`packet(p)` builds the `p`-th) through `one`, or two at a time through
/// `two` when given (a last odd packet through `one`), results to `out(p, r)` in order.
#[inline(always)]
fn each_packet<T>(
    accel: &Accel,
    cull: bool,
    n: usize,
    packet: impl Fn(usize) -> (RayPacket8, M32x8),
    one: impl Fn(&RayPacket8, M32x8) -> T,
    two: Option<Pair16<T>>,
    mut out: impl FnMut(usize, T),
) {
    let Some(two) = two else {
        for p in 0..n {
            let (q, m) = packet(p);
            out(p, one(&q, m));
        }
        return;
    };
    for p in (0..n).step_by(2) {
        let a = packet(p);
        if p + 1 < n {
            let b = packet(p + 1);
            let [r0, r1] = two(accel, [&a.0, &b.0], [a.1, b.1], cull);
            out(p, r0);
            out(p + 1, r1);
        } else {
            out(p, one(&a.0, a.1));
        }
    }
}

/// The kernel of each queue.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Kernels {
    /// Camera rays (generation 0).
    pub camera: Kernel,
    /// Shadow rays of camera-ray hits (generation 0).
    pub shadow: Kernel,
    /// Reflection and refraction rays of camera-ray hits (generation 1, in pixel order).
    pub secondary: Kernel,
    /// Shadow rays of later generations (from the hits of reflection and refraction rays).
    pub shadow_later: Kernel,
    /// Reflection and refraction rays of generations 2 and on (binned by direction octant).
    pub secondary_later: Kernel,
}

/// `--engine auto`: the kernel per queue, by measurement (README, "Engines"). Camera rays are
/// coherent: packets trace them fastest (bench primary: packet8 ~43 Mrays/s, wide1 ~24).
/// Shadow rays towards a point light are coherent too (bench shadow: packet8 ~10, hybrid8
/// ~7.6, wide1 ~4.9). Reflection and refraction rays are coherent off `phong`'s floor (packet
/// twice as fast as wide there) and scattered after a refraction (bench incoherent: wide1
/// ~3.7, hybrid8 ~3.4, packet8 ~2.8), so they go hybrid, which keeps a packet while its lanes
/// agree.
///
/// On AVX-512 the rays of generations 0 and 1 (camera rays, their hits' shadow rays, and the
/// reflection and refraction rays of those hits, all in pixel order) go in 16-ray packets
/// (`Packet16`). On an AMD EPYC Zen 5 (2026-12-07, 1920x1080, one thread, `--stats`) they
/// took `phong`'s camera phase from 0.033 to 0.024 thread-s and its reflections from 0.027
/// to 0.018; whole-process CPU time against 8-ray packets and `hybrid8`, medians of 7 and 11
/// alternating pairs: `phong` 0.92x and 0.90x, `cubemap` 0.92x and 0.99x, `refraction`
/// 0.99x and 1.01x; the same bytes. (On the Xeon of 2026-12-04 16-ray packets for camera and
/// shadow rays had rendered in the same time as 8: `phong` 1.01x, `cubemap` 1.00x,
/// `refraction` 1.02x.)
///
/// Later generations on AVX-512 take `Hybrid16`, whose 16 rays go down the wide tree together
/// when they share a direction octant, as the binned queues' packets mostly do (`refraction`
/// at 1920x1080 on one thread, `--stats`, two runs each: the later shadow rays' phase took
/// 0.130-0.133 thread-s against packet8's 0.198-0.212, the binned reflection and refraction
/// rays 0.62-0.66 against hybrid8's 0.71-0.81; `phong`, whose later generations are few,
/// level; `Packet16` there took `refraction`'s shadow phase from 0.09 to 0.14 and its
/// secondary from 0.48 to 0.61). Without AVX-512 the 16-ray kernels are two 8-ray calls, so
/// the 8-ray kernels stay everywhere.
pub fn auto() -> Kernels {
    let avx512 = crate::accel::packet16::available();
    let pick = |k16, k| if avx512 { k16 } else { k };
    Kernels {
        camera: pick(Kernel::Packet16, Kernel::Packet),
        shadow: pick(Kernel::Packet16, Kernel::Packet),
        secondary: pick(Kernel::Packet16, Kernel::Hybrid),
        shadow_later: pick(Kernel::Hybrid16, Kernel::Packet),
        secondary_later: pick(Kernel::Hybrid16, Kernel::Hybrid),
    }
}

impl Kernels {
    /// The kernels an engine uses (`Scalar` has its own renderer; here it maps to `Packet`).
    pub fn of(engine: Engine) -> Kernels {
        let all = |k| Kernels {
            camera: k,
            shadow: k,
            secondary: k,
            shadow_later: k,
            secondary_later: k,
        };
        match engine {
            Engine::Auto => auto(),
            Engine::Wide => all(Kernel::Wide),
            Engine::Hybrid => all(Kernel::Hybrid),
            Engine::Packet16 => all(Kernel::Packet16),
            Engine::Hybrid16 => all(Kernel::Hybrid16),
            Engine::Packet | Engine::Scalar => all(Kernel::Packet),
        }
    }
}
