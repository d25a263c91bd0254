//! Instanced traversal against the same scene flattened: every engine, random rays, rays at
//! vertices and edges, rays from inside closed meshes (leaks), occlusion.

use super::*;
use crate::accel::BuildQuality;
use crate::mesh::Mesh;
use crate::scene::shapes;
use glam::Quat;

/// A small deterministic generator (xorshift64*), so failures reproduce.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
}

fn kitten() -> Mesh {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/kitten.m");
    crate::io::load_mesh(&path).unwrap().0
}

fn triangles(m: &Mesh) -> Vec<[Vec3; 3]> {
    m.triangles
        .iter()
        .map(|t| t.map(|i| m.positions[i as usize]))
        .collect()
}

/// The instanced scene and the same scene flattened (vertices transformed, placements in
/// order): the flattened one's triangle ids are the instanced one's global ids.
struct Pair {
    inst: Instances,
    flat: Accel,
    flat_tris: Vec<[Vec3; 3]>,
    /// Per global id, its mesh's vertex indices (to tell neighbours on a shared edge).
    corners: Vec<[u32; 3]>,
}

fn pair(meshes: &[Mesh], placements: &[(u32, Affine3A)]) -> Pair {
    let accels = meshes
        .iter()
        .map(|m| Accel::build(&triangles(m), BuildQuality::default()))
        .collect();
    let inst = Instances::new(accels, placements);
    let mut flat_tris = Vec::new();
    let mut corners = Vec::new();
    for (k, &(mesh, m)) in placements.iter().enumerate() {
        let mesh = &meshes[mesh as usize];
        for t in &mesh.triangles {
            flat_tris.push(t.map(|i| m.transform_point3(mesh.positions[i as usize])));
            // corners offset per placement, so only triangles of one placement share them
            corners.push(t.map(|i| i + ((k as u32) << 20)));
        }
    }
    let flat = Accel::build(&flat_tris, BuildQuality::default());
    Pair {
        inst,
        flat,
        flat_tris,
        corners,
    }
}

fn placements(rng: &mut Rng, n: usize, meshes: u32, mirror: bool) -> Vec<(u32, Affine3A)> {
    (0..n)
        .map(|k| {
            let axis = rng.vec(-1.0, 1.0).normalize_or(Vec3::Y);
            let rot = Quat::from_axis_angle(axis, rng.range(0.0, std::f32::consts::TAU));
            let mut scale = Vec3::new(
                rng.range(0.5, 2.0),
                rng.range(0.5, 2.0),
                rng.range(0.5, 2.0),
            );
            if mirror && k % 3 == 1 {
                scale.x = -scale.x;
            }
            let t = Vec3::new(
                (k % 4) as f32 * 2.5,
                (k / 4) as f32 * 2.5,
                rng.range(-0.5, 0.5),
            );
            (
                k as u32 % meshes,
                Affine3A::from_scale_rotation_translation(scale, rot, t),
            )
        })
        .collect()
}

/// Random rays through the scene's box, and rays from random points at random triangles.
fn rays(rng: &mut Rng, p: &Pair, n: usize) -> Vec<Ray> {
    let (lo, hi) = p.inst.bounds().unwrap();
    let mut out = Vec::new();
    for k in 0..n {
        let o = lo + (hi - lo) * rng.vec(-0.2, 1.2);
        let d = if k % 2 == 0 {
            rng.vec(-1.0, 1.0)
        } else {
            let t =
                p.flat_tris[(rng.next() * p.flat_tris.len() as f32) as usize % p.flat_tris.len()];
            (t[0] + t[1] + t[2]) / 3.0 - o
        };
        out.push(Ray::new(o, d, 0.0, f32::INFINITY));
    }
    out
}

/// Whether two global ids are the same triangle or neighbours sharing a corner.
fn same_or_neighbour(p: &Pair, a: u64, b: u64) -> bool {
    let (ca, cb) = (p.corners[a as usize], p.corners[b as usize]);
    a == b || ca.iter().any(|c| cb.contains(c))
}

/// Check every engine's closest hits and occlusion through instances against the same
/// engine on the flattened scene. Ids must be equal, except where the flattened hit lies
/// within `1e-4` (barycentric) of an edge: there a ray at a shared edge or vertex may take
/// the neighbour (the flattened scene rounds the transformed vertices, the instanced one the
/// transformed ray), which must share a corner. `t` agrees within 1e-5 relative (to `t`, or
/// where larger to the hit point's distance from the world origin over `|d|`: rounding is
/// relative to the coordinates), except on
/// grazing rays (`|cos|` of the ray and the triangle's normal under 0.05), where the same
/// rounding moves the hit along the plane by `1 / |cos|` times as much: there within
/// `2e-7 / |cos|`. Returns how many took the neighbour.
fn check(p: &Pair, rays: &[Ray], exact: bool) -> usize {
    let mut neighbours = 0;
    for engine in Engine::ALL {
        let mut want = vec![None; rays.len()];
        crate::trace::intersect_into(&p.flat, rays, engine, false, &mut want);
        let mut got = vec![None; rays.len()];
        p.inst.intersect_into(rays, engine, false, &mut got);
        for (k, (w, g)) in want.iter().zip(&got).enumerate() {
            match (w, g) {
                (None, None) => {}
                (Some(w), Some(g)) => {
                    let id = p.inst.global(g);
                    let [a, b, c] = p.flat_tris[w.tri as usize];
                    let n = (b - a).cross(c - a).normalize_or_zero();
                    let cos = n.dot(rays[k].dir.normalize_or_zero()).abs();
                    let rel = if cos < 0.05 {
                        2e-7 / cos.max(1e-6)
                    } else {
                        1e-5
                    };
                    // (rounding is relative to the coordinates: a short hit far from the
                    // origin carries the error of its coordinates, not of its t)
                    let r = &rays[k];
                    let scale =
                        w.t.abs()
                            .max((r.origin + w.t * r.dir).length() / r.dir.length());
                    let close = (g.hit.t - w.t).abs() <= rel * scale;
                    assert!(
                        close,
                        "{engine:?} ray {k} {:?}: {g:?} (global {id}) against {w:?}",
                        rays[k]
                    );
                    if id != w.tri as u64 {
                        let edge = w.b1.min(w.b2).min(1.0 - w.b1 - w.b2) < 1e-4;
                        assert!(
                            !exact && edge && same_or_neighbour(p, id, w.tri as u64),
                            "{engine:?} ray {k} {:?}: triangle {id} against {} ({w:?} {g:?})",
                            rays[k],
                            w.tri
                        );
                        neighbours += 1;
                    }
                }
                _ => {
                    // a ray grazing a silhouette edge may pass on one side in one space
                    let edge = w.is_some_and(|w| w.b1.min(w.b2).min(1.0 - w.b1 - w.b2) < 1e-4);
                    assert!(
                        !exact && edge,
                        "{engine:?} ray {k} {:?}: {g:?} against {w:?}",
                        rays[k]
                    );
                    neighbours += 1;
                }
            }
        }
        // occlusion within a limit short of some hits and past others
        let short: Vec<Ray> = rays
            .iter()
            .zip(&want)
            .enumerate()
            .map(|(k, (r, w))| {
                let tfar = w.map_or(1e3, |w| w.t * if k % 2 == 0 { 0.5 } else { 1.5 });
                Ray { tfar, ..*r }
            })
            .collect();
        let mut blocked = vec![false; rays.len()];
        p.inst.occluded_into(&short, engine, false, &mut blocked);
        let mut flat_blocked = vec![false; rays.len()];
        crate::trace::occluded_into(&p.flat, &short, engine, false, &mut flat_blocked);
        for (k, (b, flat)) in blocked.iter().zip(&flat_blocked).enumerate() {
            if flat != b {
                let edge = want[k].is_some_and(|w| w.b1.min(w.b2).min(1.0 - w.b1 - w.b2) < 1e-4);
                assert!(
                    !exact && edge,
                    "{engine:?} ray {k}: occluded {b} against {flat}"
                );
            }
        }
    }
    neighbours
}

#[test]
fn every_engine_equals_the_flattened_scene_on_random_rays() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let meshes = [
        kitten(),
        shapes::sphere(Vec3::ZERO, 0.8, 24),
        shapes::cube(Vec3::ZERO, Vec3::new(0.5, 0.3, 0.7)),
    ];
    let pl = placements(&mut rng, 12, 3, true);
    let p = pair(&meshes, &pl);
    assert_eq!(p.inst.triangles, p.flat_tris.len() as u64);
    let rays = rays(&mut rng, &p, 4000);
    let hits = rays
        .iter()
        .filter(|r| intersect1(&p.flat, r, false).is_some())
        .count();
    assert!(hits > 1500, "only {hits} of the rays hit");
    let neighbours = check(&p, &rays, false);
    assert!(neighbours <= 4, "{neighbours} rays took a neighbour");
}

#[test]
fn identity_and_power_of_two_placements_hit_the_same_triangles_at_vertices_and_edges() {
    // Scaling by powers of two is exact in both directions, so here the ids must be equal
    // on every ray, including those aimed exactly at shared vertices and edges.
    let mut rng = Rng(7);
    let meshes = [kitten()];
    let pl: Vec<(u32, Affine3A)> = [1.0f32, 2.0, 0.5, 4.0]
        .iter()
        .map(|&s| (0, Affine3A::from_scale(Vec3::splat(s))))
        .collect();
    let p = pair(&meshes, &pl[..1]);
    let targets: Vec<Vec3> = p
        .flat_tris
        .iter()
        .step_by(7)
        .flat_map(|t| [t[0], (t[0] + t[1]) * 0.5])
        .collect();
    let aimed = |p: &Pair, rng: &mut Rng, scale: f32| -> Vec<Ray> {
        let mut out: Vec<Ray> = targets
            .iter()
            .map(|&t| {
                let o = rng.vec(-3.0, 3.0) * scale;
                Ray::new(o, t * scale - o, 0.0, f32::INFINITY)
            })
            .collect();
        out.extend(rays(rng, p, 500));
        out
    };
    for (k, &(_, m)) in pl.iter().enumerate() {
        let p = pair(&meshes, &[(0, m)]);
        let r = aimed(&p, &mut rng, [1.0f32, 2.0, 0.5, 4.0][k]);
        assert_eq!(check(&p, &r, true), 0);
    }
}

#[test]
fn no_leaks_from_inside_placed_kittens() {
    // Rays from points inside each placed (closed) kitten at its vertices and edge points,
    // in world space: every engine must hit something on every ray.
    let mut rng = Rng(11);
    let meshes = [kitten()];
    let pl = placements(&mut rng, 4, 1, true);
    let p = pair(&meshes, &pl);
    let inside = [
        Vec3::new(0.0, -0.5, 0.0),
        Vec3::new(0.05, -0.2, -0.1),
        Vec3::new(-0.1, 0.2, -0.1),
    ];
    let m = &meshes[0];
    let mut rays = Vec::new();
    for &(_, x) in &pl {
        for o in inside {
            for t in m.triangles.iter().step_by(3) {
                let (a, b) = (m.positions[t[0] as usize], m.positions[t[1] as usize]);
                for target in [a, (a + b) * 0.5] {
                    let o = x.transform_point3(o);
                    rays.push(Ray::new(
                        o,
                        x.transform_point3(target) - o,
                        0.0,
                        f32::INFINITY,
                    ));
                }
            }
        }
    }
    for engine in Engine::ALL {
        let mut got = vec![None; rays.len()];
        p.inst.intersect_into(&rays, engine, false, &mut got);
        let leaks = got.iter().filter(|h| h.is_none()).count();
        assert_eq!(
            leaks,
            0,
            "{engine:?}: {leaks} of {} rays leaked",
            rays.len()
        );
        let mut blocked = vec![false; rays.len()];
        p.inst.occluded_into(&rays, engine, false, &mut blocked);
        let open = blocked.iter().filter(|b| !**b).count();
        assert_eq!(
            open,
            0,
            "{engine:?}: {open} of {} rays unblocked",
            rays.len()
        );
    }
}

#[test]
fn packet_entry_points_equal_the_batch_calls() {
    let mut rng = Rng(5);
    let meshes = [kitten(), shapes::sphere(Vec3::ZERO, 0.8, 16)];
    let pl = placements(&mut rng, 6, 2, false);
    let p = pair(&meshes, &pl);
    let rays = rays(&mut rng, &p, 64);
    let mut want = vec![None; rays.len()];
    p.inst
        .intersect_into(&rays, Engine::Scalar, false, &mut want);
    let eight: [Option<Bottom8>; 3] = [Some(intersect8), Some(intersect_hybrid8), None];
    for group in 0..rays.len() / 16 {
        let g = &rays[group * 16..group * 16 + 16];
        let (a, ma) = RayPacket8::from_fn(|i| Some(g[i]));
        let (b, mb) = RayPacket8::from_fn(|i| (i % 3 != 0).then(|| g[8 + i]));
        for f in eight {
            let (h, ids) = p.inst.intersect_packet8(&a, ma, false, f);
            for i in 0..8 {
                let w = want[group * 16 + i];
                assert_eq!(h.lane(i), w.map(|w| w.hit));
                assert_eq!(ids[i], w.map_or(u32::MAX, |w| w.inst));
            }
        }
        for f in [intersect16 as Bottom16, intersect_hybrid16] {
            let [(_, _), (h, ids)] = p.inst.intersect_pair16([&a, &b], [ma, mb], false, f);
            for i in 0..8 {
                let w = want[group * 16 + 8 + i].filter(|_| i % 3 != 0);
                assert_eq!(h.lane(i), w.map(|w| w.hit));
                assert_eq!(ids[i], w.map_or(u32::MAX, |w| w.inst));
            }
        }
    }
}

#[test]
fn one_identity_instance_traces_exactly_as_the_mesh() {
    let mut rng = Rng(3);
    let m = kitten();
    let accel = Accel::build(&triangles(&m), BuildQuality::default());
    let inst = Instances::new(vec![accel.clone()], &[(0, Affine3A::IDENTITY)]);
    let p = Pair {
        inst,
        flat: accel,
        flat_tris: triangles(&m),
        corners: m.triangles.clone(),
    };
    let rays = rays(&mut rng, &p, 2000);
    for engine in Engine::CONCRETE {
        let mut got = vec![None; rays.len()];
        p.inst.intersect_into(&rays, engine, false, &mut got);
        for (r, g) in rays.iter().zip(&got) {
            assert_eq!(
                g.map(|g| g.hit),
                intersect1(&p.flat, r, false),
                "{engine:?}"
            );
        }
    }
}

#[test]
fn empty_meshes_and_no_instances_trace_nothing() {
    let empty = Instances::new(vec![Accel::default()], &[(0, Affine3A::IDENTITY)]);
    let none = Instances::new(vec![], &[]);
    let r = [Ray::new(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY); 3];
    for i in [&empty, &none] {
        assert_eq!(i.trace_rays(&r, Engine::Auto, false), vec![None; 3]);
        assert_eq!(i.occluded_rays(&r, Engine::Hybrid16, false), vec![false; 3]);
        assert_eq!(i.bounds(), None);
    }
}
