//! Reading textures and cube maps, writing renders (`.png` sRGB 8-bit, `.exr` linear float).

use crate::error::{Error, Result};
use crate::image::{Image, srgb_decode};
use crate::texture::{CUBE_FACES, CubeMap, Texture};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// Largest texture accepted, in pixels (checked before decoding allocates).
pub const MAX_TEXTURE_PIXELS: u64 = 1 << 26;

/// Load an image as a linear-RGB texture. 8- and 16-bit formats (PNG, JPEG, TGA, BMP) are
/// sRGB-decoded; EXR and HDR are linear. Alpha is ignored; non-finite EXR/HDR samples become 0.
pub fn load_texture(path: &Path) -> Result<Texture> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if ext == "exr" {
        return load_exr(path);
    }
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let format = image::guess_format(&bytes)
        .map_err(|_| {
            Error::image(
                path,
                "not a supported image (PNG, JPEG, TGA, BMP, HDR, EXR)",
            )
        })
        .or_else(|e| image::ImageFormat::from_path(path).map_err(|_| e))?;
    if format == image::ImageFormat::Jpeg && !jpeg_is_complete(&bytes) {
        return Err(Error::image(path, "truncated JPEG: no end-of-image marker"));
    }
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(&bytes), format);
    // Keep the image crate's default memory limits and add a pixel cap of our own.
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(1 << 16);
    limits.max_image_height = Some(1 << 16);
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| Error::image(path, format!("cannot decode: {e}")))?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w == 0 || h == 0 || (w as u64) * (h as u64) > MAX_TEXTURE_PIXELS {
        return Err(Error::image(path, format!("unusable size {w}x{h}")));
    }
    let linear = matches!(
        img,
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
    );
    let rgb = img.to_rgb32f();
    let texels = if linear {
        rgb.pixels()
            .map(|p| Vec3::from(p.0.map(|c| if c.is_finite() { c } else { 0.0 })))
            .collect()
    } else if matches!(
        img.color().bits_per_pixel() / img.color().channel_count() as u16,
        8
    ) {
        let lut: Vec<f32> = (0..256)
            .map(|v| srgb_decode(v as f64 / 255.0) as f32)
            .collect();
        img.to_rgb8()
            .pixels()
            .map(|p| {
                Vec3::new(
                    lut[p.0[0] as usize],
                    lut[p.0[1] as usize],
                    lut[p.0[2] as usize],
                )
            })
            .collect()
    } else {
        rgb.pixels()
            .map(|p| Vec3::from(p.0.map(|c| srgb_decode(c as f64) as f32)))
            .collect()
    };
    Ok(Texture::new(w, h, texels))
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

fn load_exr(path: &Path) -> Result<Texture> {
    use exr::prelude::read_first_rgba_layer_from_file;
    let bad = |e: exr::error::Error| Error::image(path, format!("cannot read EXR: {e}"));
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(bad)?;
    let header = meta
        .headers
        .first()
        .ok_or_else(|| Error::image(path, "EXR without layers"))?;
    let size = header.layer_size;
    if size.0 == 0 || size.1 == 0 || (size.0 as u64) * (size.1 as u64) > MAX_TEXTURE_PIXELS {
        return Err(Error::image(
            path,
            format!("unusable size {}x{}", size.0, size.1),
        ));
    }
    let image = read_first_rgba_layer_from_file(
        path,
        |res, _| Texture::new(res.0, res.1, vec![Vec3::ZERO; res.0 * res.1]),
        |t: &mut Texture, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let clean = |c: f32| if c.is_finite() { c } else { 0.0 };
            t.texels[pos.1 * t.width + pos.0] = Vec3::new(clean(r), clean(g), clean(b));
        },
    )
    .map_err(bad)?;
    Ok(image.layer_data.channel_data.pixels)
}

/// Load a cube map folder holding `posx negx posy negy posz negz` images (any supported
/// extension). All six must exist, be square and share one size; errors name the bad face.
pub fn load_cubemap(dir: &Path) -> Result<CubeMap> {
    if !dir.is_dir() {
        return Err(Error::image(
            dir,
            "cube map must be a folder with posx, negx, posy, negy, posz, negz images",
        ));
    }
    let mut faces = Vec::with_capacity(6);
    for name in CUBE_FACES {
        let file = face_file(dir, name)?;
        let tex = load_texture(&file)?;
        if tex.width != tex.height {
            return Err(Error::image(
                &file,
                format!(
                    "cube-map face {name} is not square ({}x{})",
                    tex.width, tex.height
                ),
            ));
        }
        if let Some(first) = faces.first().map(|f: &Texture| f.width)
            && first != tex.width
        {
            return Err(Error::image(
                &file,
                format!(
                    "cube-map face {name} is {0}x{0}, posx is {first}x{first}",
                    tex.width
                ),
            ));
        }
        faces.push(tex);
    }
    let faces: [Texture; 6] = faces.try_into().expect("six faces");
    Ok(CubeMap { faces })
}

fn face_file(dir: &Path, name: &str) -> Result<PathBuf> {
    for ext in ["png", "jpg", "jpeg", "tga", "bmp", "hdr", "exr"] {
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

/// Write a render: `.exr` as linear 32-bit float RGB, `.png` clamped and sRGB-encoded 8-bit.
pub fn save_image(image: &Image, path: &Path) -> Result<()> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    match ext.as_str() {
        "exr" => exr::prelude::write_rgb_file(path, image.width, image.height, |x, y| {
            let p = image.get(x, y);
            (p.x, p.y, p.z)
        })
        .map_err(|e| Error::image(path, format!("cannot write EXR: {e}"))),
        "png" => image::save_buffer(
            path,
            &image.to_srgb8(),
            image.width as u32,
            image.height as u32,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| Error::image(path, format!("cannot write PNG: {e}"))),
        _ => Err(Error::Usage(format!(
            "{}: unknown output format (use .png or .exr)",
            path.display()
        ))),
    }
}

/// Read a linear RGB EXR back (for tests and comparisons).
pub fn load_exr_image(path: &Path) -> Result<Image> {
    let t = load_exr(path)?;
    Ok(Image {
        width: t.width,
        height: t.height,
        pixels: t.texels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jpeg_end_marker() {
        assert!(jpeg_is_complete(&[0xFF, 0xD8, 1, 2, 0xFF, 0xD9]));
        assert!(jpeg_is_complete(&[0xFF, 0xD8, 0xFF, 0xD9, 0, 0]));
        assert!(!jpeg_is_complete(&[0xFF, 0xD8, 1, 2, 3]));
        assert!(!jpeg_is_complete(&[]));
    }
}
