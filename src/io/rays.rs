//! Binary ray and hit files of `whitted trace-rays` (little-endian).
//!
//! Ray record, 32 bytes: `f32 ox oy oz dx dy dz tnear tfar`.
//! Hit record, 16 bytes: `u32 triangle` (mesh face order, `0xFFFFFFFF` = miss), `f32 t`,
//! `f32 b1`, `f32 b2` (weights of the triangle's second and third vertex; a miss writes
//! `t = +inf`, `b1 = b2 = 0`).

use crate::error::{Error, Result};
use crate::ray::{Hit, Ray};
use glam::Vec3;
use std::io::{Read, Write};
use std::path::Path;

/// Bytes of one ray record.
pub const RAY_BYTES: usize = 32;
/// Bytes of one hit record.
pub const HIT_BYTES: usize = 16;

/// Parse a ray file's bytes; the length must be a whole number of records.
pub fn parse_rays(bytes: &[u8], path: &Path) -> Result<Vec<Ray>> {
    if !bytes.len().is_multiple_of(RAY_BYTES) {
        return Err(not_whole(bytes.len() as u64, path));
    }
    Ok(bytes.chunks_exact(RAY_BYTES).map(ray_of).collect())
}

/// The ray file at `path`, read a megabyte at a time into the rays (the file's bytes are
/// never held whole: a file of 2M rays is 64 MB, and a buffer of it as much again of fresh
/// pages to fault in and copy). The length must be a whole number of records.
pub fn read_rays(path: &Path) -> Result<Vec<Ray>> {
    let io = |e| Error::io(path, e);
    let mut file = std::fs::File::open(path).map_err(io)?;
    // (0 for a pipe, whose rays arrive as they come)
    let expect = file.metadata().map(|m| m.len()).unwrap_or(0);
    if expect > MAX_RAY_FILE_BYTES {
        return Err(too_big(expect, path));
    }
    let mut rays = Vec::new();
    let count = (expect / RAY_BYTES as u64) as usize;
    rays.try_reserve_exact(count).map_err(|_| {
        Error::parse(
            path,
            0,
            format!("{count} rays ({expect} bytes) do not fit in this machine's memory"),
        )
    })?;
    let mut buf = vec![0u8; 1 << 20];
    // bytes of `buf` held (a record may straddle two reads), and the file's bytes so far
    let (mut held, mut total) = (0usize, 0u64);
    loop {
        let n = match file.read(&mut buf[held..]) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(io(e)),
        };
        total += n as u64;
        if total > MAX_RAY_FILE_BYTES {
            return Err(too_big(total, path));
        }
        held += n;
        let whole = held - held % RAY_BYTES;
        rays.extend(buf[..whole].chunks_exact(RAY_BYTES).map(ray_of));
        buf.copy_within(whole..held, 0);
        held -= whole;
    }
    if held != 0 {
        return Err(not_whole(total, path));
    }
    Ok(rays)
}

/// The largest ray file read: 2^31 rays (64 GiB), past which a file (or a pipe that goes on)
/// is refused rather than left to exhaust memory.
pub const MAX_RAY_FILE_BYTES: u64 = (RAY_BYTES as u64) << 31;

fn too_big(bytes: u64, path: &Path) -> Error {
    Error::parse(
        path,
        0,
        format!("{bytes} bytes of rays is over the cap of {MAX_RAY_FILE_BYTES} (2^31 rays)"),
    )
}

fn not_whole(bytes: u64, path: &Path) -> Error {
    Error::parse(
        path,
        0,
        format!("{bytes} bytes is not a whole number of 32-byte ray records"),
    )
}

/// One 32-byte record as a ray.
#[inline]
fn ray_of(r: &[u8]) -> Ray {
    let f = |k: usize| f32::from_le_bytes(r[4 * k..4 * k + 4].try_into().expect("4 bytes"));
    Ray::new(
        Vec3::new(f(0), f(1), f(2)),
        Vec3::new(f(3), f(4), f(5)),
        f(6),
        f(7),
    )
}

/// The bytes of a ray file holding `rays`.
pub fn encode_rays(rays: &[Ray]) -> Vec<u8> {
    let mut out = Vec::with_capacity(rays.len() * RAY_BYTES);
    for r in rays {
        for v in [
            r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.tnear, r.tfar,
        ] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

/// The bytes of a hit file holding `hits` (`None` = a miss).
pub fn encode_hits(hits: &[Option<Hit>]) -> Vec<u8> {
    let mut out = Vec::with_capacity(hits.len() * HIT_BYTES);
    write_hits(&mut out, hits).expect("writing to a Vec");
    out
}

/// `hits` as hit records into `out`, a record at a time (`out` buffers).
pub fn write_hits(out: &mut impl Write, hits: &[Option<Hit>]) -> std::io::Result<()> {
    for h in hits {
        let h = h.unwrap_or(Hit {
            tri: Hit::NONE_ID,
            t: f32::INFINITY,
            b1: 0.0,
            b2: 0.0,
        });
        let mut record = [0u8; HIT_BYTES];
        record[..4].copy_from_slice(&h.tri.to_le_bytes());
        for (k, v) in [h.t, h.b1, h.b2].into_iter().enumerate() {
            record[4 + 4 * k..8 + 4 * k].copy_from_slice(&v.to_le_bytes());
        }
        out.write_all(&record)?;
    }
    Ok(())
}

/// `hits` into the hit file at `path`, through a temporary file renamed into place: a failed
/// write leaves whatever `path` held (as a render's image file does).
pub fn save_hits(path: &Path, hits: &[Option<Hit>]) -> Result<()> {
    crate::io::output::write_atomically(path, |out| {
        write_hits(out, hits).map_err(|e| Error::io(path, e))
    })
}

/// Parse a hit file's bytes; the length must be a whole number of records.
pub fn parse_hits(bytes: &[u8], path: &Path) -> Result<Vec<Option<Hit>>> {
    if !bytes.len().is_multiple_of(HIT_BYTES) {
        return Err(Error::parse(
            path,
            0,
            "not a whole number of 16-byte hit records",
        ));
    }
    Ok(bytes
        .chunks_exact(HIT_BYTES)
        .map(|r| {
            let w = |k: usize| <[u8; 4]>::try_from(&r[4 * k..4 * k + 4]).expect("4 bytes");
            let tri = u32::from_le_bytes(w(0));
            (tri != Hit::NONE_ID).then(|| Hit {
                tri,
                t: f32::from_le_bytes(w(1)),
                b1: f32::from_le_bytes(w(2)),
                b2: f32::from_le_bytes(w(3)),
            })
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The streamed reader gives the in-memory parse's rays and errors, and a hit file
    /// written through the temporary file holds the records.
    #[test]
    fn files_read_and_write_as_the_bytes() {
        let dir = std::env::temp_dir().join(format!("whitted-rays-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // more than the reader's megabyte, records straddling its reads
        let rays: Vec<Ray> = (0..40_000)
            .map(|i| {
                let x = i as f32;
                Ray::new(Vec3::new(x, -x, 0.5), Vec3::new(1.0, x, -2.0), 0.0, x)
            })
            .collect();
        let path = dir.join("r.bin");
        std::fs::write(&path, encode_rays(&rays)).unwrap();
        assert_eq!(read_rays(&path).unwrap(), rays);
        std::fs::write(&path, [0u8; 33]).unwrap();
        let e = read_rays(&path).unwrap_err().to_string();
        assert!(e.contains("r.bin") && e.contains("33 bytes"), "{e}");
        std::fs::write(&path, []).unwrap();
        assert_eq!(read_rays(&path).unwrap(), vec![]);
        let e = read_rays(&dir.join("missing.bin")).unwrap_err().to_string();
        assert!(e.contains("missing.bin"), "{e}");
        // an absurd size (a sparse file: no disk, no memory) is refused before anything is
        // allocated or read
        let huge = dir.join("huge.bin");
        let f = std::fs::File::create(&huge).unwrap();
        f.set_len(MAX_RAY_FILE_BYTES + RAY_BYTES as u64).unwrap();
        drop(f);
        let e = read_rays(&huge).unwrap_err().to_string();
        assert!(e.contains("huge.bin") && e.contains("over the cap"), "{e}");
        std::fs::remove_file(&huge).unwrap();
        let hits: Vec<Option<Hit>> = (0..50_000u32)
            .map(|i| {
                (i % 3 != 0).then_some(Hit {
                    tri: i,
                    t: i as f32,
                    b1: 0.25,
                    b2: 0.5,
                })
            })
            .collect();
        let out = dir.join("h.bin");
        save_hits(&out, &hits).unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), encode_hits(&hits));
        // a failed write (the target is a folder) leaves no temporary file behind
        assert!(save_hits(&dir, &hits).is_err());
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["h.bin", "r.bin"]);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn roundtrip_and_bad_length() {
        let rays = vec![Ray::new(Vec3::ONE, Vec3::Z, 0.0, f32::INFINITY); 3];
        assert_eq!(
            parse_rays(&encode_rays(&rays), Path::new("r")).unwrap(),
            rays
        );
        let e = parse_rays(&[0; 33], Path::new("r.bin"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("r.bin") && e.contains("33 bytes"), "{e}");
        let hits = vec![
            None,
            Some(Hit {
                tri: 7,
                t: 1.5,
                b1: 0.25,
                b2: 0.5,
            }),
        ];
        assert_eq!(
            parse_hits(&encode_hits(&hits), Path::new("h")).unwrap(),
            hits
        );
    }
}
