//! A triangle mesh as loaded from a file or generated in code, before any acceleration.

use glam::{Affine3A, Mat3, Vec2, Vec3};

pub(crate) mod shading;
pub use shading::MAX_CREASE_PAIRS;

/// Positions, triangles and optional per-vertex attributes. Every attribute vector, when
/// present, has exactly one entry per position.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Counter-clockwise vertex indices (front = CCW).
    pub triangles: Vec<[u32; 3]>,
    /// Unit vertex normals, if the file gave them (or after [`Mesh::ensure_normals`]).
    pub normals: Option<Vec<Vec3>>,
    /// Texture coordinates per vertex.
    pub uvs: Option<Vec<Vec2>>,
    /// Linear RGB colour per vertex.
    pub colors: Option<Vec<Vec3>>,
}

impl Mesh {
    /// Unnormalised face normal `cross(v1 - v0, v2 - v0)` (twice the area, CCW = front).
    pub fn face_cross(&self, t: usize) -> Vec3 {
        let [a, b, c] = self.triangles[t].map(|i| self.positions[i as usize]);
        (b - a).cross(c - a)
    }

    /// Area-weighted vertex normals: the sum of the incident faces' `cross` vectors, normalised.
    /// A vertex whose sum vanishes (only degenerate faces around it) gets `+y` so it stays finite;
    /// shading then falls back to the geometric normal wherever it matters.
    pub fn area_weighted_normals(&self) -> Vec<Vec3> {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for (t, tri) in self.triangles.iter().enumerate() {
            let c = self.face_cross(t);
            for &i in tri {
                acc[i as usize] += c;
            }
        }
        acc.into_iter()
            .map(|n| n.try_normalize().unwrap_or(Vec3::Y))
            .collect()
    }

    /// Fill in missing normals with area-weighted ones, and replace zero-length or non-finite
    /// normals from the file by the area-weighted normal of that vertex.
    pub fn ensure_normals(&mut self) {
        let computed = self.area_weighted_normals();
        match &mut self.normals {
            None => self.normals = Some(computed),
            Some(ns) => {
                for (n, c) in ns.iter_mut().zip(computed) {
                    *n = n.try_normalize().unwrap_or(c);
                }
            }
        }
    }

    /// This mesh carried by `m` (object to world): positions as points, normals through the
    /// inverse transpose (made unit again), uv and colours as they are; a mirroring `m`
    /// swaps two corners of every triangle, so the front stays the front.
    pub fn transformed(&self, m: &Affine3A) -> Mesh {
        let linear = Mat3::from(m.matrix3);
        let normal_matrix = linear.inverse().transpose();
        let mut triangles = self.triangles.clone();
        if linear.determinant() < 0.0 {
            for t in &mut triangles {
                t.swap(1, 2);
            }
        }
        Mesh {
            positions: self
                .positions
                .iter()
                .map(|&p| m.transform_point3(p))
                .collect(),
            triangles,
            normals: self.normals.as_ref().map(|ns| {
                ns.iter()
                    .map(|&n| (normal_matrix * n).normalize_or_zero())
                    .collect()
            }),
            uvs: self.uvs.clone(),
            colors: self.colors.clone(),
        }
    }

    /// Append `other`'s vertices and triangles (its indices shifted past this mesh's). An
    /// attribute stays only if both meshes have it (an empty mesh takes `other`'s).
    pub fn append(&mut self, other: &Mesh) {
        fn join<T: Copy>(a: &mut Option<Vec<T>>, b: &Option<Vec<T>>, first: bool) {
            match (a.as_mut(), b) {
                _ if first => *a = b.clone(),
                (Some(a), Some(b)) => a.extend_from_slice(b),
                _ => *a = None,
            }
        }
        let first = self.positions.is_empty() && self.triangles.is_empty();
        let base = self.positions.len() as u32;
        join(&mut self.normals, &other.normals, first);
        join(&mut self.uvs, &other.uvs, first);
        join(&mut self.colors, &other.colors, first);
        self.positions.extend_from_slice(&other.positions);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|v| v + base)));
    }

    /// Number of triangles with zero area (never hit by any ray).
    pub fn degenerate_count(&self) -> usize {
        (0..self.triangles.len())
            .filter(|&t| self.face_cross(t).length_squared() == 0.0)
            .count()
    }

    /// Axis-aligned bounds `(min, max)`; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let first = *self.positions.first()?;
        Some(
            self.positions
                .iter()
                .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p))),
        )
    }

    /// Edges used by exactly one triangle (0 for a closed manifold mesh).
    pub fn open_edges(&self) -> usize {
        let mut edges = std::collections::HashMap::<(u32, u32), u32>::new();
        for tri in &self.triangles {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        edges.values().filter(|&&c| c == 1).count()
    }

    /// Midpoint subdivision, `levels` times: every triangle becomes four
    /// (`[v0 m01 m20] [v1 m12 m01] [v2 m20 m12] [m01 m12 m20]`). Shared edges share their
    /// midpoint, so a closed mesh stays closed. Attributes are interpolated linearly
    /// (normals re-normalised).
    pub fn subdivide(&self, levels: u32) -> Mesh {
        let mut m = self.clone();
        for _ in 0..levels {
            m = m.subdivide_once();
        }
        m
    }

    fn subdivide_once(&self) -> Mesh {
        let mut out = self.clone();
        out.triangles = Vec::with_capacity(self.triangles.len() * 4);
        let mut mid = std::collections::HashMap::<(u32, u32), u32>::new();
        let mut midpoint = |out: &mut Mesh, a: u32, b: u32| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (ia, ib) = (a as usize, b as usize);
                out.positions
                    .push((out.positions[ia] + out.positions[ib]) * 0.5);
                if let Some(n) = &mut out.normals {
                    n.push(((n[ia] + n[ib]) * 0.5).try_normalize().unwrap_or(n[ia]));
                }
                if let Some(uv) = &mut out.uvs {
                    uv.push((uv[ia] + uv[ib]) * 0.5);
                }
                if let Some(c) = &mut out.colors {
                    c.push((c[ia] + c[ib]) * 0.5);
                }
                (out.positions.len() - 1) as u32
            })
        };
        for &[v0, v1, v2] in &self.triangles {
            let m01 = midpoint(&mut out, v0, v1);
            let m12 = midpoint(&mut out, v1, v2);
            let m20 = midpoint(&mut out, v2, v0);
            out.triangles.extend([
                [v0, m01, m20],
                [v1, m12, m01],
                [v2, m20, m12],
                [m01, m12, m20],
            ]);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn tetrahedron() -> Mesh {
        Mesh {
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(0.0, 0.0, 1.0),
            ],
            triangles: vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
            ..Default::default()
        }
    }

    #[test]
    fn area_weighted_normals_point_outwards() {
        let m = tetrahedron();
        let n = m.area_weighted_normals();
        let expect = Vec3::ONE.normalize();
        assert!((n[0] + expect).length() < 1e-6, "{:?}", n[0]);
        // Vertex 1 touches faces with normals -z, -y and (1,1,1)/sqrt3 (area sqrt3/2).
        let s = Vec3::new(0.0, -1.0, -1.0) * 0.5 + Vec3::ONE * 0.5;
        assert!((n[1] - s.normalize()).length() < 1e-6);
    }

    #[test]
    fn subdivision_quadruples_and_stays_closed() {
        let m = tetrahedron().subdivide(2);
        assert_eq!(m.triangles.len(), 4 * 16);
        assert_eq!(m.open_edges(), 0);
        assert_eq!(m.positions.len(), 4 + 6 + 24);
        assert_eq!(tetrahedron().open_edges(), 0);
    }

    #[test]
    fn zero_normals_fall_back() {
        let mut m = tetrahedron();
        m.normals = Some(vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::new(f32::NAN, 0.0, 0.0),
        ]);
        m.ensure_normals();
        let n = m.normals.unwrap();
        assert!((n[0] + Vec3::ONE.normalize()).length() < 1e-6);
        assert_eq!(n[1], Vec3::X);
        assert!(n[3].is_finite());
    }
}
