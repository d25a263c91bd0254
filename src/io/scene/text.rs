//! Reading a scene file's text: TOML parsing with the line and column of each error, the
//! refusal of files that are not scenes, and the line of the key a validation error is about.

use super::schema::{Coef, SceneFile, check_size};
use crate::error::{Error, Result};
use std::path::Path;

impl SceneFile {
    /// Parse TOML text; errors carry the line and column of the offending key.
    pub fn parse(text: &str, path: &Path) -> Result<SceneFile> {
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        // `[[instance]]` tables are read one at a time (a field of 10^6 is 97 MB of text)
        let cut = super::instance_text::cut(text);
        let whole = cut.as_ref().map_or(text, |c| c.rest.as_str());
        let mut file: SceneFile = toml::from_str(whole).map_err(|e| {
            let (line, col) = e
                .span()
                .map(|s| line_col(whole.as_bytes(), s.start))
                .unwrap_or((0, 0));
            // toml's messages span several lines (a source excerpt); keep the first line.
            let msg = e.message().lines().next().unwrap_or("invalid TOML").trim();
            Error::parse(path, line, format!("column {col}: {msg}"))
        })?;
        file.lines = KeyLines::of(whole);
        if let Some(cut) = cut {
            if let (false, Some(&(_, line))) = (file.instances.is_empty(), cut.tables.first()) {
                return Err(Error::parse(
                    path,
                    line,
                    "column 1: instance is given both as an array and as [[instance]] tables",
                ));
            }
            file.instances.reserve_exact(cut.tables.len());
            for (i, &(body, line)) in cut.tables.iter().enumerate() {
                let d = super::instance_text::instance(i, body, line, &mut file.lines)
                    .map_err(|(l, c, m)| Error::parse(path, l, format!("column {c}: {m}")))?;
                file.instances.push(d);
            }
        }
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

/// Give a validation error about a key the line of that key (or of its table) in the
/// scene's text: `scene.toml:12: material[0] 'kitten'.ior: ...`. Other errors, and scenes
/// not read from text, are returned as they are.
pub(super) fn locate(file: &SceneFile, e: Error) -> Error {
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
pub(super) fn line_col(text: &[u8], at: usize) -> (usize, usize) {
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

/// The 1-based line of each key of a scene file's text, by its path (`background.cubemap`,
/// `mesh[1].file`), so that errors about the files a key names can point at the key. Source
/// positions are not part of a scene's value: any two `KeyLines` compare equal.
#[derive(Clone, Debug, Default)]
pub struct KeyLines(pub(super) Vec<(String, usize)>);

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

    /// Add the top-level keys of the TOML table body `text` as `prefix.key`, each on its line
    /// in `text` plus `offset` (an `[[instance]]` table read alone).
    pub(super) fn extend_table(&mut self, prefix: &str, text: &str, offset: usize) {
        let Ok(doc) = toml::de::DeTable::parse(text) else {
            return;
        };
        for (k, _) in doc.get_ref().iter() {
            let line = offset + 1 + text[..k.span().start].matches('\n').count();
            self.0.push((format!("{prefix}.{}", k.get_ref()), line));
        }
    }

    /// The line of `key` (as `mesh[1].file`), if the text had it.
    pub fn line(&self, key: &str) -> Option<usize> {
        self.0.iter().find(|(k, _)| k == key).map(|&(_, l)| l)
    }
}
