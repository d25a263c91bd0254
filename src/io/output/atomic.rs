//! Every output file's way to disk: a temporary file beside the target, renamed into place
//! once complete ([`write_atomically`]), through symbolic links, straight into FIFOs and
//! devices.

use super::writeback::EarlyWriteback;
use crate::error::{Error, Result};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// Run `write` on a new temporary file beside `path` (`.NAME.PID-K.tmp` in the same folder,
/// so the rename cannot cross file systems), then rename it over `path`. On any error the
/// temporary file is removed and `path` keeps what it held. A process killed mid-write leaves
/// `path` untouched too, and its hidden temporary file behind. The kernel is asked to start
/// writing the file out as it grows ([`EarlyWriteback`]), which keeps the rename short.
///
/// Where `path` is a symbolic link, the file it names is the one replaced (beside it), and
/// the link stays a link; where it is neither a regular file nor a folder (a FIFO, a device
/// such as `/dev/stdout`), which a rename would replace rather than write to, `write` goes
/// straight into it.
pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<EarlyWriteback>) -> Result<()>,
) -> Result<()> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    // (the kernel follows the links, magic ones such as /dev/stdout's too)
    let existing = std::fs::metadata(path);
    let target = match &existing {
        Ok(m) if m.is_dir() => {
            return Err(Error::Usage(format!(
                "{}: is a folder, not a file",
                path.display()
            )));
        }
        Ok(m) if !m.is_file() => {
            let file = File::options()
                .write(true)
                .open(path)
                .map_err(|e| Error::io(path, e))?;
            let mut out = BufWriter::with_capacity(1 << 20, EarlyWriteback::new(file));
            return write(&mut out).and_then(|()| out.flush().map_err(|e| Error::io(path, e)));
        }
        Ok(_) => std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf()),
        // (a new file, or a link to one)
        Err(_) => through_links(path),
    };
    let name = target
        .file_name()
        .ok_or_else(|| Error::Usage(format!("{}: not a file name", path.display())))?;
    let tmp: PathBuf = target.with_file_name(format!(
        ".{}.{}-{}.tmp",
        name.to_string_lossy(),
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let file = File::create_new(&tmp).map_err(|e| Error::io(path, e))?;
    // a file replaced keeps its permissions (a group-writable image in a shared folder stays
    // so); a failure to carry them over leaves the new file's defaults
    if let Ok(m) = &existing {
        let _ = file.set_permissions(m.permissions());
    }
    let mut out = BufWriter::with_capacity(1 << 20, EarlyWriteback::new(file));
    let result = write(&mut out)
        .and_then(|()| out.flush().map_err(|e| Error::io(path, e)))
        .and_then(|()| std::fs::rename(&tmp, &target).map_err(|e| Error::io(path, e)));
    if result.is_err() {
        drop(out);
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// `path` with its symbolic links followed, by their text, to the name they end at (which
/// need not exist: a link to a file not yet written); `path` itself when it is no link. At
/// most 40 links, as the kernel's own limit.
fn through_links(path: &Path) -> PathBuf {
    let mut p = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::read_link(&p) {
            Ok(next) => {
                p = match p.parent() {
                    Some(dir) if next.is_relative() => dir.join(next),
                    _ => next,
                }
            }
            Err(_) => break,
        }
    }
    p
}
