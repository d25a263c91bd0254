//! Textures (bilinear, wrap = repeat) and cube maps (OpenGL faces, clamp to edge), SCENES.md §4.

use glam::{Vec2, Vec3};

/// A linear-RGB image used for lookups. Row 0 is the top row of the image file.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// `width * height` linear RGB texels, row-major.
    pub texels: Vec<Vec3>,
}

/// How lookups outside `[0, w) x [0, h)` behave.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    /// Wrap around (textures).
    Repeat,
    /// Clamp to the edge texel (cube-map faces).
    Clamp,
}

impl Texture {
    /// A texture from its texels; panics unless there are `width * height > 0` of them.
    pub fn new(width: usize, height: usize, texels: Vec<Vec3>) -> Self {
        assert_eq!(texels.len(), width * height, "texture size");
        assert!(width > 0 && height > 0, "empty texture");
        Texture {
            width,
            height,
            texels,
        }
    }

    /// A procedural checkerboard of `n x n` squares (for the demo scene; no file needed).
    pub fn checker(size: usize, n: usize, a: Vec3, b: Vec3) -> Self {
        let cell = (size / n.max(1)).max(1);
        let texels = (0..size * size)
            .map(|i| {
                if ((i % size) / cell + (i / size) / cell).is_multiple_of(2) {
                    a
                } else {
                    b
                }
            })
            .collect();
        Texture::new(size, size, texels)
    }

    #[inline(always)]
    fn texel(&self, x: i64, y: i64, wrap: Wrap) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let (x, y) = match wrap {
            Wrap::Repeat => (x.rem_euclid(w), y.rem_euclid(h)),
            Wrap::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
        };
        self.texels[(y * w + x) as usize]
    }

    /// Bilinear lookup at continuous texel coordinates (texel centres at `i + 0.5`... shifted
    /// by the caller: `x = u w - 0.5` puts texel `i`'s centre at `x = i`).
    #[inline(always)]
    pub fn bilinear(&self, x: f32, y: f32, wrap: Wrap) -> Vec3 {
        // Non-finite coordinates (from NaN uv) would make the weights NaN: look up texel 0.
        let (x, y) = if x.is_finite() && y.is_finite() {
            (x, y)
        } else {
            (0.0, 0.0)
        };
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        // f32 -> i64 saturates; huge coordinates still wrap or clamp to a valid texel.
        let (ix, iy) = (x0 as i64, y0 as i64);
        let top =
            self.texel(ix, iy, wrap) * (1.0 - fx) + self.texel(ix.saturating_add(1), iy, wrap) * fx;
        let bottom = self.texel(ix, iy.saturating_add(1), wrap) * (1.0 - fx)
            + self.texel(ix.saturating_add(1), iy.saturating_add(1), wrap) * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Texture colour at `uv`: `v = 0` is the bottom row, wrap = repeat.
    #[inline]
    pub fn sample_uv(&self, uv: Vec2) -> Vec3 {
        let x = uv.x * self.width as f32 - 0.5;
        let y = (1.0 - uv.y) * self.height as f32 - 0.5;
        self.bilinear(x, y, Wrap::Repeat)
    }
}

/// Face order of a cube map, as in the file names.
pub const CUBE_FACES: [&str; 6] = ["posx", "negx", "posy", "negy", "posz", "negz"];

/// Six square faces of one size, indexed in [`CUBE_FACES`] order.
#[derive(Clone, Debug, PartialEq)]
pub struct CubeMap {
    /// The faces in [`CUBE_FACES`] order.
    pub faces: [Texture; 6],
}

impl CubeMap {
    /// Face index and `(s, t)` in `[0, 1]` for a direction, by the OpenGL table: the major axis
    /// picks the face, then `s = (sc/|ma| + 1)/2`, `t = (tc/|ma| + 1)/2`.
    #[inline(always)]
    pub fn face_st(d: Vec3) -> (usize, f32, f32) {
        let a = d.abs();
        let (face, sc, tc, ma) = if a.x >= a.y && a.x >= a.z {
            if d.x > 0.0 {
                (0, -d.z, -d.y, a.x)
            } else {
                (1, d.z, -d.y, a.x)
            }
        } else if a.y >= a.z {
            if d.y > 0.0 {
                (2, d.x, d.z, a.y)
            } else {
                (3, d.x, -d.z, a.y)
            }
        } else if d.z > 0.0 {
            (4, d.x, -d.y, a.z)
        } else {
            (5, -d.x, -d.y, a.z)
        };
        (face, (sc / ma + 1.0) * 0.5, (tc / ma + 1.0) * 0.5)
    }

    /// Colour seen along direction `d`: bilinear, clamp to edge, row 0 at `t = 0`.
    #[inline(always)]
    pub fn sample(&self, d: Vec3) -> Vec3 {
        let (face, s, t) = Self::face_st(d);
        let f = &self.faces[face];
        f.bilinear(
            s * f.width as f32 - 0.5,
            t * f.height as f32 - 0.5,
            Wrap::Clamp,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> Texture {
        // 2x2: top row (row 0) red, green; bottom row blue, white.
        Texture::new(2, 2, vec![Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE])
    }

    #[test]
    fn uv_orientation_v0_is_bottom_row() {
        let t = ramp();
        assert_eq!(t.sample_uv(Vec2::new(0.25, 0.75)), Vec3::X);
        assert_eq!(t.sample_uv(Vec2::new(0.75, 0.75)), Vec3::Y);
        assert_eq!(t.sample_uv(Vec2::new(0.25, 0.25)), Vec3::Z);
        assert_eq!(t.sample_uv(Vec2::new(0.75, 0.25)), Vec3::ONE);
    }

    #[test]
    fn bilinear_weights_and_repeat() {
        let t = ramp();
        // Centre of the texture: the average of all four.
        let c = t.sample_uv(Vec2::new(0.5, 0.5));
        assert!((c - Vec3::new(0.5, 0.5, 0.5)).length() < 1e-6);
        // x = 0.25*2 - 0.5 + 0.25 -> a quarter of the way from red to green.
        let q = t.sample_uv(Vec2::new(0.375, 0.75));
        assert!((q - Vec3::new(0.75, 0.25, 0.0)).length() < 1e-6, "{q}");
        // u = 0: halfway between the last and the first column (repeat).
        let w = t.sample_uv(Vec2::new(0.0, 0.75));
        assert!((w - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6);
        // Whole periods away give the same value.
        assert_eq!(
            t.sample_uv(Vec2::new(3.375, -1.25)),
            t.sample_uv(Vec2::new(0.375, 0.75))
        );
        // NaN and huge coordinates stay finite.
        assert!(t.sample_uv(Vec2::new(f32::NAN, 1e30)).is_finite());
    }

    #[test]
    fn clamp_to_edge() {
        let t = ramp();
        assert_eq!(t.bilinear(-5.0, -5.0, Wrap::Clamp), Vec3::X);
        assert_eq!(t.bilinear(9.0, 9.0, Wrap::Clamp), Vec3::ONE);
    }

    #[test]
    fn cube_face_selection_follows_opengl_table() {
        let cases = [
            (Vec3::new(1.0, 0.2, -0.4), 0, 0.7, 0.4),
            (Vec3::new(-1.0, 0.2, -0.4), 1, 0.3, 0.4),
            (Vec3::new(0.2, 1.0, -0.4), 2, 0.6, 0.3),
            (Vec3::new(0.2, -1.0, -0.4), 3, 0.6, 0.7),
            (Vec3::new(0.2, -0.4, 1.0), 4, 0.6, 0.7),
            (Vec3::new(0.2, -0.4, -1.0), 5, 0.4, 0.7),
        ];
        for (d, face, s, t) in cases {
            let (f, ss, tt) = CubeMap::face_st(d * 3.0);
            assert_eq!(f, face, "{d}");
            assert!(
                (ss - s).abs() < 1e-6 && (tt - t).abs() < 1e-6,
                "{d}: {ss} {tt}"
            );
        }
    }

    #[test]
    fn cube_sample_reads_row_zero_at_t_zero() {
        let face = |c: Vec3| Texture::new(2, 2, vec![c, c, Vec3::ZERO, Vec3::ZERO]);
        let cm = CubeMap {
            faces: [
                face(Vec3::X),
                face(Vec3::Y),
                face(Vec3::Z),
                face(Vec3::ONE),
                face(Vec3::X),
                face(Vec3::Y),
            ],
        };
        // +z face, looking up (ry > 0 -> tc = -ry < 0 -> t small -> row 0).
        assert_eq!(cm.sample(Vec3::new(0.0, 0.9, 1.0)), Vec3::X);
        assert_eq!(cm.sample(Vec3::new(0.0, -0.9, 1.0)), Vec3::ZERO);
        assert_eq!(cm.sample(Vec3::new(0.0, 0.9, -1.0)), Vec3::Y);
    }
}
