//! glTF materials in whitted's terms: the metallic-roughness mapping against hand-computed
//! values, samplers' wrap modes, embedded images (GLB buffer views and data URIs) decoded to
//! the texels written, and each error naming the file and the JSON path.

use super::super::image::image_in;
use super::super::tests::{SQUARE, doc, err, floats, glb, parse};
use super::*;
use crate::io::scene::schema::Coef;
use glam::Vec3;
use serde_json::{Value, json};

/// `a` and `b` agree to 1e-5 relative (f32 arithmetic in a different order).
fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-5 * a.abs().max(b.abs()).max(1.0)
}

fn close3(a: [f32; 3], b: [f32; 3]) -> bool {
    (0..3).all(|i| close(a[i], b[i]))
}

fn coef_is(c: Coef, want: [f32; 3]) -> bool {
    close3(c.rgb(), want)
}

fn dielectric(base: [f32; 3], roughness: f32) -> Factors {
    Factors {
        base,
        metallic: 0.0,
        roughness,
        transmission: 0.0,
        ior: 1.5,
    }
}

/// Every term of the mapping, computed by hand for five materials.
#[test]
fn metallic_roughness_maps_onto_whitted_terms() {
    // Plastic, roughness 0.5: F0 = 0.04; a = 0.25, n = 0.5/0.0625 - 0.5 = 7.5; s = 0.25.
    let t = terms(dielectric([0.8, 0.4, 0.2], 0.5));
    assert!(close(t.n, 7.5) && close(t.kd, 0.96) && close(t.ka, 0.96));
    assert!(close3(t.ks, [0.19; 3])); // 0.04 * 9.5 / 2
    assert!(close3(t.kr, [0.01; 3])); // 0.04 * 0.25
    assert!(close3(t.kt, [0.0; 3]) && t.ior == 1.5);
    // Metal (1, 0.5, 0.25), roughness 0.2: a = 0.04, n = 312.5 - 0.5 = 312; s = 0.64.
    let t = terms(Factors {
        metallic: 1.0,
        ..dielectric([1.0, 0.5, 0.25], 0.2)
    });
    assert!(close(t.n, 312.0) && close(t.kd, 0.36) && close(t.ka, 0.36));
    // ks = 0.64 C (312 + 2) / 2 = 100.48 C; kr = 0.64 C.
    assert!(close3(t.ks, [100.48, 50.24, 25.12]), "{:?}", t.ks);
    assert!(close3(t.kr, [0.64, 0.32, 0.16]));
    // Rough metal (roughness 1): all diffuse, tinted by Od; no highlight, no mirror.
    let t = terms(Factors {
        metallic: 1.0,
        ..dielectric([1.0, 0.5, 0.25], 1.0)
    });
    assert!(close(t.n, 1.0) && close(t.kd, 1.0) && close3(t.ks, [0.0; 3]));
    assert!(close3(t.kr, [0.0; 3]));
    // Smooth glass (transmission 1, roughness 0, ior 1.5): n at the cap, a mirror of 0.04,
    // kt = 0.96 C, no diffuse.
    let t = terms(Factors {
        transmission: 1.0,
        ..dielectric([1.0, 0.9, 0.8], 0.0)
    });
    assert!(t.n == MAX_N && close(t.kd, 0.0) && close3(t.kr, [0.04; 3]));
    assert!(close3(t.ks, [0.04 * 4098.0 / 2.0; 3]));
    assert!(close3(t.kt, [0.96, 0.864, 0.768]) && t.ior == 1.5);
    // ior 2: F0 = (1/3)^2; ior 0 (KHR_materials_ior's "reflects everything"): F0 = 1.
    let t = terms(Factors {
        ior: 2.0,
        ..dielectric([1.0; 3], 1.0)
    });
    assert!(close(t.kd, 1.0 - 1.0 / 9.0) && t.ior == 2.0);
    assert!(close3(t.ks, [1.5 / 9.0; 3]));
    let t = terms(Factors {
        ior: 0.0,
        ..dielectric([1.0; 3], 0.0)
    });
    assert!(close(t.kd, 0.0) && close3(t.kr, [1.0; 3]) && t.ior == 1.5);
}

/// A 2x2 RGB PNG: red, green (top row), blue, white.
fn png() -> Vec<u8> {
    let mut out = Vec::new();
    let mut enc = ::png::Encoder::new(&mut out, 2, 2);
    enc.set_color(::png::ColorType::Rgb);
    enc.set_depth(::png::BitDepth::Eight);
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&[255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255])
        .unwrap();
    w.finish().unwrap();
    out
}

/// The texels [`png`] decodes to (8-bit 0 and 255 are exact in linear RGB).
const TEXELS: [Vec3; 4] = [Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE];

fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            out.push(if k <= c.len() {
                ABC[(n >> (18 - 6 * k) & 63) as usize] as char
            } else {
                '='
            });
        }
    }
    out
}

/// A textured square: uv (accessor 2), material 0 with `baseColorTexture` 0 through
/// sampler 0 (MIRRORED_REPEAT along u, CLAMP_TO_EDGE along v), [`png`] in buffer view 3 and
/// `image` as images[0].
fn textured(image: Value) -> (Value, Vec<u8>) {
    let (mut d, mut bin) = doc(&SQUARE, Some(&[0, 1, 2, 0, 2, 3]));
    let uv_start = bin.len();
    bin.extend(floats(&[0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0]));
    let png = png();
    let png_start = bin.len();
    bin.extend(&png);
    d["bufferViews"].as_array_mut().unwrap().extend([
        json!({"buffer": 0, "byteOffset": uv_start, "byteLength": 32}),
        json!({"buffer": 0, "byteOffset": png_start, "byteLength": png.len()}),
    ]);
    d["accessors"]
        .as_array_mut()
        .unwrap()
        .push(json!({"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"}));
    d["buffers"][0]["byteLength"] = json!(bin.len());
    let prim = &mut d["meshes"][0]["primitives"][0];
    prim["attributes"]["TEXCOORD_0"] = json!(2);
    prim["material"] = json!(0);
    d["materials"] = json!([{"name": "tex", "pbrMetallicRoughness": {
        "baseColorTexture": {"index": 0}, "baseColorFactor": [0.5, 1, 1, 1],
        "metallicFactor": 0, "roughnessFactor": 0.5}}]);
    d["textures"] = json!([{"source": 0, "sampler": 0}]);
    d["samplers"] = json!([{"wrapS": 33648, "wrapT": 33071}]);
    d["images"] = json!([image]);
    (d, bin)
}

fn in_view() -> Value {
    json!({"bufferView": 3, "mimeType": "image/png"})
}

fn no_files(name: &str) -> crate::error::Result<Vec<u8>> {
    Err(crate::error::Error::parse(
        Path::new(name),
        0,
        "no files in tests",
    ))
}

/// The base colour texture of a GLB: an `images[0]` reference, the sampler's wrap modes, the
/// factor moved into `ka` and `kd`; the image decodes to the texels written, from the GLB's
/// buffer view and from a data URI alike.
#[test]
fn embedded_base_colour_textures_keep_their_wrap_modes() {
    let (d, bin) = textured(in_view());
    let bytes = glb(&d, &bin);
    let (model, warnings) = parse(&bytes).unwrap();
    assert!(warnings.is_empty(), "{warnings:?}");
    let m = &model.materials[0];
    let want = format!(
        "{}#images[0]",
        std::path::absolute("t.gltf").unwrap().display()
    );
    assert_eq!(m.texture.as_deref(), Some(want.as_str()));
    assert_eq!(m.wrap, Some([Wrap::MirroredRepeat, Wrap::Clamp]));
    assert_eq!((m.color, m.vertex_color), (None, false));
    // kd = 0.96 C, ka = kd (roughness 0.5 dielectric, as above).
    assert!(coef_is(m.kd, [0.48, 0.96, 0.96]) && coef_is(m.ka, [0.48, 0.96, 0.96]));
    assert!(coef_is(m.ks, [0.19; 3]) && close(m.n, 7.5));
    assert_eq!(
        super::super::image_ref(&want),
        Some((&want[..want.len() - 10], 0))
    );
    let tex = image_in(&bytes, Path::new("t.glb"), 0, &mut no_files).unwrap();
    assert_eq!(
        (tex.width, tex.height, &tex.linear_texels()[..]),
        (2, 2, &TEXELS[..])
    );
    // The same image as a data URI in a .gltf.
    let uri = format!("data:image/png;base64,{}", base64(&png()));
    let (d, bin) = textured(json!({ "uri": uri }));
    let bytes = glb(&d, &bin);
    let (model, _) = parse(&bytes).unwrap();
    assert_eq!(model.materials[0].texture.as_deref(), Some(want.as_str()));
    let tex = image_in(&bytes, Path::new("t.glb"), 0, &mut no_files).unwrap();
    assert_eq!(tex.linear_texels(), TEXELS);
    // An image file: its absolute path, read by the scene builder as any texture file.
    let (d, bin) = textured(json!({"uri": "my%20tex.png"}));
    let (model, _) = parse(&glb(&d, &bin)).unwrap();
    let file = std::path::absolute("my tex.png").unwrap();
    assert_eq!(model.materials[0].texture.as_deref(), file.to_str());
    // No sampler, or one without wrap modes: repeat, which the description leaves out.
    for textures in [json!([{"source": 0}]), json!([{"source": 0, "sampler": 1}])] {
        let (mut d, bin) = textured(in_view());
        d["textures"] = textures;
        d["samplers"] = json!([{"wrapS": 33071}, {"magFilter": 9728}]);
        let (model, _) = parse(&glb(&d, &bin)).unwrap();
        assert_eq!(model.materials[0].wrap, None);
    }
    let (mut d, bin) = textured(in_view());
    d["samplers"] = json!([{"wrapS": 10497, "wrapT": 33648}]);
    let (model, _) = parse(&glb(&d, &bin)).unwrap();
    assert_eq!(
        model.materials[0].wrap,
        Some([Wrap::Repeat, Wrap::MirroredRepeat])
    );
}

/// Colour sources and the extensions: `Od` the factor without a texture; transmission and
/// ior; emission times its strength; textures whitted does not read named in one warning; an
/// emissive texture's material does not emit; a texture through `texCoord` 1 falls back to
/// the factor.
#[test]
fn factors_extensions_and_unread_textures() {
    let (mut d, bin) = textured(in_view());
    d["materials"] = json!([{
        "pbrMetallicRoughness": {"baseColorFactor": [1, 0.9, 0.8, 1], "metallicFactor": 0,
            "roughnessFactor": 0, "metallicRoughnessTexture": {"index": 0}},
        "normalTexture": {"index": 0},
        "emissiveFactor": [1, 0.5, 0],
        "extensions": {
            "KHR_materials_transmission": {"transmissionFactor": 1},
            "KHR_materials_ior": {"ior": 1.5},
            "KHR_materials_emissive_strength": {"emissiveStrength": 4}
        }
    }]);
    let (model, warnings) = parse(&glb(&d, &bin)).unwrap();
    let m = &model.materials[0];
    assert_eq!(
        (m.name.as_str(), m.color),
        ("material0", Some([1.0, 0.9, 0.8]))
    );
    assert!(coef_is(m.kd, [0.0; 3]) && coef_is(m.kt, [0.96, 0.864, 0.768]));
    assert!(m.ior == 1.5 && coef_is(m.kr.unwrap(), [0.04; 3]));
    assert!(coef_is(m.ke, [4.0, 2.0, 0.0]) && m.lamp);
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains(
            "materials[0].pbrMetallicRoughness.metallicRoughnessTexture, materials[0].normalTexture"
        ),
        "{warnings:?}"
    );
    // An emissive texture: not read, so no emission (its factor alone would light all).
    let (mut d, bin) = textured(in_view());
    d["materials"] = json!([{"emissiveFactor": [1, 1, 1], "emissiveTexture": {"index": 0}}]);
    let (model, warnings) = parse(&glb(&d, &bin)).unwrap();
    assert!(model.materials[0].ke.is_zero());
    assert!(
        warnings[0].contains("materials[0].emissiveTexture"),
        "{warnings:?}"
    );
    // Defaults: metallic 1 and roughness 1 (a rough metal: diffuse in its colour).
    let (mut d, bin) = textured(in_view());
    d["materials"] = json!([{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1]}}]);
    let (model, _) = parse(&glb(&d, &bin)).unwrap();
    let m = &model.materials[0];
    assert_eq!(m.color, Some([0.5; 3]));
    assert!(coef_is(m.kd, [1.0; 3]) && m.ks.is_zero() && m.kr.unwrap().is_zero());
    // texCoord 1: the factor, with a warning naming the slot.
    let (mut d, bin) = textured(in_view());
    d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["texCoord"] = json!(1);
    let (model, warnings) = parse(&glb(&d, &bin)).unwrap();
    assert_eq!(
        (model.materials[0].color, &model.materials[0].texture),
        (Some([0.5, 1.0, 1.0]), &None)
    );
    assert!(
        warnings[0].contains("materials[0].pbrMetallicRoughness.baseColorTexture reads TEXCOORD_1"),
        "{warnings:?}"
    );
    // A texture whose image comes only through an extension (EXT_texture_webp).
    let (mut d, bin) = textured(in_view());
    d["textures"] = json!([{"extensions": {"EXT_texture_webp": {"source": 0}}}]);
    d["extensionsUsed"] = json!(["EXT_texture_webp", "KHR_materials_ior"]);
    let (model, warnings) = parse(&glb(&d, &bin)).unwrap();
    assert!(model.materials[0].texture.is_none());
    // One warning names the extensions not read (and not those that are).
    assert!(
        warnings
            .iter()
            .any(|w| w.ends_with("not read (the model is drawn without them): EXT_texture_webp")),
        "{warnings:?}"
    );
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("textures[0] has no source image"))
    );
    // The material extensions may be required; others may not.
    let (mut d, bin) = textured(in_view());
    d["extensionsRequired"] = json!(["KHR_materials_transmission", "KHR_materials_ior"]);
    assert!(parse(&glb(&d, &bin)).is_ok());
    d["extensionsRequired"] = json!(["KHR_materials_ior", "KHR_materials_volume"]);
    let e = err(&glb(&d, &bin));
    assert!(
        e.contains(
            "glTF extensionsRequired[1]: the model requires extension 'KHR_materials_volume'"
        ),
        "{e}"
    );
}

/// Broken materials, textures, samplers and images: each error names the file and the JSON
/// path, at load time (structure) or when the image is decoded.
#[test]
fn material_errors_name_the_json_path() {
    let (d, bin) = textured(in_view());
    let with = |edit: &dyn Fn(&mut Value)| {
        let mut d = d.clone();
        edit(&mut d);
        err(&glb(&d, &bin))
    };
    let pbr = "materials[0].pbrMetallicRoughness";
    let cases = [
        (
            with(&|d| d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["index"] = json!(5)),
            format!("glTF {pbr}.baseColorTexture.index: no texture 5"),
        ),
        (
            with(&|d| d["materials"][0]["pbrMetallicRoughness"]["metallicRoughnessTexture"] = json!({"index": 3})),
            format!("glTF {pbr}.metallicRoughnessTexture.index: no texture 3"),
        ),
        (
            with(&|d| d["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = json!(2)),
            format!("glTF {pbr}.metallicFactor: 2 is not in [0, 1]"),
        ),
        (
            with(&|d| d["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = json!(-0.5)),
            format!("glTF {pbr}.roughnessFactor: -0.5 is not in [0, 1]"),
        ),
        (
            with(&|d| d["materials"][0]["extensions"] = json!({"KHR_materials_transmission": {"transmissionFactor": 1.5}})),
            "glTF materials[0].extensions.KHR_materials_transmission.transmissionFactor: 1.5 is not in [0, 1]".into(),
        ),
        (
            with(&|d| d["materials"][0]["extensions"] = json!({"KHR_materials_ior": {"ior": 0.5}})),
            "glTF materials[0].extensions.KHR_materials_ior.ior: 0.5: must be >= 1 (or 0)".into(),
        ),
        (
            with(&|d| {
                d["materials"][0]["emissiveFactor"] = json!([1, 1, 1]);
                d["materials"][0]["extensions"] =
                    json!({"KHR_materials_emissive_strength": {"emissiveStrength": -1}});
            }),
            "glTF materials[0].extensions.KHR_materials_emissive_strength.emissiveStrength: -1: must be finite and >= 0".into(),
        ),
        (
            with(&|d| d["textures"][0]["sampler"] = json!(4)),
            "glTF textures[0].sampler: no sampler 4 (the file has 1)".into(),
        ),
        (
            with(&|d| d["samplers"][0]["wrapT"] = json!(1234)),
            "glTF samplers[0].wrapT: 1234 is not a wrap mode".into(),
        ),
        (
            with(&|d| d["textures"][0]["source"] = json!(7)),
            "glTF textures[0].source: no image 7 (the file has 1)".into(),
        ),
        (
            with(&|d| d["images"][0]["uri"] = json!("x.png")),
            "glTF images[0]: has both a uri and a bufferView".into(),
        ),
        (
            with(&|d| d["images"] = json!([{"mimeType": "image/png"}])),
            "glTF images[0]: has neither a uri nor a bufferView".into(),
        ),
        (
            with(&|d| d["images"] = json!([{"bufferView": 3}])),
            "glTF images[0].mimeType: missing".into(),
        ),
        (
            with(&|d| d["images"][0]["mimeType"] = json!("image/webp")),
            "glTF images[0].mimeType: 'image/webp': only image/png and image/jpeg are read".into(),
        ),
        (
            with(&|d| d["images"][0]["bufferView"] = json!(9)),
            "glTF images[0].bufferView: no buffer view 9".into(),
        ),
        (
            with(&|d| d["bufferViews"][3]["byteLength"] = json!(100_000)),
            "glTF bufferViews[3]: 100000 bytes from byte".into(),
        ),
        (
            with(&|d| d["images"] = json!([{"uri": "data:image/png,abc"}])),
            "glTF images[0].uri: only base64 data URIs are read".into(),
        ),
        (
            with(&|d| d["images"] = json!([{"uri": "/etc/passwd"}])),
            "glTF images[0].uri: '/etc/passwd': only files beside the model".into(),
        ),
    ];
    for (e, want) in cases {
        assert!(
            e.starts_with("t.gltf: ") && e.contains(&want),
            "{want:?}: {e}"
        );
    }
    // Decoding: bytes that are no image, and a data URI that is no base64.
    let (mut d, mut bin) = textured(in_view());
    let start = d["bufferViews"][3]["byteOffset"].as_u64().unwrap() as usize;
    bin[start..start + 8].copy_from_slice(b"notapng!");
    d["buffers"][0]["byteLength"] = json!(bin.len());
    let e = image_in(&glb(&d, &bin), Path::new("t.glb"), 0, &mut no_files)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("t.glb: glTF images[0]: "), "{e}");
    let (d, bin) = textured(json!({"uri": "data:image/png;base64,@@@@"}));
    let e = image_in(&glb(&d, &bin), Path::new("t.glb"), 0, &mut no_files)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("t.glb: glTF images[0].uri: malformed base64"),
        "{e}"
    );
    // An image index the file does not have; a file image that is missing.
    let e = image_in(&glb(&d, &bin), Path::new("t.glb"), 3, &mut no_files)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("glTF images: no image 3 (the file has 1)"),
        "{e}"
    );
    let (d, bin) = textured(json!({"uri": "gone.png"}));
    let e = image_in(&glb(&d, &bin), Path::new("t.glb"), 0, &mut no_files)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("t.glb: glTF images[0].uri: 'gone.png': "),
        "{e}"
    );
}

/// Texture names that point into glTF files, and names that do not.
#[test]
fn image_references_are_told_from_image_files() {
    use super::super::image_ref;
    assert_eq!(image_ref("/m/a b.glb#images[12]"), Some(("/m/a b.glb", 12)));
    assert_eq!(image_ref("m.GLTF#images[0]"), Some(("m.GLTF", 0)));
    for name in [
        "tex.png",
        "a.png#images[0]",
        "m.glb#images[x]",
        "m.glb#images[1",
        "m.glb",
    ] {
        assert_eq!(image_ref(name), None, "{name}");
    }
}
