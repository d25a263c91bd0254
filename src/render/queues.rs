//! Tile-local SoA queues of the wavefront renderer: rays to trace and shadow rays to test.

use crate::packet::RayPacket8;
use crate::ray::Ray;
use crate::simd::{self, LANES, M32x8};
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

    /// Entries `start .. start + 8` as a packet (missing lanes inactive).
    pub fn packet(&self, start: usize) -> (RayPacket8, M32x8) {
        RayPacket8::from_fn(|i| (start + i < self.len()).then(|| self.ray(start + i)))
    }

    /// Reorder entries so rays with the same direction octant are adjacent (repacking for
    /// coherence). A stable counting sort over the 3 sign bits.
    pub fn bin_by_octant(&mut self) {
        let oct = |i: usize| (0..3).fold(0usize, |b, k| b | ((self.d[k][i] < 0.0) as usize) << k);
        let mut counts = [0usize; 9];
        for i in 0..self.len() {
            counts[oct(i) + 1] += 1;
        }
        for b in 0..8 {
            counts[b + 1] += counts[b];
        }
        let mut order = vec![0usize; self.len()];
        for i in 0..self.len() {
            let b = oct(i);
            order[counts[b]] = i;
            counts[b] += 1;
        }
        let permute_f = |v: &mut Vec<f32>| *v = order.iter().map(|&i| v[i]).collect();
        for v in self.o.iter_mut().chain(&mut self.d).chain(&mut self.weight) {
            permute_f(v);
        }
        self.pixel = order.iter().map(|&i| self.pixel[i]).collect();
        self.depth = order.iter().map(|&i| self.depth[i]).collect();
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
        RayPacket8::from_fn(|i| {
            let j = start + i;
            (j < self.len()).then(|| {
                let v = |a: &[Vec<f32>; 3]| Vec3::new(a[0][j], a[1][j], a[2][j]);
                Ray::new(v(&self.o), v(&self.d), 0.0, self.tfar[j])
            })
        })
    }
}

/// Lanes of a packet as an index range helper.
pub fn lanes_from(start: usize, len: usize) -> impl Iterator<Item = usize> {
    (0..LANES).filter(move |&i| start + i < len)
}

/// Whether lane `i` of `m` is set (re-exported for the wavefront loop's readability).
pub fn set(m: M32x8, i: usize) -> bool {
    simd::lane_set(m, i)
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
        q.bin_by_octant();
        assert_eq!(q.pixel, vec![0, 2, 1, 4, 3]);
        assert_eq!(q.ray(1).dir, Vec3::ONE);
        let (p, active) = q.packet(0);
        assert_eq!(simd::bitmask(active), 0b1_1111);
        assert_eq!(p.lane(4).dir, Vec3::splat(-1.0));
    }
}
