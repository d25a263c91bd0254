//! Tile-local SoA queues of the wavefront renderer: rays to trace and shadow rays to test.

use crate::packet::RayPacket8;
use crate::ray::Ray;
use crate::simd::{self, LANES, M32x8, Vec3x8};
use glam::Vec3;

/// Rays waiting for a closest-hit query (camera, reflection or refraction rays), each with
/// the pixel it contributes to, the RGB weight of that contribution and its remaining depth.
#[derive(Clone, Debug, Default)]
pub struct RayQueue {
    pub o: [Vec<f32>; 3],
    pub d: [Vec<f32>; 3],
    pub pixel: Vec<u32>,
    pub weight: [Vec<f32>; 3],
    pub depth: Vec<u32>,
}

impl RayQueue {
    pub fn push(&mut self, ray: &Ray, pixel: u32, weight: Vec3, depth: u32) {
        for k in 0..3 {
            self.o[k].push(ray.origin[k]);
            self.d[k].push(ray.dir[k]);
            self.weight[k].push(weight[k]);
        }
        self.pixel.push(pixel);
        self.depth.push(depth);
    }

    pub fn len(&self) -> usize {
        self.pixel.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pixel.is_empty()
    }

    pub fn clear(&mut self) {
        for v in self.o.iter_mut().chain(&mut self.d).chain(&mut self.weight) {
            v.clear();
        }
        self.pixel.clear();
        self.depth.clear();
    }

    pub fn ray(&self, i: usize) -> Ray {
        let v = |a: &[Vec<f32>; 3]| Vec3::new(a[0][i], a[1][i], a[2][i]);
        Ray::new(v(&self.o), v(&self.d), 0.0, f32::INFINITY)
    }

    pub fn weight(&self, i: usize) -> Vec3 {
        Vec3::new(self.weight[0][i], self.weight[1][i], self.weight[2][i])
    }

    /// Entries `start .. start + 8` as a packet (missing lanes inactive), loaded straight
    /// from the SoA arrays.
    pub fn packet(&self, start: usize) -> (RayPacket8, M32x8) {
        let n = (self.len() - start).min(LANES);
        let packet = RayPacket8 {
            o: Vec3x8::load(&self.o, start, 0.0),
            d: Vec3x8::load(&self.d, start, 1.0),
            tnear: simd::splat(0.0),
            tfar: simd::splat(f32::INFINITY),
        };
        (packet, simd::mask_from_bits((1u32 << n) - 1))
    }

    /// Make room for `n` entries without reallocating.
    pub fn reserve(&mut self, n: usize) {
        for v in self.o.iter_mut().chain(&mut self.d).chain(&mut self.weight) {
            v.reserve(n);
        }
        self.pixel.reserve(n);
        self.depth.reserve(n);
    }

    /// Reorder entries so rays with the same direction octant are adjacent (repacking for
    /// coherence). A stable counting sort over the 3 sign bits; `spare` is scratch space.
    pub fn bin_by_octant(&mut self, spare: &mut RayQueue) {
        let oct = |i: usize| (0..3).fold(0usize, |b, k| b | ((self.d[k][i] < 0.0) as usize) << k);
        let mut counts = [0usize; 9];
        for i in 0..self.len() {
            counts[oct(i) + 1] += 1;
        }
        for b in 0..8 {
            counts[b + 1] += counts[b];
        }
        spare.clear();
        for v in spare
            .o
            .iter_mut()
            .chain(&mut spare.d)
            .chain(&mut spare.weight)
        {
            v.resize(self.len(), 0.0);
        }
        spare.pixel.resize(self.len(), 0);
        spare.depth.resize(self.len(), 0);
        for i in 0..self.len() {
            let b = oct(i);
            let j = counts[b];
            counts[b] += 1;
            for k in 0..3 {
                spare.o[k][j] = self.o[k][i];
                spare.d[k][j] = self.d[k][i];
                spare.weight[k][j] = self.weight[k][i];
            }
            spare.pixel[j] = self.pixel[i];
            spare.depth[j] = self.depth[i];
        }
        std::mem::swap(self, spare);
    }
}

/// Shadow rays waiting for an any-hit query, each with the RGB contribution its pixel gets
/// when the light is visible.
#[derive(Clone, Debug, Default)]
pub struct ShadowQueue {
    pub o: [Vec<f32>; 3],
    pub d: [Vec<f32>; 3],
    pub tfar: Vec<f32>,
    pub pixel: Vec<u32>,
    pub contribution: [Vec<f32>; 3],
}

impl ShadowQueue {
    /// Make room for `n` entries without reallocating.
    pub fn reserve(&mut self, n: usize) {
        for v in self
            .o
            .iter_mut()
            .chain(&mut self.d)
            .chain(&mut self.contribution)
        {
            v.reserve(n);
        }
        self.tfar.reserve(n);
        self.pixel.reserve(n);
    }

    pub fn push(
        &mut self,
        o: [f32; 3],
        d: [f32; 3],
        tfar: f32,
        pixel: u32,
        contribution: [f32; 3],
    ) {
        for k in 0..3 {
            self.o[k].push(o[k]);
            self.d[k].push(d[k]);
            self.contribution[k].push(contribution[k]);
        }
        self.tfar.push(tfar);
        self.pixel.push(pixel);
    }

    pub fn len(&self) -> usize {
        self.pixel.len()
    }

    pub fn is_empty(&self) -> bool {
        self.pixel.is_empty()
    }

    pub fn clear(&mut self) {
        for v in self
            .o
            .iter_mut()
            .chain(&mut self.d)
            .chain(&mut self.contribution)
        {
            v.clear();
        }
        self.tfar.clear();
        self.pixel.clear();
    }

    pub fn packet(&self, start: usize) -> (RayPacket8, M32x8) {
        let n = (self.len() - start).min(LANES);
        let mut tfar = [0.0f32; LANES];
        tfar[..n].copy_from_slice(&self.tfar[start..start + n]);
        let packet = RayPacket8 {
            o: Vec3x8::load(&self.o, start, 0.0),
            d: Vec3x8::load(&self.d, start, 1.0),
            tnear: simd::splat(0.0),
            tfar: simd::from_lanes(tfar),
        };
        (packet, simd::mask_from_bits((1u32 << n) - 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binning_groups_octants_stably() {
        let mut q = RayQueue::default();
        let dirs = [
            [1.0, 1.0, 1.0],
            [-1.0, 1.0, 1.0],
            [1.0, 1.0, 1.0],
            [-1.0, -1.0, -1.0],
            [-1.0, 1.0, 1.0],
        ];
        for (k, d) in dirs.iter().enumerate() {
            q.push(
                &Ray::new(Vec3::ZERO, Vec3::from(*d), 0.0, 1.0),
                k as u32,
                Vec3::ONE,
                1,
            );
        }
        q.bin_by_octant(&mut RayQueue::default());
        assert_eq!(q.pixel, vec![0, 2, 1, 4, 3]);
        assert_eq!(q.ray(1).dir, Vec3::ONE);
        let (p, active) = q.packet(0);
        assert_eq!(simd::bitmask(active), 0b1_1111);
        assert_eq!(p.lane(4).dir, Vec3::splat(-1.0));
    }
}
