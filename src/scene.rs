//! A loaded, validated scene: camera, lights, materials, objects, background, options.

use crate::camera::Camera;
use crate::mesh::Mesh;
use crate::texture::{CubeMap, Texture};
use glam::{Vec2, Vec3};
use std::sync::Arc;

mod emitters;
pub use emitters::{
    MAX_PLACED_LAMP_TRIANGLES, emitter_lights, emitter_lights_placed, placed_lamp_triangles,
};

/// A point light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    /// Where the light is.
    pub position: Vec3,
    /// RGB intensity `Ip`.
    pub intensity: Vec3,
}

/// Where a surface's colour `Od` comes from.
#[derive(Clone, Debug, PartialEq)]
pub enum Albedo {
    /// A constant colour (linear RGB).
    Color(Vec3),
    /// The interpolated per-vertex `rgb` of the mesh.
    VertexColor,
    /// The bilinear texture colour at the interpolated `uv`.
    Texture(Arc<Texture>),
}

/// Whitted material: the colour source `Od`, RGB coefficients `ka kd ks kt`, the Phong
/// exponent `n`, the index of refraction and an emitted colour `ke`.
///
/// A scalar coefficient of a scene file is the same value in all three channels, which
/// computes exactly what the scalar model computed (`x * k` per channel).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// The name meshes refer to it by.
    pub name: String,
    /// Where `Od` comes from.
    pub albedo: Albedo,
    /// Ambient coefficient `ka`.
    pub ka: Vec3,
    /// Diffuse coefficient `kd`.
    pub kd: Vec3,
    /// Specular and reflection coefficient `ks` (per channel).
    pub ks: Vec3,
    /// Phong exponent `n`.
    pub n: f32,
    /// Transmission coefficient `kt`.
    pub kt: Vec3,
    /// Index of refraction.
    pub ior: f32,
    /// Weight of the reflection ray (`ks` unless the scene or an MTL file separates them).
    pub kr: Vec3,
    /// Emitted colour, added to the local term (`0` for everything but lamps).
    pub ke: Vec3,
    /// Whether the emission also lights the scene through point lights.
    pub lamp: bool,
}

impl Material {
    /// Whether reflection rays are traced from this material (some channel of `kr` > 0).
    #[inline]
    pub fn reflects(&self) -> bool {
        self.kr.max_element() > 0.0
    }
    /// Whether refraction rays are traced from this material (some channel of `kt` > 0).
    #[inline]
    pub fn refracts(&self) -> bool {
        self.kt.max_element() > 0.0
    }
    /// Whether the material emits light (some channel of `ke` > 0).
    #[inline]
    pub fn emits(&self) -> bool {
        self.ke.max_element() > 0.0
    }
}

/// What a ray that hits nothing sees.
#[derive(Clone, Debug, PartialEq)]
pub enum Background {
    /// A constant colour.
    Color(Vec3),
    /// The cube map's colour in the ray's direction.
    CubeMap(Arc<CubeMap>),
}

impl Background {
    /// The colour seen along `dir`.
    #[inline]
    pub fn sample(&self, dir: Vec3) -> Vec3 {
        match self {
            Background::Color(c) => *c,
            Background::CubeMap(m) => m.sample(dir),
        }
    }
}

/// A mesh placed in the scene with its material.
#[derive(Clone, Debug, PartialEq)]
pub struct Object {
    /// Its name in messages.
    pub name: String,
    /// Its triangles.
    pub mesh: Mesh,
    /// The scene material of every triangle, unless `face_materials` is given.
    pub material: usize,
    /// A scene material per triangle (meshes that bring their own materials, e.g. OBJ + MTL).
    pub face_materials: Option<Vec<u32>>,
}

/// Camera placement as written in a scene (the image size is separate so it can be overridden).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// The eye point.
    pub eye: Vec3,
    /// The point looked at.
    pub look_at: Vec3,
    /// The up direction.
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov: f32,
}

/// A validated scene, everything loaded: what [`build_scene`](crate::io::scene::build_scene)
/// makes of a scene file, ready for [`World::new`](crate::render::World::new) (or
/// [`Scene::render`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The camera placement.
    pub view: View,
    /// Ambient light `Ia`.
    pub ambient: Vec3,
    /// What rays that miss see.
    pub background: Background,
    /// Point lights.
    pub lights: Vec<Light>,
    /// Materials, referred to by index.
    pub materials: Vec<Material>,
    /// The meshes with their materials.
    pub objects: Vec<Object>,
    /// Skip back faces, for every ray.
    pub cull_backfaces: bool,
    /// Reflection / refraction bounces.
    pub depth: u32,
    /// Placements of objects (`[[instance]]`, glTF meshes used more than once). An object
    /// that any placement names is drawn only where placements put it; the others are drawn
    /// as they are. Empty: every object as it is, flattened (no top level).
    pub instances: Vec<Placement>,
}

/// One placement of an object: where (object to world) and, optionally, in which material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    /// Index of the object placed.
    pub object: usize,
    /// Object space to world space (invertible and finite: the readers check).
    pub to_world: glam::Affine3A,
    /// A scene material for every triangle of this placement, instead of the object's.
    pub material: Option<usize>,
}

impl Scene {
    /// The camera for this view and image size.
    pub fn camera(&self) -> Camera {
        let v = &self.view;
        Camera::new(v.eye, v.look_at, v.up, v.vfov, self.width, self.height)
    }

    /// Triangles the scene draws: of the objects drawn as they are, and of every placement.
    pub fn triangle_count(&self) -> usize {
        let placed = self.placed_objects();
        let own: usize = (self.objects.iter().enumerate())
            .filter(|(i, _)| !placed[*i])
            .map(|(_, o)| o.mesh.triangles.len())
            .sum();
        own + (self.instances.iter())
            .map(|p| self.objects[p.object].mesh.triangles.len())
            .sum::<usize>()
    }

    /// Triangles the scene stores: of every object once, however often it is placed (what
    /// memory grows with).
    pub fn stored_triangle_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.triangles.len()).sum()
    }

    /// Per object, whether a placement names it (then it is drawn only where placed).
    pub fn placed_objects(&self) -> Vec<bool> {
        let mut placed = vec![false; self.objects.len()];
        for p in &self.instances {
            placed[p.object] = true;
        }
        placed
    }

    /// The same scene without placements: the objects drawn as they are, then a copy of
    /// the placed object per placement (in placement order), carried into the world by
    /// [`Mesh::transformed`] and in the placement's material when it has one. Lights are
    /// kept as they are. What the instanced scene is tested against.
    pub fn flattened(&self) -> Scene {
        let placed = self.placed_objects();
        let mut objects: Vec<Object> = (self.objects.iter().zip(&placed))
            .filter(|(_, p)| !**p)
            .map(|(o, _)| o.clone())
            .collect();
        for p in &self.instances {
            let o = &self.objects[p.object];
            let mut copy = Object {
                name: o.name.clone(),
                mesh: o.mesh.transformed(&p.to_world),
                material: o.material,
                face_materials: o.face_materials.clone(),
            };
            if let Some(m) = p.material {
                copy.material = m;
                copy.face_materials = None;
            }
            objects.push(copy);
        }
        Scene {
            objects,
            instances: Vec::new(),
            ..self.clone()
        }
    }

    /// Flatten every object into one triangle list with per-vertex shading attributes
    /// (placements aside: see [`Scene::geometry_of`]).
    pub fn geometry(&self) -> Geometry {
        self.geometry_of(0..self.objects.len())
    }

    /// Flatten the objects `which` (indices, in this order) into one triangle list, each
    /// triangle's `tri_object` the object's index in the scene.
    pub fn geometry_of(&self, which: impl IntoIterator<Item = usize>) -> Geometry {
        let mut g = Geometry::default();
        for oi in which {
            let o = &self.objects[oi];
            let base = g.positions.len() as u32;
            let m = &o.mesh;
            g.positions.extend_from_slice(&m.positions);
            let normals = m
                .normals
                .clone()
                .unwrap_or_else(|| m.area_weighted_normals());
            g.normals.extend(normals);
            match &m.uvs {
                Some(uv) => g.uvs.extend_from_slice(uv),
                None => g
                    .uvs
                    .extend(std::iter::repeat_n(Vec2::ZERO, m.positions.len())),
            }
            match &m.colors {
                Some(c) => g.colors.extend_from_slice(c),
                None => g
                    .colors
                    .extend(std::iter::repeat_n(Vec3::ONE, m.positions.len())),
            }
            g.triangles
                .extend(m.triangles.iter().map(|t| t.map(|i| i + base)));
            g.tri_object
                .extend(std::iter::repeat_n(oi as u32, m.triangles.len()));
            match &o.face_materials {
                Some(f) => g.tri_material.extend_from_slice(f),
                None => g
                    .tri_material
                    .extend(std::iter::repeat_n(o.material as u32, m.triangles.len())),
            }
        }
        g.face_normals = (0..g.triangles.len() as u32)
            .map(|t| {
                let [p0, p1, p2] = g.triangle(t);
                (p1 - p0).cross(p2 - p0).normalize_or_zero()
            })
            .collect();
        g
    }
}

/// All triangles of a scene in one list (the order of objects, then of each mesh's faces),
/// with per-vertex normals, uvs and colours for shading.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    /// Vertex positions of all objects.
    pub positions: Vec<Vec3>,
    /// Unit shading normals per vertex.
    pub normals: Vec<Vec3>,
    /// Texture coordinates per vertex ((0, 0) where a mesh has none).
    pub uvs: Vec<Vec2>,
    /// Colours per vertex (white where a mesh has none).
    pub colors: Vec<Vec3>,
    /// Vertex indices per triangle.
    pub triangles: Vec<[u32; 3]>,
    /// The object each triangle belongs to.
    pub tri_object: Vec<u32>,
    /// Scene material index per triangle.
    pub tri_material: Vec<u32>,
    /// Unit geometric normal `normalize(cross(v1 - v0, v2 - v0))` per triangle (0 if degenerate).
    pub face_normals: Vec<Vec3>,
}

impl Geometry {
    /// The corners of triangle `t`.
    pub fn triangle(&self, t: u32) -> [Vec3; 3] {
        self.triangles[t as usize].map(|i| self.positions[i as usize])
    }

    /// Length of the bounding-box diagonal (`L` of the secondary-ray offset rule).
    pub fn diagonal(&self) -> f32 {
        let Some(&first) = self.positions.first() else {
            return 0.0;
        };
        let (lo, hi) = self
            .positions
            .iter()
            .fold((first, first), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        (hi - lo).length()
    }
}

/// Meshes generated in code, for the demo scene and for `shape = ...` in scene files.
pub mod shapes {
    use super::*;

    /// Triangles of [`sphere`] with `segments`, known before it is made (for the scene caps).
    pub fn sphere_triangle_count(segments: u32) -> u64 {
        let (nu, nv) = (segments.max(3) as u64 * 2, segments.max(2) as u64);
        // Every band has 2 triangles per segment, except the two polar bands (1 each).
        2 * nu * (nv - 1)
    }

    /// A UV sphere with outward normals and `(u, v)` = (longitude, latitude) in [0, 1].
    pub fn sphere(center: Vec3, radius: f32, segments: u32) -> Mesh {
        let (nu, nv) = (segments.max(3) * 2, segments.max(2));
        let mut m = Mesh::default();
        let (mut pos, mut nor, mut uv) = (Vec::new(), Vec::new(), Vec::new());
        for j in 0..=nv {
            let theta = std::f32::consts::PI * j as f32 / nv as f32;
            for i in 0..=nu {
                let phi = std::f32::consts::TAU * i as f32 / nu as f32;
                let n = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    -theta.sin() * phi.sin(),
                );
                pos.push(center + radius * n);
                nor.push(n);
                uv.push(Vec2::new(i as f32 / nu as f32, 1.0 - j as f32 / nv as f32));
            }
        }
        let idx = |i: u32, j: u32| j * (nu + 1) + i;
        for j in 0..nv {
            for i in 0..nu {
                let (a, b, c, d) = (idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1));
                if j != 0 {
                    m.triangles.push([a, d, b]);
                }
                if j != nv - 1 {
                    m.triangles.push([b, d, c]);
                }
            }
        }
        m.positions = pos;
        m.normals = Some(nor);
        m.uvs = Some(uv);
        m
    }

    /// An axis-aligned box with flat faces (each face has its own vertices and uv square).
    pub fn cube(center: Vec3, half: Vec3) -> Mesh {
        let mut m = Mesh {
            normals: Some(Vec::new()),
            uvs: Some(Vec::new()),
            ..Default::default()
        };
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let n = Vec3::AXES[axis] * sign;
                let s = Vec3::AXES[(axis + 1) % 3] * sign;
                let t = Vec3::AXES[(axis + 2) % 3];
                let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
                let base = m.positions.len() as u32;
                for (cs, ct) in corners {
                    m.positions.push(center + (n + cs * s + ct * t) * half);
                    m.normals.as_mut().unwrap().push(n);
                    m.uvs
                        .as_mut()
                        .unwrap()
                        .push(Vec2::new((cs + 1.0) * 0.5, (ct + 1.0) * 0.5));
                }
                m.triangles.push([base, base + 1, base + 2]);
                m.triangles.push([base, base + 2, base + 3]);
            }
        }
        m
    }

    /// A rectangle through `center` spanned by `s` and `t` (half extents), facing `s x t`,
    /// with uv (0,0) at `center - s - t` and (1,1) at `center + s + t`.
    pub fn quad(center: Vec3, s: Vec3, t: Vec3) -> Mesh {
        let n = s.cross(t).normalize();
        Mesh {
            positions: vec![
                center - s - t,
                center + s - t,
                center + s + t,
                center - s + t,
            ],
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            normals: Some(vec![n; 4]),
            uvs: Some(vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 1.0),
            ]),
            colors: None,
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn shapes_are_closed_and_outward() {
            for seg in [0, 1, 2, 3, 8, 48] {
                let n = sphere(Vec3::ZERO, 1.0, seg).triangles.len() as u64;
                assert_eq!(n, sphere_triangle_count(seg), "{seg} segments");
            }
            let s = sphere(Vec3::ZERO, 2.0, 8);
            // (The uv seam and the poles duplicate vertices, so open_edges() is not 0.)
            assert_eq!(s.degenerate_count(), 0);
            for t in 0..s.triangles.len() {
                let c = s.triangles[t]
                    .iter()
                    .map(|&i| s.positions[i as usize])
                    .sum::<Vec3>();
                assert!(
                    s.face_cross(t).dot(c) > 0.0,
                    "sphere face {t} faces inwards"
                );
            }
            let c = cube(Vec3::ONE, Vec3::splat(0.5));
            for t in 0..c.triangles.len() {
                let centroid = c.triangles[t]
                    .iter()
                    .map(|&i| c.positions[i as usize])
                    .sum::<Vec3>()
                    / 3.0;
                assert!(
                    c.face_cross(t).dot(centroid - Vec3::ONE) > 0.0,
                    "cube face {t}"
                );
            }
            let q = quad(Vec3::ZERO, Vec3::X, Vec3::NEG_Z);
            assert!(q.face_cross(0).normalize().abs_diff_eq(Vec3::Y, 1e-6));
        }
    }
}
