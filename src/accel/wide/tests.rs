use super::*;
use crate::accel::BuildQuality;

/// The shipped kitten's triangles and their acceleration structure.
pub(in crate::accel) fn kitten() -> (Vec<[glam::Vec3; 3]>, Accel) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/kitten.m");
    let (mesh, _) = crate::io::load_mesh(&path).unwrap();
    let tris: Vec<_> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect();
    let accel = Accel::build(&tris, BuildQuality::Binned);
    (tris, accel)
}

/// Every node's per-octant order lists its used slots first, each once, sorted along the
/// octant's diagonal (by the box centre's signed sum), ties in slot order, then the
/// unused slots in slot order: what an insertion sort of the slots gives.
#[test]
fn octant_orders_are_stable_sorts_of_the_children() {
    let (_, accel) = kitten();
    for node in &accel.wide.nodes {
        let n = node.valid().count_ones() as usize;
        assert_eq!(node.valid(), (1 << n) - 1, "used slots come first");
        let [lo, hi] = node.bounds.map(|c| c.map(crate::simd::lanes));
        for oct in 0..8 {
            let key = |i: usize| {
                let s = |k: usize| if oct >> k & 1 == 1 { -1.0 } else { 1.0 };
                (lo[0][i] + hi[0][i]) * s(0)
                    + (lo[1][i] + hi[1][i]) * s(1)
                    + (lo[2][i] + hi[2][i]) * s(2)
            };
            let mut want: Vec<usize> = (0..n).collect();
            want.sort_by(|&a, &b| key(a).total_cmp(&key(b)));
            want.extend(n..BLOCK);
            let got: Vec<usize> = (0..BLOCK)
                .map(|k| (node.order[oct] >> (3 * k) & 7) as usize)
                .collect();
            assert_eq!(got, want, "octant {oct}");
        }
    }
}

/// `fill` makes each block from the slots the collapse recorded: its ids are the slots'
/// original triangles, its lanes the SoA columns at those slots, unused lanes zero with
/// no triangle; every slot is in exactly one block; and the blocks are the same whatever
/// the pool's size (they are made in parallel).
#[test]
fn blocks_hold_their_slots_triangles_on_any_pool() {
    let (tris, accel) = kitten();
    let t = &accel.tris;
    let mut seen = vec![false; tris.len()];
    for b in &accel.wide.blocks {
        let len = b.triangles();
        for lane in 0..BLOCK {
            let field = |v: &Vec3x8| [v.x, v.y, v.z].map(|c| crate::simd::lanes(c)[lane]);
            let got = [&b.n, &b.v0, &b.p1, &b.p2].map(field);
            if lane < len {
                let s = b.slot[lane] as usize;
                assert!(!std::mem::replace(&mut seen[s], true), "slot {s} twice");
                assert_eq!(b.prim[lane], t.prim[s]);
                let col = |c: &[Vec<f32>; 3]| [c[0][s], c[1][s], c[2][s]];
                assert_eq!(got, [&t.n, &t.v0, &t.p1, &t.p2].map(col), "slot {s}");
            } else {
                assert_eq!(b.prim[lane], u32::MAX);
                assert_eq!(got, [[0.0; 3]; 4]);
            }
        }
    }
    assert!(seen.iter().all(|&s| s), "every slot in a block");
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| Accel::build(&tris, BuildQuality::Binned))
    };
    let (one, two) = (on(1), on(2));
    let bits = |a: &Accel| -> Vec<u32> {
        let lanes = |v: &Vec3x8| [v.x, v.y, v.z].map(|c| crate::simd::lanes(c).map(f32::to_bits));
        let block = |b: &TriBlock8| {
            let mut out: Vec<u32> = [&b.n, &b.v0, &b.p1, &b.p2]
                .into_iter()
                .flat_map(|v| lanes(v).into_iter().flatten())
                .collect();
            out.extend(b.prim.iter().chain(&b.slot));
            out
        };
        a.wide.blocks.iter().flat_map(block).collect()
    };
    assert_eq!(bits(&one), bits(&two));
    assert_eq!(bits(&one), bits(&accel));
    // a second fill keeps the blocks
    let mut again = accel.wide.clone();
    again.fill(&accel.tris);
    let mut copy = Accel::build(&tris, BuildQuality::Binned);
    copy.wide = again;
    assert_eq!(bits(&copy), bits(&accel));
}

/// The builder counts block lanes, not triangles (`build.rs`, `lanes`), so the collapse
/// fills its blocks: on the kitten at least 7 of 8 lanes on average (5.76 when the SAH
/// counted triangles), at under 80 bytes per triangle (89.9 then).
#[test]
fn kitten_blocks_are_nearly_full() {
    let (tris, accel) = kitten();
    let w = &accel.wide;
    let used: usize = w.blocks.iter().map(TriBlock8::triangles).sum();
    assert_eq!(used, tris.len());
    let fill = used as f64 / w.blocks.len() as f64;
    let bytes = w.bytes() as f64 / tris.len() as f64;
    assert!(fill >= 7.0, "{fill:.2} triangles per block");
    assert!(bytes < 80.0, "{bytes:.1} bytes per triangle");
}

/// Node area of a collapsed tree: the root's box and every inner child's box (what the
/// collapse's dynamic programme minimises).
fn node_area(accel: &Accel) -> f64 {
    let w = &accel.wide;
    let mut sum = area(&accel.nodes[0]) as f64;
    for node in &w.nodes {
        let [lo, hi] = node.bounds.map(|c| c.map(crate::simd::lanes));
        for slot in 0..node.valid().count_ones() as usize {
            if node.child[slot] & LEAF_BIT == 0 {
                let e = [0, 1, 2].map(|k| (hi[k][slot] - lo[k][slot]).max(0.0) as f64);
                sum += e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
            }
        }
    }
    sum
}

/// The least node area of binary node `b`'s subtree, by brute force: every way of
/// choosing its wide node's children (a cut of the binary subtree below it into 2 to 8
/// parts, each a leaf of at most a block or a node of its own), each tried.
fn brute_force(src: &Src, b: usize) -> f64 {
    // every cut of the subtree of `b` into at most 8 parts
    fn cuts(src: &Src, b: usize) -> Vec<Vec<usize>> {
        let mut all = vec![vec![b]];
        if !src.is_leaf(b) {
            let f = src.nodes[b].first as usize;
            for l in cuts(src, f) {
                for r in cuts(src, f + 1) {
                    if l.len() + r.len() <= BLOCK {
                        all.push([l.clone(), r].concat());
                    }
                }
            }
        }
        all
    }
    let f = src.nodes[b].first as usize;
    let mut best = f64::INFINITY;
    for l in cuts(src, f) {
        for r in cuts(src, f + 1) {
            if l.len() + r.len() <= BLOCK {
                let cost: f64 = l
                    .iter()
                    .chain(&r)
                    .filter(|&&c| !src.is_leaf(c))
                    .map(|&c| brute_force(src, c))
                    .sum();
                best = best.min(cost);
            }
        }
    }
    area(&src.nodes[b]) as f64 + best
}

/// The collapse picks each node's children of least SAH cost: on small random meshes the
/// tree's node area is the brute-force minimum over every possible collapse, and on the
/// kitten the programme's predicted cost is the node area of the tree it made.
#[test]
fn collapse_minimises_node_area() {
    let mut seed = 0x9e37_79b9_7f4a_7c15u64;
    let mut rand = || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 40) as f32 / (1u64 << 24) as f32
    };
    for n in [20, 40, 70, 100] {
        let tris: Vec<[glam::Vec3; 3]> = (0..n)
            .map(|_| {
                let p = glam::Vec3::new(rand(), rand(), rand()) * 4.0;
                let s = 0.05 + rand() * 0.3;
                [
                    p,
                    p + glam::Vec3::new(s, rand() * s, 0.0),
                    p + glam::Vec3::new(0.0, s, s),
                ]
            })
            .collect();
        let accel = Accel::build(&tris, BuildQuality::Binned);
        let nodes = &accel.nodes;
        let counts = subtree_counts(nodes);
        let dp = Dp::new(nodes, &counts);
        let src = Src { nodes, counts, dp };
        if src.is_leaf(0) {
            continue;
        }
        let (got, want) = (node_area(&accel), brute_force(&src, 0));
        assert!(
            (got - want).abs() <= 1e-5 * want,
            "{n} triangles: {got} against {want}"
        );
        assert!(accel.wide.nodes.len() > 1 || n <= 40, "{n}: a real tree");
    }
    let (_, accel) = kitten();
    let counts = subtree_counts(&accel.nodes);
    let dp = Dp::new(&accel.nodes, &counts);
    let (got, want) = (node_area(&accel), dp.cost[0][0] as f64);
    assert!(
        (got - want).abs() <= 1e-4 * want,
        "kitten: {got} against {want}"
    );
}
