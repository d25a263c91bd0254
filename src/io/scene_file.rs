//! The TOML scene format: parsing (`deny_unknown_fields`), validation, search-path resolution.
//!
//! Relative file names resolve against the scene file's folder, then the current folder, then
//! each folder of `WHITTED_ASSETS` (`:`-separated). See the README for the format.

use crate::error::{Error, Result};
use crate::io::image::{load_cubemap, load_texture};
use crate::io::load_scene_model;
use crate::io::obj::{Model, NO_MATERIAL};
use crate::mesh::Mesh;
use crate::scene::{Albedo, Background, Light, Material, Object, Scene, View, shapes};
use crate::texture::Texture;
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Largest image accepted, in pixels (checked in u64 before anything is allocated):
/// 2^28 = 268M pixels, e.g. 16384 x 16384 (7680 x 4320 is 33M).
pub const MAX_PIXELS: u64 = 1 << 28;
/// Deepest reflection / refraction recursion accepted.
pub const MAX_DEPTH: u32 = 64;
/// Most subdivision levels (each multiplies triangles by 4).
pub const MAX_SUBDIVIDE: u32 = 6;
/// Most triangles subdivision may make in a whole scene (checked before subdividing): a
/// one-line `subdivide = 6` multiplies a mesh by 4096, so this budget is far below the cap on
/// triangles read from files.
pub const MAX_SUBDIVIDED_TRIANGLES: u64 = 1 << 20;
/// Most triangles a whole scene may hold (after subdivision), checked mesh by mesh.
pub const MAX_SCENE_TRIANGLES: u64 = 1 << 25;
/// Most texels all `checker` materials of a scene may allocate together (2 of 4096 x 4096).
pub const MAX_CHECKER_TEXELS: u64 = 1 << 25;

/// A scene file as written: the TOML format of the README, before validation. [`build_scene`]
/// turns it into a [`Scene`]; [`scenes::builtin`](crate::scenes::builtin) makes the built-in ones.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// `[image]`: the output size (optional, default 1024 x 768).
    #[serde(default)]
    pub image: ImageDesc,
    /// `[camera]`: the pinhole camera (required: `eye` and `look_at`).
    pub camera: CameraDesc,
    /// `[render]`: depth, culling, ambient light (all optional).
    #[serde(default)]
    pub render: RenderDesc,
    /// `[background]`: a colour or a cube map (optional, default the canonical colour
    /// [`DEFAULT_BACKGROUND`]).
    #[serde(default)]
    pub background: BackgroundDesc,
    /// `[[light]]`: point lights.
    #[serde(default, rename = "light", skip_serializing_if = "Vec::is_empty")]
    pub lights: Vec<LightDesc>,
    /// `[[material]]`: named materials.
    #[serde(default, rename = "material", skip_serializing_if = "Vec::is_empty")]
    pub materials: Vec<MaterialDesc>,
    /// `[[mesh]]`: meshes from files, inline triangles or generated shapes.
    #[serde(default, rename = "mesh", skip_serializing_if = "Vec::is_empty")]
    pub meshes: Vec<MeshDesc>,
    /// Lines of the keys in the text this was parsed from (empty for scenes made in code).
    #[serde(skip)]
    pub lines: KeyLines,
}

/// The 1-based line of each key of a scene file's text, by its path (`background.cubemap`,
/// `mesh[1].file`), so that errors about the files a key names can point at the key. Source
/// positions are not part of a scene's value: any two `KeyLines` compare equal.
#[derive(Clone, Debug, Default)]
pub struct KeyLines(Vec<(String, usize)>);

impl PartialEq for KeyLines {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl KeyLines {
    /// Read the key positions of TOML text (empty when it does not parse).
    pub fn of(text: &str) -> KeyLines {
        use toml::de::{DeTable, DeValue};
        let mut out = Vec::new();
        let Ok(doc) = DeTable::parse(text) else {
            return KeyLines(out);
        };
        // Newline offsets, found once: a line is a binary search (a scene of thousands of
        // entries would otherwise rescan its text per key).
        let newlines: Vec<usize> = text
            .bytes()
            .enumerate()
            .filter_map(|(i, b)| (b == b'\n').then_some(i))
            .collect();
        let line = |at: usize| newlines.partition_point(|&n| n < at) + 1;
        let table = |prefix: String, t: &DeTable, out: &mut Vec<(String, usize)>| {
            for (k, _) in t.iter() {
                out.push((format!("{prefix}.{}", k.get_ref()), line(k.span().start)));
            }
        };
        for (k, v) in doc.get_ref().iter() {
            let name = k.get_ref().to_string();
            match v.get_ref() {
                DeValue::Table(t) => table(name, t, &mut out),
                DeValue::Array(items) => {
                    for (i, item) in items.into_iter().enumerate() {
                        if let DeValue::Table(t) = item.get_ref() {
                            table(format!("{name}[{i}]"), t, &mut out);
                        }
                    }
                }
                _ => out.push((name, line(k.span().start))),
            }
        }
        KeyLines(out)
    }

    /// The line of `key` (as `mesh[1].file`), if the text had it.
    pub fn line(&self, key: &str) -> Option<usize> {
        self.0.iter().find(|(k, _)| k == key).map(|&(_, l)| l)
    }
}

/// `[image]`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ImageDesc {
    /// Pixels across (default 1024; the image must have at most `MAX_PIXELS`).
    #[serde(default = "default_width")]
    pub width: u64,
    /// Pixels down (default 768).
    #[serde(default = "default_height")]
    pub height: u64,
}

impl Default for ImageDesc {
    fn default() -> Self {
        ImageDesc {
            width: default_width(),
            height: default_height(),
        }
    }
}

fn default_width() -> u64 {
    1024
}
fn default_height() -> u64 {
    768
}

/// `[camera]` (SCENES.md §1).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CameraDesc {
    /// The eye point.
    #[serde(deserialize_with = "exact3::de")]
    pub eye: [f32; 3],
    /// The point looked at.
    #[serde(deserialize_with = "exact3::de")]
    pub look_at: [f32; 3],
    /// The up direction (default +y); must not be parallel to the view direction.
    #[serde(default = "default_up", deserialize_with = "exact3::de")]
    pub up: [f32; 3],
    /// Vertical field of view in degrees, in (0, 180) (default 36, the canonical view's).
    #[serde(default = "default_vfov")]
    pub vfov: f32,
}

fn default_vfov() -> f32 {
    36.0
}

/// `[T; 3]` fields that refuse arrays of any other length (serde's array impl would let TOML
/// ignore extra elements).
mod exact3 {
    use serde::de::{Deserialize, Deserializer, Error};

    fn three<T, E: Error>(v: Vec<T>) -> Result<[T; 3], E> {
        let n = v.len();
        v.try_into()
            .map_err(|_| E::invalid_length(n, &"an array of 3 numbers"))
    }

    pub fn de<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<[T; 3], D::Error> {
        three(Vec::deserialize(d)?)
    }

    pub fn opt<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<[T; 3]>, D::Error> {
        Option::<Vec<T>>::deserialize(d)?.map(three).transpose()
    }

    pub fn opt_vec<'de, D: Deserializer<'de>, T: Deserialize<'de>>(
        d: D,
    ) -> Result<Option<Vec<[T; 3]>>, D::Error> {
        Option::<Vec<Vec<T>>>::deserialize(d)?
            .map(|v| v.into_iter().map(three).collect())
            .transpose()
    }
}

fn default_up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}

/// `[render]`.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RenderDesc {
    /// Reflection / refraction bounces (default 1, at most `MAX_DEPTH`).
    #[serde(default = "default_depth")]
    pub depth: u32,
    /// Skip back faces, for every ray (default true).
    #[serde(default = "default_true")]
    pub cull_backfaces: bool,
    /// Ambient light `Ia` (default SCENES.md's `[0.15, 0.15, 0.18]`, [`DEFAULT_AMBIENT`]).
    #[serde(default = "default_ambient", deserialize_with = "exact3::de")]
    pub ambient: [f32; 3],
}

impl Default for RenderDesc {
    fn default() -> Self {
        RenderDesc {
            depth: default_depth(),
            cull_backfaces: true,
            ambient: DEFAULT_AMBIENT,
        }
    }
}

/// The ambient light `Ia` of a scene that does not give one (SCENES.md's).
pub const DEFAULT_AMBIENT: [f32; 3] = [0.15, 0.15, 0.18];

fn default_ambient() -> [f32; 3] {
    DEFAULT_AMBIENT
}

fn default_depth() -> u32 {
    1
}
fn default_true() -> bool {
    true
}
fn is_true(v: &bool) -> bool {
    *v
}

/// The background colour when a scene gives neither `color` nor `cubemap` (SCENES.md's).
pub const DEFAULT_BACKGROUND: [f32; 3] = [0.1, 0.12, 0.16];

/// `[background]`: at most one of `color` or `cubemap` (neither: [`DEFAULT_BACKGROUND`]).
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BackgroundDesc {
    /// A constant colour (linear RGB).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact3::opt"
    )]
    pub color: Option<[f32; 3]>,
    /// A folder with `posx negx posy negy posz negz` images.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cubemap: Option<String>,
}

/// `[[light]]`: a point light.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct LightDesc {
    /// Where it is.
    #[serde(deserialize_with = "exact3::de")]
    pub position: [f32; 3],
    /// Its RGB intensity `Ip` (>= 0).
    #[serde(deserialize_with = "exact3::de")]
    pub intensity: [f32; 3],
}

/// `[[material]]`: Whitted's coefficients and where `Od` comes from.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialDesc {
    /// The name meshes refer to it by (unique).
    pub name: String,
    /// At most one of `color`, `vertex_color = true`, `texture` or `checker` gives `Od`
    /// (none: `color = [0.8, 0.8, 0.8]`, [`DEFAULT_COLOR`]).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact3::opt"
    )]
    pub color: Option<[f32; 3]>,
    /// `Od` is the interpolated vertex `rgb` of the mesh; `color`, if also given, colours the
    /// vertices of a `.m` file that gives only some of them an rgb (white without it).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub vertex_color: bool,
    /// `Od` from an image file at the interpolated uv.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<String>,
    /// `Od` from a procedural checker at the interpolated uv.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub checker: Option<CheckerDesc>,
    /// Ambient coefficient: a number (the same in every channel) or `[r, g, b]` (default 0.3).
    #[serde(default = "default_ka")]
    pub ka: Coef,
    /// Diffuse coefficient (a number or `[r, g, b]`, default 0.7).
    #[serde(default = "default_kd")]
    pub kd: Coef,
    /// Specular (and, unless `kr` is given, reflection) coefficient (a number or `[r, g, b]`,
    /// default 0.1; when `ks` is omitted, `kr` defaults to 0, as in [`default_material`]).
    #[serde(default = "default_ks")]
    pub ks: Coef,
    /// Phong exponent (default 40).
    #[serde(default = "default_n")]
    pub n: f32,
    /// Transmission coefficient (default 0; a number or `[r, g, b]`).
    #[serde(default, skip_serializing_if = "Coef::is_zero")]
    pub kt: Coef,
    /// Index of refraction (default 1.5, > 0).
    #[serde(default = "default_ior")]
    pub ior: f32,
    /// Weight of the reflection ray; omitted = `ks` (Whitted's one coefficient for both).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kr: Option<Coef>,
    /// Emitted colour: shown on the surface and, with `lamp` (default true), point lights.
    #[serde(default, skip_serializing_if = "Coef::is_zero")]
    pub ke: Coef,
    /// Whether `ke` also lights the scene through point lights (default true).
    #[serde(default = "default_true", skip_serializing_if = "is_true")]
    pub lamp: bool,
}

fn default_ior() -> f32 {
    1.5
}
fn default_ka() -> Coef {
    Coef::Scalar(0.3)
}
fn default_kd() -> Coef {
    Coef::Scalar(0.7)
}
fn default_ks() -> Coef {
    Coef::Scalar(0.1)
}
fn default_n() -> f32 {
    40.0
}

/// A material coefficient: one number for all three channels, or an RGB triple.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Coef {
    /// The same value in every channel.
    Scalar(f32),
    /// One value per channel, `[r, g, b]`.
    Rgb([f32; 3]),
}

impl Default for Coef {
    fn default() -> Self {
        Coef::Scalar(0.0)
    }
}

impl From<f32> for Coef {
    fn from(v: f32) -> Self {
        Coef::Scalar(v)
    }
}

impl Coef {
    /// The value per channel.
    pub fn rgb(self) -> [f32; 3] {
        match self {
            Coef::Scalar(v) => [v; 3],
            Coef::Rgb(c) => c,
        }
    }

    /// Whether every channel is 0.
    pub fn is_zero(&self) -> bool {
        self.rgb() == [0.0; 3]
    }
}

impl Serialize for Coef {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Coef::Scalar(v) => s.serialize_f32(*v),
            Coef::Rgb(c) => c.serialize(s),
        }
    }
}

impl<'de> Deserialize<'de> for Coef {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Coef;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an array of 3 numbers [r, g, b]")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<Coef, E> {
                Ok(Coef::Scalar(v as f32))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<Coef, E> {
                Ok(Coef::Scalar(v as f32))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<Coef, E> {
                Ok(Coef::Scalar(v as f32))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<Coef, A::Error> {
                let mut c = Vec::new();
                while let Some(x) = seq.next_element::<f32>()? {
                    if c.len() == 3 {
                        return Err(serde::de::Error::invalid_length(4, &self));
                    }
                    c.push(x);
                }
                let n = c.len();
                c.try_into()
                    .map(Coef::Rgb)
                    .map_err(|_| serde::de::Error::invalid_length(n, &self))
            }
        }
        d.deserialize_any(V)
    }
}

/// A procedural checker texture: `squares x squares` cells alternating `a` and `b` (linear RGB).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CheckerDesc {
    /// Cells per side, in 1..=4096.
    pub squares: u32,
    /// The colour of cell (0, 0)'s kind.
    #[serde(deserialize_with = "exact3::de")]
    pub a: [f32; 3],
    /// The other colour.
    #[serde(deserialize_with = "exact3::de")]
    pub b: [f32; 3],
}

/// `[[mesh]]`: exactly one of `file`, `vertices` + `faces`, or `shape`.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MeshDesc {
    /// A name for messages and `whitted info` (default: the file name or `meshN`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// The scene material of the whole mesh. Omitted (files only): the file's own materials
    /// (OBJ `mtllib`/`usemtl`), each replaced by a scene material of the same name if there
    /// is one, and [`DEFAULT_MATERIAL`] for faces without one.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub material: String,
    /// A `.m` or `.obj` file ...
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub file: Option<String>,
    /// ... or inline triangles (`vertices` + `faces`, 0-based, CCW = front) ...
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact3::opt_vec"
    )]
    pub vertices: Option<Vec<[f32; 3]>>,
    /// Triangles of the inline vertices (0-based indices).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact3::opt_vec"
    )]
    pub faces: Option<Vec<[u32; 3]>>,
    /// ... or a generated shape: `sphere` (center, radius), `cube` (center, size), `quad`
    /// (center, size; a horizontal square facing +y).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shape: Option<String>,
    /// Centre of a generated shape (default the origin).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact3::opt"
    )]
    pub center: Option<[f32; 3]>,
    /// Radius of a `sphere` (default 1).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    /// Size of a `cube` (x, y, z) or a `quad` (x, z) (default 1).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact3::opt"
    )]
    pub size: Option<[f32; 3]>,
    /// Midpoint subdivision levels applied after loading (each x4 triangles).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub subdivide: u32,
}

fn is_zero(v: &u32) -> bool {
    *v == 0
}

impl SceneFile {
    /// Parse TOML text; errors carry the line and column of the offending key.
    pub fn parse(text: &str, path: &Path) -> Result<SceneFile> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut file: SceneFile = toml::from_str(text).map_err(|e| {
            let (line, col) = e
                .span()
                .map(|s| line_col(text.as_bytes(), s.start))
                .unwrap_or((0, 0));
            // toml's messages span several lines (a source excerpt); keep the first line.
            let msg = e.message().lines().next().unwrap_or("invalid TOML").trim();
            Error::parse(path, line, format!("column {col}: {msg}"))
        })?;
        file.lines = KeyLines::of(text);
        // `kr` omitted = `ks`, but a material that gives neither gets the default material's
        // no reflection (a material with only a colour renders like a mesh's default).
        for (i, m) in file.materials.iter_mut().enumerate() {
            let given = |k: &str| file.lines.line(&format!("material[{i}].{k}")).is_some();
            if m.kr.is_none() && !given("ks") && !given("kr") {
                m.kr = Some(Coef::Scalar(0.0));
            }
        }
        Ok(file)
    }

    /// The image size, checked against the pixel cap; the error names the scene and the
    /// line of its `[image]` keys.
    pub fn image_size(&self, path: &Path) -> Result<(u32, u32)> {
        check_size(self.image.width, self.image.height)
            .map_err(|m| locate(self, Error::scene(path, format!("image: {m}"))))
    }

    /// Read and parse a scene file; bytes that are not UTF-8 are refused with their line. An
    /// image given where a scene is expected is refused by its extension, with how to make a
    /// scene for it (a mesh file is made a scene by
    /// [`scene_for_mesh`](crate::io::mesh_scene::scene_for_mesh) instead).
    pub fn load(path: &Path) -> Result<SceneFile> {
        not_a_scene(path)?;
        let bytes = crate::io::read_regular(path)?;
        let text = std::str::from_utf8(&bytes).map_err(|e| {
            let (line, col) = line_col(&bytes, e.valid_up_to());
            Error::parse(path, line, format!("column {col}: invalid UTF-8"))
        })?;
        SceneFile::parse(text, path)
    }

    /// The scene as TOML text (what `whitted scene NAME` prints).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("scene serialises")
    }
}

/// The index `[+]` stands for in a `-D` key: a new entry at the end of the array.
const APPEND: usize = usize::MAX;

/// One `-D key=value` override: a TOML path (`camera.vfov`, `light[0].intensity`) and a TOML
/// value (`30`, `[1, 1, 1]`, `true`, `"name"`; anything that does not parse as TOML is taken
/// as a string, so `-D background.cubemap=textures/cubemap` needs no quotes).
fn apply_override(root: &mut toml::Value, def: &str) -> std::result::Result<(), String> {
    let (key, value) = def
        .split_once('=')
        .ok_or("expected key=value (e.g. camera.vfov=30)")?;
    let key = key.trim();
    let value = value.trim();
    let value = toml::from_str::<toml::Table>(&format!("v = {value}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
        .unwrap_or_else(|| toml::Value::String(value.to_string()));
    let mut segments = Vec::new();
    for seg in key.split('.') {
        let (name, index) = match seg.split_once('[') {
            Some((name, rest)) => {
                let i = rest
                    .strip_suffix(']')
                    .and_then(|i| {
                        if i == "+" {
                            Some(APPEND)
                        } else {
                            i.parse::<usize>().ok()
                        }
                    })
                    .ok_or_else(|| format!("'{seg}': expected name[index] or name[+]"))?;
                (name, Some(i))
            }
            None => (seg, None),
        };
        if name.is_empty() {
            return Err(format!("'{key}': empty name in the key"));
        }
        segments.push((name, index));
    }
    let last = segments.len() - 1;
    // Setting one source of a table's exclusive group (background colour or cube map, a
    // material's colour source, a mesh's geometry) replaces the others.
    let replaced: &[&str] = match (segments.len(), segments[0].0, segments[last].0) {
        (2, "background", "color") => &["cubemap"],
        (2, "background", "cubemap") => &["color"],
        (2, "material", "color") => &["texture", "checker"],
        (2, "material", "vertex_color") => &["texture", "checker"],
        (2, "material", "texture") => &["color", "vertex_color", "checker"],
        (2, "material", "checker") => &["color", "vertex_color", "texture"],
        (2, "mesh", "file") => &["vertices", "faces", "shape", "center", "radius", "size"],
        (2, "mesh", "vertices" | "faces") => &["file", "shape", "center", "radius", "size"],
        (2, "mesh", "shape") => &["file", "vertices", "faces"],
        _ => &[],
    };
    let mut node = root;
    for (k, (name, index)) in segments.into_iter().enumerate() {
        let toml::Value::Table(table) = node else {
            return Err(format!("'{name}': its parent is not a table"));
        };
        if k == last && index.is_none() {
            for r in replaced {
                table.remove(*r);
            }
            table.insert(name.to_string(), value);
            return Ok(());
        }
        let entry = table.entry(name.to_string()).or_insert_with(|| {
            if index.is_some() {
                toml::Value::Array(Vec::new())
            } else {
                toml::Value::Table(toml::Table::new())
            }
        });
        node = match index {
            None => entry,
            Some(i) => {
                let toml::Value::Array(items) = entry else {
                    return Err(format!("'{name}' is not an array"));
                };
                // One past the end, or `[+]`, appends a new entry (a light, material or mesh).
                let i = if i == items.len() || i == APPEND {
                    items.push(toml::Value::Table(toml::Table::new()));
                    items.len() - 1
                } else {
                    i
                };
                let n = items.len();
                let item = items
                    .get_mut(i)
                    .ok_or_else(|| format!("'{name}' has {n} entries (index 0..={n})"))?;
                if k == last {
                    *item = value;
                    return Ok(());
                }
                item
            }
        };
    }
    unreachable!("the last segment returns")
}

impl SceneFile {
    /// Apply `-D key=value` overrides in order, each checked as the file is (unknown keys,
    /// types); errors name the `-D` argument. Values are validated by [`build_scene`].
    pub fn with_overrides(&self, defs: &[String]) -> Result<SceneFile> {
        if defs.is_empty() {
            return Ok(self.clone());
        }
        let mut root = toml::Value::try_from(self).expect("scene serialises");
        let first_line = |e: toml::de::Error| {
            e.message()
                .lines()
                .next()
                .unwrap_or("invalid")
                .trim()
                .to_string()
        };
        // A key a later -D may still give (`-D light[2].position=..` then `.intensity`).
        let mut incomplete: Option<&str> = None;
        for def in defs {
            let fail = |m: String| Error::Usage(format!("-D '{def}': {m}"));
            apply_override(&mut root, def).map_err(fail)?;
            self.follow_ks(&mut root, def);
            fill_material_defaults(&mut root);
            // Check each override at once, so the error names the one that broke the scene.
            match SceneFile::deserialize(root.clone()) {
                Ok(_) => incomplete = None,
                Err(e) if e.message().starts_with("missing field") => {
                    incomplete = incomplete.or(Some(def));
                }
                Err(e) => return Err(fail(first_line(e))),
            }
        }
        let mut file = SceneFile::deserialize(root).map_err(|e| {
            let def = incomplete.unwrap_or("");
            Error::Usage(format!("-D '{def}': {}", first_line(e)))
        })?;
        // Errors about the files the scene names still point at the lines of its text.
        file.lines = self.lines.clone();
        Ok(file)
    }
}

impl SceneFile {
    /// `-D material[i].ks=..` on a material whose file gave neither `ks` nor `kr` (so `kr`
    /// was set to 0 when it was read): `ks` is given now, so `kr` follows it, as in a file.
    fn follow_ks(&self, root: &mut toml::Value, def: &str) {
        let key = def.split_once('=').map_or(def, |(k, _)| k).trim();
        let Some(i) = key
            .strip_prefix("material[")
            .and_then(|r| r.strip_suffix("].ks"))
            .and_then(|i| i.parse::<usize>().ok())
        else {
            return;
        };
        let given = |k: &str| self.lines.line(&format!("material[{i}].{k}")).is_some();
        let filled = self
            .materials
            .get(i)
            .is_some_and(|m| m.kr == Some(Coef::Scalar(0.0)))
            && !self.lines.0.is_empty()
            && !given("ks")
            && !given("kr");
        if filled
            && let Some(toml::Value::Array(items)) = root.get_mut("material")
            && let Some(toml::Value::Table(t)) = items.get_mut(i)
        {
            t.remove("kr");
        }
    }
}

/// A material appended by `-D` that gives neither `ks` nor `kr` reflects nothing, as one
/// written in a file without them (see [`SceneFile::parse`]).
fn fill_material_defaults(root: &mut toml::Value) {
    let Some(toml::Value::Array(items)) = root.get_mut("material") else {
        return;
    };
    for item in items {
        if let toml::Value::Table(t) = item
            && !t.contains_key("ks")
            && !t.contains_key("kr")
        {
            t.insert("kr".into(), toml::Value::Float(0.0));
        }
    }
}

/// Give a validation error about a key the line of that key (or of its table) in the
/// scene's text: `scene.toml:12: material[0] 'kitten'.ior: ...`. Other errors, and scenes
/// not read from text, are returned as they are.
fn locate(file: &SceneFile, e: Error) -> Error {
    let Error::Scene { path, msg } = e else {
        return e;
    };
    // `material[0] 'kitten'.ior: ...` is about the key `material[0].ior`.
    let mut key = String::new();
    let mut quoted = false;
    for c in msg.chars() {
        match c {
            '\'' => quoted = !quoted,
            _ if quoted => {}
            ' ' => {}
            c if c.is_ascii_alphanumeric() || "_.[]".contains(c) => key.push(c),
            _ => break,
        }
    }
    let lines = &file.lines;
    // The key's own line, else the first line of the keys under it (a table's first key).
    let find = |k: &str| {
        lines.line(k).or_else(|| {
            lines
                .0
                .iter()
                .filter(|(x, _)| x.starts_with(&format!("{k}.")) || x.starts_with(&format!("{k}[")))
                .map(|&(_, l)| l)
                .min()
        })
    };
    let mut k = key.as_str();
    while !k.is_empty() {
        if let Some(line) = find(k) {
            return Error::Parse { path, line, msg };
        }
        k = match k.rfind(['.', '[']) {
            Some(at) => &k[..at],
            None => "",
        };
    }
    Error::Scene { path, msg }
}

/// A validation error about a value set by `-D`, with the argument named:
/// `... (set by -D 'camera.vfov=200')`. Other errors are returned as they are.
pub fn name_overrides(e: Error, defs: &[String]) -> Error {
    let msg = e.to_string();
    match overrides_named(&msg, defs)[..] {
        [] => e,
        ref named => Error::Usage(format!(
            "{msg} (set by {})",
            named
                .iter()
                .map(|d| format!("-D '{d}'"))
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

/// The `-D` arguments a validation message is about: the key, or its array entry and last
/// name (messages write `material[0] 'glass'.kd` for `material[0].kd`).
pub fn overrides_named<'a>(message: &str, defs: &'a [String]) -> Vec<&'a str> {
    defs.iter()
        .map(String::as_str)
        .filter(|d| {
            let key = d.split_once('=').map_or(*d, |(k, _)| k).trim();
            if message.contains(key) {
                return true;
            }
            match (key.split_once('.'), key.rsplit_once('.')) {
                (Some((first, _)), Some((_, last))) => {
                    // `image: ...` is about every key of `[image]`.
                    message.contains(&format!(" {first}: "))
                        || (message.contains(first) && message.contains(&format!(".{last}")))
                }
                _ => false,
            }
        })
        .collect()
}

/// Refuse an image, a mesh or a file of an unknown type given as a scene (TOML would call it
/// `key with no value`), naming the types read. The CLI renders a mesh file given as the
/// scene directly (see [`crate::io::mesh_scene`]) before any scene file is loaded.
fn not_a_scene(path: &Path) -> Result<()> {
    let ext = crate::io::extension(path);
    if ext == "toml" || ext.is_empty() {
        return Ok(());
    }
    if crate::io::MESH_EXTENSIONS.contains(&ext.as_str()) {
        return Err(Error::Format {
            path: path.to_path_buf(),
            msg: format!(
                "this is a mesh (.{ext}), but a scene file (.toml) is expected; \
                 `whitted scene {} > my.toml` makes one that renders it",
                path.display()
            ),
        });
    }
    if !crate::io::image::IMAGE_EXTENSIONS.contains(&ext.as_str()) {
        return Err(Error::Format {
            path: path.to_path_buf(),
            msg: format!(
                "unknown file type '.{ext}'; a scene is a .toml file, a mesh is {}",
                crate::io::list_extensions(&crate::io::MESH_EXTENSIONS)
            ),
        });
    }
    Err(Error::Format {
        path: path.to_path_buf(),
        msg: format!(
            "this is an image (.{ext}), but a scene file (.toml) is expected; make one with \
             `whitted scene phong > my.toml`, set a material's texture to \"{}\", then \
             `whitted render my.toml`",
            path.display()
        ),
    })
}

/// 1-based (line, column in characters) of byte offset `at`, clamped to the text.
fn line_col(text: &[u8], at: usize) -> (usize, usize) {
    let before = &text[..at.min(text.len())];
    let line_start = before
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    let line = before.iter().filter(|&&b| b == b'\n').count() + 1;
    // Count characters, not bytes (continuation bytes 10xxxxxx do not start one).
    let col = before[line_start..]
        .iter()
        .filter(|&&b| b & 0xC0 != 0x80)
        .count()
        + 1;
    (line, col)
}

/// The project's own data folder (holding the shipped `meshes/` and `textures/`), fixed at
/// compile time: the last folder of every [`SearchPath::for_scene`], so the built-in scenes
/// work from any working directory with no environment variable, also after `cargo install
/// --path .` (as long as the source folder stays where it was built).
pub const PROJECT_DATA: &str = env!("CARGO_MANIFEST_DIR");

/// Where scene files look for meshes and images.
#[derive(Clone, Debug, Default)]
pub struct SearchPath {
    /// Folders tried in order; the first that holds the name wins.
    pub dirs: Vec<PathBuf>,
}

impl SearchPath {
    /// The scene's folder (if any), the current folder, the `WHITTED_ASSETS` folders, then
    /// the project's own data ([`PROJECT_DATA`]). A folder listed twice is tried once.
    pub fn for_scene(scene_dir: Option<&Path>) -> Self {
        let mut dirs = Vec::new();
        if let Some(d) = scene_dir {
            dirs.push(if d.as_os_str().is_empty() {
                PathBuf::from(".")
            } else {
                d.to_path_buf()
            });
        }
        dirs.push(std::env::current_dir().unwrap_or_else(|_| PathBuf::from(".")));
        if let Some(list) = std::env::var_os("WHITTED_ASSETS") {
            dirs.extend(std::env::split_paths(&list).filter(|p| !p.as_os_str().is_empty()));
        }
        dirs.push(PathBuf::from(PROJECT_DATA));
        let mut unique: Vec<PathBuf> = Vec::with_capacity(dirs.len());
        for d in dirs {
            if !unique.iter().any(|u| same_dir(u, &d)) {
                unique.push(d);
            }
        }
        SearchPath { dirs: unique }
    }

    /// The first existing `dir/name`; an absolute `name` is used as it is. The error lists
    /// every folder searched.
    pub fn resolve(&self, name: &str) -> Result<PathBuf> {
        let p = Path::new(name);
        if p.is_absolute() {
            return if p.exists() {
                Ok(p.to_path_buf())
            } else {
                Err(Error::NotFound {
                    name: name.into(),
                    searched: vec![p.parent().unwrap_or(p).to_path_buf()],
                })
            };
        }
        self.dirs
            .iter()
            // `./meshes/x.m` reads better in messages as `meshes/x.m`.
            .map(|d| {
                if d == Path::new(".") {
                    p.to_path_buf()
                } else {
                    d.join(p)
                }
            })
            .find(|c| c.exists())
            .ok_or_else(|| Error::NotFound {
                name: name.into(),
                searched: self.dirs.clone(),
            })
    }
}

/// Two spellings of one folder (`.` and the current folder, a trailing `/`, a symlink).
fn same_dir(a: &Path, b: &Path) -> bool {
    a == b
        || matches!(
            (std::fs::canonicalize(a), std::fs::canonicalize(b)),
            (Ok(x), Ok(y)) if x == y
        )
}

fn finite3(v: [f32; 3], key: &str, path: &Path) -> Result<Vec3> {
    if v.iter().all(|c| c.is_finite()) {
        Ok(Vec3::from(v))
    } else {
        Err(Error::scene(
            path,
            format!("{key}: every component must be a finite number"),
        ))
    }
}

fn nonneg3(v: [f32; 3], key: &str, path: &Path) -> Result<Vec3> {
    let v = finite3(v, key, path)?;
    if v.cmplt(Vec3::ZERO).any() {
        return Err(Error::scene(path, format!("{key}: must be >= 0")));
    }
    Ok(v)
}

fn nonneg(v: f32, key: &str, path: &Path) -> Result<f32> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(Error::scene(
            path,
            format!("{key}: must be a finite number >= 0, found {v}"),
        ))
    }
}

/// Check an image size against the pixel cap, in u64, before anything is allocated.
pub fn check_size(width: u64, height: u64) -> std::result::Result<(u32, u32), String> {
    if width == 0 || height == 0 {
        return Err(format!(
            "image size {width}x{height}: width and height must be > 0"
        ));
    }
    let pixels = width.saturating_mul(height);
    if pixels > MAX_PIXELS || width > u32::MAX as u64 || height > u32::MAX as u64 {
        return Err(format!(
            "image size {width}x{height} is over the cap of {MAX_PIXELS} pixels"
        ));
    }
    Ok((width as u32, height as u32))
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

fn build_scene_at(
    file: &SceneFile,
    path: &Path,
    search: &SearchPath,
) -> Result<(Scene, Vec<String>)> {
    let mut warnings = Vec::new();
    let (width, height) = check_size(file.image.width, file.image.height)
        .map_err(|m| Error::scene(path, format!("image: {m}")))?;

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

    let r = &file.render;
    if r.depth > MAX_DEPTH {
        return Err(Error::scene(
            path,
            format!("render.depth: {} is over the cap of {MAX_DEPTH}", r.depth),
        ));
    }
    let ambient = nonneg3(r.ambient, "render.ambient", path)?;

    let background = match (&file.background.color, &file.background.cubemap) {
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
    };

    let mut lights = Vec::new();
    for (i, l) in file.lights.iter().enumerate() {
        lights.push(Light {
            position: finite3(l.position, &format!("light[{i}].position"), path)?,
            intensity: nonneg3(l.intensity, &format!("light[{i}].intensity"), path)?,
        });
    }

    let mut materials = Vec::new();
    let mut vertex_fill = Vec::new();
    // One texture per file, however many materials use it.
    let mut textures: Vec<(PathBuf, Arc<Texture>)> = Vec::new();
    // Checker textures are allocated below: their total size is checked before any is made.
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
        if materials.iter().any(|x: &Material| x.name == m.name) {
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
        materials.push(build_material(
            m,
            &prefix,
            path,
            search,
            &mut textures,
            &refer,
        )?);
        // The colour of vertices a mesh gives no rgb (white unless the material says).
        vertex_fill.push(match m.color {
            Some(c) if m.vertex_color => Vec3::from(c),
            _ => Vec3::ONE,
        });
    }

    // The caps first, from the parameters alone: inline and generated meshes know their
    // triangle count before they are made, so a scene of 3,719 spheres is refused before the
    // first sphere is allocated (file meshes are checked as each is read, below).
    let (mut planned, mut planned_subdivided) = (0u64, 0u64);
    for (i, d) in file.meshes.iter().enumerate() {
        if let Some(n) = planned_triangles(d) {
            let made = check_caps(i, d, n, planned, planned_subdivided, path)?;
            planned += made;
            planned_subdivided += if d.subdivide > 0 { made } else { 0 };
        }
    }

    let mut objects = Vec::new();
    let mut total_triangles = 0u64;
    let mut subdivided_total = 0u64;
    // Each mesh file is read once, however many `[[mesh]]` entries name it.
    let mut loaded: Vec<LoadedMesh> = Vec::new();
    for (i, d) in file.meshes.iter().enumerate() {
        let key = |k: &str| format!("mesh[{i}].{k}");
        if d.material.is_empty() && d.file.is_none() {
            return Err(Error::scene(
                path,
                format!(
                    "{}: required for inline and shape meshes (only files bring materials)",
                    key("material")
                ),
            ));
        }
        let named = if d.material.is_empty() {
            None
        } else {
            Some(
                materials
                    .iter()
                    .position(|m| m.name == d.material)
                    .ok_or_else(|| {
                        Error::scene(
                            path,
                            format!("{}: no material named '{}'", key("material"), d.material),
                        )
                    })?,
            )
        };
        // Checked with the entry's triangle count before its mesh is copied or generated.
        let caps = |n| check_caps(i, d, n, total_triangles, subdivided_total, path);
        let (model, name, missing_rgb) =
            mesh_of(d, i, file, path, search, &mut loaded, &mut warnings, caps)?;
        let (material, face_materials) = match named {
            Some(m) => (m, None),
            None => file_materials(
                &model,
                &name,
                i,
                file,
                path,
                search,
                &mut materials,
                &mut textures,
            )?,
        };
        let mut mesh = model.mesh;
        if let Albedo::VertexColor = materials[material].albedo
            && let Some(colors) = &mut mesh.colors
        {
            // File materials (and the default) have no fill colour: white.
            let fill = vertex_fill.get(material).copied().unwrap_or(Vec3::ONE);
            for &v in &missing_rgb {
                colors[v as usize] = fill;
            }
        }
        let mesh = if d.subdivide > 0 {
            mesh.subdivide(d.subdivide)
        } else {
            mesh
        };
        let made = mesh.triangles.len() as u64;
        total_triangles += made;
        if d.subdivide > 0 {
            subdivided_total += made;
        }
        // Subdivision makes 4 children per face, in order.
        let face_materials = face_materials.map(|f| {
            let n = 1usize << (2 * d.subdivide);
            f.iter()
                .flat_map(|&m| std::iter::repeat_n(m, n))
                .collect::<Vec<u32>>()
        });
        if !mesh.positions.iter().all(|p| p.is_finite()) {
            return Err(Error::scene(
                path,
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
        for &material in &used {
            let material = &materials[material as usize];
            match &material.albedo {
                Albedo::VertexColor if mesh.colors.is_none() => {
                    return Err(Error::scene(
                        path,
                        format!(
                            "{}: material '{}' uses vertex colours but the mesh has no rgb",
                            key("material"),
                            material.name
                        ),
                    ));
                }
                Albedo::Texture(_) if mesh.uvs.is_none() => {
                    return Err(Error::scene(
                        path,
                        format!(
                            "{}: material '{}' is textured but the mesh has no uv",
                            key("material"),
                            material.name
                        ),
                    ));
                }
                _ => {}
            }
        }
        objects.push(Object {
            name,
            mesh,
            material,
            face_materials,
        });
    }

    // Emitting materials (`ke`, `lamp`) light the scene through point lights of their own.
    lights.extend(crate::scene::emitter_lights(&objects, &materials));

    let scene = Scene {
        width,
        height,
        view: View {
            eye,
            look_at,
            up,
            vfov: c.vfov,
        },
        ambient,
        background,
        lights,
        materials,
        objects,
        cull_backfaces: r.cull_backfaces,
        depth: r.depth,
    };
    Ok((scene, warnings))
}

/// The material faces of a file get when they name none (or the file has no materials):
/// grey, or the vertex colours when the file has them.
pub const DEFAULT_MATERIAL: &str = "default";

/// [`DEFAULT_MATERIAL`] as a scene material description.
pub fn default_material(vertex_colors: bool) -> MaterialDesc {
    MaterialDesc {
        name: DEFAULT_MATERIAL.into(),
        color: (!vertex_colors).then_some([DEFAULT_COLOR; 3]),
        vertex_color: vertex_colors,
        texture: None,
        checker: None,
        ka: default_ka(),
        kd: default_kd(),
        ks: default_ks(),
        n: default_n(),
        kt: Coef::Scalar(0.0),
        ior: 1.5,
        kr: Some(Coef::Scalar(0.0)),
        ke: Coef::Scalar(0.0),
        lamp: true,
    }
}

/// `Od` of a material that names no colour source (and of [`default_material`]).
pub const DEFAULT_COLOR: f32 = 0.8;

/// Validate one material description and load its texture (one load per file).
fn build_material(
    m: &MaterialDesc,
    prefix: &str,
    path: &Path,
    search: &SearchPath,
    textures: &mut Vec<(PathBuf, Arc<Texture>)>,
    refer: &dyn Fn(Error) -> Error,
) -> Result<Material> {
    let key = |k: &str| format!("{prefix}.{k}");
    // `color` beside `vertex_color` colours the vertices a mesh gives no rgb.
    let sources = (m.color.is_some() && !m.vertex_color) as u32
        + m.vertex_color as u32
        + m.texture.is_some() as u32
        + m.checker.is_some() as u32;
    if sources > 1 {
        return Err(Error::scene(
            path,
            format!(
                "{}: give exactly one of color, vertex_color (with an optional color for vertices without rgb), texture, checker",
                key("color")
            ),
        ));
    }
    // No source at all: the default material's grey.
    let color = match (m.color, sources) {
        (None, 0) => Some(Vec3::splat(DEFAULT_COLOR)),
        (c, _) => c.map(|c| nonneg3(c, &key("color"), path)).transpose()?,
    };
    let albedo = if m.vertex_color {
        Albedo::VertexColor
    } else if let Some(col) = color {
        Albedo::Color(col)
    } else if let Some(t) = &m.texture {
        let found = search.resolve(t).map_err(refer)?;
        match textures.iter().find(|(p, _)| *p == found) {
            Some((_, tex)) => Albedo::Texture(tex.clone()),
            None => {
                let tex = Arc::new(load_texture(&found).map_err(refer)?);
                textures.push((found, tex.clone()));
                Albedo::Texture(tex)
            }
        }
    } else {
        let ch = m.checker.as_ref().expect("one source");
        if !(1..=4096).contains(&ch.squares) {
            return Err(Error::scene(
                path,
                format!("{}: squares must be in 1..=4096", key("checker")),
            ));
        }
        let size = (ch.squares as usize * 16).min(4096);
        Albedo::Texture(Arc::new(Texture::checker(
            size,
            ch.squares as usize,
            nonneg3(ch.a, &key("checker.a"), path)?,
            nonneg3(ch.b, &key("checker.b"), path)?,
        )))
    };
    let ior = m.ior;
    if !(ior.is_finite() && ior > 0.0) {
        return Err(Error::scene(
            path,
            format!("{}: must be a finite number > 0, found {ior}", key("ior")),
        ));
    }
    let coef = |c: Coef, k: &str| match c {
        Coef::Scalar(v) => nonneg(v, &key(k), path).map(Vec3::splat),
        Coef::Rgb(v) => nonneg3(v, &key(k), path),
    };
    let ks = coef(m.ks, "ks")?;
    let ke = coef(m.ke, "ke")?;
    Ok(Material {
        name: m.name.clone(),
        albedo,
        ka: coef(m.ka, "ka")?,
        kd: coef(m.kd, "kd")?,
        ks,
        n: nonneg(m.n, &key("n"), path)?,
        kt: coef(m.kt, "kt")?,
        ior,
        kr: m.kr.map_or(Ok(ks), |c| coef(c, "kr"))?,
        ke,
        lamp: m.lamp && ke.max_element() > 0.0,
    })
}

/// An error about a file the scene names: the scene, the line of `toml_key` (when the scene
/// was read from text), the key as messages spell it (`shown`, default `toml_key`), then the
/// file's own error.
fn referenced(
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

/// Segments of a generated `shape = "sphere"` (its triangle count is
/// [`shapes::sphere_triangle_count`] of this).
pub const SPHERE_SEGMENTS: u32 = 48;

/// A mesh file as read once for a scene: where it was found, the mesh with the materials it
/// brings, the vertices it gave no rgb.
type LoadedMesh = (PathBuf, Model, Vec<u32>);

/// Triangles an inline or generated mesh entry will have before subdivision, known from its
/// parameters; `None` for files (known once read) and for entries that are not valid (their
/// error comes when they are built).
fn planned_triangles(d: &MeshDesc) -> Option<u64> {
    if d.file.is_some() {
        return None;
    }
    match (&d.faces, d.shape.as_deref()) {
        (Some(f), None) => Some(f.len() as u64),
        (None, Some("sphere")) => Some(shapes::sphere_triangle_count(SPHERE_SEGMENTS)),
        (None, Some("cube")) => Some(12),
        (None, Some("quad")) => Some(2),
        _ => None,
    }
}

/// Whether mesh entry `i` with `n` triangles (before its subdivision) fits the caps, given the
/// scene's totals so far; returns the triangles it will make.
fn check_caps(
    i: usize,
    d: &MeshDesc,
    n: u64,
    total: u64,
    subdivided: u64,
    path: &Path,
) -> Result<u64> {
    let key = |k: &str| format!("mesh[{i}].{k}");
    if d.subdivide > MAX_SUBDIVIDE {
        return Err(Error::scene(
            path,
            format!(
                "{}: {} is over the cap of {MAX_SUBDIVIDE}",
                key("subdivide"),
                d.subdivide
            ),
        ));
    }
    let made = n.saturating_mul(1 << (2 * d.subdivide));
    if d.subdivide > 0 && subdivided.saturating_add(made) > MAX_SUBDIVIDED_TRIANGLES {
        return Err(Error::scene(
            path,
            format!(
                "{}: {} levels would make {made} triangles, over the scene's cap of {MAX_SUBDIVIDED_TRIANGLES} made by subdivision",
                key("subdivide"),
                d.subdivide
            ),
        ));
    }
    if total.saturating_add(made) > MAX_SCENE_TRIANGLES {
        return Err(Error::scene(
            path,
            format!(
                "mesh[{i}]: the scene's meshes add up to over {MAX_SCENE_TRIANGLES} triangles (the cap) with this one's {made}"
            ),
        ));
    }
    Ok(made)
}

/// The mesh of entry `i`, its name and the vertices its file gave no rgb. `caps` is called
/// with the triangle count before the mesh is copied or generated.
#[allow(clippy::too_many_arguments)]
fn mesh_of(
    d: &MeshDesc,
    i: usize,
    file: &SceneFile,
    path: &Path,
    search: &SearchPath,
    loaded: &mut Vec<LoadedMesh>,
    warnings: &mut Vec<String>,
    caps: impl FnOnce(u64) -> Result<u64>,
) -> Result<(Model, String, Vec<u32>)> {
    let key = |k: &str| format!("mesh[{i}].{k}");
    let sources = d.file.is_some() as u32 + d.vertices.is_some() as u32 + d.shape.is_some() as u32;
    if sources != 1 {
        return Err(Error::scene(
            path,
            format!(
                "{}: give exactly one of file, vertices + faces, shape",
                key("file")
            ),
        ));
    }
    if d.faces.is_some() && d.vertices.is_none() {
        return Err(Error::scene(
            path,
            format!("{}: faces need inline vertices", key("faces")),
        ));
    }
    if let Some(f) = &d.file {
        let refer = |e| referenced(file, path, &key("file"), None, e);
        let found = search.resolve(f).map_err(refer)?;
        let k = match loaded.iter().position(|(p, ..)| *p == found) {
            Some(k) => k,
            None => {
                let (model, w, missing) = load_scene_model(&found).map_err(refer)?;
                warnings.extend(w);
                loaded.push((found, model, missing));
                loaded.len() - 1
            }
        };
        caps(loaded[k].1.mesh.triangles.len() as u64)?;
        let (_, model, missing) = &loaded[k];
        let name = d.name.clone().unwrap_or_else(|| f.clone());
        return Ok((model.clone(), name, missing.clone()));
    }
    let name = d.name.clone().unwrap_or_else(|| format!("mesh{i}"));
    let center = finite3(d.center.unwrap_or([0.0; 3]), &key("center"), path)?;
    if let Some(verts) = &d.vertices {
        let faces = d.faces.as_ref().ok_or_else(|| {
            Error::scene(
                path,
                format!("{}: inline vertices need faces", key("faces")),
            )
        })?;
        let positions = verts
            .iter()
            .enumerate()
            .map(|(k, v)| finite3(*v, &format!("mesh[{i}].vertices[{k}]"), path))
            .collect::<Result<Vec<_>>>()?;
        if let Some((k, _)) = faces
            .iter()
            .enumerate()
            .find(|(_, f)| f.iter().any(|&v| v as usize >= positions.len()))
        {
            return Err(Error::scene(
                path,
                format!(
                    "mesh[{i}].faces[{k}]: vertex index out of range (0..{})",
                    positions.len()
                ),
            ));
        }
        if faces.is_empty() {
            return Err(Error::scene(path, format!("{}: no faces", key("faces"))));
        }
        caps(faces.len() as u64)?;
        let mut mesh = Mesh {
            positions,
            triangles: faces.clone(),
            ..Default::default()
        };
        mesh.ensure_normals();
        return Ok((plain(mesh), name, Vec::new()));
    }
    let shape = d.shape.as_deref().unwrap_or_default();
    let size = finite3(d.size.unwrap_or([1.0; 3]), &key("size"), path)?;
    let radius = d.radius.unwrap_or(1.0);
    if shape == "sphere" && !(radius.is_finite() && radius > 0.0) {
        return Err(Error::scene(
            path,
            format!("{}: must be > 0", key("radius")),
        ));
    }
    let Some(n) = planned_triangles(d) else {
        return Err(Error::scene(
            path,
            format!(
                "{}: unknown shape '{shape}' (sphere, cube, quad)",
                key("shape")
            ),
        ));
    };
    caps(n)?;
    let mut mesh = match shape {
        "sphere" => shapes::sphere(center, radius, SPHERE_SEGMENTS),
        "cube" => shapes::cube(center, size * 0.5),
        _ => shapes::quad(center, Vec3::X * size.x * 0.5, Vec3::NEG_Z * size.z * 0.5),
    };
    debug_assert_eq!(mesh.triangles.len() as u64, n, "planned_triangles is exact");
    // A zero size makes the shape's own normals 0/0: fall back to the geometric normals.
    mesh.ensure_normals();
    Ok((plain(mesh), name, Vec::new()))
}

fn plain(mesh: Mesh) -> Model {
    Model {
        mesh,
        ..Default::default()
    }
}

/// Scene materials for a mesh file's own materials: a scene material of the same name if
/// there is one, else the file's (validated and added to the scene); faces without one get
/// [`DEFAULT_MATERIAL`] (or its vertex-colour twin when the mesh has colours). Returns the
/// material of the whole mesh, or a material per triangle.
#[allow(clippy::too_many_arguments)]
fn file_materials(
    model: &Model,
    name: &str,
    i: usize,
    file: &SceneFile,
    path: &Path,
    search: &SearchPath,
    materials: &mut Vec<Material>,
    textures: &mut Vec<(PathBuf, Arc<Texture>)>,
) -> Result<(usize, Option<Vec<u32>>)> {
    let mut index_of = |desc: &MaterialDesc, materials: &mut Vec<Material>| -> Result<u32> {
        if let Some(k) = materials.iter().position(|m| m.name == desc.name) {
            return Ok(k as u32);
        }
        let prefix = format!("mesh '{name}' material '{}'", desc.name);
        // A texture of the file's materials is named by the mesh entry's file.
        let refer = |e| {
            let toml_key = format!("mesh[{i}].file");
            referenced(file, path, &toml_key, Some(format!("{prefix}.texture")), e)
        };
        materials.push(build_material(
            desc, &prefix, path, search, textures, &refer,
        )?);
        Ok(materials.len() as u32 - 1)
    };
    let colors = model.mesh.colors.is_some();
    let mut default = default_material(colors);
    if colors {
        default.name = format!("{DEFAULT_MATERIAL}_vertex_color");
    }
    let Some(faces) = &model.face_materials else {
        return Ok((index_of(&default, materials)? as usize, None));
    };
    let mut map = Vec::with_capacity(model.materials.len());
    for desc in &model.materials {
        map.push(index_of(desc, materials)?);
    }
    let mut fallback = None;
    let mut out = Vec::with_capacity(faces.len());
    for &f in faces {
        out.push(if f == NO_MATERIAL {
            match fallback {
                Some(k) => k,
                None => *fallback.insert(index_of(&default, materials)?),
            }
        } else {
            map[f as usize]
        });
    }
    Ok((out.first().copied().unwrap_or(0) as usize, Some(out)))
}

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
[image]
width = 4
height = 3
[camera]
eye = [0, 0, 5]
look_at = [0, 0, 0]
vfov = 40
[background]
color = [0.1, 0.2, 0.3]
[[material]]
name = "m"
color = [1, 1, 1]
ka = 0.1
kd = 0.9
ks = 0
n = 1
[[mesh]]
material = "m"
vertices = [[-1, -1, 0], [1, -1, 0], [0, 1, 0]]
faces = [[0, 1, 2]]
"#;

    fn build(text: &str) -> Result<Scene> {
        let p = Path::new("s.toml");
        let f = SceneFile::parse(text, p)?;
        build_scene(&f, p, &SearchPath::for_scene(None)).map(|(s, _)| s)
    }

    #[test]
    fn minimal_scene_loads_and_roundtrips() {
        let s = build(MINIMAL).unwrap();
        assert_eq!(
            (s.width, s.height, s.depth, s.cull_backfaces),
            (4, 3, 1, true)
        );
        assert_eq!(s.objects[0].mesh.triangles.len(), 1);
        let f = SceneFile::parse(MINIMAL, Path::new("s")).unwrap();
        assert_eq!(SceneFile::parse(&f.to_toml(), Path::new("s")).unwrap(), f);
    }

    #[test]
    fn overrides_replace_alternatives_and_append_entries() {
        let f = SceneFile::parse(MINIMAL, Path::new("s.toml")).unwrap();
        let d = |v: &[&str]| v.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let g = f.with_overrides(&d(&["background.cubemap=sky"])).unwrap();
        assert_eq!(g.background.color, None);
        assert_eq!(g.background.cubemap.as_deref(), Some("sky"));
        let g = f
            .with_overrides(&d(&[
                "light[+]={position=[0, 1, 0], intensity=[1, 1, 1]}",
                "light[1].position=[1, 1, 1]",
                "light[1].intensity=[0.5, 0.5, 0.5]",
                "material[0].texture=t.png",
            ]))
            .unwrap();
        assert_eq!(g.lights.len(), 2);
        assert_eq!(g.lights[1].intensity, [0.5; 3]);
        assert_eq!(g.materials[0].color, None);
        let e = f
            .with_overrides(&d(&["light[0].position=[1, 1, 1]"]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("-D 'light[0].position=[1, 1, 1]': missing field `intensity`"),
            "{e}"
        );
    }

    #[test]
    fn validation_errors_carry_the_key_line_and_defaults_fill_the_rest() {
        let e = build(&MINIMAL.replace("vfov = 40", "vfov = 400"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("s.toml:8: camera.vfov"), "{e}");
        // Only the camera's eye and look_at are required.
        let s = build(
            "[camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\n[[material]]\nname = \"m\"\n\
             [[mesh]]\nmaterial = \"m\"\nshape = \"cube\"\n",
        )
        .unwrap();
        assert_eq!(
            (s.width, s.height, s.view.vfov, s.depth),
            (1024, 768, 36.0, 1)
        );
        let m = &s.materials[0];
        assert_eq!(
            (m.ka, m.kd, m.ks, m.n),
            (Vec3::splat(0.3), Vec3::splat(0.7), Vec3::splat(0.1), 40.0)
        );
        assert_eq!(m.kr, Vec3::ZERO);
        assert!(matches!(m.albedo, Albedo::Color(c) if c == Vec3::splat(DEFAULT_COLOR)));
    }

    #[test]
    fn key_lines_point_at_keys() {
        let text = "a = 1\n[image]\nwidth = 4\n[background]\ncubemap = \"sky\"\n[[mesh]]\n\
            file = \"a.m\"\n[[mesh]]\n\nfile = \"b.m\"\n";
        let lines = KeyLines::of(text);
        for (key, line) in [
            ("a", 1),
            ("image.width", 3),
            ("background.cubemap", 5),
            ("mesh[0].file", 7),
            ("mesh[1].file", 10),
        ] {
            assert_eq!(lines.line(key), Some(line), "{key}");
        }
        assert_eq!(lines.line("mesh[2].file"), None);
        assert!(KeyLines::of("not toml = = =").line("a").is_none());
    }

    #[test]
    fn errors_name_key_or_line() {
        let cases = [
            (
                MINIMAL.replace("vfov = 40", "vfov = 40\nfov = 3"),
                "s.toml:9: column 1: unknown field `fov`",
            ),
            (MINIMAL.replace("vfov = 40", "vfov = 180"), "camera.vfov"),
            (
                MINIMAL.replace("width = 4", "width = 0"),
                "width and height must be > 0",
            ),
            (
                MINIMAL.replace(
                    "width = 4\nheight = 3",
                    "width = 4000000000\nheight = 4000000000",
                ),
                "over the cap",
            ),
            (
                MINIMAL.replace("look_at = [0, 0, 0]", "look_at = [0, 0, 0]\nup = [0, 0, 1]"),
                "camera.up",
            ),
            (MINIMAL.replace("kd = 0.9", "kd = nan"), "'m'.kd"),
            (MINIMAL.replace("kd = 0.9", "kd = 0.9\nior = 0"), "ior"),
            (
                MINIMAL.replace("kd = 0.9", "kd = -1"),
                ".kd: must be a finite number >= 0",
            ),
            (
                MINIMAL.replace("material = \"m\"", "material = \"x\""),
                "no material named 'x'",
            ),
            (
                MINIMAL.replace("[[0, 1, 2]]", "[[0, 1, 3]]"),
                "mesh[0].faces[0]",
            ),
            (
                MINIMAL.replace("[[mesh]]", "[render]\ndepth = 1000\n[[mesh]]"),
                "render.depth",
            ),
            (
                MINIMAL.replace("color = [0.1, 0.2, 0.3]", "color = [-1, 0, 0]"),
                "background.color",
            ),
            (
                MINIMAL.replace(
                    "vertices = [[-1, -1, 0], [1, -1, 0], [0, 1, 0]]\nfaces = [[0, 1, 2]]",
                    "file = \"nope/missing.m\"",
                ),
                "cannot find 'nope/missing.m'; searched:",
            ),
        ];
        for (text, want) in cases {
            let e = build(&text).unwrap_err().to_string();
            assert!(
                e.contains(want) && e.starts_with("s.toml"),
                "want {want:?}, got {e}"
            );
        }
    }
}
