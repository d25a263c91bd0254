//! A linear f32 RGB frame buffer; the one place that clamps and sRGB-encodes.

use glam::Vec3;

/// Linear RGB pixels, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<Vec3>,
}

impl Image {
    pub fn new(width: usize, height: usize) -> Self {
        Image {
            width,
            height,
            pixels: vec![Vec3::ZERO; width * height],
        }
    }

    pub fn get(&self, x: usize, y: usize) -> Vec3 {
        self.pixels[y * self.width + x]
    }

    /// 8-bit sRGB bytes of `clamp(I, 0, 1)` (NaN becomes 0).
    pub fn to_srgb8(&self) -> Vec<u8> {
        self.pixels
            .iter()
            .flat_map(|p| p.to_array())
            .map(|c| {
                (srgb_encode(if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) }) * 255.0 + 0.5) as u8
            })
            .collect()
    }
}

/// The sRGB transfer function (linear -> encoded), for values in [0, 1].
pub fn srgb_encode(c: f32) -> f32 {
    if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    }
}

/// The inverse transfer function (encoded -> linear), exact formula in f64.
pub fn srgb_decode(c: f64) -> f64 {
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_roundtrip_and_endpoints() {
        assert_eq!(srgb_encode(0.0), 0.0);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-6);
        assert!((srgb_decode(srgb_encode(0.2) as f64) - 0.2).abs() < 1e-6);
        // Middle grey 0.5 encoded is 188/255 (0.7354).
        assert!((srgb_encode(0.5) - 0.735_356_7).abs() < 1e-5);
    }

    #[test]
    fn clamps_when_encoding() {
        let mut im = Image::new(2, 1);
        im.pixels[0] = Vec3::new(-1.0, 2.0, f32::NAN);
        im.pixels[1] = Vec3::splat(0.5);
        assert_eq!(im.to_srgb8(), vec![0, 255, 0, 188, 188, 188]);
    }
}
