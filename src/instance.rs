//! Instancing: placements of a few meshes, traced through a two-level BVH.
//!
//! The bottom level is one ordinary [`Accel`] per distinct mesh, in the mesh's own (object)
//! space; the top level is a BVH2 over the placements' world boxes (each the mesh's root box
//! carried through the placement's affine transform). A ray meets an instance's box, is
//! carried into object space by the inverse transform (the direction linearly and not
//! normalised, so `t` is the same parameter in both spaces), and is traced by the chosen
//! engine's own entry point with the closest hit so far as its limit. Hits are merged with
//! the engines' closest-hit rule on *global* triangle ids: an instance's `base` (the
//! triangles of the placements before it) plus the local id, which is how the scene
//! flattened in placement order would number them.
//!
//! Per engine: `scalar` and `wide1` walk the top level per ray and call `intersect1` /
//! `intersect_wide1` (and `occluded*`); `packet8` and `hybrid8` walk it with 8 rays, the
//! lanes whose boxes meet an instance carried into its space together and traced by one
//! `intersect8` / `intersect_hybrid8` call; `packet16` and `hybrid16` the same with 16 lanes
//! and the 16-ray entry points. The top level's box tests are per lane: the top tree is
//! shallow next to the meshes' trees.

use crate::accel::{
    Accel, BOX_PAD, Node, SLAB_FAR_SCALE, intersect_hybrid8, intersect_hybrid16, intersect_wide1,
    intersect1, intersect8, intersect16, occluded_hybrid8, occluded_hybrid16, occluded_wide1,
    occluded1, occluded8, occluded16, safe_inv,
};
use crate::engine::Engine;
use crate::packet::{HitPacket8, RayPacket8};
use crate::ray::{Hit, Ray};
use crate::simd::{self, M32x8};
use glam::{Affine3A, Vec3};
use obvhs::aabb::Aabb;
use rayon::prelude::*;

/// One placement of a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Instance {
    /// Index of its mesh (bottom level).
    pub mesh: u32,
    /// Object space to world space.
    pub to_world: Affine3A,
    /// World space to object space (`to_world`'s inverse).
    pub to_object: Affine3A,
    /// Global id of its first triangle: the triangles of every placement before it.
    pub base: u64,
}

impl Instance {
    /// `ray` in this instance's object space, accepting hits in `(ray.tnear, tfar)`.
    #[inline(always)]
    pub fn object_ray(&self, ray: &Ray, tfar: f32) -> Ray {
        Ray::new(
            self.to_object.transform_point3(ray.origin),
            self.to_object.transform_vector3(ray.dir),
            ray.tnear,
            tfar,
        )
    }
}

/// A closest hit through instances: the instance and the hit on its mesh (`hit.tri` is the
/// mesh's own triangle index).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstHit {
    /// Index of the instance hit.
    pub inst: u32,
    /// The hit in the mesh's numbering; `t` is the world ray's parameter.
    pub hit: Hit,
}

/// The engines' closest-hit rule ([`crate::accel::nearer`]) on global triangle ids.
#[inline(always)]
pub fn nearer_global(t: f32, id: u64, than_t: f32, than_id: u64) -> bool {
    t < than_t || (t == than_t && id < than_id)
}

/// A two-level BVH: the meshes' trees and the placements' tree.
#[derive(Clone, Debug, Default)]
pub struct Instances {
    /// One tree per distinct mesh, in object space.
    pub meshes: Vec<Accel>,
    /// The placements, in the order their global ids follow.
    pub instances: Vec<Instance>,
    /// The top level over the instances' world boxes (padded like [`Accel`]'s nodes); a
    /// leaf's `first .. first + count` index `order`.
    top: Vec<Node>,
    /// Instance index per top-level leaf slot (instances of empty meshes are left out).
    order: Vec<u32>,
    /// Deepest root-to-leaf path of the top level.
    depth: usize,
    /// Triangles of the scene as if flattened: the sum over the instances.
    pub triangles: u64,
}

impl Instances {
    /// The two-level BVH of `meshes` placed by `placements` (mesh index, object-to-world
    /// transform). Transforms must be invertible (callers check: the scene file and glTF
    /// readers refuse singular and non-finite ones).
    ///
    /// # Panics
    /// If a placement names a mesh past `meshes`.
    pub fn new(meshes: Vec<Accel>, placements: &[(u32, Affine3A)]) -> Instances {
        let mut base = 0u64;
        let instances: Vec<Instance> = placements
            .iter()
            .map(|&(mesh, to_world)| {
                let i = Instance {
                    mesh,
                    to_world,
                    to_object: inverse(&to_world),
                    base,
                };
                base += meshes[mesh as usize].tris.len() as u64;
                i
            })
            .collect();
        let (mut boxes, mut ids) = (Vec::new(), Vec::new());
        for (k, inst) in instances.iter().enumerate() {
            if let Some(root) = meshes[inst.mesh as usize].nodes.first() {
                let (lo, hi) = world_box(root, &inst.to_world);
                boxes.push(Aabb::new(lo.into(), hi.into()));
                ids.push(k as u32);
            }
        }
        let (top, order) = if boxes.is_empty() {
            (Vec::new(), Vec::new())
        } else {
            let bvh = obvhs::bvh2::builder::build_bvh2(
                &boxes,
                obvhs::BvhBuildParams::fast_build(),
                &mut std::time::Duration::default(),
            );
            let top = bvh
                .nodes
                .iter()
                .map(|n| {
                    let (lo, hi) = pad(Vec3::from(n.aabb.min), Vec3::from(n.aabb.max));
                    Node {
                        min: lo.into(),
                        max: hi.into(),
                        count: n.prim_count,
                        first: n.first_index,
                    }
                })
                .collect();
            let order = bvh
                .primitive_indices
                .iter()
                .map(|&p| ids[p as usize])
                .collect();
            (top, order)
        };
        let depth = crate::accel::tree_depth(&top);
        Instances {
            meshes,
            instances,
            top,
            order,
            depth,
            triangles: base,
        }
    }

    /// The world box of everything placed (`None` when nothing is).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        self.top
            .first()
            .map(|n| (Vec3::from(n.min), Vec3::from(n.max)))
    }

    /// Nodes of the top level.
    pub fn top_nodes(&self) -> usize {
        self.top.len()
    }

    /// Bytes of everything traversal reads: the meshes' trees, the instances and the top level.
    pub fn bytes(&self) -> usize {
        self.meshes.iter().map(Accel::bytes).sum::<usize>()
            + self.instances.len() * size_of::<Instance>()
            + self.top.len() * size_of::<Node>()
            + self.order.len() * size_of::<u32>()
    }

    /// The global id of a hit (the flattened scene's triangle index).
    pub fn global(&self, h: &InstHit) -> u64 {
        self.instances[h.inst as usize].base + h.hit.tri as u64
    }

    /// Closest hit of one ray, each instance traced by `bottom` (`intersect1`,
    /// `intersect_wide1`, ...) with the closest hit so far as its limit.
    pub fn intersect_with(
        &self,
        ray: &Ray,
        bottom: impl Fn(&Accel, &Ray) -> Option<Hit>,
    ) -> Option<InstHit> {
        self.walk1::<false>(ray, &mut Vec::new(), bottom)
    }

    /// Whether anything blocks one ray within `(tnear, tfar)`, each instance asked by
    /// `bottom` (`occluded1`, `occluded_wide1`, ...) until one answers yes.
    pub fn occluded_with(&self, ray: &Ray, bottom: impl Fn(&Accel, &Ray) -> bool) -> bool {
        self.walk1::<true>(ray, &mut Vec::new(), |a, r| {
            bottom(a, r).then_some(Hit {
                tri: 0,
                t: 0.0,
                b1: 0.0,
                b2: 0.0,
            })
        })
        .is_some()
    }

    /// The single-ray walk of the top level: closest hit, or (`ANY_HIT`) the first hit.
    fn walk1<const ANY_HIT: bool>(
        &self,
        ray: &Ray,
        stack: &mut Vec<(u32, f32)>,
        bottom: impl Fn(&Accel, &Ray) -> Option<Hit>,
    ) -> Option<InstHit> {
        // (a ray that can hit nothing is answered before the walk: see `Ray::traceable`)
        if self.top.is_empty() || !ray.traceable() {
            return None;
        }
        let inv = Vec3::from(ray.dir.to_array().map(safe_inv));
        let (o, tnear) = (ray.origin, ray.tnear);
        let mut tfar = ray.tfar;
        let mut best: Option<(InstHit, u64)> = None;
        stack.clear();
        if let Some(t) = hit_box(&self.top[0], o, inv, tnear, tfar) {
            stack.push((0, t));
        }
        while let Some((node, tentry)) = stack.pop() {
            if tentry > tfar * SLAB_FAR_SCALE {
                continue;
            }
            let n = self.top[node as usize];
            if n.count > 0 {
                for &i in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    let inst = &self.instances[i as usize];
                    let r = inst.object_ray(ray, tfar);
                    let Some(hit) = bottom(&self.meshes[inst.mesh as usize], &r) else {
                        continue;
                    };
                    // record hit: as in the engines, the limit becomes the next float above
                    // the best t, so an exact tie with another instance reaches here and the
                    // lower global id wins whatever the visiting order.
                    let id = inst.base + hit.tri as u64;
                    if best.is_none_or(|(b, bid)| nearer_global(hit.t, id, b.hit.t, bid)) {
                        best = Some((InstHit { inst: i, hit }, id));
                        tfar = hit.t.next_up();
                    }
                    if ANY_HIT {
                        return best.map(|b| b.0);
                    }
                }
            } else {
                // the nearer child on top of the stack
                let (l, r) = (n.first, n.first + 1);
                let tl = hit_box(&self.top[l as usize], o, inv, tnear, tfar);
                let tr = hit_box(&self.top[r as usize], o, inv, tnear, tfar);
                match (tl, tr) {
                    (Some(a), Some(b)) if a <= b => stack.extend([(r, b), (l, a)]),
                    (Some(a), Some(b)) => stack.extend([(l, a), (r, b)]),
                    (Some(a), None) => stack.push((l, a)),
                    (None, Some(b)) => stack.push((r, b)),
                    (None, None) => {}
                }
            }
        }
        best.map(|b| b.0)
    }

    /// The walk of a group of up to 16 rays (lanes `active`): per node, the lanes whose rays
    /// meet its box go on; at an instance, `leaf(instance, lanes)` traces those lanes in its
    /// space and returns the lanes that are done (any hit found), which leave the walk.
    /// `limit[i]` is lane `i`'s current far limit (the leaf lowers it on closest hits).
    fn walk_group(
        &self,
        rays: &[Ray],
        active: u32,
        limit: &[f32; 16],
        stack: &mut Vec<(u32, u32)>,
        mut leaf: impl FnMut(u32, u32, &[f32; 16]) -> (u32, [f32; 16]),
    ) {
        let mut active = active;
        for (i, r) in rays.iter().enumerate() {
            if !r.traceable() {
                active &= !(1 << i);
            }
        }
        if self.top.is_empty() || active == 0 {
            return;
        }
        let inv: [Vec3; 16] = std::array::from_fn(|i| {
            rays.get(i)
                .map_or(Vec3::ONE, |r| Vec3::from(r.dir.to_array().map(safe_inv)))
        });
        let mut limit = *limit;
        let meets = |node: &Node, bits: u32, limit: &[f32; 16]| {
            let mut out = 0;
            for i in (0..rays.len()).filter(|&i| bits >> i & 1 == 1) {
                let r = &rays[i];
                out |= (hit_box(node, r.origin, inv[i], r.tnear, limit[i]).is_some() as u32) << i;
            }
            out
        };
        stack.clear();
        stack.push((0, active));
        while let Some((node, bits)) = stack.pop() {
            let n = self.top[node as usize];
            let bits = meets(&n, bits & active, &limit);
            if bits == 0 {
                continue;
            }
            if n.count > 0 {
                for &i in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    let lanes = bits & active;
                    if lanes == 0 {
                        break;
                    }
                    let (done, new_limit) = leaf(i, lanes, &limit);
                    limit = new_limit;
                    active &= !done;
                }
            } else {
                stack.extend([(n.first + 1, bits), (n.first, bits)]);
            }
        }
    }

    /// Closest hits of a group of up to 16 rays (lanes `active`); each instance's lanes go
    /// through `bottom` together (`lanes`: the rays in object space, their mask).
    fn intersect_group(
        &self,
        rays: &[Ray],
        active: u32,
        stack: &mut Vec<(u32, u32)>,
        out: &mut [Option<InstHit>],
        bottom: impl Fn(&Accel, &[Option<Ray>; 16]) -> [Option<Hit>; 16],
    ) {
        let mut best: [Option<(InstHit, u64)>; 16] = [None; 16];
        let limit = std::array::from_fn(|i| rays.get(i).map_or(0.0, |r| r.tfar));
        self.walk_group(rays, active, &limit, stack, |i, lanes, limit| {
            let inst = &self.instances[i as usize];
            let object: [Option<Ray>; 16] = std::array::from_fn(|k| {
                (lanes >> k & 1 == 1).then(|| inst.object_ray(&rays[k], limit[k]))
            });
            let hits = bottom(&self.meshes[inst.mesh as usize], &object);
            let mut limit = *limit;
            for (k, h) in hits.iter().enumerate() {
                let Some(hit) = *h else { continue };
                let id = inst.base + hit.tri as u64;
                if best[k].is_none_or(|(b, bid)| nearer_global(hit.t, id, b.hit.t, bid)) {
                    best[k] = Some((InstHit { inst: i, hit }, id));
                    limit[k] = hit.t.next_up();
                }
            }
            (0, limit)
        });
        for (o, b) in out.iter_mut().zip(best) {
            *o = b.map(|b| b.0);
        }
    }

    /// Which of a group of up to 16 rays (lanes `active`) are blocked; each instance's lanes
    /// go through `bottom` together, which returns the blocked lanes.
    fn occluded_group(
        &self,
        rays: &[Ray],
        active: u32,
        stack: &mut Vec<(u32, u32)>,
        bottom: impl Fn(&Accel, &[Option<Ray>; 16]) -> u32,
    ) -> u32 {
        let mut blocked = 0;
        let limit = std::array::from_fn(|i| rays.get(i).map_or(0.0, |r| r.tfar));
        self.walk_group(rays, active, &limit, stack, |i, lanes, limit| {
            let inst = &self.instances[i as usize];
            let object: [Option<Ray>; 16] = std::array::from_fn(|k| {
                (lanes >> k & 1 == 1).then(|| inst.object_ray(&rays[k], limit[k]))
            });
            let done = bottom(&self.meshes[inst.mesh as usize], &object) & lanes;
            blocked |= done;
            (done, *limit)
        });
        blocked
    }
}

/// The slab test of one top-level box: the entry distance, if the ray meets the box within
/// `[tnear, tfar]` (the far side widened by [`SLAB_FAR_SCALE`], as in `intersect1`).
#[inline(always)]
fn hit_box(n: &Node, o: Vec3, inv: Vec3, tnear: f32, tfar: f32) -> Option<f32> {
    let t0 = (Vec3::from(n.min) - o) * inv;
    let t1 = (Vec3::from(n.max) - o) * inv;
    let lo = t0.min(t1).max_element().max(tnear);
    let hi = t0.max(t1).min_element().min(tfar);
    (lo <= hi * SLAB_FAR_SCALE).then_some(lo)
}

/// The world box of a mesh's root box placed by `m`: its 8 corners transformed, padded for
/// the rounding of that transform.
fn world_box(root: &Node, m: &Affine3A) -> (Vec3, Vec3) {
    let (a, b) = (Vec3::from(root.min), Vec3::from(root.max));
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for k in 0..8 {
        let c = Vec3::new(
            if k & 1 == 0 { a.x } else { b.x },
            if k & 2 == 0 { a.y } else { b.y },
            if k & 4 == 0 { a.z } else { b.z },
        );
        let p = m.transform_point3(c);
        (lo, hi) = (lo.min(p), hi.max(p));
    }
    // each coordinate is a sum of three products and the translation: its rounding is
    // within a few ulps of |M| |corner| + |translation|
    let size = a.abs().max(b.abs()).max_element();
    let mag = Vec3::from(m.matrix3.x_axis).abs().max_element()
        + Vec3::from(m.matrix3.y_axis).abs().max_element()
        + Vec3::from(m.matrix3.z_axis).abs().max_element();
    let bound = mag * size + Vec3::from(m.translation).abs().max_element();
    let err = 8.0 * f32::EPSILON * bound;
    (lo - err, hi + err)
}

/// Whether `m` is finite and has an inverse that f32 holds (computed in f64): the scene
/// file and glTF readers refuse or skip placements that fail this.
pub fn invertible(m: &Affine3A) -> bool {
    let m3 = glam::DMat3::from_cols_array(&m.matrix3.to_cols_array().map(f64::from));
    let det = m3.determinant();
    // singular, or so near it that the inverse leaves f32
    m.is_finite()
        && det != 0.0
        && (m3.inverse().to_cols_array().iter()).all(|x| (*x as f32).is_finite())
}

/// `m`'s inverse, computed in f64 and rounded once (an f32 inverse of a rotated, unevenly
/// scaled placement carried object-space rays a few ulps further from the flattened scene's).
fn inverse(m: &Affine3A) -> Affine3A {
    let d = glam::DAffine3::from_cols_array(&m.to_cols_array().map(f64::from)).inverse();
    Affine3A::from_cols_array(&d.to_cols_array().map(|x| x as f32))
}

/// A top-level box padded as [`Accel::build`] pads its nodes.
fn pad(lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
    let p = BOX_PAD * lo.abs().max(hi.abs()).max_element() + f32::MIN_POSITIVE;
    (lo - p, hi + p)
}

mod batch;
pub use batch::{Bottom8, Bottom16, Occluded8, Occluded16};

#[cfg(test)]
mod tests;
