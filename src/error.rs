//! One error type for everything a user can hand to whitted: files, scenes, options.

use std::path::{Path, PathBuf};

/// Every failure whitted reports. Each variant's message names the file (and the line where
/// one applies) so a user can go straight to the problem.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The operating system refused to read or write a file.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        #[source]
        source: std::io::Error,
    },
    /// A text file (mesh, scene, ray file) is malformed at a given line, or as a whole
    /// (line 0: then the message names only the file, as in `bad.m: no faces`).
    #[error("{}{}: {msg}", path.display(), at_line(*line))]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line (for what the whole file lacks, its last line: where it ended).
        line: usize,
        /// What is wrong there.
        msg: String,
    },
    /// An image file could not be decoded, encoded or is unusable (e.g. a bad cube-map face).
    #[error("{}: {msg}", path.display())]
    Image {
        /// The image file.
        path: PathBuf,
        /// What is wrong with it.
        msg: String,
    },
    /// A file of a type whitted does not read where it was given (by its extension or its
    /// content); the message says which types are read there.
    #[error("{}: {msg}", path.display())]
    Format {
        /// The file.
        path: PathBuf,
        /// What it is and what was expected.
        msg: String,
    },
    /// A scene is well-formed but not valid (bad value, missing material, ...).
    #[error("{}: {msg}", path.display())]
    Scene {
        /// The scene file (or `<built-in scene NAME>`).
        path: PathBuf,
        /// The key and what is wrong with its value.
        msg: String,
    },
    /// A file named by a scene was not found in any folder of the search path. It comes
    /// wrapped in [`Error::Referenced`], which names the scene and the key.
    #[error("cannot find '{name}'; searched: {}", searched.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", "))]
    NotFound {
        /// The name as the scene wrote it.
        name: String,
        /// Every folder tried, in order.
        searched: Vec<PathBuf>,
    },
    /// A file a scene refers to could not be used: the scene (and the line of the key, when
    /// known), the key that named the file, then the file's own error, e.g.
    /// `scene.toml:12: mesh[1].file: meshes/bad.m:2: Vertex 2: 'NaN' is not a finite number`.
    #[error("{}{}: {key}: {source}", scene.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Referenced {
        /// The scene file (or `<built-in scene NAME>`).
        scene: PathBuf,
        /// 1-based line of the key in the scene file, when it was read from text.
        line: Option<usize>,
        /// The key that named the file, e.g. `mesh[1].file`.
        key: String,
        /// What went wrong with the file itself.
        #[source]
        source: Box<Error>,
    },
    /// A command-line value is out of range.
    #[error("{0}")]
    Usage(String),
}

impl Error {
    /// An [`Error::Io`] for `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }
    /// An [`Error::Parse`] at `line` of `path` (0: the whole file).
    pub fn parse(path: &Path, line: usize, msg: impl Into<String>) -> Self {
        Error::Parse {
            path: path.to_path_buf(),
            line,
            msg: msg.into(),
        }
    }
    /// An [`Error::Image`] for `path`.
    pub fn image(path: &Path, msg: impl Into<String>) -> Self {
        Error::Image {
            path: path.to_path_buf(),
            msg: msg.into(),
        }
    }
    /// An [`Error::Scene`] for `path`.
    pub fn scene(path: &Path, msg: impl Into<String>) -> Self {
        Error::Scene {
            path: path.to_path_buf(),
            msg: msg.into(),
        }
    }
}

/// whitted's `Result`, with [`Error`] by default.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// `:line` for a line of a file, nothing for the whole file (line 0).
fn at_line(line: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!(":{line}")
    }
}
