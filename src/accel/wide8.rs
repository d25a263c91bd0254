//! `hybrid8`'s any hit: 8 rays down the 8-wide tree together (the BVH8 x 8 rays cell of the
//! table in `accel`), as `hybrid16`'s any hit takes 16 down it with AVX-512
//! (`packet16::wide16`), each lane alone once few remain.
//!
//! At a node each child's box is tested for the lanes here (one 8-lane slab test per child:
//! each axis's near and far plane picked once when every lane's direction lies in one octant,
//! as `packet::hit_box8_octant`, else both, as `hit_box8`). A hit leaf's triangles are tested
//! for its lanes (`hit_triangle8` on each triangle of its blocks) or, when at most
//! [`SWITCH_WIDE8`] lanes meet it, by each lane against the blocks alone (`hit_block1`); hit
//! inner children are pushed with their lanes. A node reached by at most [`SWITCH_WIDE8`]
//! lanes is walked below by each of them alone (`wide1::walk`, from the node).
//!
//! The occluded lanes are `occluded1`'s: every box test is conservative (the padded boxes,
//! the slab tests of the packet engine, `SLAB_FAR_SCALE`), so every triangle a lane's ray
//! meets within its limits is tested for it, and every triangle test is the contract's.

use super::packet::{BlockLeaf, hit_box8, hit_box8_octant, hit_triangle8};
use super::robust::safe_inv8;
use super::stack::{STACK, Stack, grow_stack};
use super::tri_soa::Leaf;
use super::wide::{Node8, leaf_blocks};
use super::wide1::{Lanes, RayWide, hit_block1, walk};
use super::{Accel, Node, SLAB_FAR_SCALE};
use crate::packet::RayPacket8;
use crate::simd::{self, F32x8, M32x8, Vec3x8};

/// A node reached by at most this many lanes (or a leaf met by at most this many) is left to
/// each lane alone. Measured on the bench workloads (docs/engines.md, "8 rays down the
/// wide tree").
pub const SWITCH_WIDE8: u32 = 3;

/// What the child box tests of a packet need, made once per packet.
struct Boxes {
    inv: Vec3x8,
    /// `inv * SLAB_FAR_SCALE`, and per axis whether the box maximum is the near plane, when
    /// the active lanes share one direction octant.
    octant: Option<(Vec3x8, [bool; 3])>,
    /// `tfar * SLAB_FAR_SCALE`.
    far: F32x8,
}

impl Boxes {
    /// The lanes of `here` whose ray meets child `c` of `node` within its limits.
    #[inline(always)]
    fn child(&self, node: &Node8, c: usize, rays: &RayPacket8, here: M32x8) -> M32x8 {
        let bounds: &[[[f32; 8]; 3]; 2] = wide::bytemuck::cast_ref(&node.bounds);
        let b = |k: usize, axis: usize| bounds[k][axis][c];
        let n = Node {
            min: [b(0, 0), b(0, 1), b(0, 2)],
            max: [b(1, 0), b(1, 1), b(1, 2)],
            count: 0,
            first: 0,
        };
        self.node(&n, rays, here)
    }

    /// The lanes of `here` whose ray meets the box of `n` within its limits.
    #[inline(always)]
    fn node(&self, n: &Node, rays: &RayPacket8, here: M32x8) -> M32x8 {
        match &self.octant {
            Some((inv_far, near)) => {
                hit_box8_octant(
                    n, &rays.o, &self.inv, inv_far, *near, rays.tnear, self.far, here,
                )
                .0
            }
            None => hit_box8(n, &rays.o, &self.inv, rays.tnear, rays.tfar, here).0,
        }
    }
}

/// Lanes of `active` whose ray hits anything with `tnear < t < tfar`: the 8 rays down the
/// wide tree together (see the module header). Equals `occluded8` and `occluded1`.
pub(super) fn occluded_wide8(accel: &Accel, rays: &RayPacket8, active: M32x8, cull: bool) -> M32x8 {
    let mut active = simd::bitmask(active & rays.traceable());
    let bvh = &accel.wide;
    if bvh.nodes.is_empty() || active == 0 {
        return simd::mask_from_bits(0);
    }
    let d = rays.d;
    let inv = Vec3x8::new(safe_inv8(d.x), safe_inv8(d.y), safe_inv8(d.z));
    let neg = [inv.x, inv.y, inv.z].map(|v| simd::bitmask(simd::lt(v, simd::splat(0.0))) & active);
    let one_octant = neg.iter().all(|&b| b == 0 || b == active);
    let boxes = Boxes {
        inv,
        octant: one_octant.then(|| (inv * simd::splat(SLAB_FAR_SCALE), neg.map(|b| b != 0))),
        far: rays.tfar * simd::splat(SLAB_FAR_SCALE),
    };
    let dlen = simd::sqrt(d.dot(d));
    let mut alone = Alone {
        lanes: Lanes::of(rays),
        walkers: [None; 8],
        tfar: simd::lanes(rays.tfar),
        occluded: 0,
    };
    // entries: a node and the lanes that met its box.
    let mut stack: Stack<(u32, u32), 64> = Stack::new();
    // the scene's box first (the binary tree's root): packets that miss the mesh (camera
    // rays past it) leave here, as they leave the binary walk at its root, not after the
    // root's 8 child tests
    let Some(root) = accel.nodes.first() else {
        return simd::mask_from_bits(0);
    };
    active &= simd::bitmask(boxes.node(root, rays, simd::mask_from_bits(active)));
    if active == 0 {
        return simd::mask_from_bits(0);
    }
    let (mut cur, mut here) = (0u32, active);
    STACK.with_borrow_mut(|st| {
        grow_stack(st, bvh);
        loop {
            if here.count_ones() <= SWITCH_WIDE8 {
                // few lanes: each walks this subtree alone.
                active &= !alone.each(here, |rw, tfar| {
                    walk::<true>(accel, bvh, cur, rw, tfar, cull, st).is_some()
                });
                if active == 0 {
                    return;
                }
            } else {
                let node = &bvh.nodes[cur as usize];
                let here_mask = simd::mask_from_bits(here);
                let mut masks = [0u32; 8];
                let mut valid = node.valid();
                while valid != 0 {
                    let c = valid.trailing_zeros() as usize;
                    valid &= valid - 1;
                    masks[c] = simd::bitmask(boxes.child(node, c, rays, here_mask));
                }
                // hit leaves: for the packet, or lane by lane when few lanes meet them
                let leaves = node.leaves() & node.valid();
                let mut lm = leaves;
                while lm != 0 {
                    let c = lm.trailing_zeros() as usize;
                    lm &= lm - 1;
                    let m = masks[c] & active;
                    if m == 0 {
                        continue;
                    }
                    let (first, count) = leaf_blocks(node.child[c]);
                    if m.count_ones() <= SWITCH_WIDE8 {
                        active &= !alone.each(m, |rw, tfar| {
                            (first..first + count)
                                .any(|b| hit_block1::<true>(accel, b, rw, tfar, cull).is_some())
                        });
                    } else {
                        let mut lanes_left = m;
                        'blocks: for block in first..first + count {
                            let blk = &bvh.blocks[block];
                            let leaf = BlockLeaf::new(blk, blk.triangles() as u32);
                            for j in 0..leaf.len() {
                                let (hit, ..) = hit_triangle8(
                                    accel,
                                    &leaf,
                                    j,
                                    rays,
                                    dlen,
                                    rays.tfar,
                                    simd::mask_from_bits(lanes_left),
                                    cull,
                                );
                                let hit = simd::bitmask(hit);
                                alone.occluded |= hit;
                                active &= !hit;
                                lanes_left &= !hit;
                                if lanes_left == 0 {
                                    break 'blocks;
                                }
                            }
                        }
                    }
                    if active == 0 {
                        return;
                    }
                }
                // hit inner children pushed with their lanes (slot order)
                let mut inner = node.valid() & !leaves;
                while inner != 0 {
                    let c = inner.trailing_zeros() as usize;
                    inner &= inner - 1;
                    let m = masks[c] & active;
                    if m != 0 {
                        stack.push((node.child[c], m));
                    }
                }
            }
            // pop the next node some lane still unoccluded met
            loop {
                let Some((next, bits)) = stack.pop() else {
                    return;
                };
                let m = bits & active;
                if m != 0 {
                    (cur, here) = (next, m);
                    break;
                }
            }
        }
    });
    simd::mask_from_bits(alone.occluded)
}

/// The lanes' single-ray tests, and the occluded lanes.
struct Alone {
    lanes: Lanes,
    /// Each lane's splat for the single-ray tests, made when first needed.
    walkers: [Option<RayWide>; 8],
    tfar: [f32; 8],
    /// The lanes found occluded so far.
    occluded: u32,
}

impl Alone {
    /// `test(lane's splat, its tfar)` for each lane of `m` (`true`: it hits); the lanes
    /// that hit, also added to `occluded`.
    #[inline(always)]
    fn each(&mut self, m: u32, mut test: impl FnMut(&RayWide, f32) -> bool) -> u32 {
        let mut hit = 0;
        let mut bits = m;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let lanes = &self.lanes;
            let rw = self.walkers[i].get_or_insert_with(|| RayWide::new(&lanes.ray(i)));
            if test(rw, self.tfar[i]) {
                hit |= 1 << i;
            }
        }
        self.occluded |= hit;
        hit
    }
}
