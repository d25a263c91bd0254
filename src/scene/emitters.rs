//! Point lights standing in for emitting surfaces (materials with `ke > 0` and `lamp`): of
//! the objects drawn as they are and of every placement of a placed one, as the scene
//! flattened would give them.

use super::{Light, Material, Object, Placement};
use crate::io::model::placed_box;
use glam::Vec3;

/// Most lamp triangles the placements of emitting meshes may make lights from (each
/// placement's lamp faces are carried into the world twice); past it, placed lamps light
/// nothing (the scene builder warns).
pub const MAX_PLACED_LAMP_TRIANGLES: u64 = 1 << 25;

/// Point lights standing in for the emitting surfaces of `objects` drawn as they are.
///
/// The triangles of each emitting material are grouped by the major axis and sign of their
/// normal (a flat lamp is one group, a lamp box up to six). Each group gives one light: at
/// its area-weighted centroid, moved along the group's mean normal just past its frontmost
/// vertex (by `1e-3` of the scene's bounding-box diagonal), so the lamp's own triangles lie
/// behind it and do not shadow it. Intensities are `ke` times the group's area, scaled so
/// that the brightest channel of all emitter lights together is 1 (point lights have no
/// fall-off here, so only the ratios of `Ke` and area matter; the total matches one
/// canonical key light). The emitting surfaces themselves show `ke` as given.
pub fn emitter_lights(objects: &[Object], materials: &[Material]) -> Vec<Light> {
    emitter_lights_placed(objects, &[], materials)
}

/// [`emitter_lights`] of a scene with `placements`: an object that a placement names is
/// drawn only where placed, so its lamp faces count at every placement, carried into the
/// world (a mirroring placement turned so its front stays its front) and in the
/// placement's material when it has one: the lights of the scene flattened in placement
/// order. The scene's box is the objects' drawn as they are and the placements' boxes (each
/// object's box carried through its placement: looser than the flattened vertices' box for
/// rotated placements, which moves lights by a fraction of the `1e-3` margin). Placed lamps
/// over [`MAX_PLACED_LAMP_TRIANGLES`] (see [`placed_lamp_triangles`]) light nothing.
pub fn emitter_lights_placed(
    objects: &[Object],
    placements: &[Placement],
    materials: &[Material],
) -> Vec<Light> {
    #[derive(Clone, Copy, Default)]
    struct Group {
        area: f32,
        centroid: Vec3,
        normal: Vec3,
    }
    let is_lamp = lamps(materials);
    if !is_lamp.contains(&true) {
        return Vec::new();
    }
    let mut placed = vec![false; objects.len()];
    for p in placements {
        placed[p.object] = true;
    }
    let boxes: Vec<Option<(Vec3, Vec3)>> = objects.iter().map(|o| o.mesh.bounds()).collect();
    let own_boxes = (boxes.iter().zip(&placed))
        .filter(|(_, p)| !**p)
        .filter_map(|(b, _)| *b);
    let placed_boxes =
        (placements.iter()).filter_map(|p| boxes[p.object].map(|b| placed_box(b, &p.to_world)));
    let (lo, hi) = own_boxes.chain(placed_boxes).fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), (a, b)| (lo.min(a), hi.max(b)),
    );
    let margin = 1e-3 * (hi - lo).length();
    let bin = |n: Vec3| {
        let a = n.abs();
        let axis = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        axis * 2 + (n[axis] < 0.0) as usize
    };
    // The drawn lamp triangles: (material, corners in the world), the objects drawn as they
    // are first, then every placement of a lamp in order.
    let count = placement_lamps(objects, &is_lamp);
    let mut lamp_placements: Vec<&Placement> = placements.iter().filter(|p| count(p) > 0).collect();
    if lamp_placements.iter().map(|p| count(p)).sum::<u64>() > MAX_PLACED_LAMP_TRIANGLES {
        lamp_placements.clear();
    }
    let is_lamp = &is_lamp;
    let placed = &placed;
    let own = move || {
        (objects.iter().zip(placed))
            .filter(|(_, p)| !**p)
            .flat_map(move |(o, _)| {
                (0..o.mesh.triangles.len()).filter_map(move |t| {
                    let m = material_of(o, t);
                    is_lamp[m]
                        .then(|| (m, o.mesh.triangles[t].map(|i| o.mesh.positions[i as usize])))
                })
            })
    };
    let placed_lamps = || {
        lamp_placements.iter().flat_map(move |p| {
            let o = &objects[p.object];
            let mirror = p.to_world.matrix3.determinant() < 0.0;
            (0..o.mesh.triangles.len()).filter_map(move |t| {
                let m = p.material.unwrap_or_else(|| material_of(o, t));
                is_lamp[m].then(|| {
                    let [a, b, c] = o.mesh.triangles[t]
                        .map(|i| p.to_world.transform_point3(o.mesh.positions[i as usize]));
                    (m, if mirror { [a, c, b] } else { [a, b, c] })
                })
            })
        })
    };
    let lamp_triangles = || {
        own().chain(placed_lamps()).filter_map(|(m, [a, b, d])| {
            let c = (b - a).cross(d - a);
            (c.length_squared() > 0.0).then(|| (m * 6 + bin(c), [a, b, d], c))
        })
    };
    // One pass to sum area, centroid and normal per (material, normal bin), one for the
    // frontmost vertex of each group: linear in the triangles whatever the number of lamps.
    let mut groups = vec![Group::default(); materials.len() * 6];
    for (g, [a, b, d], c) in lamp_triangles() {
        let area = 0.5 * c.length();
        let g = &mut groups[g];
        g.area += area;
        g.centroid += area * (a + b + d) / 3.0;
        g.normal += c;
    }
    let frame: Vec<(Vec3, Vec3)> = groups
        .iter()
        .enumerate()
        .map(|(k, g)| {
            let n = g.normal.try_normalize().unwrap_or(Vec3::AXES[(k % 6) / 2]);
            (g.centroid / g.area, n)
        })
        .collect();
    let mut front = vec![0.0f32; groups.len()];
    for (g, corners, _) in lamp_triangles() {
        let (centroid, n) = frame[g];
        for p in corners {
            front[g] = front[g].max((p - centroid).dot(n));
        }
    }
    let mut lights: Vec<(Vec3, Vec3)> = Vec::new();
    for (k, g) in groups.iter().enumerate() {
        if g.area > 0.0 && g.area.is_finite() {
            let (centroid, n) = frame[k];
            lights.push((
                centroid + n * (front[k] + margin),
                materials[k / 6].ke * g.area,
            ));
        }
    }
    let total = lights.iter().fold(Vec3::ZERO, |s, l| s + l.1).max_element();
    lights
        .into_iter()
        .filter(|_| total > 0.0 && total.is_finite())
        .map(|(position, power)| Light {
            position,
            intensity: power / total,
        })
        .collect()
}

/// The scene material of triangle `t` of `o`.
fn material_of(o: &Object, t: usize) -> usize {
    o.face_materials
        .as_ref()
        .map_or(o.material, |f| f[t] as usize)
}

/// Whether each material is a lamp (emits, and lights the scene).
fn lamps(materials: &[Material]) -> Vec<bool> {
    materials.iter().map(|m| m.lamp && m.emits()).collect()
}

/// The lamp faces a placement draws: all of its object's in a lamp material of its own,
/// else the object's faces in lamp materials (counted once per object).
fn placement_lamps<'a>(
    objects: &'a [Object],
    is_lamp: &'a [bool],
) -> impl Fn(&Placement) -> u64 + 'a {
    let own: Vec<u64> = (objects.iter())
        .map(|o| match &o.face_materials {
            None if is_lamp[o.material] => o.mesh.triangles.len() as u64,
            None => 0,
            Some(f) => f.iter().filter(|&&m| is_lamp[m as usize]).count() as u64,
        })
        .collect();
    move |p| match p.material {
        Some(m) if is_lamp[m] => objects[p.object].mesh.triangles.len() as u64,
        Some(_) => 0,
        None => own[p.object],
    }
}

/// Lamp triangles the placements draw (each placement's lamp faces): what
/// [`emitter_lights_placed`] carries into the world, against
/// [`MAX_PLACED_LAMP_TRIANGLES`].
pub fn placed_lamp_triangles(
    objects: &[Object],
    placements: &[Placement],
    materials: &[Material],
) -> u64 {
    let is_lamp = lamps(materials);
    let count = placement_lamps(objects, &is_lamp);
    placements.iter().map(count).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Albedo, shapes};

    fn material(name: &str, ke: Vec3) -> Material {
        Material {
            name: name.into(),
            albedo: Albedo::Color(Vec3::ONE),
            ka: Vec3::ZERO,
            kd: Vec3::ONE,
            ks: Vec3::ZERO,
            n: 1.0,
            kt: Vec3::ZERO,
            ior: 1.0,
            kr: Vec3::ZERO,
            ke,
            lamp: true,
        }
    }

    #[test]
    fn a_lamp_gives_one_light_in_front_of_it_and_a_box_one_per_side() {
        // A 0.5 x 0.5 lamp at y = 2 facing down, beside a floor of another material.
        let lamp = shapes::quad(Vec3::new(0.0, 2.0, 0.0), Vec3::X * 0.25, Vec3::Z * 0.25);
        let floor = shapes::quad(Vec3::ZERO, Vec3::X, Vec3::NEG_Z);
        let objects = vec![
            Object {
                name: "lamp".into(),
                mesh: lamp,
                material: 0,
                face_materials: None,
            },
            Object {
                name: "floor".into(),
                mesh: floor,
                material: 1,
                face_materials: None,
            },
        ];
        let materials = vec![
            material("lamp", Vec3::new(17.0, 12.0, 4.0)),
            material("floor", Vec3::ZERO),
        ];
        let lights = emitter_lights(&objects, &materials);
        assert_eq!(lights.len(), 1);
        let l = lights[0];
        // Just below the lamp (it faces -y), over its centre.
        assert!(l.position.x.abs() < 1e-6 && l.position.z.abs() < 1e-6);
        assert!(l.position.y < 2.0 && l.position.y > 1.99, "{}", l.position);
        // Ke's ratios, the brightest channel 1.
        assert!((l.intensity - Vec3::new(1.0, 12.0 / 17.0, 4.0 / 17.0)).length() < 1e-6);
        // A lamp box: one light per side, outside the box; they sum to a brightest channel of 1.
        let cube = Object {
            name: "cube".into(),
            mesh: shapes::cube(Vec3::ZERO, Vec3::splat(0.5)),
            material: 0,
            face_materials: None,
        };
        let lights = emitter_lights(&[cube], &materials);
        assert_eq!(lights.len(), 6);
        assert!(lights.iter().all(|l| l.position.abs().max_element() > 0.5));
        let total = lights.iter().map(|l| l.intensity).sum::<Vec3>();
        assert!((total.max_element() - 1.0).abs() < 1e-5);
        // Without lamps, nothing (lamp = false also turns a material's lights off).
        let mut off = materials.clone();
        off[0].lamp = false;
        assert!(emitter_lights(&objects, &off).is_empty());
    }
}
