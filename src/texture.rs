//! Textures (bilinear; wrap = repeat unless a material asks for mirrored repeat or clamp to
//! edge) and cube maps (OpenGL faces, clamp to edge), SCENES.md §4.

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
    /// How [`Texture::sample_uv`] treats texels outside the image, along `u` then `v`
    /// ([`Wrap::Repeat`] for both unless set).
    pub wrap: [Wrap; 2],
}

/// How lookups outside `[0, w) x [0, h)` behave: the texel a bilinear lookup reads for an
/// index `i` past the edge, as OpenGL (and glTF's samplers) define the three modes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// Wrap around, `i mod w` (textures, by default).
    #[default]
    Repeat,
    /// Every other copy mirrored: `0 1 .. w-1 w-1 .. 1 0 0 1 ..` (glTF `MIRRORED_REPEAT`).
    MirroredRepeat,
    /// Clamp to the edge texel (cube-map faces; glTF `CLAMP_TO_EDGE`).
    Clamp,
}

impl Wrap {
    /// The texel index in `0..n` that index `i` reads.
    #[inline(always)]
    fn index(self, i: i64, n: i64) -> i64 {
        match self {
            Wrap::Repeat => i.rem_euclid(n),
            Wrap::MirroredRepeat => {
                let m = i.rem_euclid(2 * n);
                if m < n { m } else { 2 * n - 1 - m }
            }
            Wrap::Clamp => i.clamp(0, n - 1),
        }
    }
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
            wrap: [Wrap::Repeat; 2],
        }
    }

    /// The texture with `wrap` along `u` and `v` for [`Texture::sample_uv`].
    pub fn with_wrap(mut self, wrap: [Wrap; 2]) -> Self {
        self.wrap = wrap;
        self
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
    fn texel(&self, x: i64, y: i64, [wrap_x, wrap_y]: [Wrap; 2]) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let (x, y) = (wrap_x.index(x, w), wrap_y.index(y, h));
        self.texels[(y * w + x) as usize]
    }

    /// Bilinear lookup at continuous texel coordinates (texel centres at `i + 0.5`... shifted
    /// by the caller: `x = u w - 0.5` puts texel `i`'s centre at `x = i`).
    #[inline(always)]
    pub fn bilinear(&self, x: f32, y: f32, wrap: [Wrap; 2]) -> Vec3 {
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

    /// Texture colour at `uv`: `v = 0` is the bottom row, wrapped as [`Texture::wrap`] says.
    #[inline]
    pub fn sample_uv(&self, uv: Vec2) -> Vec3 {
        let x = uv.x * self.width as f32 - 0.5;
        let y = (1.0 - uv.y) * self.height as f32 - 0.5;
        self.bilinear(x, y, self.wrap)
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
            [Wrap::Clamp; 2],
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
        assert_eq!(t.bilinear(-5.0, -5.0, [Wrap::Clamp; 2]), Vec3::X);
        assert_eq!(t.bilinear(9.0, 9.0, [Wrap::Clamp; 2]), Vec3::ONE);
    }

    /// A 3x2 texture with one distinct grey per texel: `10 * row + column` (row 0 on top).
    fn strip() -> Texture {
        let v = |c: f32| Vec3::splat(c);
        Texture::new(
            3,
            2,
            vec![v(0.0), v(1.0), v(2.0), v(10.0), v(11.0), v(12.0)],
        )
    }

    /// The texel indices each mode reads, written out by hand from the OpenGL definitions.
    #[test]
    fn wrap_modes_pick_the_texels_opengl_defines() {
        let n = 3;
        let cases: [(Wrap, [i64; 10]); 3] = [
            // i = -4 .. 5
            (Wrap::Repeat, [2, 0, 1, 2, 0, 1, 2, 0, 1, 2]),
            (Wrap::MirroredRepeat, [2, 2, 1, 0, 0, 1, 2, 2, 1, 0]),
            (Wrap::Clamp, [0, 0, 0, 0, 0, 1, 2, 2, 2, 2]),
        ];
        for (wrap, want) in cases {
            let got: Vec<i64> = (-4..6).map(|i| wrap.index(i, n)).collect();
            assert_eq!(got, want, "{wrap:?}");
        }
        // A huge index (from a huge uv) stays in range for each mode.
        for wrap in [Wrap::Repeat, Wrap::MirroredRepeat, Wrap::Clamp] {
            assert!((0..n).contains(&wrap.index(i64::MAX, n)), "{wrap:?}");
            assert!((0..n).contains(&wrap.index(i64::MIN, n)), "{wrap:?}");
        }
    }

    /// `sample_uv` through each wrap mode, against texels and blends computed by hand on the
    /// 3x2 strip (x = 3u - 0.5, y = 2(1 - v) - 0.5).
    #[test]
    fn sample_uv_follows_the_texture_wrap_along_u_and_v() {
        let grey = |t: &Texture, u: f32, v: f32| t.sample_uv(Vec2::new(u, v)).x;
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
        // u = -1/6: x = -1, the centre of texel -1 (u = 7/6: texel 3, 11/6: texel 5);
        // v = 0.75: y = 0, row 0 exactly.
        let repeat = strip();
        assert!(close(grey(&repeat, -1.0 / 6.0, 0.75), 2.0)); // texel -1 -> 2
        assert!(close(grey(&repeat, 7.0 / 6.0, 0.75), 0.0)); // texel 3 -> 0
        let mirror = strip().with_wrap([Wrap::MirroredRepeat, Wrap::Repeat]);
        assert!(close(grey(&mirror, -1.0 / 6.0, 0.75), 0.0)); // texel -1 -> 0
        assert!(close(grey(&mirror, 7.0 / 6.0, 0.75), 2.0)); // texel 3 -> 2
        assert!(close(grey(&mirror, 11.0 / 6.0, 0.75), 0.0)); // texel 5 -> 0
        let clamp = strip().with_wrap([Wrap::Clamp, Wrap::Repeat]);
        assert!(close(grey(&clamp, -1.0 / 6.0, 0.75), 0.0));
        assert!(close(grey(&clamp, 7.0 / 6.0, 0.75), 2.0));
        // u = 0 (x = -0.5): half texel -1, half texel 0.
        assert!(close(grey(&repeat, 0.0, 0.75), 1.0)); // (2 + 0) / 2
        assert!(close(grey(&mirror, 0.0, 0.75), 0.0)); // (0 + 0) / 2
        assert!(close(grey(&clamp, 0.0, 0.75), 0.0));
        // Along v, on column 1 (u = 0.5): v = 1.25 is y = -1, row -1.
        let rows = |w: Wrap| strip().with_wrap([Wrap::Repeat, w]);
        assert!(close(grey(&rows(Wrap::Repeat), 0.5, 1.25), 11.0)); // row -1 -> 1
        assert!(close(grey(&rows(Wrap::MirroredRepeat), 0.5, 1.25), 1.0)); // row -1 -> 0
        assert!(close(grey(&rows(Wrap::Clamp), 0.5, 1.25), 1.0));
        // v = -0.75: y = 3, row 3: repeat -> row 1, mirrored -> row 0 (rows 2, 3 mirror 1, 0),
        // clamp -> row 1.
        assert!(close(grey(&rows(Wrap::Repeat), 0.5, -0.75), 11.0));
        assert!(close(grey(&rows(Wrap::MirroredRepeat), 0.5, -0.75), 1.0));
        assert!(close(grey(&rows(Wrap::Clamp), 0.5, -0.75), 11.0));
        // A blend across the mirrored edge: u = 1 (x = 2.5) reads texels 2 and 3 -> 2 and 2.
        assert!(close(grey(&mirror, 1.0, 0.75), 2.0));
        assert!(close(grey(&repeat, 1.0, 0.75), 1.0)); // (2 + 0) / 2
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
