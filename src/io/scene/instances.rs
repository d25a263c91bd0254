//! `[[instance]]` entries: placements of the scene's meshes by name, validated (a known
//! mesh and material, a finite, invertible transform).

use super::schema::{InstanceDesc, ScaleDesc, SceneFile};
use crate::error::{Error, Result};
use crate::scene::{Material, Object, Placement};
use glam::{Affine3A, EulerRot, Mat3, Quat, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// The placements of `file`'s `[[instance]]` entries over the built `objects`.
pub(super) fn placements(
    file: &SceneFile,
    path: &Path,
    objects: &[Object],
    materials: &[Material],
) -> Result<Vec<Placement>> {
    if file.instances.is_empty() {
        return Ok(Vec::new());
    }
    // (the first mesh of a name, as materials are found by name)
    let mut by_name: HashMap<&str, usize> = HashMap::new();
    for (i, o) in objects.iter().enumerate().rev() {
        by_name.insert(o.name.as_str(), i);
    }
    file.instances
        .iter()
        .enumerate()
        .map(|(i, d)| placement(i, d, path, &by_name, materials))
        .collect()
}

fn placement(
    i: usize,
    d: &InstanceDesc,
    path: &Path,
    by_name: &HashMap<&str, usize>,
    materials: &[Material],
) -> Result<Placement> {
    let fail = |k: &str, m: String| Error::scene(path, format!("instance[{i}].{k}: {m}"));
    let object = *by_name.get(d.mesh.as_str()).ok_or_else(|| {
        let mut names: Vec<&str> = by_name.keys().copied().collect();
        names.sort_unstable();
        fail(
            "mesh",
            format!("no mesh named '{}' (meshes: {})", d.mesh, names.join(", ")),
        )
    })?;
    let material = if d.material.is_empty() {
        None
    } else {
        let m = materials.iter().position(|m| m.name == d.material);
        Some(m.ok_or_else(|| fail("material", format!("no material named '{}'", d.material)))?)
    };
    let to_world = match d.matrix {
        Some(rows) => {
            if d.translate.is_some() || d.rotate.is_some() || d.scale.is_some() {
                return Err(fail(
                    "matrix",
                    "give a matrix or translate/rotate/scale, not both".into(),
                ));
            }
            if !rows.iter().flatten().all(|x| x.is_finite()) {
                return Err(fail("matrix", "every entry must be a finite number".into()));
            }
            if rows[3] != [0.0, 0.0, 0.0, 1.0] {
                return Err(fail(
                    "matrix",
                    format!(
                        "the last row must be [0, 0, 0, 1] (affine), found {:?}",
                        rows[3]
                    ),
                ));
            }
            let col = |c: usize| Vec3::new(rows[0][c], rows[1][c], rows[2][c]);
            Affine3A::from_mat3_translation(Mat3::from_cols(col(0), col(1), col(2)), col(3))
        }
        None => {
            let t = three(d.translate.unwrap_or([0.0; 3]), "translate", &fail)?;
            let r = three(d.rotate.unwrap_or([0.0; 3]), "rotate", &fail)?;
            let s = match d.scale {
                None => Vec3::ONE,
                Some(ScaleDesc::Uniform(s)) => three([s; 3], "scale", &fail)?,
                Some(ScaleDesc::Axes(s)) => three(s, "scale", &fail)?,
            };
            // about x, then y, then z: R = Rz Ry Rx
            let (x, y, z) = (r.x.to_radians(), r.y.to_radians(), r.z.to_radians());
            let q = Quat::from_euler(EulerRot::ZYX, z, y, x);
            Affine3A::from_scale_rotation_translation(s, q, t)
        }
    };
    let key = if d.matrix.is_some() {
        "matrix"
    } else {
        "scale"
    };
    if !crate::instance::invertible(&to_world) {
        return Err(fail(
            key,
            "the transform is singular (it has no inverse)".into(),
        ));
    }
    Ok(Placement {
        object,
        to_world,
        material,
    })
}

/// `instances` with the placements of the meshes files store once: each shared object
/// (appended to `objects`) at its own placements, or, when `[[instance]]` places its entry,
/// at each of those placements times its own (in the instance's material).
pub(super) fn with_shared(
    mut instances: Vec<Placement>,
    objects: &mut Vec<Object>,
    shared: Vec<(usize, Object, Vec<Affine3A>)>,
) -> Vec<Placement> {
    let own = instances.len();
    for (entry, object, placements) in shared {
        let k = objects.len();
        objects.push(object);
        let parents: Vec<(Affine3A, Option<usize>)> = (instances[..own].iter())
            .filter(|p| p.object == entry)
            .map(|p| (p.to_world, p.material))
            .collect();
        let parents = if parents.is_empty() {
            vec![(Affine3A::IDENTITY, None)]
        } else {
            parents
        };
        instances.reserve(parents.len() * placements.len());
        for (parent, material) in parents {
            instances.extend(placements.iter().map(|&m| Placement {
                object: k,
                to_world: parent * m,
                material,
            }));
        }
    }
    instances
}

/// Three numbers of key `k`, each finite.
fn three(v: [f32; 3], k: &str, fail: &impl Fn(&str, String) -> Error) -> Result<Vec3> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vec3::from(v))
    } else {
        Err(fail(k, "every component must be a finite number".into()))
    }
}
