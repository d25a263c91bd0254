//! The scene file's schema: what a TOML scene may say (`deny_unknown_fields`), with its
//! defaults and the caps a scene is checked against. Loaders use [`MaterialDesc`] and
//! [`Coef`] to describe the materials their files bring; nothing here reads a file.

use super::text::KeyLines;
use crate::texture::Wrap;
use serde::{Deserialize, Serialize};

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

/// A scene file as written: the TOML format of the README, before validation.
/// [`build_scene`](super::build_scene) turns it into a [`Scene`](crate::scene::Scene);
/// [`scenes::builtin`](crate::scenes::builtin) makes the built-in ones.
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
    /// `[[instance]]`: placements of meshes by name (a placed mesh is drawn only where
    /// its instances put it).
    #[serde(default, rename = "instance", skip_serializing_if = "Vec::is_empty")]
    pub instances: Vec<InstanceDesc>,
    /// Lines of the keys in the text this was parsed from (empty for scenes made in code).
    #[serde(skip)]
    pub lines: KeyLines,
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
    /// How the `texture` or `checker` continues outside uv `[0, 1]`: `"repeat"` (the
    /// default), `"mirrored_repeat"` or `"clamp_to_edge"`, for both axes or as `[u, v]`.
    #[serde(default, skip_serializing_if = "Option::is_none", with = "wrap_modes")]
    pub wrap: Option<[Wrap; 2]>,
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

/// A [`Wrap`] mode by its name in a scene (glTF's sampler names, lower case).
pub fn wrap_name(w: Wrap) -> &'static str {
    match w {
        Wrap::Repeat => "repeat",
        Wrap::MirroredRepeat => "mirrored_repeat",
        Wrap::Clamp => "clamp_to_edge",
    }
}

/// `wrap = "mode"` (both axes) or `wrap = ["u mode", "v mode"]`; written back the same way.
mod wrap_modes {
    use super::{Wrap, wrap_name};
    use serde::de::{Deserialize, Deserializer, Error};
    use serde::{Serialize, Serializer};

    const MODES: [Wrap; 3] = [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::Clamp];

    fn mode<E: Error>(name: &str) -> Result<Wrap, E> {
        MODES
            .into_iter()
            .find(|&w| wrap_name(w) == name)
            .ok_or_else(|| {
                E::custom(format!(
                    "unknown wrap mode '{name}': expected repeat, mirrored_repeat or clamp_to_edge"
                ))
            })
    }

    #[derive(serde::Deserialize)]
    #[serde(untagged)]
    enum Given {
        Both(String),
        Each(Vec<String>),
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<[Wrap; 2]>, D::Error> {
        let given = Option::<Given>::deserialize(d)
            .map_err(|_| D::Error::custom("wrap: expected a mode name or [u, v] mode names"))?;
        match given {
            None => Ok(None),
            Some(Given::Both(m)) => Ok(Some([mode(&m)?; 2])),
            Some(Given::Each(v)) if v.len() == 2 => Ok(Some([mode(&v[0])?, mode(&v[1])?])),
            Some(Given::Each(v)) => Err(D::Error::invalid_length(v.len(), &"[u, v]: 2 modes")),
        }
    }

    pub fn serialize<S: Serializer>(w: &Option<[Wrap; 2]>, s: S) -> Result<S::Ok, S::Error> {
        match w {
            Some([u, v]) if u == v => wrap_name(*u).serialize(s),
            Some([u, v]) => [wrap_name(*u), wrap_name(*v)].serialize(s),
            None => s.serialize_none(),
        }
    }
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

/// `[[instance]]`: a mesh by name, placed by `scale`, then `rotate`, then `translate`, or by
/// a `matrix`.
#[derive(Clone, Debug, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InstanceDesc {
    /// The `name` of a `[[mesh]]`.
    pub mesh: String,
    /// A scene material for the whole instance (default: the mesh's own).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub material: String,
    /// Offset along x, y, z (applied last).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact3::opt"
    )]
    pub translate: Option<[f32; 3]>,
    /// Rotation in degrees about x, then y, then z (applied after the scale).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "exact3::opt"
    )]
    pub rotate: Option<[f32; 3]>,
    /// Scale: one factor, or one per axis (applied first).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<ScaleDesc>,
    /// Or the whole transform: 4 rows of 4 (the last `[0, 0, 0, 1]`), object to world.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub matrix: Option<[[f32; 4]; 4]>,
}

/// `scale = 2` or `scale = [1, 2, 1]`.
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
#[serde(untagged)]
pub enum ScaleDesc {
    /// The same factor on every axis.
    Uniform(f32),
    /// One factor per axis.
    Axes([f32; 3]),
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
    /// A mesh file (`.m`, `.obj`, `.ply`, `.stl`, `.gltf`, `.glb`) ...
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
    /// Shading normals: `true` = the file's own vertex normals, or else normals averaged over
    /// the faces meeting at each point; `false` = flat (each triangle's geometric normal).
    /// Omitted: as the mesh's format means them (see the README).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smooth: Option<bool>,
    /// Smooth across edges whose dihedral angle is below this many degrees (0 to 180), flat
    /// across sharper ones, from the geometry alone (the file's normals are not used).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub crease: Option<f32>,
    /// Midpoint subdivision levels applied after loading (each x4 triangles).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub subdivide: u32,
}

fn is_zero(v: &u32) -> bool {
    *v == 0
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
        wrap: None,
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
