//! MTL material libraries (the `mtllib` of OBJ files), read strictly, and their mapping onto
//! whitted's Whitted terms (the table is in the README).
//!
//! Read: `newmtl`, `Ka Kd Ks Ke Tf` (one number or `r g b`), `Ns Ni d Tr`, `illum 0-10`,
//! `map_Kd [options] file` (file names may hold spaces). Other statements (maps other than
//! `map_Kd`, PBR extensions, `sharpness`, ...) are skipped. Every number must be finite and
//! colours >= 0; errors name the file and line.

use crate::error::{Error, Result};
use crate::io::scene::schema::{Coef, MaterialDesc};
use serde::Serialize;
use std::path::Path;

/// One `newmtl` block as written (absent statements are `None`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct MtlMaterial {
    /// Its `newmtl` name.
    pub name: String,
    /// File and line of its `newmtl`, for messages.
    #[serde(skip)]
    pub origin: String,
    /// `Ka`, ambient colour.
    pub ka: Option<[f32; 3]>,
    /// `Kd`, diffuse colour.
    pub kd: Option<[f32; 3]>,
    /// `Ks`, specular colour.
    pub ks: Option<[f32; 3]>,
    /// `Ke`, emitted colour.
    pub ke: Option<[f32; 3]>,
    /// `Tf`, transmission filter.
    pub tf: Option<[f32; 3]>,
    /// `Ns`, specular exponent.
    pub ns: Option<f32>,
    /// `Ni`, index of refraction.
    pub ni: Option<f32>,
    /// Dissolve (`d`, 1 = opaque), or `1 - Tr`.
    pub d: Option<f32>,
    /// `illum`, the illumination model.
    pub illum: Option<u8>,
    /// `map_Kd`, the diffuse texture file as written.
    pub map_kd: Option<String>,
}

/// What `whitted info` reports about one material: the statements as written, and whether
/// its `map_Kd` file was found (and used).
#[derive(Clone, Debug, Serialize, PartialEq)]
pub struct MtlInfo {
    /// The material as written.
    #[serde(flatten)]
    pub material: MtlMaterial,
    /// Whether the `map_Kd` file was found (and used).
    pub map_kd_found: Option<bool>,
}

/// Options of texture statements and how many arguments each takes (MTL spec, "Texture map
/// statements"); the file name follows them.
const MAP_OPTIONS: [(&str, usize); 13] = [
    ("-blendu", 1),
    ("-blendv", 1),
    ("-bm", 1),
    ("-boost", 1),
    ("-cc", 1),
    ("-clamp", 1),
    ("-imfchan", 1),
    ("-mm", 2),
    ("-o", 3),
    ("-s", 3),
    ("-t", 3),
    ("-texres", 1),
    ("-type", 1),
];

/// The file name of a texture statement after its options (which may take 1 to 3 numbers:
/// `-o u [v [w]]`).
fn map_file(rest: &str) -> Option<String> {
    let mut rest = rest.trim_start();
    while rest.starts_with('-') {
        let (opt, after) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
        let (_, max) = MAP_OPTIONS.iter().find(|(o, _)| *o == opt)?;
        let mut after = after.trim_start();
        for k in 0..*max {
            let (word, next) = after.split_once(char::is_whitespace).unwrap_or((after, ""));
            // -o/-s/-t take 1 to 3 numbers: stop at the first word that is not one.
            if k > 0 && word.parse::<f32>().is_err() {
                break;
            }
            after = next.trim_start();
        }
        rest = after;
    }
    let name = rest.trim();
    (!name.is_empty()).then(|| name.to_string())
}

/// Parse an MTL file.
pub fn parse_mtl(bytes: &[u8], path: &Path) -> Result<Vec<MtlMaterial>> {
    let mut out: Vec<MtlMaterial> = Vec::new();
    for (index, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = index + 1;
        let err = |msg: String| Error::parse(path, line_no, msg);
        let text = super::text_line(raw, path, line_no, "an MTL")?;
        if text.is_empty() {
            continue;
        }
        let (kind, rest) = text.split_once(char::is_whitespace).unwrap_or((text, ""));
        let rest = rest.trim();
        if kind == "newmtl" {
            if rest.is_empty() {
                return Err(err("newmtl: no material name".into()));
            }
            out.push(MtlMaterial {
                name: rest.to_string(),
                origin: format!("{}:{line_no}", path.display()),
                ..Default::default()
            });
            continue;
        }
        let number = |t: &str| -> Result<f32> {
            let x: f32 = t
                .parse()
                .map_err(|_| err(format!("{kind}: '{t}' is not a number")))?;
            if x.is_finite() {
                Ok(x)
            } else {
                Err(err(format!("{kind}: '{t}' is not a finite number")))
            }
        };
        let one = || -> Result<f32> {
            let words: Vec<&str> = rest.split_whitespace().collect();
            match words.as_slice() {
                [w] => number(w),
                // `d -halo 0.5`: the halo variant is read as plain dissolve.
                ["-halo", w] if kind == "d" => number(w),
                _ => Err(err(format!("{kind}: expected one number"))),
            }
        };
        let color = || -> Result<Option<[f32; 3]>> {
            let words: Vec<&str> = rest.split_whitespace().collect();
            // `Kd spectral file.rfl` and `Kd xyz x y z` are other colour forms: skipped.
            if matches!(words.first(), Some(&"spectral" | &"xyz")) {
                return Ok(None);
            }
            let c = match words.as_slice() {
                [r] => [number(r)?; 3],
                [r, g, b] => [number(r)?, number(g)?, number(b)?],
                _ => return Err(err(format!("{kind}: expected r [g b]"))),
            };
            if c.iter().any(|&x| x < 0.0) {
                return Err(err(format!("{kind}: colour components must be >= 0")));
            }
            Ok(Some(c))
        };
        let known = matches!(
            kind,
            "Ka" | "Kd" | "Ks" | "Ke" | "Tf" | "Ns" | "Ni" | "d" | "Tr" | "illum" | "map_Kd"
        );
        if !known {
            continue;
        }
        let Some(m) = out.last_mut() else {
            return Err(err(format!("{kind} before any newmtl")));
        };
        match kind {
            "Ka" => m.ka = color()?.or(m.ka),
            "Kd" => m.kd = color()?.or(m.kd),
            "Ks" => m.ks = color()?.or(m.ks),
            "Ke" => m.ke = color()?.or(m.ke),
            "Tf" => m.tf = color()?.or(m.tf),
            "Ns" => {
                let v = one()?;
                if v < 0.0 {
                    return Err(err("Ns: must be >= 0".into()));
                }
                m.ns = Some(v);
            }
            "Ni" => {
                let v = one()?;
                if !(v > 0.0) {
                    return Err(err("Ni: must be > 0".into()));
                }
                m.ni = Some(v);
            }
            "d" | "Tr" => {
                let v = one()?;
                if !(0.0..=1.0).contains(&v) {
                    return Err(err(format!("{kind}: must be in [0, 1]")));
                }
                m.d = Some(if kind == "d" { v } else { 1.0 - v });
            }
            "illum" => {
                m.illum = Some(
                    rest.parse::<u8>()
                        .ok()
                        .filter(|&i| i <= 10)
                        .ok_or_else(|| err(format!("illum: '{rest}' is not 0..=10")))?,
                );
            }
            _ => {
                m.map_kd = Some(map_file(rest).ok_or_else(|| err("map_Kd: no file name".into()))?);
            }
        }
    }
    Ok(out)
}

/// Defaults where an MTL block is silent (see the README's table).
const DEFAULT_KD: [f32; 3] = [0.8; 3];
const DEFAULT_NS: f32 = 40.0;
/// Phong exponents beyond this are clamped (MTL allows up to 1000; the lobe is a spike well
/// before that).
const MAX_NS: f32 = 4096.0;

/// Map one MTL material onto whitted's terms. `dir` is where `map_Kd` is looked for (the OBJ
/// file's folder); a missing texture, or one on a mesh without uv, falls back to `Kd` with a
/// warning. `vertex_colors`: the mesh has `v x y z r g b` colours, used as `Od` when there is
/// no texture.
pub fn to_material(
    m: &MtlMaterial,
    dir: &Path,
    has_uv: bool,
    vertex_colors: bool,
    warnings: &mut Vec<String>,
) -> (MaterialDesc, MtlInfo) {
    let illum = m.illum.unwrap_or(if m.ks.is_some() { 2 } else { 1 });
    let kd = m.kd.unwrap_or(DEFAULT_KD);
    // Ambient: Ka, or the diffuse colour when Ka is absent.
    let ka = m.ka.unwrap_or(kd);
    let ks = m.ks.unwrap_or([0.0; 3]);
    let d = m.d.unwrap_or(1.0);
    let mut found = None;
    let texture = m.map_kd.as_ref().and_then(|name| {
        let file = crate::io::find_beside(dir, name);
        found = Some(file.is_some());
        match (file, has_uv) {
            // Absolute, so the scene finds it whatever folders its search path holds.
            (Some(f), true) => Some(
                std::path::absolute(&f)
                    .unwrap_or(f)
                    .to_string_lossy()
                    .into_owned(),
            ),
            (Some(_), false) => {
                warnings.push(format!(
                    "{}: material '{}': map_Kd '{name}' needs uv coordinates, the mesh has none; using Kd",
                    m.origin, m.name
                ));
                found = Some(false);
                None
            }
            (None, _) => {
                warnings.push(format!(
                    "{}: material '{}': map_Kd '{name}' not found in {}; using Kd",
                    m.origin,
                    m.name,
                    crate::io::display_dir(dir)
                ));
                None
            }
        }
    });
    let zero = [0.0; 3];
    let scale = |c: [f32; 3], s: f32| c.map(|x| x * s);
    // (ka, kd, ks: highlight, kr: reflection, kt, ior)
    let (mut a, mut dd, mut s, mut r, mut t, mut ior) = (ka, kd, ks, zero, zero, 1.0);
    let transmission = m.tf.unwrap_or([1.0 - d; 3]);
    match illum {
        // colour on, ambient off: the flat colour Kd (as an emission that casts no light)
        0 => (a, dd, s) = (zero, zero, zero),
        // ambient + diffuse
        1 => s = zero,
        // + highlight; 10 (shadow matte) is drawn as 2
        2 | 10 => {}
        // + ray-traced reflection (5: Fresnel mirror, 8: reflection without ray tracing,
        // both traced as a plain mirror of weight Ks)
        3 | 5 | 8 => r = ks,
        // glass: transparency without bending, + reflection (9: without ray tracing)
        4 | 9 => {
            r = if illum == 4 { ks } else { zero };
            t = transmission;
        }
        // refraction with index Ni, + reflection (7: Fresnel, traced as constant Ks)
        _ => {
            r = ks;
            t = m.tf.unwrap_or(if m.d.is_some() {
                [1.0 - d; 3]
            } else {
                [1.0; 3]
            });
            ior = m.ni.unwrap_or(1.5);
        }
    }
    // A dissolve below 1 on an opaque model (0-3, 5, 8, 10) shows what is behind, straight
    // through; the surface's own terms are scaled by d.
    if d < 1.0 && !matches!(illum, 4 | 6 | 7 | 9) {
        t = [1.0 - d; 3];
        (a, dd, s, r) = (scale(a, d), scale(dd, d), scale(s, d), scale(r, d));
    }
    let ke = if illum == 0 { kd } else { m.ke.unwrap_or(zero) };
    let coef = |c: [f32; 3]| {
        if c[0] == c[1] && c[1] == c[2] {
            Coef::Scalar(c[0])
        } else {
            Coef::Rgb(c)
        }
    };
    let desc = MaterialDesc {
        name: m.name.clone(),
        color: (texture.is_none() && !vertex_colors).then_some([1.0; 3]),
        vertex_color: texture.is_none() && vertex_colors,
        texture,
        checker: None,
        wrap: None,
        ka: coef(a),
        kd: coef(dd),
        ks: coef(s),
        n: m.ns.unwrap_or(DEFAULT_NS).min(MAX_NS),
        kt: coef(t),
        ior,
        kr: Some(coef(r)),
        ke: coef(ke),
        lamp: illum != 0,
    };
    let info = MtlInfo {
        material: m.clone(),
        map_kd_found: found,
    };
    (desc, info)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<Vec<MtlMaterial>> {
        parse_mtl(s.as_bytes(), Path::new("t.mtl"))
    }

    #[test]
    fn reads_colours_numbers_and_map_names() {
        let m = parse(
            "# c\nnewmtl glass ball\nKd 0.5\nKs 1 0.5 0.25\nNs 80\nNi 1.45\nTr 0.25\nillum 7\n\
             map_Kd -s 2 2 1 -o 0.5 my tex.png\nmap_Bump x.png\nPr 0.3\n",
        )
        .unwrap();
        assert_eq!(m.len(), 1);
        let g = &m[0];
        assert_eq!(g.name, "glass ball");
        assert_eq!(g.kd, Some([0.5; 3]));
        assert_eq!(g.ks, Some([1.0, 0.5, 0.25]));
        assert_eq!(
            (g.ns, g.ni, g.d, g.illum),
            (Some(80.0), Some(1.45), Some(0.75), Some(7))
        );
        assert_eq!(g.map_kd.as_deref(), Some("my tex.png"));
    }

    #[test]
    fn refuses_bad_values_with_their_line() {
        for (text, want) in [
            ("newmtl a\nKd 0.5 0.5\n", "t.mtl:2: Kd: expected r [g b]"),
            (
                "newmtl a\nKd nan 0 0\n",
                "t.mtl:2: Kd: 'nan' is not a finite number",
            ),
            ("newmtl a\nKd -1\n", "t.mtl:2: Kd: colour components"),
            ("newmtl a\nillum 11\n", "t.mtl:2: illum"),
            ("newmtl a\nNi 0\n", "t.mtl:2: Ni"),
            ("newmtl a\nd 2\n", "t.mtl:2: d"),
            ("Kd 1 1 1\n", "t.mtl:1: Kd before any newmtl"),
            ("newmtl\n", "t.mtl:1: newmtl"),
            ("newmtl a\nmap_Kd -s 1 1 1\n", "t.mtl:2: map_Kd"),
        ] {
            let e = parse(text).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }

    #[test]
    fn illumination_models_map_onto_whitted_terms() {
        let base = MtlMaterial {
            name: "m".into(),
            kd: Some([0.6, 0.4, 0.2]),
            ks: Some([0.5; 3]),
            ni: Some(1.33),
            ..Default::default()
        };
        let with = |illum: u8| {
            let m = MtlMaterial {
                illum: Some(illum),
                ..base.clone()
            };
            to_material(&m, Path::new("."), true, false, &mut Vec::new()).0
        };
        let z = Coef::Scalar(0.0);
        let m0 = with(0);
        assert_eq!(
            (m0.kd, m0.ks, m0.ke, m0.lamp),
            (z, z, Coef::Rgb([0.6, 0.4, 0.2]), false)
        );
        let m1 = with(1);
        assert_eq!(
            (m1.ka, m1.ks, m1.kr),
            (Coef::Rgb([0.6, 0.4, 0.2]), z, Some(z))
        );
        let m2 = with(2);
        assert_eq!((m2.ks, m2.kr), (Coef::Scalar(0.5), Some(z)));
        assert_eq!(with(3).kr, Some(Coef::Scalar(0.5)));
        let m4 = with(4);
        assert_eq!((m4.kt, m4.ior), (z, 1.0)); // d absent: opaque glass has no transmission
        let m7 = with(7);
        assert_eq!(
            (m7.kt, m7.ior, m7.kr),
            (Coef::Scalar(1.0), 1.33, Some(Coef::Scalar(0.5)))
        );
        // a missing texture falls back to Kd with a warning
        let mut w = Vec::new();
        let m = MtlMaterial {
            map_kd: Some("nope.png".into()),
            ..base.clone()
        };
        let (d, info) = to_material(&m, Path::new("."), true, false, &mut w);
        assert_eq!(
            (d.texture, d.color, info.map_kd_found),
            (None, Some([1.0; 3]), Some(false))
        );
        assert!(
            w[0].contains("nope.png") && w[0].contains("using Kd"),
            "{w:?}"
        );
    }
}
