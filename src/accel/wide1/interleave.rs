//! Several single-ray walks at once, each taking one step (a node visit) in turn. Scattered
//! rays on a tree larger than the caches are walked eight at a time, the node and leaf
//! blocks each will read next prefetched, so that while one walk waits on memory the core
//! works on the others; every other closest-hit batch two at a time, whose steps, two
//! independent chains of loads and tests, fill the core's pipeline better than one.

use super::RayWide;
use super::walk::{Kind, Walker};
use crate::accel::Accel;
use crate::accel::stack::{STACK, stack_need};
use crate::accel::wide::{Bvh8, Node8, TriBlock8, leaf_blocks};
use crate::ray::Ray;

/// Ask for the lines of leaf `leaf`'s blocks that a single-ray test reads (all but the ids'
/// line).
#[inline(always)]
pub(super) fn prefetch_leaf(accel: &Accel, leaf: u32) {
    let (first, count) = leaf_blocks(leaf);
    for b in first..first + count {
        let p = (&accel.wide.blocks[b] as *const TriBlock8).cast::<i8>();
        for line in 0..6 {
            prefetch(p.wrapping_add(64 * line));
        }
    }
}

/// Ask for node `n`'s four cache lines ahead of its visit (nothing for a reference that is
/// not a node).
#[inline(always)]
pub(super) fn prefetch_node(bvh: &Bvh8, n: u32) {
    if let Some(node) = bvh.nodes.get(n as usize) {
        let p = (node as *const Node8).cast::<i8>();
        for line in 0..4 {
            prefetch(p.wrapping_add(64 * line));
        }
    }
}

/// Ask for the cache line at `p` into L1 (nothing elsewhere than x86-64).
#[inline(always)]
fn prefetch(p: *const i8) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        #[allow(unsafe_code)]
        // SAFETY: SSE, the one feature `_mm_prefetch` needs, is part of every x86-64 CPU; a
        // prefetch is a hint that reads nothing into the program and never faults, whatever
        // the address (every caller passes one inside the tree's arrays anyway).
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(p);
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = p;
}

/// Walks [`interleaved`] takes in turn.
const INTERLEAVE: usize = 8;

/// One walk of type `W` from the root per traceable ray of `rays`, [`INTERLEAVE`] at a
/// time taking one step each in turn, the next node of each prefetched; `done(i, walk)` as
/// ray `i`'s walk ends. The same walks as one after another, so the same answers; but a
/// random ray's walk of a mesh larger than the caches is a chain of dependent loads, each a
/// likely miss, and here each load is asked for a step ahead while the core works on the
/// other walks (a walk's hit leaves are tested at its next step, their blocks prefetched
/// meanwhile: [`Walk::step`]). `stack` holds at least `INTERLEAVE` times [`stack_need`]
/// entries.
#[inline(always)]
fn interleaved<W: Walk>(
    accel: &Accel,
    bvh: &Bvh8,
    rays: &[Ray],
    cull: bool,
    stack: &mut [(u32, f32)],
    mut done: impl FnMut(usize, &W),
) {
    let mut stacks = stack.chunks_mut(stack_need(bvh));
    let mut stacks: [&mut [(u32, f32)]; INTERLEAVE] =
        std::array::from_fn(|_| stacks.next().unwrap_or_default());
    let mut start = starts(rays);
    let mut walks: [Option<(usize, W)>; INTERLEAVE] = std::array::from_fn(|_| start());
    loop {
        let mut busy = false;
        for (slot, st) in walks.iter_mut().zip(stacks.iter_mut()) {
            if let Some((i, w)) = slot {
                busy = true;
                if w.step(accel, bvh, cull, st) {
                    done(*i, w);
                    *slot = start();
                } else {
                    prefetch_node(bvh, w.next());
                }
            }
        }
        if !busy {
            return;
        }
    }
}

/// The walks of `rays` from the root, one per traceable ray in order, as `(index, walk)`.
#[inline(always)]
fn starts<W: Walk>(rays: &[Ray]) -> impl FnMut() -> Option<(usize, W)> {
    let mut next = 0usize;
    move || {
        while next < rays.len() {
            let i = next;
            next += 1;
            if rays[i].traceable() {
                return Some((i, W::root(&rays[i])));
            }
        }
        None
    }
}

/// The walks of `rays` two at a time, a step of each in turn ([`Walk::step_now`], no
/// prefetch); `done(i, walk)` as ray `i`'s walk ends. Two independent chains of loads and
/// tests fill the core's pipeline better than one: on the kitten's random rays (2M, one
/// thread, AMD EPYC Zen 5, CPU time of the trace, medians of 9 alternating runs) one walk
/// after another took 0.291 s and two in turn 0.263 (compiled for AVX-512 VL, as
/// [`in_turn_evex`]; for AVX2 0.280); three or four in turn, from an array of walks,
/// 0.276 and 0.285. The two walks are two named values, not an array, so that each stays
/// in registers. `stacks` holds at least two times [`stack_need`] entries.
#[inline(always)]
fn paired<W: Walk>(
    accel: &Accel,
    bvh: &Bvh8,
    rays: &[Ray],
    cull: bool,
    stacks: &mut [(u32, f32)],
    mut done: impl FnMut(usize, &W),
) {
    let (sa, sb) = stacks.split_at_mut(stack_need(bvh));
    let mut start = starts::<W>(rays);
    let (mut a, mut b) = (start(), start());
    loop {
        match (&mut a, &mut b) {
            (Some((ia, wa)), Some((ib, wb))) => {
                let over_a = wa.step_now(accel, bvh, cull, sa);
                let over_b = wb.step_now(accel, bvh, cull, sb);
                if over_a {
                    done(*ia, wa);
                    a = start();
                }
                if over_b {
                    done(*ib, wb);
                    b = start();
                }
            }
            (Some((i, w)), None) => {
                if w.step_now(accel, bvh, cull, sa) {
                    done(*i, w);
                    a = start();
                }
            }
            (None, Some((i, w))) => {
                if w.step_now(accel, bvh, cull, sb) {
                    done(*i, w);
                    b = start();
                }
            }
            (None, None) => return,
        }
    }
}

/// How [`batch`] walks: [`interleaved`] or [`paired`].
#[derive(Clone, Copy)]
pub(super) enum Turns {
    /// [`INTERLEAVE`] at a time, prefetched.
    Interleaved,
    /// Two at a time, closest hit only.
    Paired,
}

/// [`interleaved`] or [`paired`].
#[inline(always)]
fn in_turn<W: Walk>(
    turns: Turns,
    accel: &Accel,
    bvh: &Bvh8,
    rays: &[Ray],
    cull: bool,
    stack: &mut [(u32, f32)],
    done: impl FnMut(usize, &W),
) {
    match turns {
        Turns::Interleaved => interleaved(accel, bvh, rays, cull, stack, done),
        Turns::Paired => paired(accel, bvh, rays, cull, stack, done),
    }
}

/// [`in_turn`] compiled for AVX-512 VL, whose 32 vector registers hold both of
/// [`paired`]'s rays where AVX2's 16 spill them (the same operations, so the same answers).
/// Called only after [`evex`].
#[target_feature(enable = "avx512f,avx512vl")]
fn in_turn_evex<W: Walk>(
    turns: Turns,
    accel: &Accel,
    bvh: &Bvh8,
    rays: &[Ray],
    cull: bool,
    stack: &mut [(u32, f32)],
    done: impl FnMut(usize, &W),
) {
    in_turn(turns, accel, bvh, rays, cull, stack, done)
}

/// Whether the CPU has AVX-512 F and VL ([`in_turn_evex`]), unless `WHITTED_NO_AVX512` is
/// set (as for the 16-ray kernels).
fn evex() -> bool {
    static HAVE: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
    *HAVE.get_or_init(|| {
        #[cfg(target_arch = "x86_64")]
        {
            std::env::var_os("WHITTED_NO_AVX512").is_none()
                && std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512vl")
        }
        #[cfg(not(target_arch = "x86_64"))]
        false
    })
}

/// Wide trees (nodes and blocks) smaller than this are never [`interleaved`]: they stay in
/// the caches, and interleaving only adds its bookkeeping. Random rays, one thread,
/// AMD EPYC Zen 3 (32 MiB L3), interleaved against one after another: kitten (1.5 MiB
/// tree) 0.93-1.0x, 82k triangles (5.8 MiB) 1.08x, 327k (23 MiB) 1.35x, 1.3M (93 MiB)
/// 1.6x.
const INTERLEAVE_MIN_BYTES: usize = 4 << 20;

/// Rays whose origins lie together but whose directions are apart (bounces) are walked
/// interleaved only on a tree at least this large: on the bench's incoherent rays, one
/// thread, AMD EPYC Zen 5 (32 MiB L3), interleaved against one after another: 82k
/// triangles (5.8 MiB) 0.84x, 327k (23 MiB) 0.92x, 1.3M (93 MiB) 1.0-1.05x, 5.2M (360 MiB)
/// 1.3-1.5x (docs/engines.md). Their first nodes and blocks, near the shared origins, stay in
/// the caches from ray to ray; only where the rest of the tree is far larger than the
/// last-level cache do the walks wait on memory as random rays' do.
const SCATTERED_MIN_BYTES: usize = 128 << 20;

/// Origins of a group of 16 rays this far apart, as a share of the scene's diagonal, on
/// average over the sampled groups, mark a batch as scattered (as `engine::TOGETHER`).
const APART: f32 = 0.2;

/// Directions of a group of 16 rays this far apart (`1 - cos` of the widest angle to the
/// group's first), on average over the sampled groups, mark a batch as scattered on a tree
/// of [`SCATTERED_MIN_BYTES`] (ten times `engine::BEAM`: camera rays and shadow rays to a
/// point light lie far below, diffuse bounces near 1 and above).
const DIRECTIONS_APART: f32 = 0.1;

/// Groups of 16 rays sampled by [`worth_it`].
const SAMPLE: usize = 4;

/// Whether `rays` are walked [`interleaved`]: on a tree larger than
/// [`INTERLEAVE_MIN_BYTES`], when a sample of groups of 16 consecutive rays shows origins
/// apart (random rays, inside/outside tests), and on a tree of [`SCATTERED_MIN_BYTES`] also
/// when it shows directions apart (bounces). Rays in order (camera rays, the shadow rays of
/// their hits) are not: consecutive walks find the same nodes in the caches and take the
/// same branches, and a walk that tests a leaf a step late descends
/// before its limit drops; interleaved, at 1.3M triangles, `wide1` traced camera rays at
/// 0.73x, their hits at 0.87x and shadow rays at 0.77x (bench, one thread).
#[inline(always)]
pub(super) fn worth_it(accel: &Accel, rays: &[Ray]) -> bool {
    worth_it_at(accel, rays, accel.wide.bytes())
}

/// [`worth_it`] as if the tree took `bytes`.
#[inline(always)]
fn worth_it_at(accel: &Accel, rays: &[Ray], bytes: usize) -> bool {
    if bytes < INTERLEAVE_MIN_BYTES {
        return false;
    }
    let Some(root) = accel.nodes.first() else {
        return false;
    };
    let diagonal = (glam::Vec3::from(root.max) - glam::Vec3::from(root.min)).length();
    let groups = rays.len() / 16;
    if groups == 0 || !(diagonal > 0.0) {
        return false;
    }
    let n = groups.min(SAMPLE);
    let (mut apart, mut turned) = (0.0, 0.0);
    for k in 0..n {
        let group = &rays[k * groups / n * 16..][..16];
        let (o, d) = (group[0].origin, group[0].dir.normalize_or_zero());
        let far = group
            .iter()
            .map(|r| (r.origin - o).length())
            .fold(0.0, f32::max);
        apart += (far / diagonal).min(1.0);
        // (NaN, a zero direction: counted as apart)
        let cos = group
            .iter()
            .map(|r| r.dir.normalize_or_zero().dot(d))
            .fold(1.0, |m: f32, c| if c.is_nan() { -1.0 } else { m.min(c) });
        turned += 1.0 - cos;
    }
    apart >= APART * n as f32
        || (bytes >= SCATTERED_MIN_BYTES && turned >= DIRECTIONS_APART * n as f32)
}

/// The walks of `rays` taken in `turns` (`done(i, walk)` as ray `i`'s ends), on the
/// thread's stack, grown for them (nothing on an empty tree), compiled for the CPU's widest
/// registers ([`in_turn_evex`]). The callers choose: [`interleaved`] where [`worth_it`]
/// says so, else [`paired`] for closest hits (the any-hit batch call walks such batches one
/// after another instead).
#[inline(always)]
pub(super) fn batch<W: Walk>(
    accel: &Accel,
    rays: &[Ray],
    cull: bool,
    turns: Turns,
    done: impl FnMut(usize, &W),
) {
    let bvh = &accel.wide;
    if bvh.nodes.is_empty() {
        return;
    }
    STACK.with_borrow_mut(|stack| {
        let need = INTERLEAVE * stack_need(bvh);
        if stack.len() < need {
            stack.resize(need, (0, 0.0));
        }
        if evex() {
            // SAFETY: `evex()` checked that the CPU has AVX-512 F and VL, the only
            // features `in_turn_evex` is compiled for beyond the crate's baseline.
            #[allow(unsafe_code)]
            unsafe {
                in_turn_evex(turns, accel, bvh, rays, cull, stack, done)
            }
        } else {
            in_turn(turns, accel, bvh, rays, cull, stack, done)
        }
    });
}

/// A walk that [`interleaved`] and [`paired`] step: made from a ray at the root, one node
/// visit per step, then the node it visits next.
pub(super) trait Walk: Copy {
    /// The walk of `ray` from the root.
    fn root(ray: &Ray) -> Self;
    /// One node visit, its hit leaves tested at the next (their blocks prefetched
    /// meanwhile); `true` when the walk is over.
    fn step(&mut self, accel: &Accel, bvh: &Bvh8, cull: bool, stack: &mut [(u32, f32)]) -> bool;
    /// One node visit, its hit leaves tested at once; `true` when the walk is over.
    fn step_now(&mut self, accel: &Accel, bvh: &Bvh8, cull: bool, stack: &mut [(u32, f32)])
    -> bool;
    /// The node the next step visits.
    fn next(&self) -> u32;
}

impl<K: Kind> Walk for Walker<K> {
    #[inline(always)]
    fn root(ray: &Ray) -> Self {
        Walker::new(RayWide::new(ray), ray.tfar, 0)
    }
    #[inline(always)]
    fn step(&mut self, accel: &Accel, bvh: &Bvh8, cull: bool, stack: &mut [(u32, f32)]) -> bool {
        self.step_deferred(accel, bvh, cull, stack)
    }
    #[inline(always)]
    fn step_now(
        &mut self,
        accel: &Accel,
        bvh: &Bvh8,
        cull: bool,
        stack: &mut [(u32, f32)],
    ) -> bool {
        Walker::step(self, accel, bvh, cull, stack)
    }
    #[inline(always)]
    fn next(&self) -> u32 {
        self.cur
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Bounces (origins together, directions apart) are interleaved on a tree of
    /// [`SCATTERED_MIN_BYTES`] only; a beam never; random rays from [`INTERLEAVE_MIN_BYTES`].
    #[test]
    fn bounces_interleave_on_the_largest_trees_only() {
        let (tris, accel) = crate::accel::wide::tests::kitten();
        // a cheap generator of spread directions (a golden-angle spiral) and positions
        let dir = |i: usize| {
            let z = 1.0 - 2.0 * ((i * 7919 % 1000) as f32 + 0.5) / 1000.0;
            let a = i as f32 * 2.399_963;
            let r = (1.0 - z * z).sqrt();
            Vec3::new(r * a.cos(), r * a.sin(), z)
        };
        let at = |i: usize| tris[i * 7 % tris.len()][0];
        let ray = |o: Vec3, d: Vec3| Ray::new(o, d, 0.0, f32::INFINITY);
        // 4x4 blocks of bounces: each block's origins within a hundredth of the box
        let bounces: Vec<Ray> = (0..256)
            .map(|i| ray(at(i / 16) + dir(i) * 1e-3, dir(i)))
            .collect();
        let random: Vec<Ray> = (0..256).map(|i| ray(at(i) * 0.9, dir(i))).collect();
        let eye = Vec3::new(1.6, 0.9, 4.4);
        let beam: Vec<Ray> = (0..256).map(|i| ray(eye, at(i / 16) - eye)).collect();
        let (small, large) = (INTERLEAVE_MIN_BYTES, SCATTERED_MIN_BYTES);
        assert!(!worth_it_at(&accel, &bounces, small));
        assert!(worth_it_at(&accel, &bounces, large));
        assert!(worth_it_at(&accel, &random, small));
        assert!(!worth_it_at(&accel, &random, small - 1));
        assert!(!worth_it_at(&accel, &beam, large));
        assert!(
            !worth_it(&accel, &random),
            "the kitten's tree fits the caches"
        );
    }
}
