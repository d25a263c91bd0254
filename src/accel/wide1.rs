//! Single-ray traversal of the 8-wide BVH: one ray against a node's 8 boxes in one slab test,
//! hit children visited nearest first from an explicit stack, one ray against a leaf's 8
//! triangles in lanes (the assignment's test with `hit_triangle1`'s arithmetic per lane).
//!
//! `intersect_wide1` / `occluded_wide1` return exactly what `intersect1` / `occluded1`
//! return: the per-triangle arithmetic is the same, the boxes are the same padded boxes, and
//! the closest hit is the smallest `(t, triangle index)` whatever the visiting order.
//!
//! The walks themselves are in `walk` (closest and any hit, as steps over a walk's state);
//! the batch calls (`intersect_wide1_many`, `occluded_wide1_many`) take several walks at a
//! time in turn: eight with prefetches on scattered rays and a large tree, else two for
//! closest hits (`interleave`).

mod interleave;
mod walk;

use super::robust::{BARY_SAFE, nearer};
use super::scalar::hit_f64;
use super::stack::{STACK, grow_stack};
use super::wide::{Bvh8, Node8, TriBlock8};
use super::{Accel, SLAB_FAR_SCALE, safe_inv};
use crate::packet::{HitPacket8, RayPacket8};
use crate::ray::{Hit, Ray};
use crate::simd::{self, F32x8, M32x8, Vec3x8};
use interleave::{Turns, batch};
pub(super) use walk::walk;
use walk::{Any, Closest};

/// A ray splatted across lanes for the wide kernels, with what the slab test needs.
#[derive(Clone, Copy, Debug)]
pub struct RayWide {
    /// Origin in every lane.
    pub o: Vec3x8,
    /// Direction in every lane (as given, not normalised).
    pub d: Vec3x8,
    /// `|d|` in every lane, computed as `Ray1::new` does.
    pub dlen: F32x8,
    /// [`safe_inv`] of each direction component, in every lane (never `±inf`).
    pub inv: Vec3x8,
    /// `inv * SLAB_FAR_SCALE` per component (rounded once): far-plane distances come out
    /// already widened (see [`hit_node1`]).
    pub inv_far: Vec3x8,
    /// Per axis, which corner of a box is its near plane (`Node8::bounds[near[k]]`): 1, the
    /// maximum, where `inv[k] < 0`, else 0; the far plane is the other one.
    pub near: [usize; 3],
    /// The direction's octant (bit k: component k negative), indexing `Node8::order`.
    pub octant: usize,
    /// Origin, once (for the f64 edge test).
    pub o1: [f32; 3],
    /// Direction, once (for the f64 edge test).
    pub d1: [f32; 3],
    /// The ray's `tnear`: hits need `t > tnear`, boxes are entered no earlier.
    pub tnear: f32,
}

impl RayWide {
    /// Splat `ray` and precompute its reciprocal direction, signs and octant.
    #[inline(always)]
    pub fn new(ray: &Ray) -> RayWide {
        let o1 = ray.origin.to_array();
        let d1 = ray.dir.to_array();
        // |d| as Ray1 computes it, so the grazing margin is the same float.
        let dlen = (d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]).sqrt();
        RayWide::from_parts(o1, d1, d1.map(safe_inv), dlen, ray.tnear)
    }

    /// Splat a ray whose reciprocal direction ([`safe_inv`] per component) and length
    /// (`sqrt((x x + y y) + z z)`) are already known, as a packet has them in its lanes.
    #[inline(always)]
    pub fn from_parts(o1: [f32; 3], d1: [f32; 3], inv: [f32; 3], dlen: f32, tnear: f32) -> RayWide {
        let near = inv.map(|v| (v < 0.0) as usize);
        RayWide {
            o: Vec3x8::splat(o1),
            d: Vec3x8::splat(d1),
            dlen: simd::splat(dlen),
            inv: Vec3x8::splat(inv),
            inv_far: Vec3x8::splat(inv.map(|v| v * SLAB_FAR_SCALE)),
            near,
            octant: near[0] | near[1] << 1 | near[2] << 2,
            o1,
            d1,
            tnear,
        }
    }
}

/// The plane + barycentric test of one ray against a block's 8 triangles: the nearest lane
/// hit with `tnear < t < tfar` (smallest `t`, then smallest triangle index) as
/// `(triangle, t, b1, b2)`; with `ANY_HIT`, any lane's hit (the first lane clear of the
/// edges, if there is one). Steps as in `hit_triangle1`, per lane:
#[inline(always)]
pub fn hit_block1<const ANY_HIT: bool>(
    accel: &Accel,
    block: usize,
    r: &RayWide,
    tfar: f32,
    cull: bool,
) -> Option<Hit> {
    let b: &TriBlock8 = &accel.wide.blocks[block];
    // plane hit: t = <v0 - p, n> / <d, n> (in-plane rays, zero-area triangles and unused
    // lanes give inf or NaN and fail the depth test).
    let dn = r.d.dot(b.n);
    let mut mask = simd::splat(f32::from_bits(u32::MAX));
    // culling: skip back faces (<d, n> >= 0).
    if cull {
        mask = simd::and_not(mask, simd::ge(dn, simd::splat(0.0)));
    }
    let t = (b.v0 - r.o).dot(b.n) / dn;
    // depth test, near side (NaN fails it and so misses); the far side for the clear lanes
    // below, a near-edge lane's from its f64 distance (`hit_f64`, as `hit_triangle1`). No
    // early exit when every lane fails: that branch went either way (at 1.3M triangles 1.58
    // of an incoherent ray's 3.52 blocks fail the depth test in every lane), and its
    // mispredictions cost more than the barycentric lanes; without it the one branch left
    // (any hit?) is nearly always "no", so the walk runs on speculatively while the block's
    // lines arrive.
    mask &= simd::gt(t, simd::splat(r.tnear));
    // barycentric: signed sub-triangle areas over the whole, as linear forms of w = q - v0.
    let q = r.o + r.d * t;
    let w = q - b.v0;
    let b1 = w.dot(b.p1);
    let b2 = w.dot(b.p2);
    let b0 = simd::splat(1.0) - b1 - b2;
    // inside when no coordinate is negative; lanes within BARY_SAFE of an edge by the f64
    // edge signs, as hit_triangle1 does.
    // (|n| per lane: the float TriangleSoa stores, see TriBlock8::n_len)
    let n_len = b.n_len();
    let s = simd::splat(BARY_SAFE) * (r.dlen * n_len / dn.abs());
    let ns = -s;
    let sure = simd::ge(b0, s) & simd::ge(b1, s) & simd::ge(b2, s);
    let near = simd::ge(b0, ns) & simd::ge(b1, ns) & simd::ge(b2, ns);
    let mut bits = simd::bitmask(mask & sure & simd::lt(t, simd::splat(tfar)));
    let mut unsure = simd::bitmask(simd::and_not(mask & near, sure));
    if bits | unsure == 0 {
        return None;
    }
    if ANY_HIT && bits != 0 {
        // any hit will do: the first sure lane, without settling the near-edge ones.
        let lane = bits.trailing_zeros() as usize;
        return Some(Hit {
            tri: b.prim[lane],
            t: simd::lanes(t)[lane],
            b1: simd::lanes(b1)[lane],
            b2: simd::lanes(b2)[lane],
        });
    }
    let (mut t, b1, b2) = (simd::lanes(t), simd::lanes(b1), simd::lanes(b2));
    while unsure != 0 {
        let lane = unsure.trailing_zeros() as usize;
        unsure &= unsure - 1;
        if let Some(t64) = hit_f64(accel, b.slot[lane] as usize, r.o1, r.d1, r.tnear, tfar) {
            bits |= 1 << lane;
            t[lane] = t64;
        }
    }
    // record hit: the smallest (t, triangle index) of the lanes that hit.
    let mut best: Option<Hit> = None;
    while bits != 0 {
        let lane = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let tri = b.prim[lane];
        if best.is_none_or(|h| nearer(t[lane], tri, h.t, h.tri)) {
            best = Some(Hit {
                tri,
                t: t[lane],
                b1: b1[lane],
                b2: b2[lane],
            });
        }
    }
    best
}

/// One ray against a node's 8 boxes: the bits of the children met within `[tnear, tfar]`,
/// their entry distances, and the bits of the boxes the ray starts in (entry at `tnear`).
/// Near and far planes are picked per axis by the direction's sign, which gives exactly
/// `min` / `max` of the two plane distances of `hit_box1`.
#[inline(always)]
pub fn hit_node1(node: &Node8, r: &RayWide, tfar: f32) -> NodeHits {
    let axis = |k: usize, o: F32x8, inv: F32x8, inv_far: F32x8| {
        // (`& 1`: the index is 0 or 1, which the compiler then knows.)
        let near = node.bounds[r.near[k] & 1][k];
        let far = node.bounds[(r.near[k] ^ 1) & 1][k];
        ((near - o) * inv, (far - o) * inv_far)
    };
    let (nx, fx) = axis(0, r.o.x, r.inv.x, r.inv_far.x);
    let (ny, fy) = axis(1, r.o.y, r.inv.y, r.inv_far.y);
    let (nz, fz) = axis(2, r.o.z, r.inv.z, r.inv_far.z);
    let lo = simd::max(simd::max(nx, ny), simd::max(nz, simd::splat(r.tnear)));
    let hi = simd::min(
        simd::min(fx, fy),
        simd::min(fz, simd::splat(tfar * SLAB_FAR_SCALE)),
    );
    let hit = simd::bitmask(simd::le(lo, hi)) & node.valid();
    // (the children whose box the ray starts in: entered no later than tnear)
    let inside = simd::bitmask(simd::le(lo, simd::splat(r.tnear)));
    NodeHits {
        bits: hit,
        lo: simd::lanes(lo),
        inside,
    }
}

/// What [`hit_node1`] finds at a node (lanes = child slots).
pub struct NodeHits {
    /// The children met within `[tnear, tfar]`.
    pub bits: u32,
    /// Entry distances.
    pub lo: [f32; 8],
    /// The children whose box the ray starts in (entered no later than `tnear`).
    pub inside: u32,
}

/// One traversal for closest hit and any hit (`ANY_HIT` stops at the first hit).
#[inline(always)]
fn traverse_wide1<const ANY_HIT: bool>(accel: &Accel, ray: &Ray, cull: bool) -> Option<Hit> {
    if !ray.traceable() {
        return None;
    }
    with_stack(&accel.wide, |bvh, stack| {
        walk::<ANY_HIT>(accel, bvh, 0, &RayWide::new(ray), ray.tfar, cull, stack)
    })
    .flatten()
}

/// `f(bvh, stack)` with the thread's traversal stack, grown to [`stack_need`]; `None` (and
/// `f` not called) for an empty tree. Borrowing the thread-local costs a few instructions and
/// a branch, so the batch entries borrow it once for all their rays.
#[inline(always)]
fn with_stack<R>(bvh: &Bvh8, f: impl FnOnce(&Bvh8, &mut [(u32, f32)]) -> R) -> Option<R> {
    if bvh.nodes.is_empty() {
        return None;
    }
    Some(STACK.with_borrow_mut(|stack| {
        grow_stack(stack, bvh);
        f(bvh, stack)
    }))
}

/// Closest hit with `tnear < t < tfar` on the wide tree; equals `intersect1` bit for bit.
pub fn intersect_wide1(accel: &Accel, ray: &Ray, cull: bool) -> Option<Hit> {
    traverse_wide1::<false>(accel, ray, cull)
}

/// Whether anything is hit with `tnear < t < tfar` on the wide tree (shadow rays).
pub fn occluded_wide1(accel: &Accel, ray: &Ray, cull: bool) -> bool {
    traverse_wide1::<true>(accel, ray, cull).is_some()
}

/// `intersect_wide1` on every ray of `rays`, into `out` (the same length): the same answers,
/// the thread's stack borrowed once for the batch. The walks take their steps in turn:
/// scattered rays on a tree larger than the caches eight at a time, each one's next node and
/// leaf blocks prefetched, other batches two at a time (`interleave`, which says when;
/// docs/engines.md has the measurements).
///
/// # Panics
/// If `out` is shorter than `rays`.
pub fn intersect_wide1_many(accel: &Accel, rays: &[Ray], cull: bool, out: &mut [Option<Hit>]) {
    let out = &mut out[..rays.len()];
    out.fill(None);
    let turns = if interleave::worth_it(accel, rays) {
        Turns::Interleaved
    } else {
        Turns::Paired
    };
    batch(accel, rays, cull, turns, |i, w: &Closest| out[i] = w.found);
}

/// Whether [`intersect_wide1_many`] and [`occluded_wide1_many`] walk `rays` eight at a time
/// with prefetches (scattered rays on a tree larger than the caches; see `interleave`).
pub fn interleaves(accel: &Accel, rays: &[Ray]) -> bool {
    interleave::worth_it(accel, rays)
}

/// `occluded_wide1` on every ray of `rays`, into `out` (the same length): scattered rays on
/// a tree larger than the caches interleaved as in [`intersect_wide1_many`], other batches
/// one ray after another.
///
/// # Panics
/// If `out` is shorter than `rays`.
pub fn occluded_wide1_many(accel: &Accel, rays: &[Ray], cull: bool, out: &mut [bool]) {
    let out = &mut out[..rays.len()];
    out.fill(false);
    // (paired, any-hit walks ran slower: 2^20 random rays through the Python package's
    // `test_occlusions`, one thread, kitten, 0.159 s against 0.144 one after another)
    if interleave::worth_it(accel, rays) {
        let found = |i, w: &Any| out[i] = w.found.is_some();
        batch(accel, rays, cull, Turns::Interleaved, found);
    } else {
        walk_each::<true>(accel, rays.iter().copied().enumerate(), cull, |i, _| {
            out[i] = true
        });
    }
}

/// One walk from the root per `(index, ray)`, the thread's stack borrowed once for all of
/// them; `hit(index, h)` for each ray that hits (nothing on an empty tree): the any-hit
/// batches not interleaved and the packets' per-lane calls.
#[inline(always)]
fn walk_each<const ANY_HIT: bool>(
    accel: &Accel,
    rays: impl Iterator<Item = (usize, Ray)>,
    cull: bool,
    mut hit: impl FnMut(usize, Hit),
) {
    with_stack(&accel.wide, |bvh, stack| {
        for (i, ray) in rays.filter(|(_, ray)| ray.traceable()) {
            let r = RayWide::new(&ray);
            if let Some(h) = walk::<ANY_HIT>(accel, bvh, 0, &r, ray.tfar, cull, stack) {
                hit(i, h);
            }
        }
    });
}

/// The active lanes of a packet as `(lane, ray)`.
fn active_lanes(rays: &RayPacket8, active: M32x8) -> impl Iterator<Item = (usize, Ray)> {
    let lanes = Lanes::of(rays);
    let mut bits = simd::bitmask(active);
    std::iter::from_fn(move || {
        (bits != 0).then(|| {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            (i, lanes.ray(i))
        })
    })
}

/// `intersect_wide1` on each active lane of a packet (how the wavefront renderer hands a
/// queue's packets to the single-ray engine); inactive lanes report no hit.
pub fn intersect_wide8(accel: &Accel, rays: &RayPacket8, active: M32x8, cull: bool) -> HitPacket8 {
    let mut hits = HitPacket8::none();
    if simd::bitmask(active) == 0 {
        return hits;
    }
    let (mut tri, mut t, mut b1, mut b2) = (
        simd::u32_lanes(hits.tri),
        simd::lanes(hits.t),
        simd::lanes(hits.b1),
        simd::lanes(hits.b2),
    );
    walk_each::<false>(accel, active_lanes(rays, active), cull, |i, h| {
        (tri[i], t[i], b1[i], b2[i]) = (h.tri, h.t, h.b1, h.b2);
    });
    hits.tri = simd::u32_from_lanes(tri);
    hits.t = simd::from_lanes(t);
    hits.b1 = simd::from_lanes(b1);
    hits.b2 = simd::from_lanes(b2);
    hits
}

/// `occluded_wide1` on each active lane of a packet.
pub fn occluded_wide8(accel: &Accel, rays: &RayPacket8, active: M32x8, cull: bool) -> M32x8 {
    let mut out = 0;
    walk_each::<true>(accel, active_lanes(rays, active), cull, |i, _| {
        out |= 1 << i
    });
    simd::mask_from_bits(out)
}

/// A packet's lanes as plain arrays (one conversion for all lanes).
pub(super) struct Lanes {
    o: [[f32; 8]; 3],
    d: [[f32; 8]; 3],
    tnear: [f32; 8],
    tfar: [f32; 8],
}

impl Lanes {
    #[inline(always)]
    pub(super) fn of(p: &RayPacket8) -> Lanes {
        Lanes {
            o: p.o.to_lanes(),
            d: p.d.to_lanes(),
            tnear: simd::lanes(p.tnear),
            tfar: simd::lanes(p.tfar),
        }
    }
    #[inline(always)]
    pub(super) fn ray(&self, i: usize) -> Ray {
        Ray::new(
            glam::Vec3::new(self.o[0][i], self.o[1][i], self.o[2][i]),
            glam::Vec3::new(self.d[0][i], self.d[1][i], self.d[2][i]),
            self.tnear[i],
            self.tfar[i],
        )
    }
}
