//! Building a [`Scene`] from a [`SceneFile`]: every value validated, every file it names
//! loaded. The steps run in the order of the file's tables (image, camera, render,
//! background, lights, materials, meshes); the meshes' steps are in `meshes.rs` and the
//! materials' in `materials.rs`.

use super::schema::{
    DEFAULT_BACKGROUND, MAX_CHECKER_TEXELS, MAX_DEPTH, MeshDesc, SceneFile, check_size,
};
use super::search::SearchPath;
use super::text::locate;
use crate::error::{Error, Result};
use crate::io::image::load_cubemap;
use crate::io::model::Model;
use crate::mesh::Mesh;
use crate::scene::{Albedo, Background, Light, Material, Object, Scene, View};
use crate::texture::Texture;
use glam::Vec3;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A three-number key as a vector, every component finite.
pub(super) fn finite3(v: [f32; 3], key: &str, path: &Path) -> Result<Vec3> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(Vec3::from(v))
    } else {
        Err(Error::scene(
            path,
            format!("{key}: every component must be a finite number"),
        ))
    }
}

/// A three-number key as a vector, every component finite and >= 0 (a colour, an intensity).
pub(super) fn nonneg3(v: [f32; 3], key: &str, path: &Path) -> Result<Vec3> {
    let v = finite3(v, key, path)?;
    if v.cmplt(Vec3::ZERO).any() {
        return Err(Error::scene(path, format!("{key}: must be >= 0")));
    }
    Ok(v)
}

/// A number key, finite and >= 0.
pub(super) fn nonneg(v: f32, key: &str, path: &Path) -> Result<f32> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(Error::scene(
            path,
            format!("{key}: must be a finite number >= 0, found {v}"),
        ))
    }
}

/// Validate a parsed scene and load everything it names. `path` is the scene's name in
/// messages; `search` finds its files.
/// Errors about a key name the scene file and the key's line (`scene.toml:9: camera.vfov:
/// ...`) when the scene was read from text.
pub fn build_scene(
    file: &SceneFile,
    path: &Path,
    search: &SearchPath,
) -> Result<(Scene, Vec<String>)> {
    build_scene_at(file, path, search).map_err(|e| locate(file, e))
}

/// [`build_scene`] before its errors are given their key's line.
fn build_scene_at(
    file: &SceneFile,
    path: &Path,
    search: &SearchPath,
) -> Result<(Scene, Vec<String>)> {
    let (width, height) = check_size(file.image.width, file.image.height)
        .map_err(|m| Error::scene(path, format!("image: {m}")))?;
    let view = view(file, path)?;
    let r = &file.render;
    if r.depth > MAX_DEPTH {
        return Err(Error::scene(
            path,
            format!("render.depth: {} is over the cap of {MAX_DEPTH}", r.depth),
        ));
    }
    let ambient = nonneg3(r.ambient, "render.ambient", path)?;
    let background = background(file, path, search)?;
    let mut lights = lights(file, path)?;

    let mut b = Builder {
        file,
        path,
        search,
        materials: Vec::new(),
        vertex_fill: Vec::new(),
        textures: Vec::new(),
        loaded: Vec::new(),
        warnings: Vec::new(),
        total_triangles: 0,
        subdivided_total: 0,
    };
    b.scene_materials()?;
    b.check_planned()?;
    let mut objects = Vec::with_capacity(file.meshes.len());
    let mut shared = Vec::new();
    for (i, d) in file.meshes.iter().enumerate() {
        let (object, parts) = b.object(i, d)?;
        objects.push(object);
        shared.extend(parts.into_iter().map(|(o, p)| (i, o, p)));
    }

    let instances = super::instances::placements(file, path, &objects, &b.materials)?;
    // The meshes files store once (glTF), placed where their entry is.
    let instances = super::instances::with_shared(instances, &mut objects, shared);

    // Emitting materials (`ke`, `lamp`) light the scene through point lights of their own,
    // at every placement of a placed lamp.
    let placed_lamps = crate::scene::placed_lamp_triangles(&objects, &instances, &b.materials);
    if placed_lamps > crate::scene::MAX_PLACED_LAMP_TRIANGLES {
        b.warnings.push(format!(
            "the placed meshes draw {placed_lamps} emitting triangles, over the {} that are made lights: placed lamps show `ke` but light nothing",
            crate::scene::MAX_PLACED_LAMP_TRIANGLES
        ));
    }
    lights.extend(crate::scene::emitter_lights_placed(
        &objects,
        &instances,
        &b.materials,
    ));

    let scene = Scene {
        width,
        height,
        view,
        ambient,
        background,
        lights,
        materials: b.materials,
        objects,
        cull_backfaces: r.cull_backfaces,
        depth: r.depth,
        instances,
    };
    Ok((scene, b.warnings))
}

/// `[camera]`, validated: finite points, a field of view in (0, 180) degrees, a view
/// direction of finite non-zero length and an `up` not parallel to it.
fn view(file: &SceneFile, path: &Path) -> Result<View> {
    let c = &file.camera;
    let eye = finite3(c.eye, "camera.eye", path)?;
    let look_at = finite3(c.look_at, "camera.look_at", path)?;
    let up = finite3(c.up, "camera.up", path)?;
    if !(c.vfov > 0.0 && c.vfov < 180.0) {
        return Err(Error::scene(
            path,
            format!("camera.vfov: must be in (0, 180) degrees, found {}", c.vfov),
        ));
    }
    let forward = look_at - eye;
    if forward.length_squared() == 0.0 {
        return Err(Error::scene(
            path,
            "camera.look_at: must differ from camera.eye",
        ));
    }
    // The camera normalises `look_at - eye`: its length (squared) must stay finite.
    if !forward.length_squared().is_finite() {
        return Err(Error::scene(
            path,
            "camera.look_at: too far from camera.eye (the distance overflows f32)",
        ));
    }
    if !(up.length_squared() > 0.0 && up.length_squared().is_finite()) {
        return Err(Error::scene(
            path,
            "camera.up: its length must be > 0 and its square finite",
        ));
    }
    let side = forward.normalize().cross(up);
    if !(side.length() > 1e-6 * up.length()) {
        return Err(Error::scene(
            path,
            "camera.up: must not be zero or parallel to the view direction",
        ));
    }
    Ok(View {
        eye,
        look_at,
        up,
        vfov: c.vfov,
    })
}

/// `[background]`: a colour, the default colour, or the cube map it names (loaded).
fn background(file: &SceneFile, path: &Path, search: &SearchPath) -> Result<Background> {
    Ok(match (&file.background.color, &file.background.cubemap) {
        (Some(col), None) => Background::Color(nonneg3(*col, "background.color", path)?),
        (None, None) => Background::Color(Vec3::from(DEFAULT_BACKGROUND)),
        (None, Some(dir)) => Background::CubeMap(Arc::new(
            search
                .resolve(dir)
                .and_then(|d| load_cubemap(&d))
                .map_err(|e| referenced(file, path, "background.cubemap", None, e))?,
        )),
        _ => {
            return Err(Error::scene(
                path,
                "background: give at most one of 'color' or 'cubemap'",
            ));
        }
    })
}

/// `[[light]]`: finite positions and intensities >= 0.
fn lights(file: &SceneFile, path: &Path) -> Result<Vec<Light>> {
    file.lights
        .iter()
        .enumerate()
        .map(|(i, l)| {
            Ok(Light {
                position: finite3(l.position, &format!("light[{i}].position"), path)?,
                intensity: nonneg3(l.intensity, &format!("light[{i}].intensity"), path)?,
            })
        })
        .collect()
}

/// An error about a file the scene names: the scene, the line of `toml_key` (when the scene
/// was read from text), the key as messages spell it (`shown`, default `toml_key`), then the
/// file's own error.
pub(super) fn referenced(
    file: &SceneFile,
    path: &Path,
    toml_key: &str,
    shown: Option<String>,
    source: Error,
) -> Error {
    Error::Referenced {
        scene: path.to_path_buf(),
        line: file.lines.line(toml_key),
        key: shown.unwrap_or_else(|| toml_key.to_string()),
        source: Box::new(source),
    }
}

/// A mesh a file stores once ([`Model::shared`]) as a scene object, with its placements
/// (object to world, before its entry's own placements).
pub(super) type SharedObject = (Object, Vec<glam::Affine3A>);

/// A mesh file as read once for a scene: where it was found, the mesh with the materials it
/// brings, the vertices it gave no rgb.
pub(super) type LoadedMesh = (PathBuf, Model, Vec<u32>);

/// What the materials and meshes of a scene are built in: the file, where its files are
/// found, and what has been made so far.
pub(super) struct Builder<'a> {
    /// The scene file.
    pub(super) file: &'a SceneFile,
    /// Its name in messages.
    pub(super) path: &'a Path,
    /// Where its files are found.
    pub(super) search: &'a SearchPath,
    /// The scene's materials: its own, then those mesh files bring.
    pub(super) materials: Vec<Material>,
    /// Per scene material (by index), the colour of vertices a mesh gives no rgb.
    pub(super) vertex_fill: Vec<Vec3>,
    /// One texture per file, however many materials use it.
    pub(super) textures: Vec<(PathBuf, Arc<Texture>)>,
    /// Each mesh file is read once, however many `[[mesh]]` entries name it.
    pub(super) loaded: Vec<LoadedMesh>,
    /// Warnings of the loaders, in order.
    pub(super) warnings: Vec<String>,
    /// Triangles of the meshes made so far (after subdivision).
    pub(super) total_triangles: u64,
    /// Of those, the triangles of subdivided meshes.
    pub(super) subdivided_total: u64,
}

impl Builder<'_> {
    /// `[[material]]`: each validated and its texture loaded, after the checker textures'
    /// total size has been checked against [`MAX_CHECKER_TEXELS`] (before any is made).
    fn scene_materials(&mut self) -> Result<()> {
        let (file, path) = (self.file, self.path);
        let checker_texels: u64 = file
            .materials
            .iter()
            .filter_map(|m| m.checker.as_ref())
            .map(|c| (c.squares.clamp(1, 4096) as u64 * 16).min(4096).pow(2))
            .sum();
        if checker_texels > MAX_CHECKER_TEXELS {
            return Err(Error::scene(
                path,
                format!(
                    "material.checker: all checker textures together would take {checker_texels} texels, over the cap of {MAX_CHECKER_TEXELS}"
                ),
            ));
        }
        for (i, m) in file.materials.iter().enumerate() {
            if self.materials.iter().any(|x| x.name == m.name) {
                return Err(Error::scene(
                    path,
                    format!("material[{i}].name: '{}' is defined twice", m.name),
                ));
            }
            let prefix = format!("material[{i}] '{}'", m.name);
            let refer = |e| {
                let toml_key = format!("material[{i}].texture");
                referenced(file, path, &toml_key, Some(format!("{prefix}.texture")), e)
            };
            let material = self.build_material(m, &prefix, &refer)?;
            self.materials.push(material);
            // The colour of vertices a mesh gives no rgb (white unless the material says).
            self.vertex_fill.push(match m.color {
                Some(c) if m.vertex_color => Vec3::from(c),
                _ => Vec3::ONE,
            });
        }
        Ok(())
    }

    /// The caps first, from the parameters alone: inline and generated meshes know their
    /// triangle count before they are made, so a scene of 3,719 spheres is refused before the
    /// first sphere is allocated (file meshes are checked as each is read).
    fn check_planned(&self) -> Result<()> {
        let (mut planned, mut planned_subdivided) = (0u64, 0u64);
        for (i, d) in self.file.meshes.iter().enumerate() {
            if let Some(n) = super::meshes::planned_triangles(d) {
                let made =
                    super::meshes::check_caps(i, d, n, planned, planned_subdivided, self.path)?;
                planned += made;
                planned_subdivided += if d.subdivide > 0 { made } else { 0 };
            }
        }
        Ok(())
    }

    /// The object of mesh entry `i`: its mesh (read, copied or generated, then subdivided)
    /// and its material, or a material per triangle from its file; and the objects of the
    /// meshes its file stores once ([`Model::shared`]) with their placements.
    fn object(&mut self, i: usize, d: &MeshDesc) -> Result<(Object, Vec<SharedObject>)> {
        let named = self.named_material(i, d)?;
        let (mut model, name, missing_rgb) = self.mesh_of(d, i)?;
        let mut parts = Vec::with_capacity(model.shared.len());
        for s in std::mem::take(&mut model.shared) {
            self.caps(i, d, s.model.mesh.triangles.len() as u64)?;
            let part_name = format!("{name}#{}", s.name);
            let object = self.object_of(i, d, named, s.model, part_name, &[])?;
            parts.push((object, s.placements));
        }
        let object = self.object_of(i, d, named, model, name, &missing_rgb)?;
        Ok((object, parts))
    }

    /// The object of `model` for mesh entry `i`, its material `named` by the entry or the
    /// model's own.
    fn object_of(
        &mut self,
        i: usize,
        d: &MeshDesc,
        named: Option<usize>,
        model: Model,
        name: String,
        missing_rgb: &[u32],
    ) -> Result<Object> {
        let file_normals = model.file_normals;
        let (material, face_materials) = match named {
            Some(m) => (m, None),
            None => self.file_materials(&model, &name, i)?,
        };
        let mut mesh = model.mesh;
        self.fill_missing_rgb(&mut mesh, material, missing_rgb);
        let mesh = self.shade(i, d, mesh, file_normals)?;
        let mesh = if d.subdivide > 0 {
            mesh.subdivide(d.subdivide)
        } else {
            mesh
        };
        let made = mesh.triangles.len() as u64;
        self.total_triangles += made;
        if d.subdivide > 0 {
            self.subdivided_total += made;
        }
        // Subdivision makes 4 children per face, in order.
        let face_materials = face_materials.map(|f| {
            let n = 1usize << (2 * d.subdivide);
            f.iter()
                .flat_map(|&m| std::iter::repeat_n(m, n))
                .collect::<Vec<u32>>()
        });
        let key = |k: &str| format!("mesh[{i}].{k}");
        if !mesh.positions.iter().all(|p| p.is_finite()) {
            return Err(Error::scene(
                self.path,
                format!(
                    "{}: coordinates overflow f32 (center, size or radius too large)",
                    key(if d.subdivide > 0 {
                        "subdivide"
                    } else {
                        "shape"
                    })
                ),
            ));
        }
        let mut used = vec![material as u32];
        if let Some(f) = &face_materials {
            used = f.clone();
            used.sort_unstable();
            used.dedup();
        }
        for &m in &used {
            self.check_albedo_source(&mesh, m as usize, &key("material"))?;
        }
        Ok(Object {
            name,
            mesh,
            material,
            face_materials,
        })
    }

    /// The scene material entry `i` names with `material = ".."` (`None`: the file's own
    /// materials are used, which only a file has).
    fn named_material(&self, i: usize, d: &MeshDesc) -> Result<Option<usize>> {
        let key = format!("mesh[{i}].material");
        if d.material.is_empty() {
            if d.file.is_none() {
                return Err(Error::scene(
                    self.path,
                    format!(
                        "{key}: required for inline and shape meshes (only files bring materials)"
                    ),
                ));
            }
            return Ok(None);
        }
        self.materials
            .iter()
            .position(|m| m.name == d.material)
            .map(Some)
            .ok_or_else(|| {
                Error::scene(
                    self.path,
                    format!("{key}: no material named '{}'", d.material),
                )
            })
    }

    /// Colour the vertices a `.m` file left without `rgb` when the mesh's material uses
    /// vertex colours: the material's fill colour (file materials and the default: white).
    fn fill_missing_rgb(&self, mesh: &mut Mesh, material: usize, missing_rgb: &[u32]) {
        if let Albedo::VertexColor = self.materials[material].albedo
            && let Some(colors) = &mut mesh.colors
        {
            let fill = self.vertex_fill.get(material).copied().unwrap_or(Vec3::ONE);
            for &v in missing_rgb {
                colors[v as usize] = fill;
            }
        }
    }

    /// Entry `i`'s `smooth` and `crease` keys applied to its mesh (neither: the mesh keeps
    /// the normals its format means). Triangles keep their order, so per-face materials
    /// still apply; only vertices are split or shared.
    fn shade(&self, i: usize, d: &MeshDesc, mesh: Mesh, file_normals: bool) -> Result<Mesh> {
        let key = |k: &str| format!("mesh[{i}].{k}");
        let fail = |k: &str, m: String| Err(Error::scene(self.path, format!("{}: {m}", key(k))));
        match (d.smooth, d.crease) {
            (Some(false), Some(_)) => fail(
                "crease",
                "a crease angle smooths the flatter edges; give it without smooth = false".into(),
            ),
            (_, Some(c)) if !(c.is_finite() && (0.0..=180.0).contains(&c)) => fail(
                "crease",
                format!("must be an angle in 0..=180 degrees, found {c}"),
            ),
            (_, Some(c)) => mesh.crease_shaded(c).or_else(|m| fail("crease", m)),
            (Some(false), None) => Ok(mesh.flat_shaded()),
            (Some(true), None) if file_normals => Ok(mesh),
            (Some(true), None) => Ok(mesh.smooth_shaded()),
            (None, None) => Ok(mesh),
        }
    }

    /// A material's colour source must be in the mesh: vertex colours need `rgb`, textures
    /// need uv.
    fn check_albedo_source(&self, mesh: &Mesh, material: usize, key: &str) -> Result<()> {
        let material = &self.materials[material];
        let missing = match &material.albedo {
            // (a file whose meshes are all stored once leaves its entry's own mesh empty)
            _ if mesh.triangles.is_empty() => return Ok(()),
            Albedo::VertexColor if mesh.colors.is_none() => {
                "uses vertex colours but the mesh has no rgb"
            }
            Albedo::Texture(_) if mesh.uvs.is_none() => "is textured but the mesh has no uv",
            _ => return Ok(()),
        };
        Err(Error::scene(
            self.path,
            format!("{key}: material '{}' {missing}", material.name),
        ))
    }
}
