//! The bodies of the fuzz targets (`fuzz/fuzz_targets/*.rs`), here so that ordinary tests can
//! run them over the seed corpora on stable. Each takes arbitrary bytes and must never panic,
//! hang or allocate without bound; an `Err` is a fine outcome.

use crate::error::{Error, Result};
use crate::io::image::{decode_cubemap_capped, decode_texture_capped};
use crate::io::model::NO_MATERIAL;
use crate::io::scene::{SceneFile, SearchPath, build_scene};
use crate::io::{mfile, obj, ply, stl};
use std::path::{Path, PathBuf};

/// The `.m` reader on arbitrary bytes.
pub fn mfile(data: &[u8]) -> Result<()> {
    let (mesh, _) = mfile::parse_m(data, Path::new("fuzz.m"))?;
    check_mesh(&mesh);
    Ok(())
}

/// The OBJ reader (geometry only) on arbitrary bytes.
pub fn obj(data: &[u8]) -> Result<()> {
    let (mesh, _) = obj::parse_obj(data, Path::new("fuzz.obj"))?;
    check_mesh(&mesh);
    Ok(())
}

/// The PLY reader (ASCII and binary) on arbitrary bytes.
pub fn ply(data: &[u8]) -> Result<()> {
    let (mesh, _) = ply::parse_ply(data, Path::new("fuzz.ply"))?;
    check_mesh(&mesh);
    Ok(())
}

/// The STL reader (ASCII and binary) on arbitrary bytes.
pub fn stl(data: &[u8]) -> Result<()> {
    let (mesh, _) = stl::parse_stl(data, Path::new("fuzz.stl"))?;
    check_mesh(&mesh);
    Ok(())
}

/// The glTF reader (JSON or GLB) on arbitrary bytes; buffers and images named by file are
/// never read (each such name is an error).
pub fn gltf(data: &[u8]) -> Result<()> {
    let path = Path::new("fuzz.gltf");
    let (model, _) = crate::io::gltf::parse_with(data, path, &mut |name| {
        Err(Error::parse(
            Path::new(name),
            0,
            "files are not read while fuzzing",
        ))
    })?;
    check_model(&model);
    Ok(())
}

/// A model's mesh holds together ([`check_mesh`]) and every face's material is one of its
/// materials; so do its shared meshes, whose placements are finite and invertible.
fn check_model(model: &crate::io::model::Model) {
    for s in &model.shared {
        check_model(&s.model);
        assert!(s.placements.iter().all(crate::instance::invertible));
    }
    // (a model whose meshes are all shared has no mesh of its own)
    if model.shared.is_empty() || !model.mesh.triangles.is_empty() {
        check_mesh(&model.mesh);
    }
    if let Some(f) = &model.face_materials {
        assert_eq!(f.len(), model.mesh.triangles.len());
        assert!(
            f.iter()
                .all(|&m| m == NO_MATERIAL || (m as usize) < model.materials.len())
        );
    }
}

/// The OBJ reader with materials: the OBJ is the bytes before the first `--mtl--` line, the
/// MTL file every `mtllib` names is the bytes after it (never a file on disk).
pub fn obj_mtl(data: &[u8]) -> Result<()> {
    let sep = b"\n--mtl--\n";
    let (obj_bytes, mtl_bytes) = match data.windows(sep.len()).position(|w| w == sep) {
        Some(at) => (&data[..at], &data[at + sep.len()..]),
        None => (data, &[][..]),
    };
    let (model, _) = obj::parse_obj_model(obj_bytes, Path::new("fuzz.obj"), &mut |_, _, _| {
        crate::io::mtl::parse_mtl(mtl_bytes, Path::new("fuzz.mtl"))
    })?;
    check_model(&model);
    Ok(())
}

/// The scene parser and validator on arbitrary bytes. Relative file names resolve only in
/// `empty_dir` (give an empty folder), so nothing outside the input is read by name.
pub fn scene(data: &[u8], empty_dir: &Path) -> Result<()> {
    let path = Path::new("fuzz.toml");
    let text = std::str::from_utf8(data).map_err(|_| Error::parse(path, 1, "invalid UTF-8"))?;
    let file = SceneFile::parse(text, path)?;
    let search = SearchPath {
        dirs: vec![empty_dir.to_path_buf()],
    };
    let (scene, _) = build_scene(&file, path, &search)?;
    assert!(scene.width > 0 && scene.height > 0);
    for o in &scene.objects {
        check_mesh(&o.mesh);
    }
    Ok(())
}

/// Extensions the image target picks from with its first byte (TGA has no signature, so the
/// name matters).
pub const IMAGE_EXTENSIONS: [&str; 6] = ["png", "jpg", "tga", "bmp", "hdr", "exr"];

/// The pixel cap the image and cube-map targets decode with, instead of the production
/// [`MAX_TEXTURE_PIXELS`](crate::io::image::MAX_TEXTURE_PIXELS) of 2^25: a few hundred bytes
/// of JPEG can claim a 16M-pixel image, and filling it took half a second per run, so the
/// targets ran at 1k executions a second. At 2^16 the fuzzer soon found JPEGs of 14852x4
/// (with large sampling factors, so the decoder works on padded blocks) at 10-25 ms each and
/// slowed to under 3k a second; 2^14 pixels (128x128, or a side up to 16384 long) keeps every
/// decoder path reachable at tens of microseconds a run. The cap check is the same code with
/// either value and is tested on its own (`tests/inputs.rs`).
pub const FUZZ_MAX_PIXELS: u64 = 1 << 14;

/// One texture decode: the first byte picks the file extension, the rest is the file.
/// Images over [`FUZZ_MAX_PIXELS`] are refused.
pub fn image(data: &[u8]) -> Result<()> {
    let (&pick, bytes) = data
        .split_first()
        .ok_or_else(|| Error::image(Path::new("fuzz"), "empty input"))?;
    let name = format!(
        "fuzz.{}",
        IMAGE_EXTENSIONS[pick as usize % IMAGE_EXTENSIONS.len()]
    );
    let (tex, info) = decode_texture_capped(bytes, Path::new(&name), FUZZ_MAX_PIXELS)?;
    let texels = tex.linear_texels();
    assert_eq!(texels.len(), tex.width * tex.height);
    assert!(info.width > 0 && info.height > 0);
    assert!(texels.iter().all(|t| t.is_finite()));
    Ok(())
}

/// Separates the six faces in a cube-map fuzz input.
pub const FACE_SEPARATOR: &[u8] = b"--face--";

/// A cube map from six face files: the first byte picks the extension (as for [`image`](fn@image)),
/// the rest is split on [`FACE_SEPARATOR`] into posx, negx, posy, negy, posz, negz. Faces
/// over [`FUZZ_MAX_PIXELS`] are refused.
pub fn cubemap(data: &[u8]) -> Result<()> {
    let (&pick, rest) = data
        .split_first()
        .ok_or_else(|| Error::image(Path::new("fuzz"), "empty input"))?;
    let ext = IMAGE_EXTENSIONS[pick as usize % IMAGE_EXTENSIONS.len()];
    let mut parts = split_on(rest, FACE_SEPARATOR);
    parts.resize(6, &[]);
    let names: [PathBuf; 6] = std::array::from_fn(|k| {
        PathBuf::from(format!("cube/{}.{ext}", crate::texture::CUBE_FACES[k]))
    });
    let faces = std::array::from_fn(|k| (names[k].as_path(), parts[k]));
    let (cube, _) = decode_cubemap_capped(faces, FUZZ_MAX_PIXELS)?;
    let w = cube.faces[0].width;
    assert!(cube.faces.iter().all(|f| f.width == w && f.height == w));
    Ok(())
}

fn split_on<'a>(mut data: &'a [u8], sep: &[u8]) -> Vec<&'a [u8]> {
    let mut out = Vec::new();
    while let Some(at) = data.windows(sep.len()).position(|w| w == sep) {
        out.push(&data[..at]);
        data = &data[at + sep.len()..];
    }
    out.push(data);
    out
}

/// What every loaded mesh promises the renderer.
fn check_mesh(mesh: &crate::mesh::Mesh) {
    let n = mesh.positions.len();
    assert!(!mesh.triangles.is_empty());
    assert!(mesh.triangles.iter().flatten().all(|&i| (i as usize) < n));
    assert!(mesh.positions.iter().all(|p| p.is_finite()));
    let normals = mesh.normals.as_ref().expect("normals filled in");
    assert_eq!(normals.len(), n);
    assert!(normals.iter().all(|v| v.is_finite()));
    assert!(mesh.uvs.as_ref().is_none_or(|u| u.len() == n));
    assert!(mesh.colors.as_ref().is_none_or(|c| c.len() == n));
}
