//! The built-in scenes: the five canonical scenes of SCENES.md §5 and the file-free demo.

use crate::io::scene::{
    BackgroundDesc, CameraDesc, CheckerDesc, ImageDesc, LightDesc, MaterialDesc, MeshDesc,
    RenderDesc, SceneFile,
};

/// Names accepted by `whitted render NAME` and `whitted scene NAME`.
pub const NAMES: [&str; 6] = [
    "phong",
    "vertex_color",
    "texture",
    "cubemap",
    "refraction",
    "demo",
];

/// A built-in scene by name, as an editable scene file.
pub fn builtin(name: &str) -> Option<SceneFile> {
    Some(match name {
        "phong" => kitten_scene(kitten_material("kitten.m", Od::Color([0.95, 0.6, 0.3]))),
        "vertex_color" => kitten_scene(kitten_material("kitten_rgb.m", Od::Vertex)),
        "texture" => kitten_scene(kitten_material(
            "kitten.m",
            Od::Texture("textures/checker.png"),
        )),
        "cubemap" => cubemap_scene(
            material(
                "kitten",
                Od::Color([0.9, 0.9, 0.9]),
                [0.0, 0.15, 0.85, 200.0, 0.0, 1.5],
            ),
            3,
            true,
        ),
        "refraction" => cubemap_scene(
            material(
                "kitten",
                Od::Color([1.0, 1.0, 1.0]),
                [0.0, 0.0, 0.1, 200.0, 0.9, 1.5],
            ),
            6,
            false,
        ),
        "demo" => demo(),
        _ => return None,
    })
}

enum Od {
    Color([f32; 3]),
    Vertex,
    Texture(&'static str),
}

fn material(name: &str, od: Od, [ka, kd, ks, n, kt, ior]: [f32; 6]) -> MaterialDesc {
    let mut m = MaterialDesc {
        name: name.into(),
        color: None,
        vertex_color: false,
        texture: None,
        checker: None,
        wrap: None,
        ka: ka.into(),
        kd: kd.into(),
        ks: ks.into(),
        n,
        kt: kt.into(),
        ior,
        kr: None,
        ke: Default::default(),
        lamp: true,
    };
    match od {
        Od::Color(c) => m.color = Some(c),
        Od::Vertex => m.vertex_color = true,
        Od::Texture(t) => m.texture = Some(t.into()),
    }
    m
}

fn kitten_material(file: &str, od: Od) -> (String, MaterialDesc) {
    (
        format!("meshes/{file}"),
        material("kitten", od, [0.3, 0.7, 0.25, 40.0, 0.0, 1.5]),
    )
}

fn base(depth: u32, cull: bool, background: BackgroundDesc) -> SceneFile {
    SceneFile {
        image: ImageDesc {
            width: 1024,
            height: 768,
        },
        camera: CameraDesc {
            eye: [1.6, 0.9, 4.4],
            look_at: [0.0, -0.15, 0.0],
            up: [0.0, 1.0, 0.0],
            vfov: 36.0,
        },
        render: RenderDesc {
            depth,
            cull_backfaces: cull,
            ambient: [0.15, 0.15, 0.18],
        },
        background,
        lights: vec![
            LightDesc {
                position: [5.0, 6.0, 3.0],
                intensity: [0.9, 0.9, 0.85],
            },
            LightDesc {
                position: [-5.0, 5.0, 3.0],
                intensity: [0.35, 0.35, 0.45],
            },
        ],
        materials: vec![],
        meshes: vec![],
        instances: Vec::new(),
        lines: Default::default(),
    }
}

fn kitten_mesh(file: String) -> MeshDesc {
    MeshDesc {
        name: Some("kitten".into()),
        material: "kitten".into(),
        file: Some(file),
        ..Default::default()
    }
}

/// The floor of SCENES.md §5: `x, z in [-6, 6]` at `y = -1.001`, two triangles facing +y.
fn floor() -> (MeshDesc, MaterialDesc) {
    let y = -1.001;
    let mesh = MeshDesc {
        name: Some("floor".into()),
        material: "floor".into(),
        vertices: Some(vec![
            [-6.0, y, -6.0],
            [6.0, y, -6.0],
            [6.0, y, 6.0],
            [-6.0, y, 6.0],
        ]),
        faces: Some(vec![[0, 3, 2], [0, 2, 1]]),
        ..Default::default()
    };
    (
        mesh,
        material(
            "floor",
            Od::Color([0.75, 0.75, 0.75]),
            [0.2, 0.6, 0.35, 60.0, 0.0, 1.5],
        ),
    )
}

fn kitten_scene((file, kitten): (String, MaterialDesc)) -> SceneFile {
    let mut s = base(
        1,
        true,
        BackgroundDesc {
            color: Some([0.1, 0.12, 0.16]),
            cubemap: None,
        },
    );
    let (floor_mesh, floor_mat) = floor();
    s.materials = vec![kitten, floor_mat];
    s.meshes = vec![kitten_mesh(file), floor_mesh];
    s
}

fn cubemap_scene(kitten: MaterialDesc, depth: u32, cull: bool) -> SceneFile {
    let mut s = base(
        depth,
        cull,
        BackgroundDesc {
            color: None,
            cubemap: Some("textures/cubemap".into()),
        },
    );
    s.materials = vec![kitten];
    s.meshes = vec![kitten_mesh("meshes/kitten.m".into())];
    s
}

/// The demo: a glass sphere, a mirror, a checker-textured cube and a floor, all generated in
/// code, so `whitted render` works on a fresh machine with no data files.
fn demo() -> SceneFile {
    let mut s = base(
        5,
        true,
        BackgroundDesc {
            color: Some([0.35, 0.45, 0.6]),
            cubemap: None,
        },
    );
    s.camera = CameraDesc {
        eye: [0.0, 1.6, 6.5],
        look_at: [0.0, 0.2, 0.0],
        up: [0.0, 1.0, 0.0],
        vfov: 40.0,
    };
    let mut checker = material(
        "checker",
        Od::Color([1.0; 3]),
        [0.3, 0.8, 0.2, 30.0, 0.0, 1.5],
    );
    checker.color = None;
    checker.checker = Some(CheckerDesc {
        squares: 4,
        a: [0.9, 0.15, 0.1],
        b: [0.95, 0.9, 0.8],
    });
    let mut floor = material(
        "floor",
        Od::Color([1.0; 3]),
        [0.2, 0.7, 0.1, 20.0, 0.0, 1.5],
    );
    floor.color = None;
    floor.checker = Some(CheckerDesc {
        squares: 16,
        a: [0.1, 0.1, 0.12],
        b: [0.8, 0.8, 0.75],
    });
    s.materials = vec![
        material(
            "glass",
            Od::Color([1.0; 3]),
            [0.0, 0.0, 0.15, 200.0, 0.85, 1.5],
        ),
        material(
            "mirror",
            Od::Color([0.9; 3]),
            [0.0, 0.05, 0.9, 500.0, 0.0, 1.5],
        ),
        checker,
        floor,
    ];
    let shape = |name: &str,
                 mat: &str,
                 shape: &str,
                 center: [f32; 3],
                 radius: Option<f32>,
                 size: Option<[f32; 3]>| MeshDesc {
        name: Some(name.into()),
        material: mat.into(),
        shape: Some(shape.into()),
        center: Some(center),
        radius,
        size,
        ..Default::default()
    };
    s.meshes = vec![
        shape(
            "glass ball",
            "glass",
            "sphere",
            [0.3, 0.0, 1.2],
            Some(1.0),
            None,
        ),
        shape(
            "mirror",
            "mirror",
            "cube",
            [-0.8, 0.5, -2.0],
            None,
            Some([4.0, 3.0, 0.1]),
        ),
        shape(
            "box",
            "checker",
            "cube",
            [2.1, -0.2, -0.2],
            None,
            Some([1.6, 1.6, 1.6]),
        ),
        shape(
            "floor",
            "floor",
            "quad",
            [0.0, -1.0, 0.0],
            None,
            Some([16.0, 0.0, 16.0]),
        ),
    ];
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn every_builtin_roundtrips_through_toml() {
        for name in NAMES {
            let s = builtin(name).unwrap();
            let text = s.to_toml();
            assert_eq!(
                SceneFile::parse(&text, Path::new(name)).unwrap(),
                s,
                "{name}"
            );
        }
        assert!(builtin("nope").is_none());
    }
}
