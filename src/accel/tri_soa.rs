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
        let col = || vec![0f32; len];
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
        // One pass, every column written at the same index: slices of exactly `len`
        // elements let the compiler drop the bounds checks.
        let [v0x, v0y, v0z] = s.v0.each_mut().map(|c| &mut c[..len]);
        let [v1x, v1y, v1z] = s.v1.each_mut().map(|c| &mut c[..len]);
        let [v2x, v2y, v2z] = s.v2.each_mut().map(|c| &mut c[..len]);
        let [nx, ny, nz] = s.n.each_mut().map(|c| &mut c[..len]);
        let [p1x, p1y, p1z] = s.p1.each_mut().map(|c| &mut c[..len]);
        let [p2x, p2y, p2z] = s.p2.each_mut().map(|c| &mut c[..len]);
        let n_len = &mut s.n_len[..len];
        for (i, &p) in order.iter().enumerate() {
            let [a, b, c] = tris[p as usize];
            let n = (b - a).cross(c - a);
            let nn = n.dot(n);
            let (n, p1, p2) = if nn.is_finite() && nn >= f32::MIN_POSITIVE {
                (n, (c - a).cross(n) / nn, n.cross(b - a) / nn)
            } else {
                (Vec3::ZERO, Vec3::ZERO, Vec3::ZERO)
            };
            (v0x[i], v0y[i], v0z[i]) = (a.x, a.y, a.z);
            (v1x[i], v1y[i], v1z[i]) = (b.x, b.y, b.z);
            (v2x[i], v2y[i], v2z[i]) = (c.x, c.y, c.z);
            (nx[i], ny[i], nz[i]) = (n.x, n.y, n.z);
            (p1x[i], p1y[i], p1z[i]) = (p1.x, p1.y, p1.z);
            (p2x[i], p2y[i], p2z[i]) = (p2.x, p2.y, p2.z);
            n_len[i] = n.length();
        }
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
