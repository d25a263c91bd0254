//! Where a scene's relative file names are found: the scene's folder, the current folder,
//! the `WHITTED_ASSETS` folders, then the project's own data.

use crate::error::{Error, Result};
use std::path::{Path, PathBuf};

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
