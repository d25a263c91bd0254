//! `-D key=value` overrides of a scene file: each applied to the scene's TOML value and
//! checked as the file is, and validation errors traced back to the `-D` that caused them.

use super::schema::{Coef, SceneFile};
use crate::error::{Error, Result};
use serde::Deserialize;

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
        (2, "material", "color") => &["texture", "checker", "wrap"],
        (2, "material", "vertex_color") => &["texture", "checker", "wrap"],
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
    /// types); errors name the `-D` argument. Values are validated by
    /// [`build_scene`](super::build_scene).
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
