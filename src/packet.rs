//! 8-ray packets in SoA form: `RayPacket8`, `HitPacket8`, and camera packets.

use crate::camera::Camera;
use crate::ray::{Hit, Ray};
use crate::simd::{self, F32x8, LANES, M32x8, U32x8, Vec3x8};
use glam::Vec3;

/// Eight rays, one per lane. Padding lanes hold a harmless ray and are kept out of every
/// computation by the `active` mask that travels with the packet.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayPacket8 {
    /// Origins.
    pub o: Vec3x8,
    /// Directions.
    pub d: Vec3x8,
    /// Near bounds.
    pub tnear: F32x8,
    /// Far bounds.
    pub tfar: F32x8,
}

impl RayPacket8 {
    /// Build from up to eight rays; `None` lanes are padding (inactive).
    pub fn from_fn(f: impl Fn(usize) -> Option<Ray>) -> (RayPacket8, M32x8) {
        let rays: [Option<Ray>; LANES] = std::array::from_fn(f);
        let get = |i: usize| rays[i].unwrap_or(Ray::new(Vec3::ZERO, Vec3::Z, 0.0, 0.0));
        let packet = RayPacket8 {
            o: Vec3x8::from_fn(|i| get(i).origin.to_array()),
            d: Vec3x8::from_fn(|i| get(i).dir.to_array()),
            tnear: simd::from_lanes(std::array::from_fn(|i| get(i).tnear)),
            tfar: simd::from_lanes(std::array::from_fn(|i| get(i).tfar)),
        };
        let bits = (0..LANES)
            .filter(|&i| rays[i].is_some())
            .fold(0, |b, i| b | 1 << i);
        (packet, simd::mask_from_bits(bits))
    }

    /// The lanes whose ray can hit anything ([`Ray::traceable`], per lane): every origin
    /// and direction component below infinity in size (NaN fails the comparison) and bounds
    /// that equal themselves (not NaN).
    #[inline(always)]
    pub fn traceable(&self) -> M32x8 {
        let inf = simd::splat(f32::INFINITY);
        let finite = |v: Vec3x8| {
            simd::lt(v.x.abs(), inf) & simd::lt(v.y.abs(), inf) & simd::lt(v.z.abs(), inf)
        };
        finite(self.o)
            & finite(self.d)
            & simd::eq(self.tnear, self.tnear)
            & simd::eq(self.tfar, self.tfar)
    }

    /// Lane `i` as a ray.
    pub fn lane(&self, i: usize) -> Ray {
        Ray::new(
            Vec3::from(self.o.lane(i)),
            Vec3::from(self.d.lane(i)),
            simd::lanes(self.tnear)[i],
            simd::lanes(self.tfar)[i],
        )
    }

    /// Replace lane `i` (slow; for tests).
    pub fn set_lane(&mut self, i: usize, ray: &Ray) {
        let mut lanes = (0..LANES).map(|k| self.lane(k)).collect::<Vec<_>>();
        lanes[i] = *ray;
        *self = RayPacket8::from_fn(|k| Some(lanes[k])).0;
    }
}

/// Arrangement of a camera packet's eight pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum PacketShape {
    /// 4 columns x 2 rows (lane = row * 4 + column).
    #[default]
    Block4x2,
    /// 8 columns x 1 row.
    Row8x1,
}

impl PacketShape {
    /// `(columns, rows)` of the packet's pixels.
    pub fn size(self) -> (u32, u32) {
        match self {
            PacketShape::Block4x2 => (4, 2),
            PacketShape::Row8x1 => (8, 1),
        }
    }

    /// Pixel offset of lane `i` from the packet's corner.
    pub fn offset(self, i: usize) -> (u32, u32) {
        let (w, _) = self.size();
        (i as u32 % w, i as u32 / w)
    }
}

/// The camera rays of the pixels of one packet with corner `(x0, y0)`, at sub-pixel position
/// `(sx, sy)` (0.5, 0.5 = centre). Lanes outside the image are inactive. Each lane's ray is
/// exactly `camera.ray_at` of its pixel, so packets and the scalar path see identical rays.
pub fn camera_packet(
    camera: &Camera,
    shape: PacketShape,
    x0: u32,
    y0: u32,
    sx: f32,
    sy: f32,
) -> (RayPacket8, M32x8) {
    let mut bits = 0;
    let (mut px, mut py) = ([0.0f32; LANES], [0.0f32; LANES]);
    for i in 0..LANES {
        let (dx, dy) = shape.offset(i);
        let (x, y) = (x0 + dx, y0 + dy);
        if x < camera.width && y < camera.height {
            bits |= 1 << i;
        }
        px[i] = x as f32 + sx;
        py[i] = y as f32 + sy;
    }
    let packet = RayPacket8 {
        o: Vec3x8::splat(camera.eye.to_array()),
        d: camera.dirs8(simd::from_lanes(px), simd::from_lanes(py)),
        tnear: simd::splat(0.0),
        tfar: simd::splat(f32::INFINITY),
    };
    (packet, simd::mask_from_bits(bits))
}

/// Closest hits of a packet; lanes without a hit have `tri == Hit::NONE_ID`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HitPacket8 {
    /// Triangle per lane (`Hit::NONE_ID` = no hit).
    pub tri: U32x8,
    /// Ray parameter per lane.
    pub t: F32x8,
    /// Barycentric weight of the second vertex.
    pub b1: F32x8,
    /// Barycentric weight of the third vertex.
    pub b2: F32x8,
}

impl HitPacket8 {
    /// A packet of misses (`t = inf`).
    pub fn none() -> Self {
        HitPacket8 {
            tri: U32x8::splat(Hit::NONE_ID),
            t: simd::splat(f32::INFINITY),
            b1: simd::splat(0.0),
            b2: simd::splat(0.0),
        }
    }

    /// Lane `i`'s hit, if any.
    pub fn lane(&self, i: usize) -> Option<Hit> {
        let tri = simd::u32_lanes(self.tri)[i];
        (tri != Hit::NONE_ID).then(|| Hit {
            tri,
            t: simd::lanes(self.t)[i],
            b1: simd::lanes(self.b1)[i],
            b2: simd::lanes(self.b2)[i],
        })
    }

    /// Set lane `i`'s hit (`None` = a miss). By blends into the registers: writing the lane
    /// into arrays of the lanes and loading them back whole stalled on the stores (the
    /// renderer sets every lane of a queue with twin rays this way).
    #[inline]
    pub fn set_lane(&mut self, i: usize, hit: Option<Hit>) {
        let h = hit.unwrap_or(Hit {
            tri: Hit::NONE_ID,
            t: f32::INFINITY,
            b1: 0.0,
            b2: 0.0,
        });
        assert!(i < LANES, "lane {i} of a packet of {LANES}");
        let m = simd::mask_from_bits(1 << i);
        self.tri = simd::select_u32(m, U32x8::splat(h.tri), self.tri);
        self.t = simd::select(m, simd::splat(h.t), self.t);
        self.b1 = simd::select(m, simd::splat(h.b1), self.b1);
        self.b2 = simd::select(m, simd::splat(h.b2), self.b2);
    }

    /// Lanes with a hit.
    pub fn hit_mask(&self) -> M32x8 {
        simd::lt_u32(self.tri, U32x8::splat(Hit::NONE_ID))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_roundtrip_and_padding_is_inactive() {
        let ray = |i: usize| Ray::new(Vec3::splat(i as f32), Vec3::X, 0.5, 9.0);
        let (mut p, active) = RayPacket8::from_fn(|i| (i < 5).then(|| ray(i)));
        assert_eq!(simd::bitmask(active), 0b1_1111);
        assert_eq!(p.lane(3), ray(3));
        p.set_lane(6, &ray(1));
        assert_eq!(p.lane(6), ray(1));
        let mut h = HitPacket8::none();
        assert_eq!(simd::bitmask(h.hit_mask()), 0);
        let hit = Hit {
            tri: 4,
            t: 2.0,
            b1: 0.25,
            b2: 0.5,
        };
        h.set_lane(2, Some(hit));
        assert_eq!(h.lane(2), Some(hit));
        assert_eq!(simd::bitmask(h.hit_mask()), 0b100);
    }

    #[test]
    fn camera_packets_equal_scalar_rays_and_clip_at_the_border() {
        let cam = Camera::new(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 40.0, 10, 3);
        for shape in [PacketShape::Block4x2, PacketShape::Row8x1] {
            let (p, active) = camera_packet(&cam, shape, 8, 2, 0.5, 0.5);
            for i in 0..8 {
                let (dx, dy) = shape.offset(i);
                let inside = 8 + dx < 10 && 2 + dy < 3;
                assert_eq!(simd::lane_set(active, i), inside);
                if inside {
                    assert_eq!(p.lane(i), cam.primary_ray(8 + dx, 2 + dy));
                }
            }
        }
    }
}
