//! Which glTF meshes are stored once and where they are drawn: a mesh drawn by several
//! nodes, meshes whose primitives are the same (the same accessors and material), and a
//! node's `EXT_mesh_gpu_instancing` copies (TRANSLATION, ROTATION, SCALE per copy, each copy
//! at the node's world matrix times T * R * S) become one stored mesh with placements; a mesh
//! drawn once is flattened as before.

use super::accessor::view;
use super::{Document, Primitive, at};
use crate::error::Result;
use crate::instance::invertible;
use glam::{Affine3A, Mat4, Quat, Vec3, Vec4};
use serde::Deserialize;
use std::borrow::Cow;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

/// Most copies a model's nodes and `EXT_mesh_gpu_instancing` may place together (each
/// costs about 300 bytes once traced: the placement, its inverse and the top level).
pub const MAX_INSTANCES: u64 = 1 << 22;

/// `nodes[i].extensions.EXT_mesh_gpu_instancing`.
#[derive(Debug, Deserialize)]
pub(super) struct GpuInstancing {
    #[serde(default)]
    attributes: BTreeMap<String, usize>,
}

/// A node drawing a mesh: its world transform, the mesh and the node's index.
pub(super) type Use = (Mat4, usize, usize);

/// What the model draws, mesh by mesh.
pub(super) enum Draw {
    /// A mesh drawn once, flattened at this world transform.
    Flat(Mat4, usize),
    /// A mesh stored once (in its own space) and drawn at each placement.
    Shared(usize, Vec<Affine3A>),
}

/// The draws of `uses` (in the order their meshes are first met), the singular placements
/// skipped counted in a warning. Meshes with the same primitives are one mesh; a mesh
/// drawn more than once, or by a node with `EXT_mesh_gpu_instancing`, is shared. The copies
/// are counted against [`MAX_INSTANCES`] from the accessors' counts before any is read.
pub(super) fn draws(
    doc: &Document,
    buffers: &[Cow<'_, [u8]>],
    uses: &[Use],
    path: &Path,
    warnings: &mut Vec<String>,
) -> Result<Vec<Draw>> {
    // meshes with equal primitives: the first mesh of each kind stands for them
    let mut first: HashMap<&[Primitive], usize> = HashMap::new();
    let mut order: Vec<(usize, Vec<&Use>)> = Vec::new();
    let mut slot: HashMap<usize, usize> = HashMap::new();
    let mut copies = 0u64;
    for u in uses {
        let m = *first
            .entry(doc.meshes[u.1].primitives.as_slice())
            .or_insert(u.1);
        let k = *slot.entry(m).or_insert_with(|| {
            order.push((m, Vec::new()));
            order.len() - 1
        });
        order[k].1.push(u);
        copies = copies.saturating_add(match gpu(doc, u.2) {
            Some(g) => count(doc, g, u.2, path)?,
            None => 1,
        });
        if copies > MAX_INSTANCES {
            return Err(at(
                path,
                &format!("nodes[{}]", u.2),
                format!("the scene's nodes place over {MAX_INSTANCES} copies of meshes (the cap)"),
            ));
        }
    }
    let mut singular = 0usize;
    let mut out = Vec::with_capacity(order.len());
    for (m, us) in order {
        if let [u] = us[..]
            && gpu(doc, u.2).is_none()
        {
            out.push(Draw::Flat(u.0, m));
            continue;
        }
        let mut placements = Vec::new();
        for &&(world, _, node) in &us {
            let locals = match gpu(doc, node) {
                Some(g) => transforms(doc, buffers, g, node, path)?,
                None => vec![Mat4::IDENTITY],
            };
            placements.reserve(locals.len());
            for local in locals {
                match affine(world * local) {
                    Some(a) => placements.push(a),
                    None => singular += 1,
                }
            }
        }
        out.push(Draw::Shared(m, placements));
    }
    if singular > 0 {
        warnings.push(format!(
            "{}: {singular} copies of meshes have a singular transform (a zero scale); they draw nothing",
            path.display()
        ));
    }
    Ok(out)
}

/// Node `i`'s `EXT_mesh_gpu_instancing`, if it has one.
fn gpu(doc: &Document, i: usize) -> Option<&GpuInstancing> {
    doc.nodes[i].extensions.as_ref()?.gpu_instancing.as_ref()
}

/// `m` as an affine transform, if it is one that is finite and invertible.
fn affine(m: Mat4) -> Option<Affine3A> {
    let a = Affine3A::from_mat4(m);
    (m.is_finite() && m.row(3) == Vec4::W && invertible(&a)).then_some(a)
}

/// The JSON path of node `i`'s instancing attribute `name`.
fn key(i: usize, name: &str) -> String {
    format!("nodes[{i}].extensions.EXT_mesh_gpu_instancing.attributes.{name}")
}

/// The attribute names read, with their accessor types and component types (rotations
/// also as normalised bytes and shorts, as the extension allows).
const ATTRIBUTES: [(&str, &str, &[u32]); 3] = [
    ("TRANSLATION", "VEC3", &[5126]),
    ("ROTATION", "VEC4", &[5126, 5120, 5122]),
    ("SCALE", "VEC3", &[5126]),
];

/// The number of copies node `i`'s instancing attributes give, every attribute's count
/// checked against the others (and each accessor against its buffer: see [`transforms`]).
fn count(doc: &Document, g: &GpuInstancing, i: usize, path: &Path) -> Result<u64> {
    let mut n: Option<(u64, &str)> = None;
    for (name, ..) in ATTRIBUTES {
        let Some(&a) = g.attributes.get(name) else {
            continue;
        };
        let c = doc.accessors.get(a).ok_or_else(|| {
            at(
                path,
                &key(i, name),
                format!("no accessor {a} (the file has {})", doc.accessors.len()),
            )
        })?;
        match n {
            Some((m, other)) if m != c.count => {
                return Err(at(
                    path,
                    &key(i, name),
                    format!("{} copies, but {other} has {m}", c.count),
                ));
            }
            Some(_) => {}
            None => n = Some((c.count, name)),
        }
    }
    n.map(|n| n.0).ok_or_else(|| {
        at(
            path,
            &format!("nodes[{i}].extensions.EXT_mesh_gpu_instancing.attributes"),
            "none of TRANSLATION, ROTATION or SCALE",
        )
    })
}

/// The local transform `T * R * S` of every copy node `i`'s instancing attributes give,
/// each accessor checked against its buffer and every element finite (rotations unit
/// quaternions).
fn transforms(
    doc: &Document,
    buffers: &[Cow<'_, [u8]>],
    g: &GpuInstancing,
    i: usize,
    path: &Path,
) -> Result<Vec<Mat4>> {
    let n = count(doc, g, i, path)? as usize;
    let mut views = Vec::new();
    for (name, kind, components) in ATTRIBUTES {
        let Some(&a) = g.attributes.get(name) else {
            views.push(None);
            continue;
        };
        let v = view(doc, buffers, a, &[kind], components, &key(i, name), path)?;
        if doc.accessors[a].component_type != 5126 && !doc.accessors[a].normalized {
            return Err(at(
                path,
                &key(i, name),
                format!("accessors[{a}] holds integers that are not normalized"),
            ));
        }
        views.push(Some(v));
    }
    let read = |which: usize, k: usize, width: usize| -> Option<[f32; 4]> {
        let v = views[which].as_ref()?;
        let mut out = [0.0; 4];
        for (c, x) in out.iter_mut().enumerate().take(width) {
            *x = v.float(k, c);
        }
        Some(out)
    };
    let bad = |name: &str, k: usize, what: &str| {
        Err(at(path, &key(i, name), format!("element {k} is {what}")))
    };
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let t = read(0, k, 3).map_or(Vec3::ZERO, |v| Vec3::new(v[0], v[1], v[2]));
        let q = read(1, k, 4).map_or(Quat::IDENTITY, Quat::from_array);
        let s = read(2, k, 3).map_or(Vec3::ONE, |v| Vec3::new(v[0], v[1], v[2]));
        if !t.is_finite() {
            return bad("TRANSLATION", k, "not finite");
        }
        if !s.is_finite() {
            return bad("SCALE", k, "not finite");
        }
        // (normalised shorts hold a unit quaternion to about 1e-4, bytes to about 1e-2)
        if !(q.is_finite() && (q.length() - 1.0).abs() < 2e-2) {
            return bad("ROTATION", k, "not a unit quaternion");
        }
        out.push(Mat4::from_scale_rotation_translation(s, q.normalize(), t));
    }
    Ok(out)
}
