//! Single-ray traversal and the assignment's ray/triangle test, one ray at a time.
//!
//! `intersect1` / `occluded1` are the scalar twins of `intersect8` / `occluded8`: the same
//! steps in the same order with the same arithmetic, so every packet lane equals them bit for
//! bit. `literal_hit` is the contract of SCENES.md §2 written out in f64, the yardstick the
//! fast forms are held to.

use super::Accel;
use super::robust::{BARY_SAFE, SLAB_FAR_SCALE, nearer, safe_inv};
use super::stack::Stack;
use crate::ray::{Hit, Ray};

#[inline(always)]
fn sub(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline(always)]
fn dot(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A ray as the kernel reads it: origin, direction and `|d|` (for the grazing margin),
/// computed once per ray rather than once per triangle.
#[derive(Clone, Copy, Debug)]
pub struct Ray1 {
    /// Origin.
    pub o: [f32; 3],
    /// Direction, as given (not normalised; `t` is in units of it).
    pub d: [f32; 3],
    /// `|d|`.
    pub dlen: f32,
}

impl Ray1 {
    /// The kernel's view of `ray`.
    #[inline(always)]
    pub fn new(ray: &Ray) -> Self {
        let d = ray.dir.to_array();
        Ray1 {
            o: ray.origin.to_array(),
            d,
            dlen: dot(d, d).sqrt(),
        }
    }
}

/// The plane + barycentric test against SoA slot `i`; `Some((t, b1, b2))` when the ray hits
/// with `tnear < t < tfar`. Steps (identical in the 8-wide kernel):
#[inline(always)]
pub fn hit_triangle1(
    accel: &Accel,
    i: usize,
    ray: &Ray1,
    tnear: f32,
    tfar: f32,
    cull: bool,
) -> Option<(f32, f32, f32)> {
    let (o, d) = (ray.o, ray.d);
    let tri = &accel.tris;
    let n = tri.n(i);
    let v0 = tri.v0(i);
    // plane hit: t = <v0 - p, n> / <d, n>. A ray in the plane gives x/0 = inf or 0/0 = NaN,
    // a zero-area triangle (n = 0) gives 0/0 = NaN; both fail the depth test below.
    let dn = dot(d, n);
    // culling: skip back faces (<d, n> >= 0); NaN is not culled here and fails below.
    if cull && dn >= 0.0 {
        return None;
    }
    let t = dot(sub(v0, o), n) / dn;
    // depth test, near side: NaN fails the comparison and so misses. The far side waits for
    // the barycentrics: a hit near an edge takes its distance from f64 (below), and whether
    // a triangle is a hit must not hang on the limit a walk has reached, or two walks that
    // meet triangles in different orders could return different ones.
    if !(t > tnear) {
        return None;
    }
    // barycentric: q = p + t d; each weight is the signed area of the sub-triangle opposite
    // its vertex over the whole area, precomputed as a linear form of w = q - v0 (tri_soa.rs).
    let q = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
    let w = sub(q, v0);
    let b1 = dot(w, tri.p1(i));
    let b2 = dot(w, tri.p2(i));
    let b0 = 1.0 - b1 - b2;
    // inside when no coordinate is negative (NaN fails >= and so misses). Clear cases are
    // decided here; within BARY_SAFE of an edge the f32 areas are rounding noise, so the
    // edge signs are decided exactly-enough in f64 (the same call in the packet kernel).
    // The noise grows as the ray grazes the plane (q slides along it): the margin is
    // BARY_SAFE / |cos(d, n)|.
    let s = BARY_SAFE * (ray.dlen * tri.n_len[i] / dn.abs());
    if b0 >= s && b1 >= s && b2 >= s {
        return (t < tfar).then_some((t, b1, b2));
    }
    if b0 < -s || b1 < -s || b2 < -s || !(b0 >= -s && b1 >= -s && b2 >= -s) {
        return None;
    }
    hit_f64(accel, i, o, d, tnear, tfar).map(|t| (t, b1, b2))
}

/// The near-edge decision of every kernel: whether the ray passes through triangle `i`
/// ([`inside_f64`]) and, if so, its distance from the plane in f64, rounded once to f32, when
/// that lies within `(tnear, tfar)`. Near an edge or a vertex the f32 distance can be far
/// off (a small triangle nearly edge-on to the ray: on the kitten 4e-6 short of the true
/// distance), which put the hit point outside the triangle's box: a walk that had culled
/// that box found another triangle than a walk that had not. The f64 distance puts the
/// point where the ray meets the plane, within the triangle's padded box.
pub fn hit_f64(
    accel: &Accel,
    i: usize,
    o: [f32; 3],
    d: [f32; 3],
    tnear: f32,
    tfar: f32,
) -> Option<f32> {
    if !inside_f64(accel, i, o, d) {
        return None;
    }
    let tri = &accel.tris;
    let f = |v: [f32; 3]| [0, 1, 2].map(|k| v[k] as f64 - o[k] as f64);
    let (a, b, c) = (f(tri.v0(i)), f(tri.v1(i)), f(tri.v2(i)));
    let e1 = [0, 1, 2].map(|k| b[k] - a[k]);
    let e2 = [0, 1, 2].map(|k| c[k] - a[k]);
    let n = [
        e1[1] * e2[2] - e1[2] * e2[1],
        e1[2] * e2[0] - e1[0] * e2[2],
        e1[0] * e2[1] - e1[1] * e2[0],
    ];
    let dot = |x: [f64; 3], y: [f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    // (a zero-area triangle gives 0 / 0 = NaN, which fails both comparisons)
    let t = (dot(a, n) / dot(d.map(f64::from), n)) as f32;
    (t > tnear && t < tfar).then_some(t)
}

/// Whether the ray passes through the triangle, from the signs of the three edge functions
/// `<d, cross(vi - o, vj - o)>` (each the signed sub-triangle area times `<d, n>`) in f64.
/// A shared edge gives exactly opposite values in its two triangles, and f64 resolves rays
/// aimed at a vertex of f32 meshes, so closed meshes do not leak at edges and vertices.
pub fn inside_f64(accel: &Accel, i: usize, o: [f32; 3], d: [f32; 3]) -> bool {
    let tri = &accel.tris;
    let f = |v: [f32; 3]| {
        [
            v[0] as f64 - o[0] as f64,
            v[1] as f64 - o[1] as f64,
            v[2] as f64 - o[2] as f64,
        ]
    };
    let (a, b, c) = (f(tri.v0(i)), f(tri.v1(i)), f(tri.v2(i)));
    let d = d.map(f64::from);
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let e0 = dot(d, cross(b, c));
    let e1 = dot(d, cross(c, a));
    let e2 = dot(d, cross(a, b));
    // A ray through a vertex makes two edge functions exactly 0 in exact arithmetic, but f64
    // rounding can give them either sign, and a fan whose spokes all round the same way
    // would leak. Values within f64 noise of 0 (1e-13 of |d| |vi - o| |vj - o|) count as 0
    // on both sides: such a ray may hit two neighbours (fine), never none.
    let len = |v: [f64; 3]| dot(v, v).sqrt();
    let (ld, la, lb, lc) = (len(d), len(a), len(b), len(c));
    let tol = |x: f64, y: f64| 1e-13 * ld * x * y;
    let (t0, t1, t2) = (tol(lb, lc), tol(lc, la), tol(la, lb));
    (e0 >= -t0 && e1 >= -t1 && e2 >= -t2) || (e0 <= t0 && e1 <= t1 && e2 <= t2)
}

/// Slab test: the entry distance when the ray meets the box within `[tnear, tfar]`, else `None`.
#[inline(always)]
fn hit_box1(
    min: [f32; 3],
    max: [f32; 3],
    o: [f32; 3],
    inv: [f32; 3],
    tnear: f32,
    tfar: f32,
) -> Option<f32> {
    let mut lo = tnear;
    let mut hi = tfar;
    for k in 0..3 {
        let t0 = (min[k] - o[k]) * inv[k];
        let t1 = (max[k] - o[k]) * inv[k];
        lo = lo.max(t0.min(t1));
        hi = hi.min(t0.max(t1));
    }
    (lo <= hi * SLAB_FAR_SCALE).then_some(lo)
}

/// One traversal for closest hit and any hit (`ANY_HIT` stops at the first hit).
#[inline(always)]
fn traverse1<const ANY_HIT: bool>(accel: &Accel, ray: &Ray, cull: bool) -> Option<Hit> {
    // (a ray that can hit nothing is answered before the walk: see `Ray::traceable`)
    if accel.nodes.is_empty() || !ray.traceable() {
        return None;
    }
    let r1 = Ray1::new(ray);
    let (o, d) = (r1.o, r1.d);
    let inv = d.map(safe_inv);
    let mut best: Option<Hit> = None;
    let mut tfar = ray.tfar;
    let root = accel.nodes[0];
    hit_box1(root.min, root.max, o, inv, ray.tnear, tfar)?;
    let mut stack: Stack<(u32, f32), 64> = Stack::new();
    let mut node = 0u32;
    loop {
        let n = accel.nodes[node as usize];
        if n.count > 0 {
            for slot in n.first..n.first + n.count {
                let slot = slot as usize;
                if let Some((t, b1, b2)) = hit_triangle1(accel, slot, &r1, ray.tnear, tfar, cull) {
                    // record hit: once a hit exists the limit is the next float above its t,
                    // so an exact tie reaches here and keeps the lower original index; the
                    // result does not depend on the visiting order (BVH == brute force exactly).
                    let tri = accel.tris.prim[slot];
                    if best.is_none_or(|b| nearer(t, tri, b.t, b.tri)) {
                        best = Some(Hit { tri, t, b1, b2 });
                        tfar = t.next_up();
                    }
                    if ANY_HIT {
                        return best;
                    }
                }
            }
        } else {
            // ordered children: visit the nearer box first, push the farther one.
            let (l, r) = (n.first, n.first + 1);
            let (nl, nr) = (accel.nodes[l as usize], accel.nodes[r as usize]);
            let tl = hit_box1(nl.min, nl.max, o, inv, ray.tnear, tfar);
            let tr = hit_box1(nr.min, nr.max, o, inv, ray.tnear, tfar);
            match (tl, tr) {
                (Some(a), Some(b)) => {
                    let (near, far, tf) = if a <= b { (l, r, b) } else { (r, l, a) };
                    stack.push((far, tf));
                    node = near;
                    continue;
                }
                (Some(_), None) => {
                    node = l;
                    continue;
                }
                (None, Some(_)) => {
                    node = r;
                    continue;
                }
                (None, None) => {}
            }
        }
        // pop the next node still in front of the closest hit.
        loop {
            match stack.pop() {
                None => return best,
                Some((next, tentry)) if tentry <= tfar * SLAB_FAR_SCALE => {
                    node = next;
                    break;
                }
                Some(_) => {}
            }
        }
    }
}

/// Closest hit with `tnear < t < tfar`; back faces skipped when `cull`.
pub fn intersect1(accel: &Accel, ray: &Ray, cull: bool) -> Option<Hit> {
    traverse1::<false>(accel, ray, cull)
}

/// Whether anything is hit with `tnear < t < tfar` (shadow rays).
pub fn occluded1(accel: &Accel, ray: &Ray, cull: bool) -> bool {
    traverse1::<true>(accel, ray, cull).is_some()
}

/// Brute force: every triangle in SoA order, same kernel and tie rule (tests and checks).
pub fn intersect_brute1(accel: &Accel, ray: &Ray, cull: bool) -> Option<Hit> {
    let r1 = Ray1::new(ray);
    let mut best: Option<Hit> = None;
    let mut tfar = ray.tfar;
    for slot in 0..accel.tris.len() {
        if let Some((t, b1, b2)) = hit_triangle1(accel, slot, &r1, ray.tnear, tfar, cull) {
            let tri = accel.tris.prim[slot];
            if best.is_none_or(|b| nearer(t, tri, b.t, b.tri)) {
                best = Some(Hit { tri, t, b1, b2 });
                tfar = t.next_up();
            }
        }
    }
    best
}

/// SCENES.md §2 literally, in f64: `Ng = normalize(cross(v1 - v0, v2 - v0))`,
/// `t = <v0 - p, Ng> / <d, Ng>`, `q = p + t d`, barycentrics from the three sub-triangle
/// areas (signed by `Ng`), inside when none is negative. Returns `(t, b1, b2)`.
pub fn literal_hit(
    v: [[f64; 3]; 3],
    o: [f64; 3],
    d: [f64; 3],
    tnear: f64,
    tfar: f64,
    cull: bool,
) -> Option<(f64, f64, f64)> {
    let sub = |a: [f64; 3], b: [f64; 3]| [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let cross = |a: [f64; 3], b: [f64; 3]| {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    };
    let c = cross(sub(v[1], v[0]), sub(v[2], v[0]));
    let len = dot(c, c).sqrt();
    if len == 0.0 || !len.is_finite() {
        return None; // zero-area triangles are never hit
    }
    let ng = c.map(|x| x / len);
    let dn = dot(d, ng);
    if cull && dn >= 0.0 {
        return None;
    }
    let t = dot(sub(v[0], o), ng) / dn;
    if !(t > tnear && t < tfar) {
        return None;
    }
    let q = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
    let area = |a: [f64; 3], b: [f64; 3], c: [f64; 3]| dot(cross(sub(b, a), sub(c, a)), ng) * 0.5;
    let whole = len * 0.5;
    let b0 = area(q, v[1], v[2]) / whole;
    let b1 = area(v[0], q, v[2]) / whole;
    let b2 = area(v[0], v[1], q) / whole;
    (b0 >= 0.0 && b1 >= 0.0 && b2 >= 0.0).then_some((t, b1, b2))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::BuildQuality;
    use glam::Vec3;

    fn one(tri: [Vec3; 3]) -> Accel {
        Accel::build(&[tri], BuildQuality::Medium)
    }

    const T: [Vec3; 3] = [
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(2.0, 0.0, 0.0),
        Vec3::new(0.0, 2.0, 0.0),
    ];

    fn ray(o: [f32; 3], d: [f32; 3]) -> Ray {
        Ray::new(Vec3::from(o), Vec3::from(d), 0.0, f32::INFINITY)
    }

    #[test]
    fn hand_computed_hit() {
        // Ray down -z through (0.5, 0.25): t = 3, q = (0.5, 0.25, 0).
        // Areas (x2): whole 4; opposite v1: q.x * 2 = 1 -> b1 = 0.25; opposite v2: q.y * 2 = 0.5 -> b2 = 0.125.
        let a = one(T);
        let h = intersect1(&a, &ray([0.5, 0.25, 3.0], [0.0, 0.0, -1.0]), true).unwrap();
        assert_eq!((h.tri, h.t, h.b1, h.b2), (0, 3.0, 0.25, 0.125));
        let l = literal_hit(
            [[0.0; 3], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]],
            [0.5, 0.25, 3.0],
            [0.0, 0.0, -1.0],
            0.0,
            f64::INFINITY,
            true,
        )
        .unwrap();
        assert_eq!(l, (3.0, 0.25, 0.125));
    }

    #[test]
    fn misses_outside_and_beyond_tfar_and_behind() {
        let a = one(T);
        assert!(
            intersect1(&a, &ray([1.5, 1.5, 3.0], [0.0, 0.0, -1.0]), true).is_none(),
            "outside the hypotenuse"
        );
        assert!(intersect1(&a, &ray([-0.1, 0.5, 3.0], [0.0, 0.0, -1.0]), true).is_none());
        let mut r = ray([0.5, 0.5, 3.0], [0.0, 0.0, -1.0]);
        r.tfar = 3.0;
        assert!(intersect1(&a, &r, true).is_none(), "t == tfar is excluded");
        r.tfar = 3.0001;
        assert!(intersect1(&a, &r, true).is_some());
        r.tnear = 3.0;
        assert!(intersect1(&a, &r, true).is_none(), "t == tnear is excluded");
        assert!(
            intersect1(&a, &ray([0.5, 0.5, 3.0], [0.0, 0.0, 1.0]), false).is_none(),
            "behind the origin"
        );
    }

    #[test]
    fn edges_and_vertices_count_as_inside() {
        let a = one(T);
        for (x, y) in [
            (0.0, 0.0),
            (2.0, 0.0),
            (0.0, 2.0),
            (1.0, 0.0),
            (0.0, 1.0),
            (1.0, 1.0),
        ] {
            assert!(
                intersect1(&a, &ray([x, y, 1.0], [0.0, 0.0, -1.0]), true).is_some(),
                "({x}, {y})"
            );
        }
    }

    #[test]
    fn back_face_culling() {
        let a = one(T);
        let from_behind = ray([0.5, 0.5, -1.0], [0.0, 0.0, 1.0]);
        assert!(intersect1(&a, &from_behind, true).is_none());
        let h = intersect1(&a, &from_behind, false).unwrap();
        assert_eq!(h.t, 1.0);
        assert!(!occluded1(&a, &from_behind, true));
        assert!(occluded1(&a, &from_behind, false));
    }

    #[test]
    fn zero_area_and_in_plane_rays_never_hit() {
        let flat = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let a = one(flat);
        for d in [[0.0, 0.0, -1.0], [0.0, -1.0, 0.0], [-1.0, 0.0, 0.0]] {
            assert!(intersect1(&a, &ray([1.0, 1.0, 1.0], d), false).is_none());
        }
        let point = one([Vec3::ONE; 3]);
        assert!(intersect1(&point, &ray([1.0, 1.0, 3.0], [0.0, 0.0, -1.0]), false).is_none());
        // A ray running inside the triangle's plane.
        let a = one(T);
        assert!(intersect1(&a, &ray([-1.0, 0.5, 0.0], [1.0, 0.0, 0.0]), false).is_none());
        assert!(
            literal_hit(
                [[0.0; 3], [2.0, 0.0, 0.0], [0.0, 2.0, 0.0]],
                [-1.0, 0.5, 0.0],
                [1.0, 0.0, 0.0],
                0.0,
                f64::INFINITY,
                false
            )
            .is_none()
        );
    }

    #[test]
    fn nan_rays_miss() {
        let a = one(T);
        assert!(intersect1(&a, &ray([f32::NAN, 0.5, 1.0], [0.0, 0.0, -1.0]), false).is_none());
        assert!(intersect1(&a, &ray([0.5, 0.5, 1.0], [0.0, f32::NAN, -1.0]), false).is_none());
        assert!(!occluded1(&a, &ray([0.5, 0.5, 1.0], [f32::NAN; 3]), false));
    }

    #[test]
    fn nearest_of_several_and_bvh_equals_brute_force() {
        let mut tris = Vec::new();
        for k in 0..50 {
            let z = -(k as f32) * 0.1;
            tris.push([
                Vec3::new(-1.0, -1.0, z),
                Vec3::new(1.0, -1.0, z),
                Vec3::new(0.0, 1.0, z),
            ]);
        }
        let a = Accel::build(&tris, BuildQuality::Medium);
        let h = intersect1(&a, &ray([0.0, 0.0, 5.0], [0.0, 0.0, -1.0]), true).unwrap();
        assert_eq!((h.tri, h.t), (0, 5.0));
        let mut r = ray([0.0, 0.0, 5.0], [0.0, 0.0, -1.0]);
        r.tnear = 5.05;
        assert_eq!(intersect1(&a, &r, true).unwrap().tri, 1);
        for i in 0..200 {
            let f = i as f32 * 0.37;
            let r = ray(
                [f.sin() * 2.0, f.cos() * 2.0, 3.0],
                [f.cos() * 0.3, f.sin() * 0.3, -1.0],
            );
            assert_eq!(intersect1(&a, &r, true), intersect_brute1(&a, &r, true));
        }
    }
}
