//! Reading textures and cube maps, writing renders (`.png` sRGB 8-bit, `.exr` linear float).

use crate::error::{Error, Result};
use crate::image::{Image, srgb_decode};
use crate::texture::{CUBE_FACES, CubeMap, Texture};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// Largest texture accepted, in pixels (checked from the header, before decoding allocates):
/// 2^25, e.g. 8192 x 4096; such a texture takes 400 MB as linear f32 RGB.
pub const MAX_TEXTURE_PIXELS: u64 = 1 << 25;

/// Image file extensions the texture loader reads, in lower case (it also recognises the
/// formats by content).
pub const IMAGE_EXTENSIONS: [&str; 7] = ["png", "jpg", "jpeg", "tga", "bmp", "hdr", "exr"];

/// What a decoded image file was: its format, size and channel layout (for `whitted info`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ImageInfo {
    /// The decoder's name for the format (`png`, `jpeg`, `exr`, ...).
    pub format: String,
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Channels in the file (1 grey, 2 grey + alpha, 3 RGB, 4 RGBA; EXR: its channel count).
    pub channels: usize,
    /// Bits per channel sample in the file (EXR: 16 or 32).
    pub bits: usize,
}

/// Load an image as a linear-RGB texture. 8- and 16-bit formats (PNG, JPEG, TGA, BMP) are
/// sRGB-decoded; EXR and HDR are linear. Alpha is ignored; non-finite EXR/HDR samples become 0.
pub fn load_texture(path: &Path) -> Result<Texture> {
    let bytes = super::read_regular(path)?;
    decode_texture(&bytes, path).map(|(t, _)| t)
}

/// [`load_texture`] on bytes already read; `path` names the file in messages and gives the
/// format when the bytes do not (TGA has no signature).
pub fn decode_texture(bytes: &[u8], path: &Path) -> Result<(Texture, ImageInfo)> {
    decode_texture_capped(bytes, path, MAX_TEXTURE_PIXELS)
}

/// [`decode_texture`] with a pixel cap of the caller's choosing instead of
/// [`MAX_TEXTURE_PIXELS`]. The fuzz targets use a small one: a 700-byte JPEG whose header
/// claims 65531x252 decodes to 16M pixels (half a second and 250 MB), which is the cap
/// working as meant but makes fuzzing crawl.
pub fn decode_texture_capped(
    bytes: &[u8],
    path: &Path,
    max_pixels: u64,
) -> Result<(Texture, ImageInfo)> {
    let ext = crate::io::extension(path);
    if bytes.starts_with(&EXR_MAGIC) || (ext == "exr" && !bytes.is_empty()) {
        return decode_exr(bytes, path, max_pixels);
    }
    let format = image::guess_format(bytes)
        .map_err(|_| {
            Error::image(
                path,
                "not a supported image (PNG, JPEG, TGA, BMP, HDR, EXR)",
            )
        })
        .or_else(|e| image::ImageFormat::from_path(path).map_err(|_| e))?;
    if format == image::ImageFormat::Jpeg && !jpeg_is_complete(bytes) {
        return Err(Error::image(path, "truncated JPEG: no end-of-image marker"));
    }
    use image::ImageDecoder;
    let bad = |e: image::ImageError| Error::image(path, format!("cannot decode: {e}"));
    // Keep the image crate's default memory limits and add a size cap of our own.
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(1 << 16);
    limits.max_image_height = Some(1 << 16);
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), format);
    reader.limits(limits.clone());
    // One decoder, so the header is parsed once (a JPEG's Huffman tables, a PNG's chunks up
    // to the pixels); an absurd size is refused from it before anything is allocated.
    let mut decoder = reader.into_decoder().map_err(bad)?;
    let (w, h) = decoder.dimensions();
    check_texture_size(w as u64, h as u64, max_pixels, path)?;
    // What `ImageReader::decode` does: the pixel buffer counts against the memory limit.
    limits.reserve(decoder.total_bytes()).map_err(bad)?;
    decoder.set_limits(limits).map_err(bad)?;
    let img = image::DynamicImage::from_decoder(decoder).map_err(bad)?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    check_texture_size(w as u64, h as u64, max_pixels, path)?;
    let color = img.color();
    let info = ImageInfo {
        format: format!("{format:?}").to_ascii_lowercase(),
        width: w,
        height: h,
        channels: color.channel_count() as usize,
        bits: (color.bits_per_pixel() / color.channel_count().max(1) as u16) as usize,
    };
    let texture = if matches!(
        img,
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
    ) {
        let texels = img
            .into_rgb32f()
            .pixels()
            .map(|p| Vec3::from(p.0.map(|c| if c.is_finite() { c } else { 0.0 })))
            .collect();
        Texture::new(w, h, texels)
    } else if info.bits == 8 {
        // kept as the file's sRGB bytes, decoded on lookup: a quarter of the memory of
        // linear floats, and no pass over the image here
        Texture::from_srgb8(w, h, img.into_rgb8().into_raw())
    } else {
        let texels = img
            .into_rgb32f()
            .pixels()
            .map(|p| Vec3::from(p.0.map(|c| srgb_decode(c as f64) as f32)))
            .collect();
        Texture::new(w, h, texels)
    };
    Ok((texture, info))
}

const EXR_MAGIC: [u8; 4] = [0x76, 0x2f, 0x31, 0x01];

fn check_texture_size(w: u64, h: u64, max_pixels: u64, path: &Path) -> Result<()> {
    if w == 0 || h == 0 || w.saturating_mul(h) > max_pixels {
        return Err(Error::image(
            path,
            format!("unusable size {w}x{h} (the cap is {max_pixels} pixels)"),
        ));
    }
    Ok(())
}

/// A JPEG must reach its end-of-image marker (FF D9); trailing padding is allowed.
fn jpeg_is_complete(bytes: &[u8]) -> bool {
    let end = bytes.len()
        - bytes
            .iter()
            .rev()
            .take_while(|&&b| b == 0 || b.is_ascii_whitespace())
            .count();
    end >= 2 && bytes[end - 2..end] == [0xFF, 0xD9]
}

fn decode_exr(bytes: &[u8], path: &Path, max_pixels: u64) -> Result<(Texture, ImageInfo)> {
    use exr::prelude::{ReadChannels, ReadLayers, read};
    let bad = |e: exr::error::Error| Error::image(path, format!("cannot read EXR: {e}"));
    let meta =
        exr::meta::MetaData::read_from_buffered(std::io::Cursor::new(bytes), false).map_err(bad)?;
    let first = meta
        .headers
        .first()
        .ok_or_else(|| Error::image(path, "EXR without layers"))?;
    // Every layer's size is checked: the reader may pick any of them.
    for header in &meta.headers {
        let size = header.layer_size;
        check_texture_size(size.0 as u64, size.1 as u64, max_pixels, path)?;
    }
    let info = ImageInfo {
        format: "exr".into(),
        width: first.layer_size.0,
        height: first.layer_size.1,
        channels: first.channels.list.len(),
        bits: first
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample() * 8)
            .max()
            .unwrap_or(0),
    };
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |res, _| {
                // Zeroed f32s come from calloc: pages a truncated file never reaches are never
                // touched, so a header claiming a big size costs little until pixels arrive.
                // (The size was checked above for every layer.)
                let (w, h) = (res.0.max(1), res.1.max(1));
                (w, h, vec![0f32; 3 * w * h])
            },
            |(w, _, t): &mut (usize, usize, Vec<f32>), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                let clean = |c: f32| if c.is_finite() { c } else { 0.0 };
                let i = 3 * (pos.1 * *w + pos.0);
                if let Some(px) = t.get_mut(i..i + 3) {
                    px.copy_from_slice(&[clean(r), clean(g), clean(b)]);
                }
            },
        )
        .first_valid_layer()
        .all_attributes()
        .non_parallel()
        .from_buffered(std::io::Cursor::new(bytes))
        .map_err(bad)?;
    let (w, h, samples) = image.layer_data.channel_data.pixels;
    let tex = Texture::new(
        w,
        h,
        samples.chunks_exact(3).map(Vec3::from_slice).collect(),
    );
    let info = ImageInfo {
        width: tex.width,
        height: tex.height,
        ..info
    };
    Ok((tex, info))
}

/// Load a cube map folder holding `posx negx posy negy posz negz` images (any supported
/// extension). All six must exist, be square and share one size; errors name the bad face.
pub fn load_cubemap(dir: &Path) -> Result<CubeMap> {
    load_cubemap_info(dir).map(|(c, _)| c)
}

/// [`load_cubemap`], also returning what the `posx` face file was (all faces share its size).
pub fn load_cubemap_info(dir: &Path) -> Result<(CubeMap, ImageInfo)> {
    if !dir.is_dir() {
        return Err(Error::image(
            dir,
            "cube map must be a folder with posx, negx, posy, negy, posz, negz images",
        ));
    }
    let mut files = Vec::with_capacity(6);
    for name in CUBE_FACES {
        let file = face_file(dir, name)?;
        let bytes = super::read_regular(&file)?;
        files.push((file, bytes));
    }
    let faces: [(&Path, &[u8]); 6] =
        std::array::from_fn(|k| (files[k].0.as_path(), files[k].1.as_slice()));
    decode_cubemap(faces)
}

/// Decode six face files, in [`CUBE_FACES`] order, given as (name for messages, bytes), and
/// check them: square, one size. Errors name the bad face.
pub fn decode_cubemap(faces: [(&Path, &[u8]); 6]) -> Result<(CubeMap, ImageInfo)> {
    decode_cubemap_capped(faces, MAX_TEXTURE_PIXELS)
}

/// [`decode_cubemap`] with a per-face pixel cap of the caller's choosing (see
/// [`decode_texture_capped`]).
pub fn decode_cubemap_capped(
    faces: [(&Path, &[u8]); 6],
    max_pixels: u64,
) -> Result<(CubeMap, ImageInfo)> {
    // the six faces decoded on the pool's threads (a cube map's decode is most of a
    // render's load); checked in face order, so the error named is the first bad face's
    use rayon::prelude::*;
    let decoded: Vec<Result<(Texture, ImageInfo)>> = faces
        .par_iter()
        .map(|&(file, bytes)| decode_texture_capped(bytes, file, max_pixels))
        .collect();
    let mut out: Vec<Texture> = Vec::with_capacity(6);
    let mut first_info = None;
    for ((name, (file, _)), face) in CUBE_FACES.iter().zip(faces).zip(decoded) {
        let (tex, info) = face?;
        if tex.width != tex.height {
            return Err(Error::image(
                file,
                format!(
                    "cube-map face {name} is not square ({}x{})",
                    tex.width, tex.height
                ),
            ));
        }
        if let Some(first) = out.first().map(|f| f.width)
            && first != tex.width
        {
            return Err(Error::image(
                file,
                format!(
                    "cube-map face {name} is {0}x{0}, posx is {first}x{first}",
                    tex.width
                ),
            ));
        }
        first_info.get_or_insert(info);
        out.push(tex);
    }
    let faces: [Texture; 6] = out
        .try_into()
        .map_err(|_| Error::image(Path::new("cube map"), "needs six faces"))?;
    let info = first_info.ok_or_else(|| Error::image(Path::new("cube map"), "no faces"))?;
    Ok((CubeMap { faces }, info))
}

fn face_file(dir: &Path, name: &str) -> Result<PathBuf> {
    for ext in IMAGE_EXTENSIONS {
        let p = dir.join(format!("{name}.{ext}"));
        if p.is_file() {
            return Ok(p);
        }
    }
    Err(Error::image(
        dir,
        format!("cube-map face {name} missing (looked for {name}.png/.jpg/.tga/.bmp/.hdr/.exr)"),
    ))
}

/// Write a render: `.exr` as linear float RGB (ZIP-compressed 32-bit, see
/// [`crate::io::output`]), `.png` clamped and sRGB-encoded 8-bit; through a temporary file, so
/// a failed write leaves what `path` held.
pub fn save_image(image: &Image, path: &Path) -> Result<()> {
    let (w, h) = (image.width as u32, image.height as u32);
    crate::io::output::write_streamed(
        path,
        (w, h),
        crate::image::PixelBounds::full(w, h),
        crate::io::output::ExrOptions::default(),
        &mut |sink| sink(0, &image.pixels),
    )
}

/// Read a linear RGB EXR back (for tests and comparisons).
pub fn load_exr_image(path: &Path) -> Result<Image> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let (t, _) = decode_exr(&bytes, path, MAX_TEXTURE_PIXELS)?;
    Ok(Image {
        width: t.width,
        height: t.height,
        pixels: t.into_linear_texels(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The faces are decoded in parallel, and the error still names the first bad face in
    /// face order, whichever thread failed first.
    #[test]
    fn cube_faces_decode_in_parallel_and_name_the_first_bad_face() {
        let mut png = Vec::new();
        image::RgbImage::from_pixel(4, 4, image::Rgb([10, 200, 30]))
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let names: Vec<std::path::PathBuf> = CUBE_FACES
            .iter()
            .map(|n| std::path::PathBuf::from(format!("cube/{n}.png")))
            .collect();
        let garbage = b"not an image".as_slice();
        let pick = |bad: &[usize]| -> [(&Path, &[u8]); 6] {
            std::array::from_fn(|k| {
                let bytes = if bad.contains(&k) {
                    garbage
                } else {
                    png.as_slice()
                };
                (names[k].as_path(), bytes)
            })
        };
        let (cube, info) = decode_cubemap(pick(&[])).unwrap();
        assert_eq!((info.width, info.height), (4, 4));
        let texel = srgb_decode(200.0 / 255.0) as f32;
        assert!(
            cube.faces
                .iter()
                .all(|f| f.linear_texels().iter().all(|t| t.y == texel))
        );
        // 8-bit faces are kept as their bytes, three a texel
        assert!(cube.faces.iter().all(|f| f.texel_bytes() == 3 * 4 * 4));
        for bad in [[2, 5], [5, 2], [0, 1]] {
            let e = decode_cubemap(pick(&bad)).unwrap_err().to_string();
            let first = CUBE_FACES[bad[0].min(bad[1])];
            assert!(e.contains(&format!("cube/{first}.png")), "{e}");
        }
    }

    #[test]
    fn jpeg_end_marker() {
        assert!(jpeg_is_complete(&[0xFF, 0xD8, 1, 2, 0xFF, 0xD9]));
        assert!(jpeg_is_complete(&[0xFF, 0xD8, 0xFF, 0xD9, 0, 0]));
        assert!(!jpeg_is_complete(&[0xFF, 0xD8, 1, 2, 3]));
        assert!(!jpeg_is_complete(&[]));
    }
}
