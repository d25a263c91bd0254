//! Which part of the image a render makes: `--crop`, `--pixel-bounds`, `--tile I/N`.

use super::TILE;
use crate::image::PixelBounds;

/// A part of the image, as the command line names it; [`Part::bounds`] turns it into pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Part {
    /// The whole image.
    Full,
    /// `--crop x0,x1,y0,y1`: fractions of the image, pbrt's `--cropwindow`. Pixel bounds are
    /// `ceil(width x0) .. ceil(width x1)` and the same in y, as pbrt-v4 computes them, so
    /// crops that share an edge fraction share the pixel edge (no gap, no overlap).
    Crop([f64; 4]),
    /// `--pixel-bounds x0,x1,y0,y1`: pixels, exclusive ends.
    Pixels(PixelBounds),
    /// `--tile I/N`: the I-th (0-based) of N bands of whole [`TILE`]-row tile bands, top to
    /// bottom. Band `I` takes tile rows `floor(I T / N) .. floor((I + 1) T / N)` of the image's
    /// `T = ceil(height / 16)`: the split depends on `I`, `N` and the height only, so every
    /// task of an array job computes the same split, and every part sits on the tile grid.
    Tile {
        /// Which band, from 0.
        index: u32,
        /// How many bands.
        count: u32,
    },
}

impl Part {
    /// `x0,x1,y0,y1` as four fractions in [0, 1] with `x0 < x1`, `y0 < y1`.
    pub fn parse_crop(s: &str) -> Result<Part, String> {
        let v = four(s, "--crop")?;
        let f: Vec<f64> = v
            .iter()
            .map(|t| t.parse::<f64>().ok().filter(|f| (0.0..=1.0).contains(f)))
            .collect::<Option<_>>()
            .ok_or_else(|| {
                format!("--crop {s}: four fractions in [0, 1] expected (x0,x1,y0,y1)")
            })?;
        if !(f[0] < f[1] && f[2] < f[3]) {
            return Err(format!("--crop {s}: needs x0 < x1 and y0 < y1"));
        }
        Ok(Part::Crop([f[0], f[1], f[2], f[3]]))
    }

    /// `x0,x1,y0,y1` as pixels, exclusive ends.
    pub fn parse_pixel_bounds(s: &str) -> Result<Part, String> {
        let v = four(s, "--pixel-bounds")?;
        let p: Vec<u32> = v
            .iter()
            .map(|t| t.parse::<u32>().ok())
            .collect::<Option<_>>()
            .ok_or_else(|| {
                format!("--pixel-bounds {s}: four pixel coordinates expected (x0,x1,y0,y1)")
            })?;
        Ok(Part::Pixels(PixelBounds {
            x0: p[0],
            x1: p[1],
            y0: p[2],
            y1: p[3],
        }))
    }

    /// `I/N` with `I < N`.
    pub fn parse_tile(s: &str) -> Result<Part, String> {
        let bad = || format!("--tile {s}: expected I/N with 0 <= I < N (e.g. 0/4)");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse::<u32>().map_err(|_| bad())?,
            n.trim().parse::<u32>().map_err(|_| bad())?,
        );
        if index >= count {
            return Err(bad());
        }
        Ok(Part::Tile { index, count })
    }

    /// The pixels of this part in a `width x height` image; an empty part or one reaching
    /// outside the image is an error (the message names the option).
    pub fn bounds(&self, width: u32, height: u32) -> Result<PixelBounds, String> {
        let full = PixelBounds::full(width, height);
        let b = match *self {
            Part::Full => full,
            Part::Crop([x0, x1, y0, y1]) => {
                let px = |f: f64, n: u32| (f * n as f64).ceil() as u32;
                let b = PixelBounds {
                    x0: px(x0, width),
                    x1: px(x1, width),
                    y0: px(y0, height),
                    y1: px(y1, height),
                };
                if b.is_empty() {
                    return Err(format!(
                        "--crop {x0},{x1},{y0},{y1}: no pixel of the {width}x{height} image \
                         is inside ({b})"
                    ));
                }
                b
            }
            Part::Pixels(b) => {
                if b.is_empty() || !full.contains(&b) {
                    return Err(format!(
                        "--pixel-bounds {},{},{},{}: must be a non-empty part of the \
                         {width}x{height} image (x0 < x1 <= {width}, y0 < y1 <= {height})",
                        b.x0, b.x1, b.y0, b.y1
                    ));
                }
                b
            }
            Part::Tile { index, count } => {
                let bands = height.div_ceil(TILE);
                if count > bands {
                    return Err(format!(
                        "--tile {index}/{count}: the {width}x{height} image has only {bands} \
                         bands of {TILE} rows to share out"
                    ));
                }
                let row = |i: u32| (i as u64 * bands as u64 / count as u64) as u32 * TILE;
                PixelBounds {
                    x0: 0,
                    x1: width,
                    y0: row(index),
                    y1: row(index + 1).min(height),
                }
            }
        };
        Ok(b)
    }

    /// Whether this is the whole image (not a part).
    pub fn is_full(&self) -> bool {
        matches!(self, Part::Full)
    }
}

fn four<'a>(s: &'a str, opt: &str) -> Result<Vec<&'a str>, String> {
    let v: Vec<&str> = s.split(',').map(str::trim).collect();
    if v.len() != 4 {
        return Err(format!(
            "{opt} {s}: four comma-separated values expected (x0,x1,y0,y1)"
        ));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_cover_the_image_on_the_tile_grid_without_overlap() {
        for (h, n) in [(768, 4), (768, 48), (100, 3), (17, 2), (8192, 7)] {
            let mut next = 0;
            for i in 0..n {
                let b = Part::Tile { index: i, count: n }.bounds(1024, h).unwrap();
                assert_eq!((b.x0, b.x1, b.y0), (0, 1024, next), "{h} {i}/{n}");
                assert!(b.y0.is_multiple_of(TILE) && !b.is_empty());
                next = b.y1;
            }
            assert_eq!(next, h);
        }
        assert_eq!(
            Part::Tile { index: 1, count: 4 }.bounds(1024, 768),
            Ok(PixelBounds {
                x0: 0,
                x1: 1024,
                y0: 192,
                y1: 384
            })
        );
        assert!(
            Part::Tile {
                index: 0,
                count: 49
            }
            .bounds(1024, 768)
            .unwrap_err()
            .contains("only 48 bands")
        );
    }

    #[test]
    fn crop_rounds_like_pbrt_and_shares_edges() {
        let b = Part::parse_crop("0,0.5,0.25,1")
            .unwrap()
            .bounds(101, 10)
            .unwrap();
        assert_eq!((b.x0, b.x1, b.y0, b.y1), (0, 51, 3, 10));
        let c = Part::parse_crop("0.5,1,0,0.25")
            .unwrap()
            .bounds(101, 10)
            .unwrap();
        assert_eq!((c.x0, c.y1), (51, 3));
        assert!(
            Part::parse_crop("0.31,0.32,0,1")
                .unwrap()
                .bounds(10, 10)
                .is_err()
        );
    }

    #[test]
    fn bad_parts_are_refused_with_the_option_named() {
        for (r, opt) in [
            (Part::parse_crop("0,1,0"), "--crop"),
            (Part::parse_crop("0,1.5,0,1"), "--crop"),
            (Part::parse_crop("0.5,0.5,0,1"), "--crop"),
            (Part::parse_crop("NaN,1,0,1"), "--crop"),
            (Part::parse_pixel_bounds("0,10,0,-1"), "--pixel-bounds"),
            (Part::parse_tile("4/4"), "--tile"),
            (Part::parse_tile("1"), "--tile"),
            (Part::parse_tile("0/0"), "--tile"),
        ] {
            assert!(r.clone().unwrap_err().starts_with(opt), "{r:?}");
        }
        let p = Part::parse_pixel_bounds("0,65,0,10").unwrap();
        assert!(p.bounds(64, 48).unwrap_err().contains("x0 < x1 <= 64"));
        let p = Part::parse_pixel_bounds("5,5,0,10").unwrap();
        assert!(p.bounds(64, 48).is_err());
        let p = Part::parse_pixel_bounds("3,64,7,48").unwrap();
        assert_eq!(p.bounds(64, 48).unwrap().area(), 61 * 41);
    }
}
