//! glTF images as textures: a file beside the model (`uri`), a base64 `data:` URI, or PNG or
//! JPEG bytes in a buffer view (GLB files keep them in their binary chunk).
//!
//! A material's texture names an embedded image as `MODEL#images[N]` (the model's path, then
//! the image's JSON path), so a scene printed by `whitted scene model.glb` still finds it; the
//! scene builder decodes it through [`load_image`] when the material is built. The mesh loader
//! only checks where the bytes are ([`source`]), so loading a mesh decodes no image.

use super::{Document, FileReader, at, load_buffers, percent_decode};
use crate::error::{Error, Result};
use crate::io::image::decode_texture;
use crate::texture::Texture;
use serde::Deserialize;
use std::path::Path;

/// `images[i]`: a file or data URI (`uri`), or bytes in a buffer view (`bufferView` with
/// `mimeType`).
#[derive(Debug, Deserialize)]
#[serde(rename_all = "camelCase")]
pub(super) struct ImageJson {
    uri: Option<String>,
    buffer_view: Option<usize>,
    mime_type: Option<String>,
}

/// The image types glTF 2.0 defines (others come with extensions whitted does not read).
const MIME_TYPES: [(&str, &str); 2] = [("image/png", "png"), ("image/jpeg", "jpg")];

/// Where an image's bytes are.
#[derive(Debug, PartialEq)]
pub(super) enum Source {
    /// A file beside the model (the `uri` with its `%`-escapes decoded).
    File(String),
    /// In the model: a `data:` URI or a buffer view.
    Embedded,
}

/// Where `images[i]`'s bytes are, checked without reading them: exactly one of `uri` and
/// `bufferView`, a buffer view inside its buffer, a PNG or JPEG `mimeType`.
pub(super) fn source(doc: &Document, i: usize, path: &Path) -> Result<Source> {
    let key = format!("images[{i}]");
    let image = doc.images.get(i).ok_or_else(|| {
        at(
            path,
            "images",
            format!("no image {i} (the file has {})", doc.images.len()),
        )
    })?;
    match (&image.uri, image.buffer_view) {
        (Some(_), Some(_)) => Err(at(path, &key, "has both a uri and a bufferView")),
        (None, None) => Err(at(path, &key, "has neither a uri nor a bufferView")),
        (Some(uri), None) if uri.starts_with("data:") => {
            if !uri
                .split_once(',')
                .is_some_and(|(h, _)| h.ends_with(";base64"))
            {
                return Err(at(
                    path,
                    &format!("{key}.uri"),
                    "only base64 data URIs are read",
                ));
            }
            Ok(Source::Embedded)
        }
        (Some(uri), None) => percent_decode(uri)
            .map(Source::File)
            .map_err(|m| at(path, &format!("{key}.uri"), m)),
        (None, Some(v)) => {
            extension_of(image, &key, path)?;
            let view = doc.buffer_views.get(v).ok_or_else(|| {
                at(
                    path,
                    &format!("{key}.bufferView"),
                    format!(
                        "no buffer view {v} (the file has {})",
                        doc.buffer_views.len()
                    ),
                )
            })?;
            let buffer = doc.buffers.get(view.buffer).ok_or_else(|| {
                at(
                    path,
                    &format!("bufferViews[{v}].buffer"),
                    format!("no buffer {}", view.buffer),
                )
            })?;
            let end = view.byte_offset.checked_add(view.byte_length);
            if end.is_none_or(|e| e > buffer.byte_length) {
                return Err(at(
                    path,
                    &format!("bufferViews[{v}]"),
                    format!(
                        "{} bytes from byte {} run past buffer {} ({} bytes)",
                        view.byte_length, view.byte_offset, view.buffer, buffer.byte_length
                    ),
                ));
            }
            Ok(Source::Embedded)
        }
    }
}

/// The file extension of a buffer-view image's `mimeType` (required with `bufferView`).
fn extension_of(image: &ImageJson, key: &str, path: &Path) -> Result<&'static str> {
    let mime = image.mime_type.as_deref().ok_or_else(|| {
        at(
            path,
            &format!("{key}.mimeType"),
            "missing (an image in a bufferView needs one)",
        )
    })?;
    MIME_TYPES
        .iter()
        .find(|(m, _)| *m == mime)
        .map(|(_, ext)| *ext)
        .ok_or_else(|| {
            at(
                path,
                &format!("{key}.mimeType"),
                format!("'{mime}': only image/png and image/jpeg are read"),
            )
        })
}

/// The texture name of `images[i]` embedded in the model at `model`: `model#images[i]`.
pub(super) fn reference(model: &Path, i: usize) -> String {
    let abs = std::path::absolute(model).unwrap_or_else(|_| model.to_path_buf());
    format!("{}#images[{i}]", abs.display())
}

/// A material texture that names an image inside a glTF file (`model.glb#images[2]`): the
/// model's path and the image's index. `None` for anything else (an image file).
pub fn image_ref(texture: &str) -> Option<(&str, usize)> {
    let (file, rest) = texture.rsplit_once("#images[")?;
    let index = rest.strip_suffix(']')?.parse().ok()?;
    let ext = crate::io::extension(Path::new(file));
    (ext == "gltf" || ext == "glb").then_some((file, index))
}

/// Decode `images[index]` of the glTF or GLB file at `path` into a linear-RGB texture
/// (8-bit PNG and JPEG are sRGB-decoded, as image files are). Errors name the file and the
/// JSON path (`model.glb: glTF images[0]: cannot decode: ...`).
pub fn load_image(path: &Path, index: usize) -> Result<Texture> {
    let bytes = crate::io::read_regular(path)?;
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    image_in(&bytes, path, index, &mut |name| {
        crate::io::read_regular(&dir.join(name))
    })
}

/// [`load_image`] on the model's bytes, `read_file` reading the files it names.
pub(super) fn image_in(
    bytes: &[u8],
    path: &Path,
    index: usize,
    read_file: &mut FileReader,
) -> Result<Texture> {
    let (doc, bin) = super::document(bytes, path)?;
    let key = format!("images[{index}]");
    let image = &doc.images.get(index).ok_or_else(|| {
        at(
            path,
            "images",
            format!("no image {index} (the file has {})", doc.images.len()),
        )
    })?;
    let (data, ext): (Vec<u8>, &str) = match (source(&doc, index, path)?, &image.uri) {
        (Source::File(name), _) => {
            let data = read_file(&name)
                .map_err(|e| at(path, &format!("{key}.uri"), format!("'{name}': {e}")))?;
            // The decoder tells PNG and JPEG by content; the name is for the others.
            let ext = MIME_TYPES
                .iter()
                .map(|m| m.1)
                .find(|e| crate::io::extension(Path::new(&name)) == *e)
                .unwrap_or("png");
            (data, ext)
        }
        (Source::Embedded, Some(uri)) => {
            let head = uri.split_once(',').map_or("", |h| h.0);
            let ext = MIME_TYPES
                .iter()
                .find(|(m, _)| head.starts_with(&format!("data:{m}")))
                .map_or("png", |m| m.1);
            let data =
                super::decode_data_uri(uri).map_err(|m| at(path, &format!("{key}.uri"), m))?;
            (data, ext)
        }
        (Source::Embedded, None) => {
            let ext = extension_of(image, &key, path)?;
            let buffers = load_buffers(&doc, bin, path, read_file)?;
            // `source` found the view inside its buffer's byteLength, and `load_buffers` the
            // buffer holding at least that many bytes.
            let view = image.buffer_view.and_then(|v| doc.buffer_views.get(v));
            let bytes = view.and_then(|v| {
                let start = usize::try_from(v.byte_offset).ok()?;
                let end = start.checked_add(usize::try_from(v.byte_length).ok()?)?;
                buffers.get(v.buffer)?.get(start..end)
            });
            let bytes =
                bytes.ok_or_else(|| at(path, &format!("{key}.bufferView"), "out of range"))?;
            (bytes.to_vec(), ext)
        }
    };
    // The decoder names what it reads by this path: the JSON path, with an extension for
    // formats it cannot tell by content.
    let named = format!("{key}.{ext}");
    decode_texture(&data, Path::new(&named))
        .map(|(t, _)| t)
        .map_err(|e| match e {
            Error::Image { msg, .. } => at(path, &key, msg),
            e => e,
        })
}
