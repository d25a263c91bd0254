//! A linear f32 RGB frame buffer; the one place that clamps and sRGB-encodes.

use glam::Vec3;

/// Linear RGB pixels, row-major, row 0 at the top.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// `width * height` linear RGB values, row-major.
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// A black image.
    pub fn new(width: usize, height: usize) -> Self {
        Image {
            width,
            height,
            pixels: vec![Vec3::ZERO; width * height],
        }
    }

    /// The pixel at column `x`, row `y` (row 0 at the top); panics outside the image.
    pub fn get(&self, x: usize, y: usize) -> Vec3 {
        self.pixels[y * self.width + x]
    }

    /// 8-bit sRGB bytes of `clamp(I, 0, 1)` (NaN becomes 0): [`srgb8`] per channel.
    pub fn to_srgb8(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.pixels.len() * 3);
        for p in &self.pixels {
            out.extend(p.to_array().map(srgb8));
        }
        out
    }
}

/// A rectangle of pixels of an image, `x0..x1` by `y0..y1` (exclusive ends, pbrt's
/// `--pixelbounds` order): the part of a render that `--crop`, `--pixel-bounds` and `--tile`
/// select, and an EXR file's data window inside its display window.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PixelBounds {
    /// First column.
    pub x0: u32,
    /// One past the last column.
    pub x1: u32,
    /// First row (row 0 is the top).
    pub y0: u32,
    /// One past the last row.
    pub y1: u32,
}

impl PixelBounds {
    /// The whole `width x height` image.
    pub fn full(width: u32, height: u32) -> Self {
        PixelBounds {
            x0: 0,
            x1: width,
            y0: 0,
            y1: height,
        }
    }

    /// Columns inside (0 when empty).
    pub fn width(&self) -> u32 {
        self.x1.saturating_sub(self.x0)
    }

    /// Rows inside (0 when empty).
    pub fn height(&self) -> u32 {
        self.y1.saturating_sub(self.y0)
    }

    /// Pixels inside (0 when empty).
    pub fn area(&self) -> u64 {
        self.width() as u64 * self.height() as u64
    }

    /// Whether no pixel is inside.
    pub fn is_empty(&self) -> bool {
        self.area() == 0
    }

    /// The overlap of two rectangles (possibly empty).
    pub fn intersect(&self, o: &PixelBounds) -> PixelBounds {
        PixelBounds {
            x0: self.x0.max(o.x0),
            x1: self.x1.min(o.x1),
            y0: self.y0.max(o.y0),
            y1: self.y1.min(o.y1),
        }
    }

    /// Whether `o` lies inside `self`.
    pub fn contains(&self, o: &PixelBounds) -> bool {
        o.x0 >= self.x0 && o.x1 <= self.x1 && o.y0 >= self.y0 && o.y1 <= self.y1
    }
}

impl std::fmt::Display for PixelBounds {
    /// `x 0..1024, y 192..384`: half-open ranges, as `--pixel-bounds` takes them.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "x {}..{}, y {}..{}", self.x0, self.x1, self.y0, self.y1)
    }
}

/// The 8-bit sRGB code of a linear value: `round(255 srgb_encode(clamp(c, 0, 1)))`, NaN -> 0.
pub fn srgb8_formula(c: f32) -> u8 {
    (srgb_encode(if c.is_nan() { 0.0 } else { c.clamp(0.0, 1.0) }) * 255.0 + 0.5) as u8
}

/// Buckets of [`srgb8`]'s table over [0, 1].
const SRGB8_BUCKETS: usize = 4096;

struct Srgb8Table {
    /// `thresholds[k]`: the smallest f32 whose code is `k + 1`.
    thresholds: [f32; 255],
    /// The code of `i / SRGB8_BUCKETS`.
    start: [u8; SRGB8_BUCKETS],
}

/// [`srgb8_formula`] without a `powf` per channel (a 4K PNG has 25M channels). The code is
/// monotonic in `c`: the table holds the 255 values where it steps up, found once by
/// bisection over the f32 bit patterns with the formula itself, and the code at the start
/// of each of 4096 buckets; a value takes its bucket's code and steps past the (at most
/// two) thresholds inside the bucket. Equal to the formula for every f32 (exhaustive test).
pub fn srgb8(c: f32) -> u8 {
    static TABLE: std::sync::OnceLock<Box<Srgb8Table>> = std::sync::OnceLock::new();
    let t = TABLE.get_or_init(|| {
        let thresholds: [f32; 255] = std::array::from_fn(|k| {
            let (mut lo, mut hi) = (0u32, 1f32.to_bits());
            while lo < hi {
                let mid = lo + (hi - lo) / 2;
                if srgb8_formula(f32::from_bits(mid)) as usize > k {
                    hi = mid;
                } else {
                    lo = mid + 1;
                }
            }
            f32::from_bits(lo)
        });
        let start = std::array::from_fn(|i| {
            let c = i as f32 / SRGB8_BUCKETS as f32;
            thresholds.partition_point(|&x| x <= c) as u8
        });
        Box::new(Srgb8Table { thresholds, start })
    });
    if !(c > 0.0) {
        return 0; // zero, negative, NaN
    }
    if c >= 1.0 {
        return srgb8_formula(1.0);
    }
    let mut code = t.start[(c * SRGB8_BUCKETS as f32) as usize];
    while code < 255 && t.thresholds[code as usize] <= c {
        code += 1;
    }
    code
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
    fn srgb8_equals_the_formula_around_every_threshold_and_across_the_range() {
        let mut checked = 0;
        for k in 1..=255u8 {
            // the first value with code k, found by scanning the formula from below
            let first = (0..=1f32.to_bits())
                .rev()
                .step_by(1 << 12)
                .map(f32::from_bits)
                .find(|&c| srgb8_formula(c) < k)
                .unwrap();
            let mut b = first.to_bits();
            while srgb8_formula(f32::from_bits(b)) < k {
                b += 1;
            }
            for bits in b.saturating_sub(64)..b + 64 {
                let c = f32::from_bits(bits);
                assert_eq!(srgb8(c), srgb8_formula(c), "{c:e}");
                checked += 1;
            }
        }
        for bits in (0..=1f32.to_bits()).step_by(4099) {
            let c = f32::from_bits(bits);
            assert_eq!(srgb8(c), srgb8_formula(c), "{c:e}");
            checked += 1;
        }
        for c in [
            -1.0,
            -0.0,
            1.0,
            1.5,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ] {
            assert_eq!(srgb8(c), srgb8_formula(c), "{c:e}");
        }
        assert!(checked > 250_000);
    }

    /// Every f32 in [0, 1] (about 10^9 values; tens of seconds):
    /// `cargo test --release --lib srgb8_exhaustive -- --ignored`.
    #[test]
    #[ignore]
    fn srgb8_exhaustive() {
        for bits in 0..=1f32.to_bits() {
            let c = f32::from_bits(bits);
            assert_eq!(srgb8(c), srgb8_formula(c), "{c:e}");
        }
    }

    #[test]
    fn clamps_when_encoding() {
        let mut im = Image::new(2, 1);
        im.pixels[0] = Vec3::new(-1.0, 2.0, f32::NAN);
        im.pixels[1] = Vec3::splat(0.5);
        assert_eq!(im.to_srgb8(), vec![0, 255, 0, 188, 188, 188]);
    }
}
