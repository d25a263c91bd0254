//! Binary ray and hit files of `whitted trace-rays` (little-endian).
//!
//! Ray record, 32 bytes: `f32 ox oy oz dx dy dz tnear tfar`.
//! Hit record, 16 bytes: `u32 triangle` (mesh face order, `0xFFFFFFFF` = miss), `f32 t`,
//! `f32 b1`, `f32 b2` (weights of the triangle's second and third vertex; a miss writes
//! `t = +inf`, `b1 = b2 = 0`).

use crate::error::{Error, Result};
use crate::ray::{Hit, Ray};
use glam::Vec3;
use std::path::Path;

/// Bytes of one ray record.
pub const RAY_BYTES: usize = 32;
/// Bytes of one hit record.
pub const HIT_BYTES: usize = 16;

/// Parse a ray file's bytes; the length must be a whole number of records.
pub fn parse_rays(bytes: &[u8], path: &Path) -> Result<Vec<Ray>> {
    if !bytes.len().is_multiple_of(RAY_BYTES) {
        return Err(Error::parse(
            path,
            0,
            format!(
                "{} bytes is not a whole number of 32-byte ray records",
                bytes.len()
            ),
        ));
    }
    Ok(bytes
        .chunks_exact(RAY_BYTES)
        .map(|r| {
            let f = |k: usize| f32::from_le_bytes(r[4 * k..4 * k + 4].try_into().expect("4 bytes"));
            Ray::new(
                Vec3::new(f(0), f(1), f(2)),
                Vec3::new(f(3), f(4), f(5)),
                f(6),
                f(7),
            )
        })
        .collect())
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
    for h in hits {
        let h = h.unwrap_or(Hit {
            tri: Hit::NONE_ID,
            t: f32::INFINITY,
            b1: 0.0,
            b2: 0.0,
        });
        out.extend_from_slice(&h.tri.to_le_bytes());
        for v in [h.t, h.b1, h.b2] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
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
