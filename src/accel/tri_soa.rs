//! Triangles in structure-of-arrays form, permuted once into BVH leaf order.

use glam::Vec3;

/// What the plane + barycentric test needs, one array per component, in BVH order:
/// the vertices, the plane normal `n = cross(v1 - v0, v2 - v0)` (unnormalised: twice the
/// area, CCW = front), and the sub-triangle areas precomputed as linear forms of
/// `w = q - v0`: the area opposite `v1` over the whole is
/// `<cross(v2 - q, v0 - q), n> / <n, n> = <w, cross(e2, n) / <n, n>> = <w, p1>`, and the area
/// opposite `v2` is `<w, cross(n, e1) / <n, n>> = <w, p2>` (`e1 = v1 - v0`, `e2 = v2 - v0`).
/// `prim[slot]` is the triangle's index in the scene's original order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TriangleSoa {
    /// First vertex, per component (`v0[k][slot]`).
    pub v0: [Vec<f32>; 3],
    /// Second vertex, per component.
    pub v1: [Vec<f32>; 3],
    /// Third vertex, per component.
    pub v2: [Vec<f32>; 3],
    /// Unnormalised normal `cross(v1 - v0, v2 - v0)`; 0 for a degenerate triangle.
    pub n: [Vec<f32>; 3],
    /// `cross(e2, n) / <n, n>`: `<w, p1>` is the barycentric weight of `v1`; 0 if degenerate.
    pub p1: [Vec<f32>; 3],
    /// `cross(n, e1) / <n, n>`: `<w, p2>` is the barycentric weight of `v2`; 0 if degenerate.
    pub p2: [Vec<f32>; 3],
    /// `|n|`, to scale the barycentric safety margin by how grazing a ray is.
    pub n_len: Vec<f32>,
    /// Index of the triangle at each slot in the scene's original order.
    pub prim: Vec<u32>,
}

impl TriangleSoa {
    /// Lay out `tris` in the order `order` (BVH leaf order; entries index `tris`).
    ///
    /// Degenerate policy: a triangle whose `<n, n>` is zero, subnormal or not finite is stored
    /// with `n = 0`, so its plane test computes `0 / 0 = NaN`, which fails the depth test:
    /// zero-area triangles are never hit.
    pub fn new(tris: &[[Vec3; 3]], order: &[u32]) -> Self {
        let len = order.len();
        // (zeroed pages, untouched until the fill: advised first, they come huge)
        let col = || {
            let c = vec![0f32; len];
            super::pages::advise_huge(&c);
            c
        };
        let cols = || [col(), col(), col()];
        let mut s = TriangleSoa {
            v0: cols(),
            v1: cols(),
            v2: cols(),
            n: cols(),
            p1: cols(),
            p2: cols(),
            n_len: col(),
            prim: order.to_vec(),
        };
        let [v0x, v0y, v0z] = &mut s.v0;
        let [v1x, v1y, v1z] = &mut s.v1;
        let [v2x, v2y, v2z] = &mut s.v2;
        let [nx, ny, nz] = &mut s.n;
        let [p1x, p1y, p1z] = &mut s.p1;
        let [p2x, p2y, p2z] = &mut s.p2;
        let cols = Columns([
            v0x,
            v0y,
            v0z,
            v1x,
            v1y,
            v1z,
            v2x,
            v2y,
            v2z,
            nx,
            ny,
            nz,
            p1x,
            p1y,
            p1z,
            p2x,
            p2y,
            p2z,
            &mut s.n_len,
        ]);
        cols.fill(tris, order);
        s
    }

    /// Number of triangles (slots).
    pub fn len(&self) -> usize {
        self.prim.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.prim.is_empty()
    }

    /// First vertex of slot `i`, gathered from the SoA arrays.
    #[inline(always)]
    pub fn v0(&self, i: usize) -> [f32; 3] {
        [self.v0[0][i], self.v0[1][i], self.v0[2][i]]
    }
    /// Second vertex of slot `i`, gathered from the SoA arrays.
    #[inline(always)]
    pub fn v1(&self, i: usize) -> [f32; 3] {
        [self.v1[0][i], self.v1[1][i], self.v1[2][i]]
    }
    /// Third vertex of slot `i`, gathered from the SoA arrays.
    #[inline(always)]
    pub fn v2(&self, i: usize) -> [f32; 3] {
        [self.v2[0][i], self.v2[1][i], self.v2[2][i]]
    }
    /// Unnormalised normal of slot `i`, gathered from the SoA arrays.
    #[inline(always)]
    pub fn n(&self, i: usize) -> [f32; 3] {
        [self.n[0][i], self.n[1][i], self.n[2][i]]
    }
    /// Barycentric form `p1` of slot `i`, gathered from the SoA arrays.
    #[inline(always)]
    pub fn p1(&self, i: usize) -> [f32; 3] {
        [self.p1[0][i], self.p1[1][i], self.p1[2][i]]
    }
    /// Barycentric form `p2` of slot `i`, gathered from the SoA arrays.
    #[inline(always)]
    pub fn p2(&self, i: usize) -> [f32; 3] {
        [self.p2[0][i], self.p2[1][i], self.p2[2][i]]
    }
}

/// What the plane + barycentric test reads of the slots `first .. first + len` (a leaf):
/// each column sliced once, so a loop over the leaf's triangles indexes slices whose length
/// it knows, with no bounds check per triangle and column.
#[derive(Clone, Copy, Debug)]
pub struct LeafView<'a> {
    /// The first slot.
    pub first: usize,
    n: [&'a [f32]; 3],
    v0: [&'a [f32]; 3],
    p1: [&'a [f32]; 3],
    p2: [&'a [f32]; 3],
    n_len: &'a [f32],
}

/// A leaf's triangles as the packet test (`packet::hit_triangle8`) reads them: from the SoA
/// columns ([`LeafView`]) or from a block of the wide tree (`packet::BlockLeaf`); the same
/// floats either way.
pub trait Leaf {
    /// Triangles in the leaf.
    fn len(&self) -> usize;
    /// Whether the leaf has no triangles.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// `n` of the `j`-th triangle.
    fn n(&self, j: usize) -> [f32; 3];
    /// `v0` of the `j`-th triangle.
    fn v0(&self, j: usize) -> [f32; 3];
    /// `p1` of the `j`-th triangle.
    fn p1(&self, j: usize) -> [f32; 3];
    /// `p2` of the `j`-th triangle.
    fn p2(&self, j: usize) -> [f32; 3];
    /// `|n|` of the `j`-th triangle.
    fn n_len(&self, j: usize) -> f32;
    /// SoA slot of the `j`-th triangle.
    fn slot(&self, j: usize) -> usize;
}

impl Leaf for LeafView<'_> {
    #[inline(always)]
    fn len(&self) -> usize {
        self.n_len.len()
    }
    #[inline(always)]
    fn n(&self, j: usize) -> [f32; 3] {
        self.n.map(|c| c[j])
    }
    #[inline(always)]
    fn v0(&self, j: usize) -> [f32; 3] {
        self.v0.map(|c| c[j])
    }
    #[inline(always)]
    fn p1(&self, j: usize) -> [f32; 3] {
        self.p1.map(|c| c[j])
    }
    #[inline(always)]
    fn p2(&self, j: usize) -> [f32; 3] {
        self.p2.map(|c| c[j])
    }
    #[inline(always)]
    fn n_len(&self, j: usize) -> f32 {
        self.n_len[j]
    }
    #[inline(always)]
    fn slot(&self, j: usize) -> usize {
        self.first + j
    }
}

impl TriangleSoa {
    /// The slots `first .. first + count` as a [`LeafView`] (panics if out of range).
    #[inline(always)]
    pub fn leaf(&self, first: usize, count: usize) -> LeafView<'_> {
        let r = first..first + count;
        fn cut(c: &[Vec<f32>; 3], r: std::ops::Range<usize>) -> [&[f32]; 3] {
            [&c[0][r.clone()], &c[1][r.clone()], &c[2][r]]
        }
        LeafView {
            first,
            n: cut(&self.n, r.clone()),
            v0: cut(&self.v0, r.clone()),
            p1: cut(&self.p1, r.clone()),
            p2: cut(&self.p2, r.clone()),
            n_len: &self.n_len[r],
        }
    }
}

/// The float columns of a [`TriangleSoa`] over one range of slots, in field order (`v0`,
/// `v1`, `v2`, `n`, `p1`, `p2` by axis, then `n_len`).
struct Columns<'a>([&'a mut [f32]; 19]);

impl<'a> Columns<'a> {
    /// Fill every column for the triangles `order` (one per slot), halving the range across
    /// rayon's threads down to runs of 16k slots.
    fn fill(self, tris: &[[Vec3; 3]], order: &[u32]) {
        const RUN: usize = 1 << 14;
        if order.len() > RUN {
            let mid = order.len() / 2;
            let (a, b) = self.split_at(mid);
            rayon::join(
                || a.fill(tris, &order[..mid]),
                || b.fill(tris, &order[mid..]),
            );
            return;
        }
        // Slices of exactly `len` elements let the compiler drop the bounds checks.
        let len = order.len();
        let c = self.0.map(|c| &mut c[..len]);
        for (i, &p) in order.iter().enumerate() {
            let [a, b, v2] = tris[p as usize];
            let n = (b - a).cross(v2 - a);
            let nn = n.dot(n);
            let (n, p1, p2) = if nn.is_finite() && nn >= f32::MIN_POSITIVE {
                (n, (v2 - a).cross(n) / nn, n.cross(b - a) / nn)
            } else {
                (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO)
            };
            for (k, v) in [a, b, v2, n, p1, p2].into_iter().enumerate() {
                c[3 * k][i] = v.x;
                c[3 * k + 1][i] = v.y;
                c[3 * k + 2][i] = v.z;
            }
            c[18][i] = n.length();
        }
    }

    fn split_at(self, mid: usize) -> (Columns<'a>, Columns<'a>) {
        let (mut l, mut r) = (Vec::with_capacity(19), Vec::with_capacity(19));
        for c in self.0 {
            let (a, b) = c.split_at_mut(mid);
            l.push(a);
            r.push(b);
        }
        let arr = |v: Vec<&'a mut [f32]>| Columns(v.try_into().expect("19 columns"));
        (arr(l), arr(r))
    }
}
