//! Triangles in structure-of-arrays form, permuted once into BVH leaf order.

use crate::simd::{self, LANES, Vec3x8};
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
    /// Bytes of the columns and the index map (what the packet engines' leaves read).
    pub fn bytes(&self) -> usize {
        let cols = [&self.v0, &self.v1, &self.v2, &self.n, &self.p1, &self.p2];
        let floats: usize = cols.iter().flat_map(|c| c.iter()).map(Vec::len).sum();
        (floats + self.n_len.len()) * size_of::<f32>() + self.prim.len() * size_of::<u32>()
    }

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

/// One triangle's 19 column values (`v0`, `v1`, `v2`, `n`, `p1`, `p2` by axis, then `n_len`),
/// as the contract defines them: the scalar form of the 8-lane fill in [`Columns::fill`].
fn fields([a, b, v2]: [Vec3; 3]) -> [f32; 19] {
    let n = (b - a).cross(v2 - a);
    let nn = n.dot(n);
    let (n, p1, p2) = if nn.is_finite() && nn >= f32::MIN_POSITIVE {
        (n, (v2 - a).cross(n) / nn, n.cross(b - a) / nn)
    } else {
        (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO)
    };
    let mut out = [0f32; 19];
    for (k, v) in [a, b, v2, n, p1, p2].into_iter().enumerate() {
        out[3 * k..3 * k + 3].copy_from_slice(&v.to_array());
    }
    out[18] = n.length();
    out
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
        let mut c = self.0.map(|c| &mut c[..len]);
        // 8 slots at a time in lanes: the same IEEE operations in the same order as the
        // scalar loop below (products, differences, quotients and the square root are
        // correctly rounded either way), so the same floats, at about a third of the time.
        let full = len - len % LANES;
        for i in (0..full).step_by(LANES) {
            let corner = |v: usize| Vec3x8::from_fn(|k| tris[order[i + k] as usize][v].to_array());
            let (a, b, v2) = (corner(0), corner(1), corner(2));
            let (e1, e2) = (b - a, v2 - a);
            let n = e1.cross(e2);
            let nn = n.dot(n);
            // is_finite && >= MIN_POSITIVE (NaN fails both compares)
            let ok =
                simd::ge(nn, simd::splat(f32::MIN_POSITIVE)) & simd::le(nn, simd::splat(f32::MAX));
            let zero = Vec3x8::default();
            let quot = |v: Vec3x8| Vec3x8::new(v.x / nn, v.y / nn, v.z / nn);
            let n = Vec3x8::select(ok, n, zero);
            let p1 = Vec3x8::select(ok, quot(e2.cross(n)), zero);
            let p2 = Vec3x8::select(ok, quot(n.cross(e1)), zero);
            for (k, v) in [a, b, v2, n, p1, p2].into_iter().enumerate() {
                for (axis, lanes) in v.to_lanes().into_iter().enumerate() {
                    c[3 * k + axis][i..i + LANES].copy_from_slice(&lanes);
                }
            }
            c[18][i..i + LANES].copy_from_slice(&simd::lanes(simd::sqrt(n.dot(n))));
        }
        for (i, &p) in order.iter().enumerate().skip(full) {
            for (column, v) in c.iter_mut().zip(fields(tris[p as usize])) {
                column[i] = v;
            }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The 8-lane fill writes exactly the scalar formula's floats (bit for bit), over
    /// triangles of every scale, degenerate ones (collinear, repeated vertices, `<n, n>`
    /// subnormal, zero or overflowing) and a tail shorter than 8.
    #[test]
    fn lane_fill_equals_the_scalar_formula() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        };
        let mut tris = Vec::new();
        for i in 0..2000 {
            let scale = [1.0, 1e-3, 1e3, 1e-10, 1e-19, 1e19, 1e-30, 1e30][i % 8];
            let mut v = || Vec3::new(rnd(), rnd(), rnd()) * scale;
            let (a, b, c) = (v(), v(), v());
            tris.push(match i % 11 {
                0 => [a, a, b],                 // repeated vertex
                1 => [a, b, a + (b - a) * 0.5], // collinear
                _ => [a, b, c],
            });
        }
        // a reversed order, so slots and input indices differ
        let order: Vec<u32> = (0..tris.len() as u32 - 3).rev().collect();
        let soa = TriangleSoa::new(&tris, &order);
        let cols: [&Vec<f32>; 19] = [
            &soa.v0[0], &soa.v0[1], &soa.v0[2], &soa.v1[0], &soa.v1[1], &soa.v1[2], &soa.v2[0],
            &soa.v2[1], &soa.v2[2], &soa.n[0], &soa.n[1], &soa.n[2], &soa.p1[0], &soa.p1[1],
            &soa.p1[2], &soa.p2[0], &soa.p2[1], &soa.p2[2], &soa.n_len,
        ];
        let mut degenerate = 0;
        for (slot, &p) in order.iter().enumerate() {
            let want = fields(tris[p as usize]);
            degenerate += (want[9..12] == [0.0; 3]) as usize;
            for (k, col) in cols.iter().enumerate() {
                assert_eq!(
                    col[slot].to_bits(),
                    want[k].to_bits(),
                    "slot {slot} column {k}"
                );
            }
        }
        // the set really holds degenerate triangles of each kind
        assert!(degenerate > 400, "{degenerate}");
    }
}
