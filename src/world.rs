//! What shading and rendering share: the world (scene + geometry + BVH), stages and terms.
//! It sits below both `shade` and `render`, so the imports run one way.

use crate::accel::{Accel, BuildQuality};
use crate::scene::{Geometry, Scene};
use glam::Vec3;

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

/// A scene ready to render: flattened geometry, its BVH, the offset `eps`.
pub struct World {
    /// The scene.
    pub scene: Scene,
    /// Its triangles flattened, with shading attributes.
    pub geometry: Geometry,
    /// The BVH over them.
    pub accel: Accel,
    /// `1e-5 L`, `L` the scene bounding-box diagonal (secondary-ray origin offset).
    pub eps: f32,
}

impl World {
    /// Flatten `scene` and build its BVH.
    pub fn new(scene: Scene) -> World {
        crate::cpu::warn_if_slow_build();
        let geometry = scene.geometry();
        let tris: Vec<[Vec3; 3]> = (0..geometry.triangles.len() as u32)
            .map(|t| geometry.triangle(t))
            .collect();
        let accel = Accel::build(&tris, BuildQuality::default());
        let eps = 1e-5 * geometry.diagonal();
        World {
            scene,
            geometry,
            accel,
            eps,
        }
    }
}
