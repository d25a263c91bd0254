//! `whitted info FILE`: what a mesh, scene, image or cube-map folder holds, after the same
//! validation as loading it for a render. As `key: value` lines or one JSON object.

use crate::error::{Error, Result};
use crate::io::image::{IMAGE_EXTENSIONS, ImageInfo, decode_texture, load_cubemap_info};
use crate::io::scene::{SceneFile, SearchPath, build_scene};
use crate::io::{MESH_EXTENSIONS, list_extensions, load_mesh_detail};
use crate::mesh::Mesh;
use crate::scene::Background;
use serde_json::{Value, json};
use std::path::Path;

/// An ordered list of facts about one file; `kind` comes first.
#[derive(Clone, Debug, PartialEq)]
pub struct Info {
    /// `(key, value)` in print order.
    pub fields: Vec<(&'static str, Value)>,
    /// Loader warnings (degenerate faces, ignored `.mtl`, ...).
    pub warnings: Vec<String>,
}

impl Info {
    /// The value of one field.
    pub fn get(&self, key: &str) -> Option<&Value> {
        self.fields.iter().find(|(k, _)| *k == key).map(|(_, v)| v)
    }

    /// One JSON object on one line: every field, plus `warnings`.
    pub fn to_json(&self) -> String {
        let mut map = serde_json::Map::new();
        for (k, v) in &self.fields {
            map.insert((*k).to_string(), v.clone());
        }
        map.insert("warnings".into(), json!(self.warnings));
        Value::Object(map).to_string()
    }

    /// `key: value` lines for people.
    pub fn to_text(&self) -> String {
        let mut out = String::new();
        for (k, v) in &self.fields {
            let v = match v {
                Value::String(s) => s.clone(),
                other => other.to_string(),
            };
            out.push_str(&format!("{k}: {v}\n"));
        }
        for w in &self.warnings {
            out.push_str(&format!("warning: {w}\n"));
        }
        out
    }
}

/// Inspect `path`: a folder is a cube map, `.m` / `.obj` / `.ply` / `.stl` / `.gltf` / `.glb` a
/// mesh, `.toml` a scene, anything else an image. Errors are the loaders' one-line errors.
pub fn info(path: &Path) -> Result<Info> {
    if path.is_dir() {
        let (cube, img) = load_cubemap_info(path)?;
        let mut info = image_fields("cubemap", &img);
        info.fields.push(("faces", json!(cube.faces.len())));
        return Ok(info);
    }
    let ext = crate::io::extension(path);
    match ext.as_str() {
        "gltf" | "glb" => gltf_info(path, &ext),
        e if crate::io::MESH_EXTENSIONS.contains(&e) => {
            let (mesh, warnings, file_normals) = load_mesh_detail(path)?;
            let mut info = mesh_fields(&mesh, &ext, file_normals);
            info.warnings = warnings;
            if ext == "obj" {
                // The materials its mtllib files bring (name, illum, colours, textures found).
                let (model, warnings) = crate::io::obj::load_obj_model(path)?;
                info.fields.push(("materials", json!(model.material_info)));
                info.warnings = warnings;
            }
            Ok(info)
        }
        "toml" => scene_info(path),
        _ => {
            let bytes = crate::io::read_regular(path)?;
            let known = IMAGE_EXTENSIONS.contains(&ext.as_str());
            // An image is also recognised by its content, whatever its name.
            match decode_texture(&bytes, path) {
                Ok((_, img)) => {
                    let mut info = image_fields("image", &img);
                    if img.format == "exr" {
                        info.fields.extend(exr_windows(&bytes));
                    }
                    Ok(info)
                }
                Err(Error::Image { msg, .. }) if !known && msg.starts_with("not a supported") => {
                    Err(Error::Format {
                        path: path.to_path_buf(),
                        msg: format!("not a file type whitted reads; {}", file_types()),
                    })
                }
                Err(e) => Err(e),
            }
        }
    }
}

/// A glTF model: the mesh statistics of what it stores (each mesh drawn more than once
/// counted once), the triangles it draws, the box of everything drawn, its meshes,
/// instances, lights and cameras as the file lists them, and its materials as whitted reads
/// them.
fn gltf_info(path: &Path, ext: &str) -> Result<Info> {
    let (model, warnings) = crate::io::load_model(path)?;
    let mut stored = model.mesh.clone();
    for s in &model.shared {
        stored.append(&s.model.mesh);
    }
    let file_normals = model.file_normals && model.shared.iter().all(|s| s.model.file_normals);
    let mut info = mesh_fields(&stored, ext, file_normals);
    info.warnings = warnings;
    let bounds = model
        .bounds()
        .map(|(lo, hi)| json!({"min": lo.to_array().map(short), "max": hi.to_array().map(short)}));
    for (k, v) in &mut info.fields {
        if *k == "bounds" {
            *v = bounds.clone().unwrap_or(Value::Null);
        }
    }
    info.fields
        .push(("drawn_triangles", json!(model.drawn_triangles())));
    // Through text, so that f32s print as written (0.8, not 0.800000011920929).
    let text = serde_json::to_string(&model.materials).expect("materials serialise");
    let materials: Value = serde_json::from_str(&text).expect("just written");
    let bytes = crate::io::read_regular(path)?;
    info.fields.extend(crate::io::gltf::listing(&bytes, path)?);
    info.fields.push(("materials", materials));
    Ok(info)
}

/// An EXR's display window (the whole image) and data window (the pixels stored: a part, for
/// `render --tile/--crop`), as `{"x": [x0, x1], "y": [y0, y1]}` with exclusive ends, and its
/// compression. The file decoded already, so its header is valid.
fn exr_windows(bytes: &[u8]) -> Vec<(&'static str, Value)> {
    let Ok(meta) = exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false)
    else {
        return Vec::new();
    };
    let Some(h) = meta.headers.first() else {
        return Vec::new();
    };
    let window = |x0: i32, y0: i32, w: usize, h: usize| json!({"x": [x0 as i64, x0 as i64 + w as i64], "y": [y0 as i64, y0 as i64 + h as i64]});
    let d = &h.shared_attributes.display_window;
    let p = h.own_attributes.layer_position;
    vec![
        (
            "display_window",
            window(d.position.0, d.position.1, d.size.0, d.size.1),
        ),
        (
            "data_window",
            window(p.0, p.1, h.layer_size.0, h.layer_size.1),
        ),
        (
            "compression",
            json!(format!("{:?}", h.compression).to_ascii_lowercase()),
        ),
    ]
}

/// What `whitted info` reads, for its message about a file it does not.
fn file_types() -> String {
    format!(
        "it reads meshes ({}), scenes (.toml), images ({}) and cube-map folders",
        list_extensions(&MESH_EXTENSIONS),
        list_extensions(&IMAGE_EXTENSIONS)
    )
}

/// An f32 as the f64 with the same shortest decimal form (0.1, not 0.10000000149011612).
fn short(x: f32) -> f64 {
    x.to_string().parse().unwrap_or(f64::NAN)
}

fn image_fields(kind: &str, img: &ImageInfo) -> Info {
    Info {
        fields: vec![
            ("kind", json!(kind)),
            ("format", json!(img.format)),
            ("width", json!(img.width)),
            ("height", json!(img.height)),
            ("channels", json!(img.channels)),
            ("bits", json!(img.bits)),
        ],
        warnings: Vec::new(),
    }
}

/// Counts, attributes, bounds, degenerate triangles and open edges of a loaded mesh.
pub fn mesh_fields(mesh: &Mesh, format: &str, file_normals: bool) -> Info {
    let mut attributes = Vec::new();
    if file_normals {
        attributes.push("normal");
    }
    if mesh.uvs.is_some() {
        attributes.push("uv");
    }
    if mesh.colors.is_some() {
        attributes.push("rgb");
    }
    let bounds = mesh
        .bounds()
        .map(|(lo, hi)| json!({"min": lo.to_array().map(short), "max": hi.to_array().map(short)}))
        .unwrap_or(Value::Null);
    Info {
        fields: vec![
            ("kind", json!("mesh")),
            ("format", json!(format)),
            ("vertices", json!(mesh.positions.len())),
            ("triangles", json!(mesh.triangles.len())),
            ("attributes", json!(attributes)),
            ("bounds", bounds),
            ("degenerate_triangles", json!(mesh.degenerate_count())),
            ("open_edges", json!(open_edges_by_position(mesh))),
        ],
        warnings: Vec::new(),
    }
}

/// Edges used by exactly one triangle, with vertices at the same position counted as one:
/// formats that split vertices at uv or normal seams (OBJ, PLY) leave a closed surface
/// closed. Positions are compared bit for bit (`-0.0` as `0.0`).
pub fn open_edges_by_position(mesh: &Mesh) -> usize {
    use std::collections::HashMap;
    let mut ids = HashMap::<[u32; 3], u32>::with_capacity(mesh.positions.len());
    let welded: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            let key = p.to_array().map(|c| (c + 0.0).to_bits());
            let next = ids.len() as u32;
            *ids.entry(key).or_insert(next)
        })
        .collect();
    let mut edges = HashMap::<(u32, u32), u32>::new();
    for tri in &mesh.triangles {
        let t = tri.map(|i| welded.get(i as usize).copied().unwrap_or(i));
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a != b {
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
    }
    edges.values().filter(|&&c| c == 1).count()
}

fn scene_info(path: &Path) -> Result<Info> {
    let file = SceneFile::load(path)?;
    scene_file_info(&file, path, path.parent())
}

/// What a scene holds after validation: `file` as read (or built in, or with `-D`
/// overrides), `path` its name in messages, `dir` the folder its relative paths start from.
pub fn scene_file_info(file: &SceneFile, path: &Path, dir: Option<&Path>) -> Result<Info> {
    let search = SearchPath::for_scene(dir);
    let (scene, warnings) = build_scene(file, path, &search)?;
    let background = match &scene.background {
        Background::Color(c) => json!({"color": c.to_array().map(short)}),
        Background::CubeMap(cube) => {
            json!({"cubemap": file.background.cubemap, "size": cube.faces[0].width})
        }
    };
    let mut placements = vec![0usize; scene.objects.len()];
    for p in &scene.instances {
        placements[p.object] += 1;
    }
    let objects: Vec<Value> = scene
        .objects
        .iter()
        .zip(&placements)
        .map(|(o, &placed)| {
            let mut v = json!({
                "name": o.name,
                "material": scene.materials.get(o.material).map(|m| m.name.as_str()),
                "vertices": o.mesh.positions.len(),
                "triangles": o.mesh.triangles.len(),
            });
            if placed > 0 {
                v["instances"] = json!(placed);
            }
            v
        })
        .collect();
    // the first placements, each as its mesh, material and 3x4 matrix (rows)
    let listed: Vec<Value> = scene
        .instances
        .iter()
        .take(MAX_LISTED_INSTANCES)
        .map(|p| {
            let m = p.to_world.matrix3;
            let t = p.to_world.translation;
            let row = |r: usize| [m.x_axis[r], m.y_axis[r], m.z_axis[r], t[r]].map(short);
            json!({
                "mesh": scene.objects[p.object].name,
                "material": p.material.map(|m| scene.materials[m].name.as_str()),
                "matrix": [row(0), row(1), row(2)],
            })
        })
        .collect();
    let mut instance_fields = Vec::new();
    if !scene.instances.is_empty() {
        instance_fields = vec![
            ("instances", json!(scene.instances.len())),
            ("instance_list", json!(listed)),
            ("stored_triangles", json!(scene.stored_triangle_count())),
        ];
    }
    let v = &scene.view;
    Ok(Info {
        fields: vec![
            ("kind", json!("scene")),
            ("width", json!(scene.width)),
            ("height", json!(scene.height)),
            ("depth", json!(scene.depth)),
            ("cull_backfaces", json!(scene.cull_backfaces)),
            (
                "camera",
                json!({"eye": v.eye.to_array().map(short), "look_at": v.look_at.to_array().map(short), "up": v.up.to_array().map(short), "vfov": short(v.vfov)}),
            ),
            ("background", background),
            ("lights", json!(scene.lights.len())),
            (
                "materials",
                json!(
                    scene
                        .materials
                        .iter()
                        .map(|m| m.name.as_str())
                        .collect::<Vec<_>>()
                ),
            ),
            ("objects", json!(objects)),
            ("triangles", json!(scene.triangle_count())),
        ]
        .into_iter()
        .chain(instance_fields)
        .collect(),
        warnings,
    })
}

/// Placements `whitted info` lists one by one (a scene may have millions); `instances` counts
/// them all.
pub const MAX_LISTED_INSTANCES: usize = 100;

/// `whitted info` as a library call: the text (or JSON) to print, or the one-line error.
pub fn run(path: &Path, as_json: bool) -> Result<String> {
    let info = info(path)?;
    Ok(if as_json {
        info.to_json() + "\n"
    } else {
        info.to_text()
    })
}

/// `whitted info ARG [-D key=value]...`: a built-in scene name (`phong`), or a file as for
/// [`run`]; `-D` overrides apply to scenes (built-in or `.toml`) only.
pub fn run_arg(arg: &str, defines: &[String], as_json: bool) -> Result<String> {
    let path = Path::new(arg);
    let builtin = crate::scenes::builtin(arg);
    if builtin.is_none() && defines.is_empty() {
        return run(path, as_json);
    }
    let (file, name, dir) = match builtin {
        Some(s) => (s, format!("<built-in scene {arg}>"), None),
        None if crate::io::extension(path) == "toml" => {
            (SceneFile::load(path)?, arg.to_string(), path.parent())
        }
        None => {
            return Err(Error::Usage(format!(
                "-D applies to scenes (a built-in name or a .toml file), not to '{arg}'"
            )));
        }
    };
    let file = file.with_overrides(defines)?;
    let info = scene_file_info(&file, Path::new(&name), dir)
        .map_err(|e| crate::io::scene::name_overrides(e, defines))?;
    Ok(if as_json {
        info.to_json() + "\n"
    } else {
        info.to_text()
    })
}

/// [`run_arg`], printed to stdout (a closed pipe is not an error worth a panic).
pub fn print(arg: &str, defines: &[String], as_json: bool) -> Result<()> {
    use std::io::Write;
    let text = run_arg(arg, defines, as_json)?;
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
    Ok(())
}
