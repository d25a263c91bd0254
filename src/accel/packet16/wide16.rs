//! `hybrid16`'s walks of the 8-wide tree with 16 rays together (the BVH8 x 16 rays cell of
//! `accel`'s table): any hit always, closest hit when the lanes share a direction octant,
//! each lane alone once few remain. The 16-lane steps (`hit_triangle16`, `take_hits16`,
//! `take_lane16`, `nearer16`, the set-up) are `packet16`'s.

use super::*;

/// Child slot `c` of a wide node against the lanes `here`: the lanes that meet its box within
/// `[tnear, tfar]`, and their entry distances (`far` is `tfar * SLAB_FAR_SCALE`). When the
/// lanes share an octant each axis's near and far plane is picked once (the far distances
/// widened through `inv_far`, as `hit_node1`); otherwise both planes of each axis, as
/// `hit_box16`. (A macro, as `hit_triangle16`: as a `#[target_feature]` function LLVM kept it
/// out of line, a call per child.)
macro_rules! child_box16 {
    ($node:expr, $c:expr, $r:expr, $tfar:expr, $far:expr, $here:expr) => {{
        let (node, c, r, tfar, far, here): (
            &crate::accel::wide::Node8,
            usize,
            &Rays16,
            __m512,
            __m512,
            u16,
        ) = ($node, $c, $r, $tfar, $far, $here);
        let b = |k: usize, axis: usize| -> f32 {
            bytemuck::cast::<_, [f32; 8]>(node.bounds[k][axis])[c]
        };
        if let Some(near) = r.octant {
            let t = |bound: f32, o: __m512, inv: __m512| {
                _mm512_mul_ps(_mm512_sub_ps(splat(bound), o), inv)
            };
            let n = |axis: usize| near[axis] as usize;
            let nx = t(b(n(0), 0), r.o.x, r.inv.x);
            let fx = t(b(1 - n(0), 0), r.o.x, r.inv_far.x);
            let ny = t(b(n(1), 1), r.o.y, r.inv.y);
            let fy = t(b(1 - n(1), 1), r.o.y, r.inv_far.y);
            let nz = t(b(n(2), 2), r.o.z, r.inv.z);
            let fz = t(b(1 - n(2), 2), r.o.z, r.inv_far.z);
            let lo = _mm512_max_ps(_mm512_max_ps(nx, ny), _mm512_max_ps(nz, r.tnear));
            let hi = _mm512_min_ps(_mm512_min_ps(fx, fy), _mm512_min_ps(fz, far));
            (_mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(here, lo, hi), lo)
        } else {
            let n = crate::accel::Node {
                min: [b(0, 0), b(0, 1), b(0, 2)],
                max: [b(1, 0), b(1, 1), b(1, 2)],
                count: 0,
                first: 0,
            };
            let (m, lo, _) = hit_box16(&n, r, tfar, here);
            (m, lo)
        }
    }};
}

/// `hybrid16`'s any hit: the 16 rays down the wide tree together, as Embree's hybrid
/// packets go down its BVH8. At a node each child's box is tested for the lanes here (one
/// 16-lane slab test per child, each axis's near and far plane picked once when every lane's
/// direction lies in one octant, as `hit_box16`); a hit leaf's triangles are tested for its
/// lanes (`hit_triangle16` on each lane of its blocks), or, when at most [`SWITCH_WIDE16`]
/// lanes meet it, each lane against the blocks alone (`hit_block1`); hit inner children are
/// pushed with their lanes. A node reached by at most [`SWITCH_WIDE16`] lanes is walked
/// below by each of them alone (`wide1::walk_any`, from the node: no descent from the
/// root). The occluded lanes are `occluded1`'s: every box test is conservative (the padded
/// boxes, `SLAB_FAR_SCALE`) and every triangle test is the contract's.
#[target_feature(enable = "avx512f,avx512dq")]
pub(super) fn traverse_wide16_any(
    accel: &Accel,
    rays: [&RayPacket8; 2],
    active: [M32x8; 2],
    cull: bool,
) -> u16 {
    let mut active = (simd::bitmask(active[0]) | simd::bitmask(active[1]) << 8) as u16;
    let bvh = &accel.wide;
    if bvh.nodes.is_empty() || active == 0 {
        return 0;
    }
    let (mut r, tfar) = rays16(rays);
    r.octant = octant_of([r.inv.x, r.inv.y, r.inv.z], active);
    let far = _mm512_mul_ps(tfar, splat(SLAB_FAR_SCALE));
    let tf = lanes16(tfar);
    let mut occluded = 0u16;
    // entries: a node and the lanes that met its box.
    let mut stack: Stack<(u32, u16), 64> = Stack::new();
    // each lane's splat for the single-ray walks, made when first needed
    let mut walkers: [Option<RayWide>; 16] = [None; 16];
    let (mut cur, mut here) = (0u32, active);
    // (the thread's stack borrowed here rather than through `wide1::with_stack`, whose
    // closure, compiled without AVX-512, would call this one out of line)
    STACK.with_borrow_mut(|st| {
        grow_stack(st, bvh);
        loop {
            if here.count_ones() <= SWITCH_WIDE16 {
                // few lanes: each walks this subtree alone.
                let mut bits = here;
                while bits != 0 {
                    let i = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    let rw = walkers[i].get_or_insert_with(|| r.walker(i));
                    if walk::<true>(accel, bvh, cur, rw, tf[i], cull, st).is_some() {
                        occluded |= 1 << i;
                        active &= !(1 << i);
                    }
                }
                if active == 0 {
                    return occluded;
                }
            } else {
                // each child's box for the lanes here
                let node = &bvh.nodes[cur as usize];
                let mut masks = [0u16; 8];
                let mut valid = node.valid();
                while valid != 0 {
                    let c = valid.trailing_zeros() as usize;
                    valid &= valid - 1;
                    masks[c] = child_box16!(node, c, &r, tfar, far, here).0;
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
                    let (first, count) = crate::accel::wide::leaf_blocks(node.child[c]);
                    if m.count_ones() <= SWITCH_WIDE16 {
                        let mut bits = m;
                        while bits != 0 {
                            let i = bits.trailing_zeros() as usize;
                            bits &= bits - 1;
                            let rw = walkers[i].get_or_insert_with(|| r.walker(i));
                            for block in first..first + count {
                                if crate::accel::wide1::hit_block1::<true>(
                                    accel, block, rw, tf[i], cull,
                                )
                                .is_some()
                                {
                                    occluded |= 1 << i;
                                    active &= !(1 << i);
                                    break;
                                }
                            }
                        }
                    } else {
                        for block in first..first + count {
                            let blk = &bvh.blocks[block];
                            let leaf =
                                crate::accel::packet::BlockLeaf::new(blk, blk.triangles() as u32);
                            let mut lanes = m & active;
                            for j in 0..leaf.len() {
                                if lanes == 0 {
                                    break;
                                }
                                let (hit, ..) =
                                    hit_triangle16!(accel, &leaf, j, &r, tfar, lanes, cull);
                                occluded |= hit;
                                active &= !hit;
                                lanes &= !hit;
                            }
                        }
                    }
                    if active == 0 {
                        return occluded;
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
                    return occluded;
                };
                let m = bits & active;
                if m != 0 {
                    (cur, here) = (next, m);
                    break;
                }
            }
        }
    })
}

/// `hybrid16`'s closest hit for packets whose lanes share a direction octant: the 16 rays
/// down the wide tree together, as `traverse_wide16_any`, with each lane's closest hit so
/// far kept in lanes. A node's hit leaves are tested first (for the packet, or lane by lane
/// when at most [`SWITCH_WIDE16`] lanes meet them, each skipped by the lanes whose hit lies
/// before its box), then its hit inner children are pushed farthest first in the octant's
/// order, each with its lanes and their entry distances; a popped entry keeps the lanes
/// whose hit still lies beyond its box. A node reached by at most [`SWITCH_WIDE16`] lanes is
/// walked below by each lane alone from its hit so far (`wide1::walk`). Hits are recorded
/// as everywhere: nearer, or as near with a lower triangle index, so each lane's answer is
/// `intersect1`'s.
#[target_feature(enable = "avx512f,avx512dq")]
pub(super) fn traverse_wide16_closest(
    accel: &Accel,
    rays: [&RayPacket8; 2],
    active: [M32x8; 2],
    cull: bool,
) -> [HitPacket8; 2] {
    let none = [HitPacket8::none(); 2];
    let active = (simd::bitmask(active[0]) | simd::bitmask(active[1]) << 8) as u16;
    let bvh = &accel.wide;
    if bvh.nodes.is_empty() || active == 0 {
        return none;
    }
    let (mut r, mut tfar) = rays16(rays);
    r.octant = octant_of([r.inv.x, r.inv.y, r.inv.z], active);
    let octant = r
        .octant
        .map(|n| n[0] as usize | (n[1] as usize) << 1 | (n[2] as usize) << 2);
    let mut tri = _mm512_set1_epi32(Hit::NONE_ID as i32);
    let mut t_hit = splat(f32::INFINITY);
    let (mut b1_hit, mut b2_hit) = (splat(0.0), splat(0.0));
    // entries: a node, the lanes that met its box and their entry distances.
    let mut stack: Stack<(u32, u16, [f32; 16]), 64> = Stack::new();
    // each lane's splat for the single-ray walks, made when first needed
    let mut walkers: [Option<RayWide>; 16] = [None; 16];
    let (mut cur, mut here) = (0u32, active);
    // (the thread's stack borrowed here rather than through `wide1::with_stack`, whose
    // closure, compiled without AVX-512, would call this one out of line)
    STACK.with_borrow_mut(|st| {
        grow_stack(st, bvh);
        loop {
            if here.count_ones() <= SWITCH_WIDE16 {
                // few lanes: each walks this subtree alone.
                let tf = lanes16(tfar);
                let mut bits = here;
                while bits != 0 {
                    let i = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    let rw = walkers[i].get_or_insert_with(|| r.walker(i));
                    if let Some(h) = walk::<false>(accel, bvh, cur, rw, tf[i], cull, st) {
                        take_lane16!(i, h; tri, t_hit, b1_hit, b2_hit, tfar);
                    }
                }
            } else {
                // each child's box for the lanes here, with their entry distances
                let node = &bvh.nodes[cur as usize];
                let far = _mm512_mul_ps(tfar, splat(SLAB_FAR_SCALE));
                let mut masks = [0u16; 8];
                let mut los = [splat(0.0); 8];
                let mut valid = node.valid();
                while valid != 0 {
                    let c = valid.trailing_zeros() as usize;
                    valid &= valid - 1;
                    (masks[c], los[c]) = child_box16!(node, c, &r, tfar, far, here);
                }
                // hit leaves: for the packet, or lane by lane when few lanes meet them
                let leaves = node.leaves() & node.valid();
                let mut lm = leaves;
                while lm != 0 {
                    let c = lm.trailing_zeros() as usize;
                    lm &= lm - 1;
                    // lanes whose closest hit so far lies beyond the leaf's entry
                    let far = _mm512_mul_ps(tfar, splat(SLAB_FAR_SCALE));
                    let m = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(masks[c], los[c], far);
                    if m == 0 {
                        continue;
                    }
                    let (first, count) = crate::accel::wide::leaf_blocks(node.child[c]);
                    if m.count_ones() <= SWITCH_WIDE16 {
                        let tf = lanes16(tfar);
                        let mut bits = m;
                        while bits != 0 {
                            let i = bits.trailing_zeros() as usize;
                            bits &= bits - 1;
                            let rw = walkers[i].get_or_insert_with(|| r.walker(i));
                            let mut limit = tf[i];
                            for block in first..first + count {
                                if let Some(h) = crate::accel::wide1::hit_block1::<false>(
                                    accel, block, rw, limit, cull,
                                ) {
                                    take_lane16!(i, h; tri, t_hit, b1_hit, b2_hit, tfar);
                                    limit = h.t.next_up();
                                }
                            }
                        }
                    } else {
                        for block in first..first + count {
                            let blk = &bvh.blocks[block];
                            let leaf =
                                crate::accel::packet::BlockLeaf::new(blk, blk.triangles() as u32);
                            for j in 0..leaf.len() {
                                let (mask, t, b1, b2) =
                                    hit_triangle16!(accel, &leaf, j, &r, tfar, m, cull);
                                if mask == 0 {
                                    continue;
                                }
                                // record hit (as `traverse16`)
                                let id = _mm512_set1_epi32(blk.prim[j] as i32);
                                let better = _mm512_cmp_ps_mask::<_CMP_LT_OQ>(t, t_hit)
                                    | _mm512_cmplt_epu32_mask(id, tri);
                                take_hits16!(mask & better, id, t, b1, b2, next_up(t);
                                    tri, t_hit, b1_hit, b2_hit, tfar);
                            }
                        }
                    }
                }
                // inner children pushed farthest first (the octant's order when the lanes
                // share one, else slot order)
                let inner = node.valid() & !leaves;
                let order = octant.map_or(0o76543210, |o| node.order[o]);
                for k in (0..8).rev() {
                    let c = (order >> (3 * k) & 7) as usize;
                    if inner >> c & 1 == 0 || masks[c] == 0 {
                        continue;
                    }
                    stack.push((node.child[c], masks[c], lanes16(los[c])));
                }
            }
            // pop the next node some lane reaches before its closest hit
            loop {
                let Some((next, bits, lo)) = stack.pop() else {
                    let (tri, t, b1, b2): ([u32; 16], [f32; 16], [f32; 16], [f32; 16]) = (
                        bytemuck::cast(tri),
                        lanes16(t_hit),
                        lanes16(b1_hit),
                        lanes16(b2_hit),
                    );
                    let half = |h: usize| {
                        let s =
                            |a: &[f32; 16]| simd::from_lanes(std::array::from_fn(|i| a[8 * h + i]));
                        HitPacket8 {
                            tri: simd::u32_from_lanes(std::array::from_fn(|i| tri[8 * h + i])),
                            t: s(&t),
                            b1: s(&b1),
                            b2: s(&b2),
                        }
                    };
                    return [half(0), half(1)];
                };
                let far = _mm512_mul_ps(tfar, splat(SLAB_FAR_SCALE));
                let m = _mm512_mask_cmp_ps_mask::<_CMP_LE_OQ>(bits, bytemuck::cast(lo), far);
                if m != 0 {
                    (cur, here) = (next, m);
                    break;
                }
            }
        }
    })
}
