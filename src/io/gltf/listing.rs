//! What `whitted info model.gltf` lists beside the mesh statistics: the file's meshes (with
//! the nodes that place them), how many mesh instances its nodes make, its lights and its
//! cameras, read from the JSON as written (the materials come from the loaded model, in
//! whitted's terms).

use super::{GLB_MAGIC, glb_chunks};
use crate::error::{Error, Result};
use serde_json::{Value, json};
use std::path::Path;

/// `meshes`, `instances`, `lights` and `cameras` of the glTF or GLB `bytes` at `path`, as
/// `whitted info` fields. `instances` counts the copies of meshes the nodes draw: one per
/// node that names a mesh, or its `EXT_mesh_gpu_instancing` count; each mesh lists its own.
pub fn listing(bytes: &[u8], path: &Path) -> Result<Vec<(&'static str, Value)>> {
    let (json, _) = if bytes.starts_with(GLB_MAGIC) {
        glb_chunks(bytes, path)?
    } else {
        (bytes, None)
    };
    let doc: Value = serde_json::from_slice(json).map_err(|e| {
        Error::parse(
            path,
            e.line(),
            format!("glTF JSON, column {}: {e}", e.column()),
        )
    })?;
    let list = |key: &str| {
        doc.get(key)
            .and_then(Value::as_array)
            .cloned()
            .unwrap_or_default()
    };
    let name = |v: &Value| v.get("name").and_then(Value::as_str).map(str::to_string);
    let nodes = list("nodes");
    let accessors = list("accessors");
    let count = |i: Option<u64>| {
        i.and_then(|i| accessors.get(i as usize))
            .and_then(|a| a.get("count"))
            .and_then(Value::as_u64)
            .unwrap_or(0)
    };
    // the copies a node draws: one, or its `EXT_mesh_gpu_instancing` attributes' count
    let copies = |n: &Value| {
        n.pointer("/extensions/EXT_mesh_gpu_instancing/attributes")
            .and_then(Value::as_object)
            .and_then(|a| a.values().next())
            .map_or(1, |a| count(a.as_u64()))
    };
    let meshes: Vec<Value> = list("meshes")
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let prims = m
                .get("primitives")
                .and_then(Value::as_array)
                .cloned()
                .unwrap_or_default();
            let triangles: u64 = prims
                .iter()
                .map(|p| {
                    let indices = p.get("indices").and_then(Value::as_u64);
                    let position = p.pointer("/attributes/POSITION").and_then(Value::as_u64);
                    count(indices.or(position)) / 3
                })
                .sum();
            let placed_by: Vec<usize> = (0..nodes.len())
                .filter(|&n| nodes[n].get("mesh").and_then(Value::as_u64) == Some(i as u64))
                .collect();
            let instances: u64 = placed_by.iter().map(|&n| copies(&nodes[n])).sum();
            json!({
                "index": i,
                "name": name(m),
                "primitives": prims.len(),
                "triangles": triangles,
                "nodes": placed_by,
                "instances": instances,
            })
        })
        .collect();
    let instances: u64 = (nodes.iter())
        .filter(|n| n.get("mesh").is_some())
        .map(copies)
        .sum();
    let lights: Vec<Value> = doc
        .pointer("/extensions/KHR_lights_punctual/lights")
        .and_then(Value::as_array)
        .cloned()
        .unwrap_or_default()
        .iter()
        .enumerate()
        .map(|(i, l)| {
            json!({
                "index": i,
                "name": name(l),
                "type": l.get("type"),
                "color": l.get("color").cloned().unwrap_or(json!([1.0, 1.0, 1.0])),
                "intensity": l.get("intensity").cloned().unwrap_or(json!(1.0)),
            })
        })
        .collect();
    let cameras: Vec<Value> = list("cameras")
        .iter()
        .enumerate()
        .map(|(i, c)| {
            let kind = c.get("type").and_then(Value::as_str).unwrap_or("");
            let mut v = json!({"index": i, "name": name(c), "type": kind});
            if let Some(y) = c.pointer("/perspective/yfov").and_then(Value::as_f64) {
                v["yfov_degrees"] = json!((y.to_degrees() * 1e3).round() / 1e3);
            }
            v
        })
        .collect();
    Ok(vec![
        ("meshes", json!(meshes)),
        ("instances", json!(instances)),
        ("lights", json!(lights)),
        ("cameras", json!(cameras)),
    ])
}
