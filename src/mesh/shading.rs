//! Shading normals a file's format means: flat (each triangle its geometric normal),
//! averaged within smoothing groups, or averaged across edges sharper than a crease angle.
//!
//! The renderer interpolates per-vertex normals, so a vertex where faces of different
//! normals meet is split into one vertex per normal: every corner gets its normal, and
//! corners of the same vertex with bit-identical normals share one vertex again. Positions
//! are not changed, so the surface (and every ray hit) is the same as before; only the
//! number of vertices grows. Faces meet where their corners have bit-identical positions
//! (`-0` and `0` are one point), whatever the vertex indices: a seam of uv or colour does not
//! stop smoothing.

use super::Mesh;
use glam::Vec3;
use std::collections::HashMap;

/// Most face pairs a crease angle may compare (each vertex compares every pair of the faces
/// around it): 2^28, so a hostile fan of a million faces at one point is refused in a moment
/// rather than compared for hours.
pub const MAX_CREASE_PAIRS: u64 = 1 << 28;

/// A position as a hash key: its bits, with `-0` turned into `0`.
fn point_key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

impl Mesh {
    /// The unit geometric normal of triangle `t` (`+y` for a zero-area one, which no ray hits).
    fn face_normal(&self, t: usize) -> Vec3 {
        self.face_cross(t).try_normalize().unwrap_or(Vec3::Y)
    }

    /// Flat shading: every triangle's shading normal is its geometric normal.
    pub fn flat_shaded(&self) -> Mesh {
        self.with_corner_normals(|t, _| self.face_normal(t))
    }

    /// Smoothing groups (OBJ's `s`): `groups[t]` is triangle `t`'s group; group 0 is flat,
    /// and the faces of any other group that meet at a point share that point's
    /// area-weighted normal (faces of other groups do not count).
    pub fn group_shaded(&self, groups: &[u32]) -> Mesh {
        debug_assert_eq!(groups.len(), self.triangles.len());
        let mut sums: HashMap<([u32; 3], u32), Vec3> = HashMap::new();
        for (t, tri) in self.triangles.iter().enumerate() {
            if groups[t] != 0 {
                let c = self.face_cross(t);
                for &v in tri {
                    *sums
                        .entry((point_key(self.positions[v as usize]), groups[t]))
                        .or_default() += c;
                }
            }
        }
        self.with_corner_normals(|t, v| {
            if groups[t] == 0 {
                return self.face_normal(t);
            }
            sums[&(point_key(self.positions[v as usize]), groups[t])]
                .try_normalize()
                .unwrap_or_else(|| self.face_normal(t))
        })
    }

    /// Smooth shading from the geometry: every face at a point shares the point's
    /// area-weighted normal (whatever normals the mesh had).
    pub fn smooth_shaded(&self) -> Mesh {
        self.group_shaded(&vec![1; self.triangles.len()])
    }

    /// Smooth across edges flatter than `degrees`: a corner's normal is the area-weighted sum
    /// of the faces at its point whose normals are within `degrees` of its own face's (180:
    /// every face at the point; 0: flat). Refused (with the count) when the faces at the
    /// points would need more than [`MAX_CREASE_PAIRS`] comparisons.
    pub fn crease_shaded(&self, degrees: f32) -> Result<Mesh, String> {
        let mut around: HashMap<[u32; 3], Vec<u32>> = HashMap::new();
        for (t, tri) in self.triangles.iter().enumerate() {
            for &v in tri {
                around
                    .entry(point_key(self.positions[v as usize]))
                    .or_default()
                    .push(t as u32);
            }
        }
        let pairs: u64 = around.values().map(|f| (f.len() as u64).pow(2)).sum();
        if pairs > MAX_CREASE_PAIRS {
            return Err(format!(
                "the faces meeting at the mesh's points need {pairs} comparisons, over the cap of {MAX_CREASE_PAIRS} (use smooth = true or false)"
            ));
        }
        // Compared as cosines, with a margin of 1e-6: an edge at exactly the angle is a
        // crease (cos 90 degrees is -4e-8 in f32, so a cube's faces would otherwise merge at
        // `crease = 90`).
        let cos = degrees.to_radians().cos() + 1e-6;
        let units: Vec<Vec3> = (0..self.triangles.len())
            .map(|t| self.face_normal(t))
            .collect();
        Ok(self.with_corner_normals(|t, v| {
            let own = units[t];
            around[&point_key(self.positions[v as usize])]
                .iter()
                .filter(|&&u| u as usize == t || own.dot(units[u as usize]) > cos)
                .map(|&u| self.face_cross(u as usize))
                .sum::<Vec3>()
                .try_normalize()
                .unwrap_or(own)
        }))
    }

    /// The mesh with corner `(t, v)` (triangle `t`, vertex `v`) given `normal(t, v)`: one
    /// vertex per distinct (vertex, normal bits), attributes copied, triangles in order.
    fn with_corner_normals(&self, normal: impl Fn(usize, u32) -> Vec3) -> Mesh {
        let mut index: HashMap<(u32, [u32; 3]), u32> = HashMap::new();
        let mut out = Mesh {
            triangles: Vec::with_capacity(self.triangles.len()),
            ..Default::default()
        };
        let mut normals = Vec::new();
        let mut uvs = self.uvs.as_ref().map(|_| Vec::new());
        let mut colors = self.colors.as_ref().map(|_| Vec::new());
        for (t, tri) in self.triangles.iter().enumerate() {
            let corners = tri.map(|v| {
                let n = normal(t, v);
                let next = out.positions.len() as u32;
                *index
                    .entry((v, n.to_array().map(f32::to_bits)))
                    .or_insert_with(|| {
                        let i = v as usize;
                        out.positions.push(self.positions[i]);
                        normals.push(n);
                        if let (Some(dst), Some(src)) = (&mut uvs, &self.uvs) {
                            dst.push(src[i]);
                        }
                        if let (Some(dst), Some(src)) = (&mut colors, &self.colors) {
                            dst.push(src[i]);
                        }
                        next
                    })
            });
            out.triangles.push(corners);
        }
        out.normals = Some(normals);
        out.uvs = uvs;
        out.colors = colors;
        out
    }
}

/// Every corner's normal is its triangle's geometric normal (the tests' check of flat
/// shading, here and in the loaders').
#[cfg(test)]
pub(crate) fn is_flat(m: &crate::mesh::Mesh) -> bool {
    let n = m.normals.as_ref().unwrap();
    (0..m.triangles.len()).all(|t| {
        let g = m.face_cross(t).normalize();
        m.triangles[t]
            .iter()
            .all(|&v| n[v as usize].distance(g) < 1e-6)
    })
}

#[cfg(test)]
mod tests {
    use crate::mesh::Mesh;
    use crate::scene::shapes;
    use glam::Vec3;

    use super::is_flat;

    #[test]
    fn flat_cube_has_face_normals_and_shares_vertices_within_a_face() {
        let mut cube = shapes::cube(Vec3::ZERO, Vec3::ONE);
        cube.ensure_normals();
        let flat = cube.flat_shaded();
        assert!(is_flat(&flat));
        assert_eq!(flat.triangles.len(), 12);
        // 6 faces of 4 corners (the two triangles of a face share their diagonal's normal).
        assert!(flat.positions.len() <= 24, "{}", flat.positions.len());
        // Same positions triangle by triangle: the surface did not move.
        for (a, b) in cube.triangles.iter().zip(&flat.triangles) {
            for k in 0..3 {
                assert_eq!(cube.positions[a[k] as usize], flat.positions[b[k] as usize]);
            }
        }
    }

    #[test]
    fn groups_smooth_within_a_group_only() {
        let s = shapes::sphere(Vec3::ZERO, 1.0, 8);
        let n = s.triangles.len();
        // One group: a smooth sphere, with no split at the uv seam.
        let smooth = s.group_shaded(&vec![1; n]);
        assert!(!is_flat(&smooth));
        let mut weld = std::collections::HashMap::new();
        let ns = smooth.normals.as_ref().unwrap();
        for (p, nn) in smooth.positions.iter().zip(ns) {
            let prev = weld.insert(p.to_array().map(|x| (x + 0.0).to_bits()), *nn);
            assert!(prev.is_none_or(|q| q == *nn), "one normal per point");
        }
        // Group 0 is flat.
        assert!(is_flat(&s.group_shaded(&vec![0; n])));
        // Each face its own group: flat too.
        let own: Vec<u32> = (1..=n as u32).collect();
        assert!(is_flat(&s.group_shaded(&own)));
    }

    #[test]
    fn crease_angle_splits_sharp_edges_only() {
        let mut cube = shapes::cube(Vec3::ZERO, Vec3::ONE);
        cube.ensure_normals();
        assert!(is_flat(&cube.crease_shaded(60.0).unwrap()));
        assert!(is_flat(&cube.crease_shaded(90.0).unwrap()));
        assert!(!is_flat(&cube.crease_shaded(100.0).unwrap()));
        let s = shapes::sphere(Vec3::ZERO, 1.0, 16);
        let smooth = s.crease_shaded(30.0).unwrap();
        assert!(!is_flat(&smooth));
        assert!(is_flat(&s.crease_shaded(0.0).unwrap()));
        // A fan of many faces at one point is refused before it is compared.
        let k = 20_000u32;
        let fan = Mesh {
            positions: (0..=k + 1)
                .map(|i| {
                    let a = i as f32 * 0.0003;
                    if i == 0 {
                        Vec3::ZERO
                    } else {
                        Vec3::new(a.cos(), a.sin(), 0.0)
                    }
                })
                .collect(),
            triangles: (1..=k).map(|i| [0, i, i + 1]).collect(),
            ..Default::default()
        };
        assert!(fan.crease_shaded(30.0).unwrap_err().contains("cap"));
    }
}
