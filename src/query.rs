//! Queries beside closest-hit tracing, over the same [`Accel`]: shadow-ray batches, every hit
//! along a ray, the nearest point of the surface to a point, and inside/outside.
//!
//! The any-hit and closest-hit batches call the engines' kernels, so their answers are the
//! engines' bit for bit. The walks for every hit and for the nearest point are written here
//! over the binary tree (`accel.nodes`), with the engines' triangle test
//! ([`hit_triangle1`]) for the first and an f64 point-triangle distance for the second; both
//! are checked against brute force in the tests below.

use crate::accel::scalar::{Ray1, hit_triangle1};
use crate::accel::{Accel, SLAB_FAR_SCALE, safe_inv};
use crate::ray::Ray;
use crate::trace::Engine;
use glam::Vec3;

/// Whether each ray hits anything with `tnear < t < tfar`, in parallel, in input order:
/// [`crate::trace::occluded_rays`] (for `Auto`, the engine chosen from the rays).
pub fn occlude_rays(accel: &Accel, rays: &[Ray], engine: Engine, cull: bool) -> Vec<bool> {
    crate::trace::occluded_rays(accel, rays, engine, cull)
}

/// One hit of [`all_hits`]: the triangle (original index), `t` and the barycentric weights
/// of its second and third vertex, as in [`Hit`](crate::ray::Hit).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnyHit {
    /// Index of the triangle hit.
    pub tri: u32,
    /// Ray parameter.
    pub t: f32,
    /// Weight of the second vertex.
    pub b1: f32,
    /// Weight of the third vertex.
    pub b2: f32,
}

/// Slab test against a (padded) node box within `[tnear, tfar]`.
#[inline(always)]
fn meets_box(min: [f32; 3], max: [f32; 3], o: [f32; 3], inv: [f32; 3], tn: f32, tf: f32) -> bool {
    let mut lo = tn;
    let mut hi = tf * SLAB_FAR_SCALE;
    for k in 0..3 {
        let a = (min[k] - o[k]) * inv[k];
        let b = (max[k] - o[k]) * inv[k];
        // NaN (an origin or direction component NaN) fails both and so misses.
        lo = lo.max(a.min(b));
        hi = hi.min(a.max(b));
        if !(lo <= hi) {
            return false;
        }
    }
    !(a_nan(o) || a_nan(inv))
}

#[inline(always)]
fn a_nan(v: [f32; 3]) -> bool {
    v.iter().any(|x| x.is_nan())
}

/// Call `f` for every triangle the ray hits with `tnear < t < tfar` (no culling), each
/// once, in no particular order.
pub fn for_each_hit(accel: &Accel, ray: &Ray, mut f: impl FnMut(AnyHit)) {
    if accel.nodes.is_empty() {
        return;
    }
    let r1 = Ray1::new(ray);
    let inv = r1.d.map(safe_inv);
    let (tn, tf) = (ray.tnear, ray.tfar);
    let mut stack = vec![0u32];
    while let Some(i) = stack.pop() {
        let n = accel.nodes[i as usize];
        if !meets_box(n.min, n.max, r1.o, inv, tn, tf) {
            continue;
        }
        if n.count > 0 {
            for slot in n.first as usize..(n.first + n.count) as usize {
                if let Some((t, b1, b2)) = hit_triangle1(accel, slot, &r1, tn, tf, false) {
                    let tri = accel.tris.prim[slot];
                    f(AnyHit { tri, t, b1, b2 });
                }
            }
        } else {
            stack.push(n.first);
            stack.push(n.first + 1);
        }
    }
}

/// Every hit of the ray with `tnear < t < tfar` (no culling), sorted by `t`, ties by
/// triangle index. A ray through an edge or a vertex may hit each triangle there.
pub fn all_hits(accel: &Accel, ray: &Ray) -> Vec<AnyHit> {
    let mut hits = Vec::new();
    for_each_hit(accel, ray, |h| hits.push(h));
    hits.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.tri.cmp(&b.tri)));
    hits
}

/// How many triangles the ray hits with `tnear < t < tfar` (no culling).
pub fn count_hits(accel: &Accel, ray: &Ray) -> u32 {
    let mut n = 0;
    for_each_hit(accel, ray, |_| n += 1);
    n
}

/// The nearest point of the surface to a query point: the triangle (original index), the
/// point, its barycentric weights of the second and third vertex and its squared distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// Index of the nearest triangle (the lowest index among equally near ones).
    pub tri: u32,
    /// The nearest point, `v0 + b1 (v1 - v0) + b2 (v2 - v0)`.
    pub point: Vec3,
    /// Weight of the second vertex.
    pub b1: f32,
    /// Weight of the third vertex.
    pub b2: f32,
    /// Squared distance from the query point, computed in f64.
    pub dist2: f64,
}

type V = [f64; 3];
fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn axpy(a: V, s: f64, x: V) -> V {
    [a[0] + s * x[0], a[1] + s * x[1], a[2] + s * x[2]]
}
fn wide(v: [f32; 3]) -> V {
    v.map(f64::from)
}

/// The parameter `s` in `0..=1` of the point `a + s (b - a)` of the segment nearest `p` (0
/// for a segment of zero length).
fn nearest_on_segment(p: V, a: V, b: V) -> f64 {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    if !(l2 > 0.0) {
        return 0.0;
    }
    (dot(sub(p, a), ab) / l2).clamp(0.0, 1.0)
}

/// The point of triangle `(a, b, c)` nearest `p` as barycentric weights `(b1, b2)` of `b`
/// and `c` (Ericson, "Real-Time Collision Detection" 5.1.5, in f64); a triangle of zero area
/// is treated as its three edges.
pub fn nearest_on_triangle(p: V, a: V, b: V, c: V) -> (f64, f64) {
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let cr = [
        ab[1] * ac[2] - ab[2] * ac[1],
        ab[2] * ac[0] - ab[0] * ac[2],
        ab[0] * ac[1] - ab[1] * ac[0],
    ];
    if !(dot(cr, cr) > 0.0) {
        // degenerate: the nearest of the three edges
        let cands = [
            {
                let s = nearest_on_segment(p, a, b);
                (s, 0.0)
            },
            {
                let s = nearest_on_segment(p, a, c);
                (0.0, s)
            },
            {
                let s = nearest_on_segment(p, b, c);
                (1.0 - s, s)
            },
        ];
        let d2 = |(u, v): (f64, f64)| {
            let q = axpy(axpy(a, u, ab), v, ac);
            let e = sub(p, q);
            dot(e, e)
        };
        return cands
            .into_iter()
            .min_by(|x, y| d2(*x).total_cmp(&d2(*y)))
            .unwrap_or((0.0, 0.0));
    }
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (0.0, 0.0);
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (1.0, 0.0);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return ((d1 / (d1 - d3)).clamp(0.0, 1.0), 0.0);
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (0.0, 1.0);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (0.0, (d2 / (d2 - d6)).clamp(0.0, 1.0));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = ((d4 - d3) / ((d4 - d3) + (d5 - d6))).clamp(0.0, 1.0);
        return (1.0 - w, w);
    }
    let denom = 1.0 / (va + vb + vc);
    (vb * denom, vc * denom)
}

/// [`Closest`] for SoA slot `slot`.
fn closest_in_slot(accel: &Accel, slot: usize, p: V) -> Closest {
    let t = &accel.tris;
    let (a, b, c) = (wide(t.v0(slot)), wide(t.v1(slot)), wide(t.v2(slot)));
    let (b1, b2) = nearest_on_triangle(p, a, b, c);
    let q = axpy(axpy(a, b1, sub(b, a)), b2, sub(c, a));
    let e = sub(p, q);
    Closest {
        tri: t.prim[slot],
        point: Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32),
        b1: b1 as f32,
        b2: b2 as f32,
        dist2: dot(e, e),
    }
}

/// Whether `c` replaces `best`: nearer, or as near with a lower triangle index (so the
/// answer does not depend on the order triangles are visited in).
fn better(c: &Closest, best: &Option<Closest>) -> bool {
    best.is_none_or(|b| c.dist2 < b.dist2 || (c.dist2 == b.dist2 && c.tri < b.tri))
}

/// Squared distance from `p` to the box (0 inside), in f64.
fn box_dist2(min: [f32; 3], max: [f32; 3], p: V) -> f64 {
    let mut d2 = 0.0;
    for k in 0..3 {
        let e = (f64::from(min[k]) - p[k])
            .max(p[k] - f64::from(max[k]))
            .max(0.0);
        d2 += e * e;
    }
    d2
}

/// The nearest point of the surface to `p`, or `None` for an empty accel or a point with a
/// NaN coordinate. A best-first walk of the binary tree: the padded node boxes hold their
/// triangles, so the f64 box distance never exceeds a triangle's, and nodes no nearer than
/// the best so far are skipped only when strictly farther (ties keep the lowest index).
pub fn closest_point(accel: &Accel, p: Vec3) -> Option<Closest> {
    if accel.nodes.is_empty() || p.is_nan() {
        return None;
    }
    let p = wide(p.to_array());
    let mut best: Option<Closest> = None;
    let root = accel.nodes[0];
    let mut stack = vec![(0u32, box_dist2(root.min, root.max, p))];
    while let Some((i, d2)) = stack.pop() {
        if best.is_some_and(|b| d2 > b.dist2) {
            continue;
        }
        let n = accel.nodes[i as usize];
        if n.count > 0 {
            for slot in n.first as usize..(n.first + n.count) as usize {
                let c = closest_in_slot(accel, slot, p);
                if better(&c, &best) {
                    best = Some(c);
                }
            }
        } else {
            let (l, r) = (n.first, n.first + 1);
            let (nl, nr) = (accel.nodes[l as usize], accel.nodes[r as usize]);
            let (dl, dr) = (box_dist2(nl.min, nl.max, p), box_dist2(nr.min, nr.max, p));
            // nearer child on top
            if dl <= dr {
                stack.push((r, dr));
                stack.push((l, dl));
            } else {
                stack.push((l, dl));
                stack.push((r, dr));
            }
        }
    }
    best
}

/// [`closest_point`] by testing every triangle (tests and checks).
pub fn closest_point_brute(accel: &Accel, p: Vec3) -> Option<Closest> {
    if p.is_nan() {
        return None;
    }
    let p = wide(p.to_array());
    let mut best = None;
    for slot in 0..accel.tris.len() {
        let c = closest_in_slot(accel, slot, p);
        if better(&c, &best) {
            best = Some(c);
        }
    }
    best
}

/// Directions of the rays [`inside`] casts: points spread over the sphere by the golden
/// angle, turned off the axes and the coordinate planes so that axis-aligned meshes' edges
/// and faces are not met edge-on.
pub fn vote_direction(k: u32) -> Vec3 {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    let z = 1.0 - (2.0 * f64::from(k) + 1.0) / 15.0 * 0.999;
    let z = z.clamp(-1.0, 1.0);
    let r = (1.0 - z * z).sqrt();
    let phi = golden * f64::from(k) + 0.3;
    let d = [r * phi.cos() + 0.131, r * phi.sin() - 0.077, z + 0.053];
    Vec3::new(d[0] as f32, d[1] as f32, d[2] as f32).normalize()
}

/// Whether `p` is inside the (closed) surface: rays in `nsamples` directions
/// ([`vote_direction`]), each voting inside when it crosses the surface an odd number of
/// times, and the majority decides (ties: outside). A ray through an edge or a vertex may
/// count the triangles there twice and vote wrong; the other directions outvote it, so use
/// an odd `nsamples` of 3 or more. `false` for a NaN point.
pub fn inside(accel: &Accel, p: Vec3, nsamples: u32) -> bool {
    if p.is_nan() || nsamples == 0 {
        return false;
    }
    let votes = (0..nsamples)
        .filter(|&k| {
            let ray = Ray::new(p, vote_direction(k), 0.0, f32::INFINITY);
            count_hits(accel, &ray) % 2 == 1
        })
        .count() as u32;
    2 * votes > nsamples
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::BuildQuality;
    use crate::mesh::Mesh;
    use crate::trace::trace_rays;

    fn lcg(s: &mut u64) -> f32 {
        *s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*s >> 40) as f32 / (1u64 << 24) as f32
    }

    /// The unit cube as 12 counter-clockwise triangles (outward normals).
    fn cube() -> Mesh {
        let positions = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let quads: [[u32; 4]; 6] = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let triangles = quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        Mesh {
            positions,
            triangles,
            ..Mesh::default()
        }
    }

    fn accel_of(mesh: &Mesh) -> Accel {
        let tris: Vec<[Vec3; 3]> = mesh
            .triangles
            .iter()
            .map(|t| t.map(|i| mesh.positions[i as usize]))
            .collect();
        Accel::build(&tris, BuildQuality::Binned)
    }

    /// The cube subdivided (768 triangles), so leaves hold many.
    fn scene() -> (Accel, Mesh) {
        let mesh = cube().subdivide(3);
        (accel_of(&mesh), mesh)
    }

    #[test]
    fn closest_point_equals_brute_force() {
        let (accel, _) = scene();
        let mut s = 7u64;
        for _ in 0..2000 {
            let p = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 4.0 - 2.0;
            let a = closest_point(&accel, p).unwrap();
            let b = closest_point_brute(&accel, p).unwrap();
            assert_eq!(a, b, "{p}");
            assert!(a.b1 >= 0.0 && a.b2 >= 0.0 && a.b1 + a.b2 <= 1.0 + 1e-6);
        }
        assert!(closest_point(&accel, Vec3::NAN).is_none());
        assert!(closest_point(&Accel::default(), Vec3::ZERO).is_none());
    }

    #[test]
    fn nearest_on_triangle_regions() {
        let (a, b, c) = ([0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]);
        let near =
            |(u, v): (f64, f64), (x, y): (f64, f64)| (u - x).abs() < 1e-12 && (v - y).abs() < 1e-12;
        assert!(near(
            nearest_on_triangle([0.2, 0.3, 5.0], a, b, c),
            (0.2, 0.3)
        ));
        assert_eq!(nearest_on_triangle([-1.0, -1.0, 0.0], a, b, c), (0.0, 0.0));
        assert_eq!(nearest_on_triangle([3.0, -1.0, 0.0], a, b, c), (1.0, 0.0));
        assert_eq!(nearest_on_triangle([0.5, -1.0, 1.0], a, b, c), (0.5, 0.0));
        let (u, v) = nearest_on_triangle([1.0, 1.0, 0.0], a, b, c);
        assert!((u - 0.5).abs() < 1e-12 && (v - 0.5).abs() < 1e-12);
        // zero area: a segment
        let (u, v) = nearest_on_triangle([0.5, 1.0, 0.0], a, b, [2.0, 0.0, 0.0]);
        assert!((u - 0.5).abs() < 1e-12 && v == 0.0, "{u} {v}");
    }

    #[test]
    fn all_hits_equal_brute_force_and_start_with_the_closest_hit() {
        let (accel, _) = scene();
        let mut s = 11u64;
        let rays: Vec<Ray> = (0..3000)
            .map(|_| {
                let o = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 3.0 - 1.5;
                let d = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) - 0.5;
                Ray::new(o, d, 0.0, f32::INFINITY)
            })
            .collect();
        let closest = trace_rays(&accel, &rays, Engine::Scalar, false);
        let occluded = occlude_rays(&accel, &rays, Engine::Auto, false);
        for (e, expect) in Engine::ALL.into_iter().map(|e| (e, &occluded)) {
            assert_eq!(&occlude_rays(&accel, &rays, e, false), expect, "{e:?}");
        }
        for ((ray, c), occ) in rays.iter().zip(&closest).zip(&occluded) {
            let hits = all_hits(&accel, ray);
            let r1 = Ray1::new(ray);
            let mut brute: Vec<AnyHit> = (0..accel.tris.len())
                .filter_map(|slot| {
                    hit_triangle1(&accel, slot, &r1, ray.tnear, ray.tfar, false).map(
                        |(t, b1, b2)| AnyHit {
                            tri: accel.tris.prim[slot],
                            t,
                            b1,
                            b2,
                        },
                    )
                })
                .collect();
            brute.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.tri.cmp(&b.tri)));
            assert_eq!(hits, brute);
            assert_eq!(count_hits(&accel, ray) as usize, hits.len());
            assert_eq!(*occ, c.is_some());
            if let Some(c) = c {
                assert_eq!((hits[0].tri, hits[0].t), (c.tri, c.t));
            }
        }
        let nan = Ray::new(Vec3::NAN, Vec3::X, 0.0, f32::INFINITY);
        assert!(all_hits(&accel, &nan).is_empty());
        assert!(!occlude_rays(&accel, &[nan], Engine::Auto, false)[0]);
    }

    #[test]
    fn inside_survives_rays_through_vertices_and_edges() {
        // the unit cube: points on the axes through its centre send axis rays through its
        // vertices and edges; the voting directions are off-axis
        let accel = accel_of(&cube());
        let mut s = 3u64;
        for _ in 0..2000 {
            let p = Vec3::new(lcg(&mut s), lcg(&mut s), lcg(&mut s)) * 2.0 - 0.5;
            let truth = p.cmpgt(Vec3::ZERO).all() && p.cmplt(Vec3::ONE).all();
            assert_eq!(inside(&accel, p, 3), truth, "{p}");
        }
        for p in [
            Vec3::splat(0.5),
            Vec3::new(0.5, 0.5, 0.25),
            Vec3::splat(0.25),
        ] {
            assert!(inside(&accel, p, 3) && inside(&accel, p, 5), "{p}");
        }
        assert!(!inside(&accel, Vec3::splat(2.0), 3));
        assert!(!inside(&accel, Vec3::NAN, 3));
    }
}
