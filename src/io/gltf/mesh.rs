//! A glTF document's scene as one [`Model`]: the meshes drawn once flattened into its mesh
//! (node transforms applied, every primitive's triangles appended with its material), the
//! meshes drawn more than once read once in their own space with their placements
//! ([`Model::shared`], decided in `instancing.rs`); accessors read after their bounds are
//! checked.

use super::accessor::{View, view};
use super::instancing::{Draw, Use, draws};
use super::material::materials;
use super::view::{lights, view_of};
use super::{Document, Node, Primitive, at};
use crate::error::Result;
use crate::io::model::{Model, NO_MATERIAL, Shared};
use crate::io::scene::schema::{MAX_SCENE_TRIANGLES, MaterialDesc};
use crate::mesh::Mesh;
use glam::{Affine3A, Mat4, Quat, Vec2, Vec3};
use std::borrow::Cow;
use std::path::Path;

/// Most vertices the model's meshes may store together: three per triangle of the cap.
const MAX_STORED_VERTICES: u64 = 3 * MAX_SCENE_TRIANGLES;

/// The model of `doc`'s default scene: meshes drawn once flattened into `mesh`, the others
/// stored once with their placements (`shared`).
pub(super) fn build(
    doc: &Document,
    buffers: &[Cow<'_, [u8]>],
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<Model> {
    let (uses, camera, light_nodes) = instances(doc, path)?;
    let camera = camera.and_then(|(world, c)| view_of(doc, world, c, path, warnings));
    let draws = draws(doc, buffers, &uses, path, warnings)?;
    // The caps first: every flattened mesh and every shared one once.
    let (mut planned, mut planned_vertices) = (0u64, 0u64);
    for d in &draws {
        let (Draw::Flat(_, m) | Draw::Shared(m, _)) = *d;
        stored(doc, buffers, m, path, &mut planned, &mut planned_vertices)?;
    }
    let mut flat = Gather::default();
    let mut shared = Vec::new();
    for d in draws {
        match d {
            Draw::Flat(world, m) => {
                let world = Affine3A::from_mat4(world);
                flat.add(doc, buffers, m, Some(&world), path)?;
            }
            Draw::Shared(m, placements) => {
                let mut g = Gather::default();
                g.add(doc, buffers, m, None, path)?;
                shared.push((m, g, placements));
            }
        }
    }
    // (a mesh without primitives, or whose copies are all left out, draws nothing)
    shared.retain(|(_, g, p): &(usize, Gather, Vec<Affine3A>)| {
        !(g.mesh.triangles.is_empty() || p.is_empty())
    });
    if flat.mesh.triangles.is_empty() && shared.is_empty() {
        return Err(at(path, "scenes", "no triangles in the scene's nodes"));
    }
    let all_uv = flat.all_uv && shared.iter().all(|(_, g, _)| g.all_uv);
    let all_color = flat.all_color && shared.iter().all(|(_, g, _)| g.all_color);
    let degenerate = flat.mesh.degenerate_count()
        + (shared.iter())
            .map(|(_, g, _)| g.mesh.degenerate_count())
            .sum::<usize>();
    if degenerate > 0 {
        warnings.push(format!(
            "{}: {degenerate} degenerate (zero-area) faces; they are never hit",
            path.display()
        ));
    }
    let materials = materials(doc, path, all_uv, all_color, warnings)?;
    let shared = shared
        .into_iter()
        .map(|(m, g, placements)| Shared {
            name: format!("meshes[{m}]"),
            model: g.model(materials.clone()),
            placements,
        })
        .collect();
    let mut model = flat.model(materials);
    model.shared = shared;
    model.camera = camera;
    model.lights = lights(doc, &light_nodes, model.bounds(), path, warnings)?;
    Ok(model)
}

/// Mesh `m`'s triangles and vertices added to the totals stored, against the caps; each
/// accessor is checked against its buffer first (so a count no buffer holds is named as
/// such, not as the cap).
fn stored(
    doc: &Document,
    buffers: &[Cow<'_, [u8]>],
    m: usize,
    path: &Path,
    planned: &mut u64,
    planned_vertices: &mut u64,
) -> Result<()> {
    for (p, prim) in doc.meshes[m].primitives.iter().enumerate() {
        let key = format!("meshes[{m}].primitives[{p}]");
        let positions = match prim.attributes.get("POSITION") {
            Some(&i) => {
                let used_as = format!("{key}.attributes.POSITION");
                view(doc, buffers, i, &["VEC3"], &[5126], &used_as, path)?.count as u64
            }
            None => 0,
        };
        let n = match prim.indices {
            Some(i) => {
                let used_as = format!("{key}.indices");
                let kinds = [5121, 5123, 5125];
                view(doc, buffers, i, &["SCALAR"], &kinds, &used_as, path)?.count as u64 / 3
            }
            None => positions / 3,
        };
        *planned = planned.saturating_add(n);
        if *planned > MAX_SCENE_TRIANGLES {
            return Err(at(
                path,
                &key,
                format!(
                    "the scene's meshes add up to over {MAX_SCENE_TRIANGLES} triangles (the cap)"
                ),
            ));
        }
        // Positions count too, used by the indices or not: a few triangles over millions of
        // vertices, drawn by many nodes, must not fill the memory either.
        *planned_vertices = planned_vertices.saturating_add(positions);
        if *planned_vertices > MAX_STORED_VERTICES {
            return Err(at(
                path,
                &key,
                format!(
                    "the scene's meshes add up to over {MAX_STORED_VERTICES} vertices (the cap)"
                ),
            ));
        }
    }
    Ok(())
}

/// Primitives gathered into one mesh with their materials.
struct Gather {
    /// Their triangles (attributes kept where every primitive has them).
    mesh: Mesh,
    /// Per triangle, its glTF material or [`NO_MATERIAL`].
    face_materials: Vec<u32>,
    /// Whether every primitive has uv, colours, normals of the file's.
    all_uv: bool,
    all_color: bool,
    all_normals: bool,
}

impl Default for Gather {
    fn default() -> Gather {
        Gather {
            mesh: Mesh::default(),
            face_materials: Vec::new(),
            all_uv: true,
            all_color: true,
            all_normals: true,
        }
    }
}

impl Gather {
    /// Every primitive of mesh `m`, carried by `world` (`None`: in the mesh's own space).
    fn add(
        &mut self,
        doc: &Document,
        buffers: &[Cow<'_, [u8]>],
        m: usize,
        world: Option<&Affine3A>,
        path: &Path,
    ) -> Result<()> {
        for (p, prim) in doc.meshes[m].primitives.iter().enumerate() {
            let key = format!("meshes[{m}].primitives[{p}]");
            let part = primitive(doc, buffers, prim, &key, world, path)?;
            self.all_uv &= part.mesh.uvs.is_some();
            self.all_color &= part.mesh.colors.is_some();
            self.all_normals &= part.file_normals;
            self.mesh.append(&part.mesh);
            let material = match prim.material {
                Some(k) if k < doc.materials.len() => k as u32,
                Some(k) => {
                    return Err(at(
                        path,
                        &format!("{key}.material"),
                        format!("no material {k}"),
                    ));
                }
                None => NO_MATERIAL,
            };
            let n = part.mesh.triangles.len();
            self.face_materials.extend(std::iter::repeat_n(material, n));
        }
        Ok(())
    }

    /// The gathered mesh as a model with `materials`.
    fn model(self, materials: Vec<MaterialDesc>) -> Model {
        let any_material = self.face_materials.iter().any(|&m| m != NO_MATERIAL);
        Model {
            mesh: self.mesh,
            materials,
            face_materials: any_material.then_some(self.face_materials),
            file_normals: self.all_normals,
            ..Default::default()
        }
    }
}

/// The instances of a scene: every (world transform, mesh, node), the first (world
/// transform, camera) met, and every (world transform, light).
type Instances = (Vec<Use>, Option<(Mat4, usize)>, Vec<(Mat4, usize)>);

/// Every (world transform, mesh, node) of the default scene's node trees, in depth-first order,
/// and the first node with a camera. A node met twice (a cycle, or a node with two parents)
/// is an error.
fn instances(doc: &Document, path: &Path) -> Result<Instances> {
    let roots: Vec<usize> = match doc.scene.or((!doc.scenes.is_empty()).then_some(0)) {
        Some(s) => doc
            .scenes
            .get(s)
            .ok_or_else(|| at(path, "scene", format!("no scene {s}")))?
            .nodes
            .clone(),
        None => {
            let mut child = vec![false; doc.nodes.len()];
            for n in &doc.nodes {
                for &c in &n.children {
                    if let Some(x) = child.get_mut(c) {
                        *x = true;
                    }
                }
            }
            (0..doc.nodes.len()).filter(|&i| !child[i]).collect()
        }
    };
    let mut seen = vec![false; doc.nodes.len()];
    let mut out = Vec::new();
    let mut camera = None;
    let mut lights = Vec::new();
    let defined = doc
        .extensions
        .as_ref()
        .and_then(|e| e.lights.as_ref())
        .map_or(0, |l| l.lights.len());
    // An explicit stack: a chain of a million nodes must not overflow the thread's stack.
    let mut stack: Vec<(usize, Mat4)> = roots.iter().rev().map(|&r| (r, Mat4::IDENTITY)).collect();
    while let Some((i, parent)) = stack.pop() {
        let node: &Node = doc.nodes.get(i).ok_or_else(|| {
            at(
                path,
                "nodes",
                format!("no node {i} (the file has {})", doc.nodes.len()),
            )
        })?;
        if std::mem::replace(&mut seen[i], true) {
            return Err(at(
                path,
                &format!("nodes[{i}]"),
                "reached twice: the node graph has a cycle or a node with two parents",
            ));
        }
        let world = parent * local(node, i, path)?;
        if let Some(m) = node.mesh {
            if m >= doc.meshes.len() {
                return Err(at(
                    path,
                    &format!("nodes[{i}].mesh"),
                    format!("no mesh {m}"),
                ));
            }
            out.push((world, m, i));
        }
        if let Some(c) = node.camera {
            if c >= doc.cameras.len() {
                return Err(at(
                    path,
                    &format!("nodes[{i}].camera"),
                    format!("no camera {c}"),
                ));
            }
            camera = camera.or(Some((world, c)));
        }
        if let Some(l) = node.extensions.as_ref().and_then(|e| e.light.as_ref()) {
            if l.light >= defined {
                return Err(at(
                    path,
                    &format!("nodes[{i}].extensions.KHR_lights_punctual.light"),
                    format!("no light {} (the file defines {defined})", l.light),
                ));
            }
            lights.push((world, l.light));
        }
        for &c in node.children.iter().rev() {
            stack.push((c, world));
        }
    }
    Ok((out, camera, lights))
}

/// A node's own transform: `matrix` (column-major), or scale, then rotation, then
/// translation.
fn local(node: &Node, i: usize, path: &Path) -> Result<Mat4> {
    let key = format!("nodes[{i}]");
    let m = match node.matrix {
        Some(m) => {
            if node.translation.is_some() || node.rotation.is_some() || node.scale.is_some() {
                return Err(at(
                    path,
                    &format!("{key}.matrix"),
                    "given with translation, rotation or scale",
                ));
            }
            let m = Mat4::from_cols_array(&m);
            if m.row(3) != glam::Vec4::W {
                return Err(at(
                    path,
                    &format!("{key}.matrix"),
                    "its last row is not [0, 0, 0, 1] (glTF node matrices are affine)",
                ));
            }
            m
        }
        None => {
            let q = node.rotation.map_or(Quat::IDENTITY, Quat::from_array);
            if !(q.is_finite() && (q.length() - 1.0).abs() < 1e-3) {
                return Err(at(
                    path,
                    &format!("{key}.rotation"),
                    "not a unit quaternion",
                ));
            }
            Mat4::from_scale_rotation_translation(
                node.scale.map_or(Vec3::ONE, Vec3::from),
                q.normalize(),
                node.translation.map_or(Vec3::ZERO, Vec3::from),
            )
        }
    };
    if !m.is_finite() {
        return Err(at(path, &key, "its transform is not finite"));
    }
    Ok(m)
}

/// One primitive's triangles.
struct Part {
    /// Positions, triangles, normals (the file's, else flat), `TEXCOORD_0` (v flipped to
    /// whitted's bottom-up convention) and `COLOR_0` (alpha dropped).
    mesh: Mesh,
    /// Whether the normals are the file's.
    file_normals: bool,
}

/// Primitive `key` of a mesh, carried by `world` (`None`: in the mesh's own space).
fn primitive(
    doc: &Document,
    buffers: &[Cow<'_, [u8]>],
    prim: &Primitive,
    key: &str,
    world: Option<&Affine3A>,
    path: &Path,
) -> Result<Part> {
    if prim.mode != 4 {
        let name = match prim.mode {
            0 => "POINTS",
            1 => "LINES",
            2 => "LINE_LOOP",
            3 => "LINE_STRIP",
            5 => "TRIANGLE_STRIP",
            6 => "TRIANGLE_FAN",
            _ => "an unknown mode",
        };
        return Err(at(
            path,
            &format!("{key}.mode"),
            format!("{name} ({}) is not read; only TRIANGLES (4)", prim.mode),
        ));
    }
    let attr = |name: &str| prim.attributes.get(name).copied();
    let use_as = |name: &str| format!("{key}.attributes.{name}");
    let pos_i =
        attr("POSITION").ok_or_else(|| at(path, &format!("{key}.attributes"), "no POSITION"))?;
    let pos = view(
        doc,
        buffers,
        pos_i,
        &["VEC3"],
        &[5126],
        &use_as("POSITION"),
        path,
    )?;
    let n = pos.count;
    let not_finite = |i: usize, k: usize| {
        at(
            path,
            &format!("accessors[{i}]"),
            format!("element {k} is not finite (after its node's transform)"),
        )
    };
    let mut positions = Vec::with_capacity(n);
    for k in 0..n {
        let p = Vec3::new(pos.float(k, 0), pos.float(k, 1), pos.float(k, 2));
        if !p.is_finite() {
            return Err(not_finite(pos_i, k));
        }
        positions.push(p);
    }
    let same_count = |v: &View, name: &str, i: usize| -> Result<()> {
        if v.count != n {
            return Err(at(
                path,
                &format!("accessors[{i}].count"),
                format!("{} {name} elements for {n} positions", v.count),
            ));
        }
        Ok(())
    };
    let mut triangles = Vec::new();
    match prim.indices {
        Some(ii) => {
            let idx = view(
                doc,
                buffers,
                ii,
                &["SCALAR"],
                &[5121, 5123, 5125],
                &format!("{key}.indices"),
                path,
            )?;
            if idx.count % 3 != 0 {
                return Err(at(
                    path,
                    &format!("accessors[{ii}].count"),
                    format!("{} indices is not a whole number of triangles", idx.count),
                ));
            }
            triangles.reserve(idx.count / 3);
            for t in 0..idx.count / 3 {
                let tri = [idx.index(3 * t), idx.index(3 * t + 1), idx.index(3 * t + 2)];
                if let Some(&v) = tri.iter().find(|&&v| v as usize >= n) {
                    return Err(at(
                        path,
                        &format!("accessors[{ii}]"),
                        format!(
                            "index {v} (element {}) is out of range: {n} vertices",
                            3 * t
                        ),
                    ));
                }
                triangles.push(tri);
            }
        }
        None => {
            if n % 3 != 0 {
                return Err(at(
                    path,
                    &format!("accessors[{pos_i}].count"),
                    format!("{n} positions without indices is not a whole number of triangles"),
                ));
            }
            triangles.extend((0..n as u32 / 3).map(|t| [3 * t, 3 * t + 1, 3 * t + 2]));
        }
    }
    let mut mesh = Mesh {
        positions,
        triangles,
        ..Default::default()
    };
    let uvs = match attr("TEXCOORD_0") {
        Some(i) => {
            let v = view(
                doc,
                buffers,
                i,
                &["VEC2"],
                &[5126, 5121, 5123],
                &use_as("TEXCOORD_0"),
                path,
            )?;
            same_count(&v, "TEXCOORD_0", i)?;
            let uv: Vec<Vec2> = (0..n)
                .map(|k| Vec2::new(v.float(k, 0), 1.0 - v.float(k, 1)))
                .collect();
            if !uv.iter().all(|u| u.is_finite()) {
                return Err(at(
                    path,
                    &format!("accessors[{i}]"),
                    "a TEXCOORD_0 element is not finite",
                ));
            }
            Some(uv)
        }
        None => None,
    };
    let colors = match attr("COLOR_0") {
        Some(i) => {
            let v = view(
                doc,
                buffers,
                i,
                &["VEC3", "VEC4"],
                &[5126, 5121, 5123],
                &use_as("COLOR_0"),
                path,
            )?;
            same_count(&v, "COLOR_0", i)?;
            let c: Vec<Vec3> = (0..n)
                .map(|k| Vec3::new(v.float(k, 0), v.float(k, 1), v.float(k, 2)))
                .collect();
            if !c.iter().all(|c| c.is_finite() && c.cmpge(Vec3::ZERO).all()) {
                return Err(at(
                    path,
                    &format!("accessors[{i}]"),
                    "a COLOR_0 element is not finite and >= 0",
                ));
            }
            Some(c)
        }
        None => None,
    };
    let file_normals = match attr("NORMAL") {
        Some(i) => {
            let v = view(doc, buffers, i, &["VEC3"], &[5126], &use_as("NORMAL"), path)?;
            same_count(&v, "NORMAL", i)?;
            mesh.normals = Some(
                (0..n)
                    .map(|k| Vec3::new(v.float(k, 0), v.float(k, 1), v.float(k, 2)))
                    .collect(),
            );
            true
        }
        None => false,
    };
    // The file's normals, made unit (zero or non-finite ones replaced by the area-weighted
    // normal); without them, flat, as glTF specifies.
    mesh.ensure_normals();
    mesh.uvs = uvs;
    mesh.colors = colors;
    if !file_normals {
        mesh = mesh.flat_shaded();
    }
    // A mirroring transform swaps two corners of each triangle, so the front stays the front
    // (glTF: a negative determinant turns the winding).
    if let Some(world) = world {
        mesh = mesh.transformed(world);
        if let Some(k) = mesh.positions.iter().position(|p| !p.is_finite()) {
            return Err(not_finite(pos_i, k));
        }
    }
    Ok(Part { mesh, file_normals })
}
