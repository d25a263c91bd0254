//! What shading and rendering share: the world (scene + geometry + BVH), stages and terms.
//! It sits below both `shade` and `render`, so the imports run one way.

use crate::accel::{Accel, BuildQuality};
use crate::instance::{Instance, Instances};
use crate::ray::{Hit, Ray};
use crate::scene::{Geometry, Scene};
use glam::{Affine3A, Vec3};

/// The assignment's stages (SCENES.md §5); `None` renders the scene in full.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Stage {
    /// White where a primary ray hits, background elsewhere; depth 0.
    Intersection,
    /// Ambient + diffuse, no shadows; depth 0.
    Diffuse,
    /// Ambient + diffuse + specular, no shadows; depth 0.
    Specular,
    /// Ambient + diffuse + specular with shadows; depth 0.
    Shadow,
    /// The full equation at the scene's depth.
    Reflection,
}

impl Stage {
    /// Every stage, in the assignment's order.
    pub const ALL: [Stage; 5] = [
        Stage::Intersection,
        Stage::Diffuse,
        Stage::Specular,
        Stage::Shadow,
        Stage::Reflection,
    ];

    /// The stage's name on the command line.
    pub fn name(self) -> &'static str {
        [
            "intersection",
            "diffuse",
            "specular",
            "shadow",
            "reflection",
        ][self as usize]
    }

    /// The stage of a command-line name.
    pub fn from_name(s: &str) -> Option<Stage> {
        Stage::ALL.into_iter().find(|st| st.name() == s)
    }
}

/// Which terms of the equation are on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Terms {
    /// White wherever a primary ray hits (the `intersection` stage).
    pub white: bool,
    /// The Phong term is on.
    pub specular: bool,
    /// Shadow rays are traced.
    pub shadows: bool,
}

impl Terms {
    /// The terms of a stage (`None`: all).
    pub fn of(stage: Option<Stage>) -> Terms {
        use Stage::*;
        Terms {
            white: stage == Some(Intersection),
            specular: !matches!(stage, Some(Intersection | Diffuse)),
            shadows: !matches!(stage, Some(Intersection | Diffuse | Specular)),
        }
    }
}

/// A scene ready to render: flattened geometry, its BVH, the offset `eps`; or, for a scene
/// with placements, its meshes and their two-level BVH.
pub struct World {
    /// The scene.
    pub scene: Scene,
    /// Its triangles flattened, with shading attributes (empty when `instanced`).
    pub geometry: Geometry,
    /// The BVH over them (empty when `instanced`).
    pub accel: Accel,
    /// `1e-5 L`, `L` the scene bounding-box diagonal (secondary-ray origin offset).
    pub eps: f32,
    /// The scene's meshes and placements, when it has placements ([`Scene::instances`]).
    pub instanced: Option<Instanced>,
}

/// What a scene with placements renders from: each mesh once, in object space.
pub struct Instanced {
    /// The two-level BVH. Mesh 0 holds the objects drawn as they are (if any), placed once
    /// with the identity; then one mesh per placed object.
    pub tracer: Instances,
    /// Per mesh, its triangles with shading attributes, in object space.
    pub geometries: Vec<Geometry>,
    /// Per instance, the material that replaces its triangles' own.
    pub materials: Vec<Option<u32>>,
    /// Wall time of building the meshes' trees and the top level.
    pub build_time: std::time::Duration,
}

/// A hit's placement as shading reads it: the instance and the material replacing its
/// triangles' own.
pub type Placed<'a> = (&'a Instance, Option<u32>);

/// The instance lane of a hit that is not through instances.
pub const NOT_INSTANCED: u32 = u32::MAX;

impl World {
    /// Flatten `scene` and build its BVH; a scene with placements gets its meshes once each
    /// and a two-level BVH instead ([`Instanced`]).
    pub fn new(scene: Scene) -> World {
        crate::cpu::warn_if_slow_build();
        if !scene.instances.is_empty() {
            return World::instanced(scene);
        }
        let geometry = scene.geometry();
        let accel = Accel::build(&corners(&geometry), BuildQuality::default());
        let eps = 1e-5 * geometry.diagonal();
        World {
            scene,
            geometry,
            accel,
            eps,
            instanced: None,
        }
    }

    fn instanced(scene: Scene) -> World {
        let start = std::time::Instant::now();
        let placed = scene.placed_objects();
        let own: Vec<usize> = (0..scene.objects.len()).filter(|&i| !placed[i]).collect();
        // mesh 0: the objects drawn as they are; then the placed objects, one mesh each
        let mut mesh_of = vec![u32::MAX; scene.objects.len()];
        let mut geometries = Vec::new();
        let mut placements = Vec::new();
        if !own.is_empty() {
            geometries.push(scene.geometry_of(own));
            placements.push((0, Affine3A::IDENTITY));
        }
        for (i, _) in placed.iter().enumerate().filter(|(_, p)| **p) {
            mesh_of[i] = geometries.len() as u32;
            geometries.push(scene.geometry_of([i]));
        }
        let mut materials = vec![None; placements.len()];
        for p in &scene.instances {
            placements.push((mesh_of[p.object], p.to_world));
            materials.push(p.material.map(|m| m as u32));
        }
        let accels = geometries
            .iter()
            .map(|g| Accel::build(&corners(g), BuildQuality::default()))
            .collect();
        let tracer = Instances::new(accels, &placements);
        let eps = 1e-5 * tracer.bounds().map_or(0.0, |(lo, hi)| (hi - lo).length());
        World {
            scene,
            geometry: Geometry::default(),
            accel: Accel::default(),
            eps,
            instanced: Some(Instanced {
                tracer,
                geometries,
                materials,
                build_time: start.elapsed(),
            }),
        }
    }

    /// Wall time of the BVH build (both levels when instanced).
    pub fn build_time(&self) -> std::time::Duration {
        self.instanced
            .as_ref()
            .map_or(self.accel.build_time, |i| i.build_time)
    }

    /// Triangles traced: as the flattened scene would number them (every placement's).
    pub fn triangles(&self) -> u64 {
        self.instanced
            .as_ref()
            .map_or(self.accel.tris.len() as u64, |i| i.tracer.triangles)
    }

    /// Closest hit of one ray (`intersect1`, through instances when the scene has them) and
    /// the instance hit ([`NOT_INSTANCED`] without).
    pub fn intersect1(&self, ray: &Ray) -> Option<(Hit, u32)> {
        let cull = self.scene.cull_backfaces;
        match &self.instanced {
            None => crate::accel::intersect1(&self.accel, ray, cull).map(|h| (h, NOT_INSTANCED)),
            Some(i) => i
                .tracer
                .intersect_with(ray, |a, r| crate::accel::intersect1(a, r, cull))
                .map(|h| (h.hit, h.inst)),
        }
    }

    /// Whether anything blocks `ray` (`occluded1`, through instances when the scene has them).
    pub fn occluded1(&self, ray: &Ray) -> bool {
        let cull = self.scene.cull_backfaces;
        match &self.instanced {
            None => crate::accel::occluded1(&self.accel, ray, cull),
            Some(i) => i
                .tracer
                .occluded_with(ray, |a, r| crate::accel::occluded1(a, r, cull)),
        }
    }

    /// The shading data of a hit on instance `inst` ([`NOT_INSTANCED`]: the flattened
    /// geometry): the triangles it numbers, and the placement with its material.
    #[inline]
    pub fn shading(&self, inst: u32) -> (&Geometry, Option<Placed<'_>>) {
        match &self.instanced {
            Some(i) if inst != NOT_INSTANCED => {
                let k = inst as usize;
                let placement = &i.tracer.instances[k];
                (
                    &i.geometries[placement.mesh as usize],
                    Some((placement, i.materials[k])),
                )
            }
            _ => (&self.geometry, None),
        }
    }

    /// The flattened scene's index of triangle `tri` of instance `inst` (the id AOV), or
    /// `u32::MAX - 1` past what u32 holds.
    pub fn global_id(&self, tri: u32, inst: u32) -> u32 {
        match &self.instanced {
            Some(i) if inst != NOT_INSTANCED => {
                let g = i.tracer.instances[inst as usize].base + tri as u64;
                g.min(u32::MAX as u64 - 1) as u32
            }
            _ => tri,
        }
    }
}

/// The corners of every triangle of `g`.
fn corners(g: &Geometry) -> Vec<[Vec3; 3]> {
    (0..g.triangles.len() as u32)
        .map(|t| g.triangle(t))
        .collect()
}
