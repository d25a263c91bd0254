//! Unit tests of the binned SAH builder (`accel/build.rs`).
use super::*;

/// Every triangle in exactly one leaf of at most MAX_LEAF; every box holds its triangles
/// and its children; children in pairs; returns the depth.
fn check(tris: &[[Vec3; 3]]) -> usize {
    let (nodes, order) = build_bvh2(tris);
    let mut seen = vec![0u32; tris.len()];
    let mut stack = vec![(0usize, 1usize)];
    let mut depth = 0;
    let inside = |n: &Node, lo: Vec3, hi: Vec3| {
        Vec3::from(n.min).cmple(lo).all() && Vec3::from(n.max).cmpge(hi).all()
    };
    while let Some((i, d)) = stack.pop() {
        depth = depth.max(d);
        let n = &nodes[i];
        if n.count > 0 {
            assert!(n.count as usize <= MAX_LEAF, "leaf of {}", n.count);
            for &p in &order[n.first as usize..(n.first + n.count) as usize] {
                seen[p as usize] += 1;
                let t = tris[p as usize];
                let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
                assert!(inside(n, lo, hi) || !lo.is_finite() || !hi.is_finite());
            }
        } else {
            for c in [n.first as usize, n.first as usize + 1] {
                assert!(c > i && c < nodes.len());
                let k = &nodes[c];
                assert!(inside(n, k.min.into(), k.max.into()) || !Vec3::from(k.min).is_finite());
                stack.push((c, d + 1));
            }
        }
    }
    assert!(seen.iter().all(|&s| s == 1), "each triangle in one leaf");
    assert_eq!(nodes.len() % 2, 1, "root plus pairs");
    depth
}

fn grid(n: usize, f: impl Fn(usize) -> Vec3) -> Vec<[Vec3; 3]> {
    (0..n)
        .map(|i| {
            let p = f(i);
            [p, p + Vec3::X * 0.1, p + Vec3::Y * 0.1]
        })
        .collect()
}

#[test]
fn spread_triangles_make_a_shallow_tree() {
    let tris = grid(20_000, |i| {
        Vec3::new((i % 100) as f32, (i / 100) as f32, (i % 7) as f32)
    });
    let depth = check(&tris);
    assert!((12..=30).contains(&depth), "depth {depth}");
}

/// The parallel split gives the serial walk's tree, node for node, on any pool.
#[test]
fn same_tree_on_any_number_of_threads() {
    let tris = grid(3 * PARALLEL_MIN, |i| {
        Vec3::new(
            (i % 173) as f32,
            (i / 173) as f32 * 0.7,
            ((i * 7919) % 31) as f32,
        )
    });
    let on = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| build_bvh2(&tris))
    };
    let one = on(1);
    assert_eq!(one, on(3));
    // and the plain serial walk over the same boxes
    let (mut lo, mut hi): (Vec<Vec3A>, Vec<Vec3A>) = tris
        .iter()
        .map(|t| {
            let (a, b, c) = (Vec3A::from(t[0]), Vec3A::from(t[1]), Vec3A::from(t[2]));
            (a.min(b).min(c), a.max(b).max(c))
        })
        .unzip();
    let (mut root, mut cent) = (Box3::EMPTY, Box3::EMPTY);
    for (&l, &h) in lo.iter().zip(&hi) {
        root.grow(l, h);
        cent.grow(l + h, l + h);
    }
    let mut ids: Vec<u32> = (0..tris.len() as u32).collect();
    let nodes = serial(Prims::new(&mut lo, &mut hi, &mut ids), 0, root, cent, 0);
    assert_eq!(one, (nodes, ids));
    check(&tris);
}

/// A floor under many small triangles is set apart at the root (binned by centroid it
/// would share a bin with the lowest small ones and stretch every box above them).
#[test]
fn a_floor_is_set_apart_at_the_root() {
    let mut tris = grid(30_000, |i| {
        Vec3::new(
            (i % 50) as f32 * 0.02,
            (i / 50 % 30) as f32 * 0.02,
            (i / 1500) as f32 * 0.02,
        )
    });
    let n = tris.len();
    let p = |x: f32, z: f32| Vec3::new(x, -1.0, z);
    tris.push([p(-6.0, -6.0), p(-6.0, 6.0), p(6.0, 6.0)]);
    tris.push([p(-6.0, -6.0), p(6.0, 6.0), p(6.0, -6.0)]);
    check(&tris);
    let (nodes, order) = build_bvh2(&tris);
    let root = nodes[0];
    let floor_leaf = [root.first, root.first + 1].into_iter().any(|c| {
        let c = nodes[c as usize];
        c.count == 2
            && order[c.first as usize..][..2]
                .iter()
                .all(|&p| p as usize >= n)
    });
    assert!(
        floor_leaf,
        "the two floor triangles are one child of the root"
    );
}

#[test]
fn coincident_triangles_split_at_the_median() {
    // all centroids equal: no bin boundary separates them, so ranges are halved.
    let tris = grid(1000, |_| Vec3::ONE);
    let depth = check(&tris);
    assert!(depth <= 10, "depth {depth}");
    let tris = grid(3, |_| Vec3::ONE);
    assert_eq!(check(&tris), 1, "a small clump is one leaf");
}

#[test]
fn exponential_spacing_stays_logarithmic() {
    // each triangle twice as far as the last: binning peels off one at a time, until
    // MEDIAN_DEPTH switches to halving.
    let tris = grid(4000, |i| Vec3::splat(1.001f32.powi(i as i32 * 20)));
    let depth = check(&tris);
    assert!(depth <= MEDIAN_DEPTH as usize + 12, "depth {depth}");
}

#[test]
fn single_and_non_finite_triangles_do_not_panic() {
    check(&grid(1, |_| Vec3::ZERO));
    let mut tris = grid(100, |i| Vec3::splat(i as f32));
    tris[3][1] = Vec3::splat(f32::NAN);
    tris[7][0] = Vec3::splat(f32::INFINITY);
    tris[9][2] = Vec3::new(f32::NEG_INFINITY, 0.0, f32::MAX);
    check(&tris);
}
