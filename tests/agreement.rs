//! Every engine (packet8 and packet16 on the binary tree, wide1 and wide8 on the 8-wide
//! tree, hybrid8 and hybrid16 on both) held to the
//! scalar reference bit for bit, the scalar kernel held to the literal
//! f64 formula of SCENES.md §2, and the BVH held to brute force.
//!
//! Input ranges: triangle vertices in [-4, 4]^3 (plus exact degenerate cases), ray origins in
//! [-8, 8]^3, directions from [-1, 1]^3 (not normalised, sometimes with exact zeros, NaN or
//! inf), tnear in [0, 1), tfar in (0, inf]. Packets are partly active at random.

#![allow(clippy::needless_range_loop)]

mod common;

use glam::Vec3;
use proptest::prelude::*;
use whitted::accel::scalar::{intersect_brute1, literal_hit};
use whitted::accel::{
    Accel, BuildQuality, intersect_hybrid8, intersect_hybrid16, intersect_wide1,
    intersect_wide1_many, intersect_wide8, intersect1, intersect8, intersect16, occluded_hybrid8,
    occluded_hybrid16, occluded_wide1, occluded_wide1_many, occluded_wide8, occluded1, occluded8,
    occluded16,
};
use whitted::io::load_mesh;
use whitted::packet::RayPacket8;
use whitted::ray::{Hit, Ray};
use whitted::simd;

fn coord() -> impl Strategy<Value = f32> + Clone {
    prop_oneof![4 => -4.0f32..4.0, 1 => (-4i32..=4).prop_map(|i| i as f32)]
}

fn vec3(s: impl Strategy<Value = f32> + Clone) -> impl Strategy<Value = Vec3> {
    (s.clone(), s.clone(), s).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn triangle() -> impl Strategy<Value = [Vec3; 3]> {
    prop_oneof![
        8 => [vec3(coord()), vec3(coord()), vec3(coord())],
        // zero-area: a repeated vertex, or three collinear points
        1 => (vec3(coord()), vec3(coord())).prop_map(|(a, b)| [a, b, a]),
        1 => (vec3(coord()), vec3(coord())).prop_map(|(a, b)| [a, b, (a + b) * 0.5]),
    ]
}

fn direction() -> impl Strategy<Value = Vec3> {
    prop_oneof![
        12 => vec3(-1.0f32..1.0),
        2 => vec3(prop_oneof![Just(0.0f32), Just(1.0), Just(-1.0), -1.0f32..1.0]),
        1 => vec3(prop_oneof![Just(f32::NAN), Just(f32::INFINITY), -1.0f32..1.0]),
    ]
}

fn tfar() -> impl Strategy<Value = f32> {
    prop_oneof![3 => Just(f32::INFINITY), 1 => 0.01f32..20.0]
}

/// Rays aimed at random points of random triangles: vertices, edge points, interiors.
fn aimed_rays(tris: Vec<[Vec3; 3]>) -> impl Strategy<Value = (Vec<[Vec3; 3]>, Vec<Ray>)> {
    let n = tris.len();
    let ray = (
        0..n,
        0u8..4,
        0.0f32..1.0,
        0.0f32..1.0,
        vec3(-8.0f32..8.0),
        tfar(),
        0.0f32..0.5,
        direction(),
        0u8..5,
    )
        .prop_map(
            move |(t, kind, s, u, origin, tfar, tnear, free_dir, free)| {
                (t, kind, s, u, origin, tfar, tnear, free_dir, free)
            },
        );
    (Just(tris.clone()), prop::collection::vec(ray, 1..40)).prop_map(move |(tris, specs)| {
        let rays = specs
            .into_iter()
            .map(|(t, kind, s, u, origin, tfar, tnear, free_dir, free)| {
                let [a, b, c] = tris[t];
                let target = match kind {
                    0 => [a, b, c][(s * 2.99) as usize],
                    1 => a + (b - a) * s,
                    2 => b + (c - b) * s,
                    _ => a + (b - a) * s * (1.0 - u) + (c - a) * u * (1.0 - s),
                };
                let dir = if free == 0 { free_dir } else { target - origin };
                Ray::new(origin, dir, tnear, tfar)
            })
            .collect();
        (tris, rays)
    })
}

fn scene() -> impl Strategy<Value = (Vec<[Vec3; 3]>, Vec<Ray>)> {
    prop::collection::vec(triangle(), 1..60).prop_flat_map(aimed_rays)
}

fn big_scene() -> impl Strategy<Value = (Vec<[Vec3; 3]>, Vec<Ray>)> {
    prop::collection::vec(small_triangle(), 100..600).prop_flat_map(aimed_rays)
}

/// Small triangles spread over the box (big soups of big triangles overlap everywhere and
/// make flat trees).
fn small_triangle() -> impl Strategy<Value = [Vec3; 3]> {
    (
        vec3(coord()),
        vec3(-0.4f32..0.4),
        vec3(-0.4f32..0.4),
        0u8..10,
    )
        .prop_map(|(a, e1, e2, k)| {
            match k {
                0 => [a, a + e1, a], // zero-area
                _ => [a, a + e1, a + e2],
            }
        })
}

/// Trace `rays` in packets of 8 with a random activity pattern per packet and compare every
/// lane with the scalar twins.
fn check_packets(
    accel: &Accel,
    rays: &[Ray],
    masks: &[u8],
    cull: bool,
) -> Result<(), TestCaseError> {
    let packets: Vec<(RayPacket8, simd::M32x8)> = rays
        .chunks(8)
        .enumerate()
        .map(|(k, chunk)| {
            let (packet, active) = RayPacket8::from_fn(|i| chunk.get(i).copied());
            let bits = masks[k % masks.len()] as u32;
            (packet, active & simd::mask_from_bits(bits))
        })
        .collect();
    // packet16: packets 2j and 2j + 1 as one 16-ray packet (a last odd one beside itself
    // with no lane active)
    let (mut hits16, mut occ16, mut hhits16, mut hocc16) = (vec![], vec![], vec![], vec![]);
    for pair in packets.chunks(2) {
        let (a, b) = (&pair[0], pair.get(1).unwrap_or(&pair[0]));
        let b_active = if pair.len() == 2 {
            b.1
        } else {
            simd::mask_from_bits(0)
        };
        hits16.extend(intersect16(accel, [&a.0, &b.0], [a.1, b_active], cull));
        occ16.extend(occluded16(accel, [&a.0, &b.0], [a.1, b_active], cull));
        hhits16.extend(intersect_hybrid16(
            accel,
            [&a.0, &b.0],
            [a.1, b_active],
            cull,
        ));
        hocc16.extend(occluded_hybrid16(
            accel,
            [&a.0, &b.0],
            [a.1, b_active],
            cull,
        ));
    }
    // the batch entries over every ray at once (one stack borrow for all of them)
    let mut many = vec![None; rays.len()];
    let mut many_occ = vec![false; rays.len()];
    intersect_wide1_many(accel, rays, cull, &mut many);
    occluded_wide1_many(accel, rays, cull, &mut many_occ);
    for (k, chunk) in rays.chunks(8).enumerate() {
        let (packet, active) = packets[k];
        let hits = intersect8(accel, &packet, active, cull);
        let occ = occluded8(accel, &packet, active, cull);
        let whits = intersect_wide8(accel, &packet, active, cull);
        let wocc = occluded_wide8(accel, &packet, active, cull);
        let hhits = intersect_hybrid8(accel, &packet, active, cull);
        let hocc = occluded_hybrid8(accel, &packet, active, cull);
        for i in 0..8 {
            let lane_active = simd::lane_set(active, i);
            if !lane_active {
                // Inactive and padding lanes never produce hits.
                prop_assert_eq!(hits.lane(i), None);
                prop_assert!(!simd::lane_set(occ, i));
                prop_assert_eq!(whits.lane(i), None);
                prop_assert!(!simd::lane_set(wocc, i));
                prop_assert_eq!(hhits.lane(i), None);
                prop_assert!(!simd::lane_set(hocc, i));
                prop_assert_eq!(hits16[k].lane(i), None);
                prop_assert!(!simd::lane_set(occ16[k], i));
                prop_assert_eq!(hhits16[k].lane(i), None);
                prop_assert!(!simd::lane_set(hocc16[k], i));
                continue;
            }
            let ray = chunk[i];
            let scalar = intersect1(accel, &ray, cull);
            // Bit for bit: triangle, t and barycentrics (compared as bits so NaN-free equality is exact).
            let bits_of =
                |h: Option<Hit>| h.map(|h| (h.tri, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()));
            prop_assert_eq!(
                bits_of(hits.lane(i)),
                bits_of(scalar),
                "lane {} ray {:?}",
                i,
                ray
            );
            // The 8-wide tree, ray by ray and lane by lane, equals the binary tree.
            prop_assert_eq!(
                bits_of(intersect_wide1(accel, &ray, cull)),
                bits_of(scalar),
                "wide1 {:?}",
                ray
            );
            prop_assert_eq!(bits_of(whits.lane(i)), bits_of(scalar), "wide8 lane {}", i);
            prop_assert_eq!(
                bits_of(many[8 * k + i]),
                bits_of(scalar),
                "wide1 batch {:?}",
                ray
            );
            prop_assert_eq!(many_occ[8 * k + i], scalar.is_some());
            prop_assert_eq!(occluded_wide1(accel, &ray, cull), scalar.is_some());
            prop_assert_eq!(simd::lane_set(wocc, i), scalar.is_some());
            prop_assert_eq!(
                bits_of(hhits.lane(i)),
                bits_of(scalar),
                "hybrid8 lane {}",
                i
            );
            prop_assert_eq!(simd::lane_set(hocc, i), scalar.is_some());
            prop_assert_eq!(
                bits_of(hits16[k].lane(i)),
                bits_of(scalar),
                "packet16 lane {}",
                i
            );
            prop_assert_eq!(simd::lane_set(occ16[k], i), scalar.is_some());
            prop_assert_eq!(
                bits_of(hhits16[k].lane(i)),
                bits_of(scalar),
                "hybrid16 lane {}",
                i
            );
            prop_assert_eq!(simd::lane_set(hocc16[k], i), scalar.is_some());
            // BVH traversal equals brute force.
            prop_assert_eq!(
                bits_of(scalar),
                bits_of(intersect_brute1(accel, &ray, cull))
            );
            // occluded8 == "the closest hit is nearer than tfar" == occluded1.
            prop_assert_eq!(simd::lane_set(occ, i), scalar.is_some());
            prop_assert_eq!(occluded1(accel, &ray, cull), scalar.is_some());
        }
    }
    Ok(())
}

/// `rays` sorted by direction octant (sign bits, -0 counting as negative, as `safe_inv`
/// keeps the sign), so that most packets of 8 share one octant: the hybrid engine's
/// per-packet slab test (`hit_box8_octant`) runs on those.
fn by_octant(rays: &[Ray]) -> Vec<Ray> {
    let mut sorted = rays.to_vec();
    sorted.sort_by_key(|r| r.dir.to_array().map(|c| c.is_sign_negative() as u8));
    sorted
}

/// The tree under test: whitted's binned SAH builder or an obvhs preset (both must give
/// every engine the same hits).
fn builder(binned: bool) -> BuildQuality {
    if binned {
        BuildQuality::Binned
    } else {
        BuildQuality::Medium
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    /// Packet == wide == scalar == brute force on random triangle soups, culled and not.
    #[test]
    fn packet_equals_scalar_equals_brute_force((tris, rays) in scene(), masks in prop::collection::vec(any::<u8>(), 1..4), cull in any::<bool>(), binned in any::<bool>()) {
        let accel = Accel::build(&tris, builder(binned));
        check_packets(&accel, &rays, &masks, cull)?;
        check_packets(&accel, &by_octant(&rays), &masks, cull)?;
    }

    /// The same on soups big enough for wide trees of several levels, leaves of several
    /// blocks and every octant order (up to 600 triangles: BVH2 leaves of up to 8, merged
    /// subtrees, nodes of 2 to 8 children).
    #[test]
    fn engines_agree_on_deep_trees((tris, rays) in big_scene(), masks in prop::collection::vec(any::<u8>(), 1..4), cull in any::<bool>(), binned in any::<bool>()) {
        let accel = Accel::build(&tris, builder(binned));
        prop_assert!(accel.wide.depth >= 1);
        check_packets(&accel, &rays, &masks, cull)?;
        check_packets(&accel, &by_octant(&rays), &masks, cull)?;
    }

    /// The scalar kernel agrees with the literal f64 formula: same hit / miss wherever the
    /// f64 barycentrics are clear of the edges by 1e-3 and the ray is not grazing (|cos| >= 0.05), with t
    /// within 1e-4 relative.
    #[test]
    fn scalar_kernel_matches_literal_formula(tri in triangle(), origin in vec3(-8.0f32..8.0), dir in vec3(-1.0f32..1.0), cull in any::<bool>(), s in 0.0f32..1.0, u in 0.0f32..1.0, aim in any::<bool>()) {
        let [a, b, c] = tri;
        // Nearly collinear vertices: the f32 cross product is rounding noise, no kernel in
        // f32 can agree with f64 there (such triangles are "degenerate" at f32 precision).
        let n32 = (b - a).cross(c - a);
        prop_assume!(n32.length() > 1e-4 * (b - a).length() * (c - a).length());
        let dir = if aim { a + (b - a) * s + (c - a) * u - origin } else { dir };
        let accel = Accel::build(&[tri], BuildQuality::Medium);
        let ray = Ray::new(origin, dir, 0.0, f32::INFINITY);
        let f32_hit = intersect1(&accel, &ray, cull);
        let v = tri.map(|p| p.to_array().map(f64::from));
        let o = origin.to_array().map(f64::from);
        let d = dir.to_array().map(f64::from);
        let lit = literal_hit(v, o, d, 0.0, f64::INFINITY, cull);
        let n = (b - a).cross(c - a);
        let grazing = n.length_squared() == 0.0 || (dir.normalize_or_zero().dot(n.normalize_or_zero())).abs() < 0.05;
        match (f32_hit, lit) {
            // Grazing rays are outside the property: their t is ill-conditioned (|cos| 7e-5
            // gave t 1.000281 vs 0.9999969).
            (Some(_), Some(_)) if grazing => {}
            (Some(h), Some((t, b1, b2))) => {
                prop_assert!((h.t as f64 - t).abs() <= 1e-4 * t.abs().max(1e-3), "t {} vs {}", h.t, t);
                prop_assert!((h.b1 as f64 - b1).abs() < 1e-3 && (h.b2 as f64 - b2).abs() < 1e-3);
            }
            (Some(h), None) => {
                // Only allowed on the boundary or for grazing rays.
                let b0 = 1.0 - h.b1 - h.b2;
                prop_assert!(grazing || h.b1.min(h.b2).min(b0) < 1e-3, "f32 hit {:?}, f64 miss", h);
            }
            (None, Some((_, b1, b2))) => {
                prop_assert!(grazing || b1.min(b2).min(1.0 - b1 - b2) < 1e-3, "f64 hit ({} {}), f32 miss", b1, b2);
            }
            (None, None) => {}
        }
    }
}

/// A sphere-like closed mesh (the subdivided tetrahedron) with rays aimed at every vertex and
/// edge point from random origins: packets equal scalar.
#[test]
fn packet_equals_scalar_on_closed_meshes_at_vertices_and_edges() {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes");
    for name in ["tetrahedron.m", "prism.m", "cube.obj"] {
        let (mesh, _) = load_mesh(&dir.join(name)).unwrap();
        let mesh = mesh.subdivide(2);
        let tris: Vec<[Vec3; 3]> = mesh
            .triangles
            .iter()
            .map(|t| t.map(|i| mesh.positions[i as usize]))
            .collect();
        for quality in [BuildQuality::Binned, BuildQuality::Medium] {
            let accel = Accel::build(&tris, quality);
            let mut rays = Vec::new();
            for (k, p) in mesh.positions.iter().enumerate() {
                let origin = Vec3::new(
                    (k as f32 * 0.7).sin() * 5.0,
                    (k as f32 * 1.3).cos() * 5.0,
                    3.0,
                );
                rays.push(Ray::new(origin, *p - origin, 0.0, f32::INFINITY));
            }
            for cull in [false, true] {
                check_packets(&accel, &rays, &[0xFF, 0b1011_0110], cull).unwrap();
            }
        }
    }
}

/// Rays from inside closed meshes aimed at every vertex and at points on every edge must hit
/// something (no culling): the leak count is 0. A double hit on an edge is fine.
fn leaks(tris: &[[Vec3; 3]], origins: &[Vec3], targets: &[Vec3]) -> (usize, usize) {
    let (a, b) = leaks_on(tris, origins, targets, BuildQuality::Binned);
    let (c, d) = leaks_on(tris, origins, targets, BuildQuality::Medium);
    (a + c, b + d)
}

/// `leaks` on one builder's tree.
fn leaks_on(
    tris: &[[Vec3; 3]],
    origins: &[Vec3],
    targets: &[Vec3],
    quality: BuildQuality,
) -> (usize, usize) {
    let accel = Accel::build(tris, quality);
    let mut rays = Vec::new();
    for o in origins {
        for t in targets {
            rays.push(Ray::new(*o, *t - *o, 0.0, f32::INFINITY));
        }
    }
    let mut leaked = 0;
    for pair in rays.chunks(16) {
        let (lo, hi) = pair.split_at(pair.len().min(8));
        let (p0, a0) = RayPacket8::from_fn(|i| lo.get(i).copied());
        let (p1, a1) = RayPacket8::from_fn(|i| hi.get(i).copied());
        let h16 = intersect16(&accel, [&p0, &p1], [a0, a1], false);
        let hh16 = intersect_hybrid16(&accel, [&p0, &p1], [a0, a1], false);
        for (i, ray) in pair.iter().enumerate() {
            if h16[i / 8].lane(i % 8).is_none() || hh16[i / 8].lane(i % 8).is_none() {
                let brute = whitted::accel::scalar::intersect_brute1(&accel, ray, false);
                eprintln!("packet16 leak: {ray:?} brute {brute:?}");
                leaked += 1;
            }
        }
    }
    let mut many = vec![None; rays.len()];
    intersect_wide1_many(&accel, &rays, false, &mut many);
    leaked += many.iter().filter(|h| h.is_none()).count();
    for chunk in rays.chunks(8) {
        let (packet, active) = RayPacket8::from_fn(|i| chunk.get(i).copied());
        let hits = intersect8(&accel, &packet, active, false);
        let whits = intersect_wide8(&accel, &packet, active, false);
        let hhits = intersect_hybrid8(&accel, &packet, active, false);
        for i in 0..chunk.len() {
            let scalar = intersect1(&accel, &chunk[i], false);
            let wide = intersect_wide1(&accel, &chunk[i], false);
            if hits.lane(i).is_none()
                || scalar.is_none()
                || wide.is_none()
                || whits.lane(i).is_none()
                || hhits.lane(i).is_none()
            {
                let brute = whitted::accel::scalar::intersect_brute1(&accel, &chunk[i], false);
                eprintln!("leak: {:?} brute {:?}", chunk[i], brute);
                leaked += 1;
            }
        }
    }
    (leaked, rays.len())
}

fn edge_targets(mesh: &whitted::mesh::Mesh) -> Vec<Vec3> {
    let mut targets = mesh.positions.clone();
    for t in &mesh.triangles {
        for k in 0..3 {
            let (a, b) = (
                mesh.positions[t[k] as usize],
                mesh.positions[t[(k + 1) % 3] as usize],
            );
            for s in [0.5f32, 0.25, 1.0 / 3.0] {
                targets.push(a + (b - a) * s);
            }
        }
    }
    targets
}

#[test]
fn watertight_from_inside_the_kitten() {
    let (mesh, _) = load_mesh(&common::assets().join("meshes/kitten.m")).unwrap();
    let tris: Vec<[Vec3; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect();
    let origins = [
        Vec3::new(0.0, -0.5, 0.0),
        Vec3::new(0.05, -0.2, -0.1),
        Vec3::new(-0.1, 0.2, -0.1),
    ];
    let targets = edge_targets(&mesh);
    let (leaked, total) = leaks(&tris, &origins, &targets);
    println!("kitten: {leaked} leaks of {total} rays");
    assert_eq!(
        leaked, 0,
        "{leaked} of {total} rays escaped the closed kitten"
    );
}

#[test]
fn watertight_from_inside_a_needle_prism() {
    let dir = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("meshes");
    let (mesh, _) = load_mesh(&dir.join("prism.m")).unwrap();
    let mesh = mesh.subdivide(3);
    let tris: Vec<[Vec3; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect();
    let origins: Vec<Vec3> = (1..10)
        .map(|k| Vec3::new(0.0002, 0.0003, k as f32 * 0.1))
        .collect();
    let targets = edge_targets(&mesh);
    let (leaked, total) = leaks(&tris, &origins, &targets);
    println!("prism: {leaked} leaks of {total} rays");
    assert_eq!(
        leaked, 0,
        "{leaked} of {total} rays escaped the closed prism"
    );
}

/// The batch entries on an empty tree report nothing, overwriting what the buffers held, and
/// on a real one they write exactly the rays' slots.
#[test]
fn wide1_batch_entries_fill_every_slot() {
    let ray = Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z, 0.0, f32::INFINITY);
    let empty = Accel::build(&[], BuildQuality::Binned);
    let stale = Some(Hit {
        tri: 7,
        t: 1.0,
        b1: 0.0,
        b2: 0.0,
    });
    let (mut hits, mut occ) = (vec![stale; 3], vec![true; 3]);
    intersect_wide1_many(&empty, &[ray; 2], false, &mut hits);
    occluded_wide1_many(&empty, &[ray; 2], false, &mut occ);
    assert_eq!(hits, [None, None, stale]);
    assert_eq!(occ, [false, false, true]);
    let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let accel = Accel::build(&[tri], BuildQuality::Binned);
    let miss = Ray::new(Vec3::new(2.0, 2.0, -1.0), Vec3::Z, 0.0, f32::INFINITY);
    intersect_wide1_many(&accel, &[ray, miss], false, &mut hits);
    occluded_wide1_many(&accel, &[ray, miss], false, &mut occ);
    assert_eq!(hits[0], intersect1(&accel, &ray, false));
    assert_eq!(hits[0].map(|h| h.tri), Some(0));
    assert_eq!((hits[1], hits[2]), (None, stale));
    assert_eq!(occ, [true, false, true]);
}

/// Packet `h` (0 or 1) of a group of up to 16 rays, its lanes active where `mask` (bit `i`
/// for ray `i` of the group) says so and a ray is there.
fn half16(group: &[Ray], mask: u16, h: usize) -> (RayPacket8, simd::M32x8) {
    let part = group.get(8 * h..).unwrap_or(&[]);
    let (p, active) = RayPacket8::from_fn(|i| part.get(i).copied());
    (
        p,
        active & simd::mask_from_bits((mask >> (8 * h)) as u32 & 0xFF),
    )
}

/// `hybrid16`'s any hit takes 16 rays down the wide tree together, testing a leaf for the
/// packet when more than `SWITCH_WIDE16` lanes meet it and lane by lane otherwise, and walks a
/// node's subtree lane by lane once few lanes reach it. Coherent shadow rays (the bench's, on
/// the kitten: 16 neighbouring surface points towards one light) take every one of those
/// branches, and the octant-wide slab test; the same rays reversed (from beyond the light
/// back to the surface points, shortened to end just before them) mostly go unoccluded.
/// Every lane must equal `occluded1`, culled and not, all lanes active or some. Closest hit
/// likewise on the camera rays that hit and the reversed shadow rays: `intersect1` bit for bit.
#[test]
fn hybrid16_wide_packets_equal_scalar_on_coherent_rays() {
    use whitted::bench::{Workload, Workloads, triangles};
    let (mesh, _) = load_mesh(&common::assets().join("meshes/kitten.m")).unwrap();
    let accel = Accel::build(&triangles(&mesh), BuildQuality::Binned);
    let work = Workloads::generate_with(&mesh, &accel, 320, 180, 0);
    let shadow = work
        .sets()
        .into_iter()
        .find(|(w, _)| *w == Workload::Shadow)
        .unwrap()
        .1
        .to_vec();
    assert!(shadow.len() > 3000, "{} shadow rays", shadow.len());
    let reversed: Vec<Ray> = shadow
        .iter()
        .map(|r| {
            let end = r.origin + r.dir * r.tfar;
            Ray::new(end, -r.dir, 0.0, r.tfar * 0.999)
        })
        .collect();
    let (mut occluded, mut total) = (0, 0);
    for rays in [&shadow, &reversed] {
        for cull in [false, true] {
            for mask in [0xFFFFu16, 0b1011_0111_1110_1101] {
                for group in rays.chunks(16) {
                    let ((p0, a0), (p1, a1)) = (half16(group, mask, 0), half16(group, mask, 1));
                    let got = occluded_hybrid16(&accel, [&p0, &p1], [a0, a1], cull);
                    for (i, ray) in group.iter().enumerate() {
                        let (h, lane) = (i / 8, i % 8);
                        let active = mask >> i & 1 == 1;
                        let want = active && occluded1(&accel, ray, cull);
                        let lane_bit = simd::bitmask(got[h]) >> lane & 1 == 1;
                        assert_eq!(lane_bit, want, "lane {i} of {ray:?}, cull {cull}");
                        occluded += want as usize;
                        total += 1;
                    }
                }
            }
        }
    }
    // both outcomes occur in numbers
    assert!(
        occluded > total / 10 && occluded < total * 9 / 10,
        "{occluded} of {total}"
    );

    // closest hit: packets sharing an octant go down the wide tree together too; the
    // camera rays that hit (primary-hits-only) and the reversed shadow rays
    let camera = work
        .sets()
        .into_iter()
        .find(|(w, _)| *w == Workload::PrimaryHits)
        .unwrap()
        .1
        .to_vec();
    let bits_of =
        |h: Option<Hit>| h.map(|h| (h.tri, h.t.to_bits(), h.b1.to_bits(), h.b2.to_bits()));
    let (mut hit, mut total) = (0, 0);
    for rays in [&camera, &reversed] {
        for cull in [false, true] {
            for mask in [0xFFFFu16, 0b1011_0111_1110_1101] {
                for group in rays.chunks(16) {
                    let ((p0, a0), (p1, a1)) = (half16(group, mask, 0), half16(group, mask, 1));
                    let got = intersect_hybrid16(&accel, [&p0, &p1], [a0, a1], cull);
                    for (i, ray) in group.iter().enumerate() {
                        let want = if mask >> i & 1 == 1 {
                            intersect1(&accel, ray, cull)
                        } else {
                            None
                        };
                        assert_eq!(
                            bits_of(got[i / 8].lane(i % 8)),
                            bits_of(want),
                            "lane {i} of {ray:?}, cull {cull}"
                        );
                        hit += want.is_some() as usize;
                        total += 1;
                    }
                }
            }
        }
    }
    assert!(hit > total / 10, "{hit} of {total}");
}
