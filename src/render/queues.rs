//! Tile-local SoA queues of the wavefront renderer: rays to trace and shadow rays to test.

use crate::packet::RayPacket8;
use crate::ray::Ray;
use crate::simd::{self, F32x8, LANES, M32x8, Vec3x8};
use glam::Vec3;

/// The set lanes of an 8-bit lane mask, in order: the compaction that repacks a packet's
/// surviving lanes densely onto the end of a queue.
#[derive(Clone, Copy, Debug)]
pub struct LaneList {
    idx: [u8; LANES],
    len: usize,
}

impl LaneList {
    /// The lanes whose bits are set in the low 8 bits of `bits`.
    #[inline(always)]
    pub fn new(bits: u32) -> Self {
        let mut idx = [0u8; LANES];
        let mut len = 0;
        let mut b = bits & 0xff;
        while b != 0 {
            idx[len] = b.trailing_zeros() as u8;
            len += 1;
            b &= b - 1;
        }
        LaneList { idx, len }
    }

    /// No lane set.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Append the listed lanes of `v` to `out`.
    #[inline(always)]
    pub fn extend<T: Copy>(&self, out: &mut Vec<T>, v: [T; LANES]) {
        if self.len == LANES {
            out.extend_from_slice(&v);
        } else {
            out.extend(self.idx[..self.len].iter().map(|&i| v[i as usize]));
        }
    }

    #[inline(always)]
    fn extend3(&self, out: &mut [Vec<f32>; 3], v: &Vec3x8) {
        for (o, l) in out.iter_mut().zip(v.to_lanes()) {
            self.extend(o, l);
        }
    }
}

/// Rays waiting for a closest-hit query (camera, reflection or refraction rays), each with
/// the pixel it contributes to, the RGB weight of that contribution and its remaining depth.
#[derive(Clone, Debug, Default)]
pub struct RayQueue {
    /// Origins, SoA.
    pub o: [Vec<f32>; 3],
    /// Directions, SoA.
    pub d: [Vec<f32>; 3],
    /// Pixel index (`y * width + x`) each ray adds to.
    pub pixel: Vec<u32>,
    /// RGB weight of each ray's contribution, SoA.
    pub weight: [Vec<f32>; 3],
    /// Remaining recursion depth of each ray.
    pub depth: Vec<u32>,
    /// Per ray, an earlier entry holding the very same ray (origin and direction bit for
    /// bit), whose hit it takes instead of being traced. Total internal reflection makes
    /// such pairs (the refraction ray is the reflection ray), and the rays a twin spawns
    /// are twins of what its original spawns.
    pub twins: Twins,
}

/// The twin of a ray that is traced itself.
pub const NO_TWIN: u32 = u32::MAX;

/// Per entry of a queue, an earlier entry holding the very same ray, or [`NO_TWIN`]. Stored
/// only once the queue has a twin: until then a push costs one branch.
#[derive(Clone, Debug, Default)]
pub struct Twins {
    /// Per entry (empty while `count == 0`).
    of: Vec<u32>,
    count: usize,
}

impl Twins {
    /// Entries with a twin.
    #[inline]
    pub fn count(&self) -> usize {
        self.count
    }

    /// Entry `j`'s twin, or [`NO_TWIN`].
    #[inline]
    pub fn get(&self, j: usize) -> u32 {
        if self.count == 0 { NO_TWIN } else { self.of[j] }
    }

    /// Record the twins of the lanes just appended after `before` entries (`None`: none).
    #[inline(always)]
    fn extend(&mut self, lanes: &LaneList, before: usize, twin: Option<[u32; LANES]>) {
        match twin {
            Some(t) => {
                let n = lanes.idx[..lanes.len]
                    .iter()
                    .filter(|&&i| t[i as usize] != NO_TWIN)
                    .count();
                if n == 0 && self.count == 0 {
                    return;
                }
                if self.count == 0 {
                    self.of.clear();
                    self.of.resize(before, NO_TWIN);
                }
                lanes.extend(&mut self.of, t);
                self.count += n;
            }
            None if self.count > 0 => lanes.extend(&mut self.of, [NO_TWIN; LANES]),
            None => {}
        }
    }

    /// The entries of a queue of `len` that are traced themselves (no twin), into `out`.
    pub fn originals(&self, len: usize, out: &mut Vec<u32>) {
        out.clear();
        out.extend((0..len as u32).filter(|&j| self.get(j as usize) == NO_TWIN));
    }

    fn clear(&mut self) {
        self.of.clear();
        self.count = 0;
    }
}

impl RayQueue {
    /// Append one ray.
    pub fn push(&mut self, ray: &Ray, pixel: u32, weight: Vec3, depth: u32) {
        for k in 0..3 {
            self.o[k].push(ray.origin[k]);
            self.d[k].push(ray.dir[k]);
            self.weight[k].push(weight[k]);
        }
        self.pixel.push(pixel);
        self.depth.push(depth);
        if self.twins.count > 0 {
            self.twins.of.push(NO_TWIN);
        }
    }

    /// Append the lanes of `bits`, densely (the repacking step): one argument per field.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn push_lanes(
        &mut self,
        bits: u32,
        o: &Vec3x8,
        d: &Vec3x8,
        pixel: [u32; LANES],
        weight: &Vec3x8,
        depth: [u32; LANES],
        twin: Option<[u32; LANES]>,
    ) {
        let lanes = LaneList::new(bits);
        if lanes.is_empty() {
            return;
        }
        let before = self.len();
        lanes.extend3(&mut self.o, o);
        lanes.extend3(&mut self.d, d);
        lanes.extend3(&mut self.weight, weight);
        lanes.extend(&mut self.pixel, pixel);
        lanes.extend(&mut self.depth, depth);
        self.twins.extend(&lanes, before, twin);
    }

    /// Pixels of entries `start .. start + 8` (0 past the end).
    #[inline]
    pub fn pixel_lanes(&self, start: usize) -> [u32; LANES] {
        simd::lanes_from(&self.pixel, start, 0)
    }

    /// Remaining depths of entries `start .. start + 8` (0 past the end).
    #[inline]
    pub fn depth_lanes(&self, start: usize) -> [u32; LANES] {
        simd::lanes_from(&self.depth, start, 0)
    }

    /// Weights of entries `start .. start + 8` (0 past the end).
    #[inline]
    pub fn weight_lanes(&self, start: usize) -> Vec3x8 {
        Vec3x8::load(&self.weight, start, 0.0)
    }

    /// Rays queued.
    pub fn len(&self) -> usize {
        self.pixel.len()
    }

    /// Whether no ray is queued.
    pub fn is_empty(&self) -> bool {
        self.pixel.is_empty()
    }

    /// Empty the queue, keeping its memory.
    pub fn clear(&mut self) {
        for v in self.o.iter_mut().chain(&mut self.d).chain(&mut self.weight) {
            v.clear();
        }
        self.pixel.clear();
        self.depth.clear();
        self.twins.clear();
    }

    /// Entry `i` as a ray (`tnear = 0`, `tfar = inf`).
    pub fn ray(&self, i: usize) -> Ray {
        let v = |a: &[Vec<f32>; 3]| Vec3::new(a[0][i], a[1][i], a[2][i]);
        Ray::new(v(&self.o), v(&self.d), 0.0, f32::INFINITY)
    }

    /// Entry `i`'s weight.
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

    /// Reorder entries so that rays with the same direction octant and the same origin octant
    /// (about the queue's mean origin) are adjacent: repacking for coherence. A stable
    /// counting sort over the 64 keys.
    pub fn bin_by_direction_and_origin(&mut self, scratch: &mut BinScratch) {
        let len = self.len();
        let n = len.max(1) as f32;
        let mean: [f32; 3] = std::array::from_fn(|k| self.o[k].iter().sum::<f32>() / n);
        let BinScratch {
            keys,
            perm,
            spare,
            at,
        } = scratch;
        keys.clear();
        keys.extend((0..len).map(|i| {
            let dir = (0..3).fold(0u8, |b, k| b | ((self.d[k][i] < 0.0) as u8) << k);
            let side = (0..3).fold(0u8, |b, k| b | ((self.o[k][i] < mean[k]) as u8) << k);
            dir * 8 + side
        }));
        let mut start = [0u32; 65];
        for &k in keys.iter() {
            start[k as usize + 1] += 1;
        }
        for b in 0..64 {
            start[b + 1] += start[b];
        }
        // the permutation: perm[j] = the entry that goes to position j
        perm.clear();
        perm.resize(len, 0);
        for (i, &k) in keys.iter().enumerate() {
            perm[start[k as usize] as usize] = i as u32;
            start[k as usize] += 1;
        }
        // gather every field through it (sequential writes, no per-element resize)
        fn gather<T: Copy>(out: &mut Vec<T>, from: &[T], perm: &[u32]) {
            out.clear();
            out.extend(perm.iter().map(|&i| from[i as usize]));
        }
        for k in 0..3 {
            gather(&mut spare.o[k], &self.o[k], perm);
            gather(&mut spare.d[k], &self.d[k], perm);
            gather(&mut spare.weight[k], &self.weight[k], perm);
        }
        gather(&mut spare.pixel, &self.pixel, perm);
        gather(&mut spare.depth, &self.depth, perm);
        // twins move with their entries: a twin and its original have the same key, so the
        // stable sort keeps the original first
        spare.twins.clear();
        if self.twins.count > 0 {
            // where each entry went (the inverse permutation)
            at.clear();
            at.resize(len, 0);
            for (j, &i) in perm.iter().enumerate() {
                at[i as usize] = j as u32;
            }
            let of = &self.twins.of;
            spare.twins.count = self.twins.count;
            spare
                .twins
                .of
                .extend(perm.iter().map(|&i| match of[i as usize] {
                    NO_TWIN => NO_TWIN,
                    t => at[t as usize],
                }));
        }
        std::mem::swap(self, spare);
    }
}

/// Scratch space of `RayQueue::bin_by_direction_and_origin`, kept between calls.
#[derive(Clone, Debug, Default)]
pub struct BinScratch {
    keys: Vec<u8>,
    perm: Vec<u32>,
    spare: RayQueue,
    at: Vec<u32>,
}

/// Shadow rays waiting for an any-hit query, each with the RGB contribution its pixel gets
/// when the light is visible.
#[derive(Clone, Debug, Default)]
pub struct ShadowQueue {
    /// Origins, SoA.
    pub o: [Vec<f32>; 3],
    /// Directions, SoA.
    pub d: [Vec<f32>; 3],
    /// Distance to the light (hits must be nearer).
    pub tfar: Vec<f32>,
    /// Pixel index each ray adds to.
    pub pixel: Vec<u32>,
    /// What the pixel gets when the light is visible, SoA.
    pub contribution: [Vec<f32>; 3],
    /// Per ray, an earlier entry holding the very same shadow ray, whose answer it takes
    /// instead of being traced (the shadow rays of a twin's hit).
    pub twins: Twins,
}

impl ShadowQueue {
    /// Append the lanes of `bits`, densely: one argument per field.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub fn push_lanes(
        &mut self,
        bits: u32,
        o: &Vec3x8,
        d: &Vec3x8,
        tfar: F32x8,
        pixel: [u32; LANES],
        contribution: &Vec3x8,
        twin: Option<[u32; LANES]>,
    ) {
        let lanes = LaneList::new(bits);
        if lanes.is_empty() {
            return;
        }
        let before = self.len();
        lanes.extend3(&mut self.o, o);
        lanes.extend3(&mut self.d, d);
        lanes.extend3(&mut self.contribution, contribution);
        lanes.extend(&mut self.tfar, simd::lanes(tfar));
        lanes.extend(&mut self.pixel, pixel);
        self.twins.extend(&lanes, before, twin);
    }

    /// Shadow rays queued.
    pub fn len(&self) -> usize {
        self.pixel.len()
    }

    /// Whether no shadow ray is queued.
    pub fn is_empty(&self) -> bool {
        self.pixel.is_empty()
    }

    /// Empty the queue, keeping its memory.
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
        self.twins.clear();
    }

    /// Entry `i` as a ray.
    pub fn ray(&self, i: usize) -> Ray {
        let v = |a: &[Vec<f32>; 3]| Vec3::new(a[0][i], a[1][i], a[2][i]);
        Ray::new(v(&self.o), v(&self.d), 0.0, self.tfar[i])
    }

    /// What entry `i`'s pixel gets when its light is visible.
    #[inline]
    pub fn contribution(&self, i: usize) -> Vec3 {
        let c = &self.contribution;
        Vec3::new(c[0][i], c[1][i], c[2][i])
    }

    /// Entries `start .. start + 8` as a packet and its active mask (missing lanes inactive).
    pub fn packet(&self, start: usize) -> (RayPacket8, M32x8) {
        let n = (self.len() - start).min(LANES);
        let packet = RayPacket8 {
            o: Vec3x8::load(&self.o, start, 0.0),
            d: Vec3x8::load(&self.d, start, 1.0),
            tnear: simd::splat(0.0),
            tfar: simd::from_lanes(simd::lanes_from(&self.tfar, start, 0.0)),
        };
        (packet, simd::mask_from_bits((1u32 << n) - 1))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn binning_groups_octants_and_origin_sides_stably() {
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
        q.bin_by_direction_and_origin(&mut BinScratch::default());
        assert_eq!(q.pixel, vec![0, 2, 1, 4, 3]);
        assert_eq!(q.ray(1).dir, Vec3::ONE);
        let (p, active) = q.packet(0);
        assert_eq!(simd::bitmask(active), 0b1_1111);
        assert_eq!(p.lane(4).dir, Vec3::splat(-1.0));

        // one direction: grouped by the side of the mean origin, order kept within a side
        let mut q = RayQueue::default();
        for (k, x) in [1.0, -1.0, 1.0, -2.0].into_iter().enumerate() {
            q.push(
                &Ray::new(Vec3::new(x, 0.0, 0.0), Vec3::ONE, 0.0, 1.0),
                k as u32,
                Vec3::ONE,
                1,
            );
        }
        q.bin_by_direction_and_origin(&mut BinScratch::default());
        assert_eq!(q.pixel, vec![0, 2, 1, 3]);
    }

    #[test]
    fn binning_keeps_each_twin_on_its_original() {
        // entries 0..6 with directions of three octants; 3 repeats 0, 4 repeats 1 and 5
        // repeats 3 (a twin of a twin)
        let dirs = [[1.0, 1.0, 1.0], [-1.0, 1.0, 1.0], [1.0, -1.0, 1.0]];
        let mut q = RayQueue::default();
        let twins = [NO_TWIN, NO_TWIN, NO_TWIN, 0, 1, 3];
        for (k, &t) in twins.iter().enumerate() {
            let d = Vec3::from(
                dirs[if t == NO_TWIN {
                    k
                } else {
                    [0, 1, 0, 0][t as usize]
                }],
            );
            let mut one = [NO_TWIN; LANES];
            one[0] = t;
            let one = Some(one);
            q.push_lanes(
                1,
                &Vec3x8::splat([0.0; 3]),
                &Vec3x8::splat(d.to_array()),
                [k as u32; LANES],
                &Vec3x8::splat([1.0; 3]),
                [1; LANES],
                one,
            );
        }
        assert_eq!(q.twins.count(), 3);
        q.bin_by_direction_and_origin(&mut BinScratch::default());
        assert_eq!(q.twins.count(), 3);
        for j in 0..q.len() {
            let t = q.twins.get(j);
            if t != NO_TWIN {
                assert!((t as usize) < j, "an original comes first");
                assert_eq!(q.ray(t as usize).dir, q.ray(j).dir);
                let original = twins[q.pixel[j] as usize];
                assert_eq!(q.pixel[t as usize], original);
            }
        }
        // octant 0 (pixels 0, 3, 5), then -x (1, 4), then -y (2): every twin moved
        assert_eq!(q.pixel, vec![0, 3, 5, 1, 4, 2]);
        let twins: Vec<u32> = (1..5).map(|j| q.twins.get(j)).collect();
        assert_eq!(twins, [0, 1, NO_TWIN, 3]);
    }
}
