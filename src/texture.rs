//! Textures (bilinear; wrap = repeat unless a material asks for mirrored repeat or clamp to
//! edge) and cube maps (OpenGL faces, clamp to edge), SCENES.md §4.

use crate::simd::{self, Vec3x8};
use glam::{Vec2, Vec3};

/// An image used for lookups, read as linear RGB. Row 0 is the top row of the image file.
#[derive(Clone, Debug, PartialEq)]
pub struct Texture {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// `width * height` texels, row-major.
    texels: Texels,
    /// How [`Texture::sample_uv`] treats texels outside the image, along `u` then `v`
    /// ([`Wrap::Repeat`] for both unless set).
    pub wrap: [Wrap; 2],
}

/// How a texture keeps its texels.
#[derive(Clone, Debug, PartialEq)]
enum Texels {
    /// Linear RGB floats (HDR, EXR and 16-bit images, and textures made in code).
    Linear(Vec<Vec3>),
    /// sRGB-encoded 8-bit RGB, three bytes a texel, as an 8-bit image file holds them:
    /// decoded on lookup through [`srgb8_table`], which gives what converting the whole
    /// image at load gave, bit for bit, in a quarter of the memory and without the pass.
    Srgb8(Vec<u8>, Table),
}

/// [`srgb8_table`], held by the textures that read through it (no check of its
/// initialisation on every lookup).
#[derive(Clone, Copy)]
struct Table(&'static [f32; 256]);

impl std::fmt::Debug for Table {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("sRGB 8-bit table")
    }
}

impl PartialEq for Table {
    fn eq(&self, _: &Table) -> bool {
        true // there is one table
    }
}

/// Linear values of the 256 sRGB-encoded 8-bit levels (the exact formula in f64, rounded to
/// f32 once).
pub fn srgb8_table() -> &'static [f32; 256] {
    static TABLE: std::sync::OnceLock<[f32; 256]> = std::sync::OnceLock::new();
    TABLE
        .get_or_init(|| std::array::from_fn(|v| crate::image::srgb_decode(v as f64 / 255.0) as f32))
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
    /// A texture from its linear RGB texels; panics unless there are `width * height > 0`.
    pub fn new(width: usize, height: usize, texels: Vec<Vec3>) -> Self {
        assert_eq!(texels.len(), width * height, "texture size");
        assert!(width > 0 && height > 0, "empty texture");
        Texture {
            width,
            height,
            texels: Texels::Linear(texels),
            wrap: [Wrap::Repeat; 2],
        }
    }

    /// A texture from sRGB-encoded 8-bit RGB bytes (three a texel, row-major), kept as they
    /// are and decoded on lookup ([`srgb8_table`]); panics unless there are
    /// `3 * width * height > 0` bytes.
    pub fn from_srgb8(width: usize, height: usize, rgb: Vec<u8>) -> Self {
        assert_eq!(rgb.len(), 3 * width * height, "texture size");
        assert!(width > 0 && height > 0, "empty texture");
        Texture {
            width,
            height,
            texels: Texels::Srgb8(rgb, Table(srgb8_table())),
            wrap: [Wrap::Repeat; 2],
        }
    }

    /// Texel `i` (row-major) in linear RGB.
    #[inline(always)]
    pub fn texel_at(&self, i: usize) -> Vec3 {
        match &self.texels {
            Texels::Linear(t) => t[i],
            Texels::Srgb8(b, Table(table)) => {
                // the texel's three bytes in one load (with the next texel's first, unused),
                // but for the last texel
                let at = 3 * i;
                let v = match b.get(at..at + 4) {
                    Some(w) => u32::from_le_bytes([w[0], w[1], w[2], w[3]]),
                    None => u32::from_le_bytes([b[at], b[at + 1], b[at + 2], 0]),
                };
                Vec3::new(
                    table[(v & 255) as usize],
                    table[(v >> 8 & 255) as usize],
                    table[(v >> 16 & 255) as usize],
                )
            }
        }
    }

    /// Every texel in linear RGB, row-major.
    pub fn linear_texels(&self) -> Vec<Vec3> {
        match &self.texels {
            Texels::Linear(t) => t.clone(),
            Texels::Srgb8(..) => (0..self.width * self.height)
                .map(|i| self.texel_at(i))
                .collect(),
        }
    }

    /// The linear RGB texels, without a copy where they are kept that way.
    pub fn into_linear_texels(self) -> Vec<Vec3> {
        match self.texels {
            Texels::Linear(t) => t,
            Texels::Srgb8(..) => self.linear_texels(),
        }
    }

    /// Bytes the texels take.
    pub fn texel_bytes(&self) -> usize {
        match &self.texels {
            Texels::Linear(t) => std::mem::size_of_val(t.as_slice()),
            Texels::Srgb8(b, _) => b.len(),
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
        self.texel_at((y * w + x) as usize)
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

    /// Whether every face has the first face's size (as the loaders make them): what
    /// [`CubeMap::footprint8`] needs.
    pub fn faces_alike(&self) -> bool {
        let (w, h) = (self.faces[0].width, self.faces[0].height);
        self.faces.iter().all(|f| f.width == w && f.height == h)
    }

    /// Where [`CubeMap::sample`] reads for eight directions at once: the face, the bilinear
    /// footprint's columns and rows (clamped) and its weights, in lanes, by the same IEEE
    /// operations in the same order as [`CubeMap::face_st`] and [`Texture::bilinear`], so
    /// that [`CubeMap::blend`] of a lane is `sample`'s colour to the bit. Without branches:
    /// the renderer looks up the background for every ray that escapes, and the scalar
    /// face choice mispredicts wherever neighbouring rays see different faces. Every face
    /// must have the first face's size ([`CubeMap::faces_alike`]).
    #[inline(always)]
    pub fn footprint8(&self, d: Vec3x8) -> Footprint8 {
        use crate::simd::{ge, gt, select, splat};
        let (ax, ay, az) = (d.x.abs(), d.y.abs(), d.z.abs());
        // the major axis as `face_st` picks it (ties to x, then y; NaN to z)
        let xm = ge(ax, ay) & ge(ax, az);
        let ym = !xm & ge(ay, az);
        let pos = select(
            xm,
            gt(d.x, splat(0.0)),
            select(ym, gt(d.y, splat(0.0)), gt(d.z, splat(0.0))),
        );
        let face = select(xm, splat(0.0), select(ym, splat(2.0), splat(4.0)))
            + select(pos, splat(0.0), splat(1.0));
        let sc = select(
            xm,
            select(pos, -d.z, d.z),
            select(ym, d.x, select(pos, d.x, -d.x)),
        );
        let tc = select(ym, select(pos, d.z, -d.z), -d.y);
        let ma = select(xm, ax, select(ym, ay, az));
        let (one, half) = (splat(1.0), splat(0.5));
        let s = (sc / ma + one) * half;
        let t = (tc / ma + one) * half;
        let (w, h) = (self.faces[0].width as f32, self.faces[0].height as f32);
        let x = s * splat(w) - half;
        let y = t * splat(h) - half;
        // `bilinear`: non-finite coordinates look up texel 0
        let finite = x.is_finite() & y.is_finite();
        let (x, y) = (select(finite, x, splat(0.0)), select(finite, y, splat(0.0)));
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        // clamp to edge: the floored coordinates are whole numbers in [-1, size - 1], so
        // clamping them as floats is the scalar integer clamp
        let clamp = |v: simd::F32x8, n: f32| simd::int_lanes(v.max(splat(0.0)).min(splat(n - 1.0)));
        Footprint8 {
            face: simd::int_lanes(face),
            x: [clamp(x0, w), clamp(x0 + one, w)],
            y: [clamp(y0, h), clamp(y0 + one, h)],
            fx: simd::lanes(fx),
            fy: simd::lanes(fy),
        }
    }

    /// Lane `i`'s colour from [`CubeMap::footprint8`]: [`Texture::bilinear`]'s blend of the
    /// four texels, equal to [`CubeMap::sample`] of that lane's direction.
    #[inline(always)]
    pub fn blend(&self, p: &Footprint8, i: usize) -> Vec3 {
        let f = &self.faces[p.face[i] as usize];
        let texel = |x: i32, y: i32| f.texel_at(y as usize * f.width + x as usize);
        let ([x0, x1], [y0, y1]) = ([p.x[0][i], p.x[1][i]], [p.y[0][i], p.y[1][i]]);
        let (fx, fy) = (p.fx[i], p.fy[i]);
        let top = texel(x0, y0) * (1.0 - fx) + texel(x1, y0) * fx;
        let bottom = texel(x0, y1) * (1.0 - fx) + texel(x1, y1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

/// Eight cube-map lookups' faces, bilinear footprints and weights ([`CubeMap::footprint8`]).
#[derive(Clone, Copy, Debug)]
pub struct Footprint8 {
    face: [i32; 8],
    /// The footprint's two columns, clamped to the face.
    x: [[i32; 8]; 2],
    /// Its two rows.
    y: [[i32; 8]; 2],
    fx: [f32; 8],
    fy: [f32; 8],
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

    /// A cube map of `n x n` faces whose texels all differ (so a wrong face or texel shows).
    fn numbered_cube(n: usize) -> CubeMap {
        let face = |f: usize| {
            let texels = (0..n * n)
                .map(|i| {
                    let k = (f * n * n + i) as f32;
                    Vec3::new(k + 0.25, 1.0 / (k + 1.5), k * k * 0.01 - 3.0)
                })
                .collect();
            Texture::new(n, n, texels)
        };
        CubeMap {
            faces: std::array::from_fn(face),
        }
    }

    /// Every lane of `footprint8` + `blend` against `sample`, bit for bit.
    fn assert_lanes_match(cm: &CubeMap, dirs: &[Vec3]) {
        for group in dirs.chunks(8) {
            let lane = |i: usize| group.get(i).copied().unwrap_or(Vec3::X).to_array();
            let p = cm.footprint8(Vec3x8::from_fn(lane));
            for (i, &d) in group.iter().enumerate() {
                let (want, got) = (cm.sample(d), cm.blend(&p, i));
                assert_eq!(
                    want.to_array().map(f32::to_bits),
                    got.to_array().map(f32::to_bits),
                    "direction {d:?}: sample {want}, lanes {got}"
                );
            }
        }
    }

    #[test]
    fn cube_lanes_equal_the_scalar_lookup_on_edges_ties_and_odd_values() {
        let mut dirs = Vec::new();
        // the axes, the ties between them (face choice), face edges and corners
        for v in [-1.0f32, -0.5, 0.0, 0.5, 1.0] {
            for w in [-1.0f32, -0.999_999, 0.0, 1e-30, 0.999_999, 1.0] {
                for u in [-1.0f32, 1.0, -0.0, 2.0] {
                    dirs.extend([Vec3::new(u, v, w), Vec3::new(v, u, w), Vec3::new(w, v, u)]);
                }
            }
        }
        // no direction, NaN, infinities, denormals, huge and tiny lengths
        let odd = [
            0.0,
            -0.0,
            f32::NAN,
            f32::INFINITY,
            -f32::INFINITY,
            1e-45,
            3e38,
            -1e-20,
        ];
        for &a in &odd {
            for &b in &odd {
                dirs.extend([
                    Vec3::new(a, b, 0.3),
                    Vec3::new(0.3, a, b),
                    Vec3::new(b, 0.3, a),
                ]);
            }
        }
        for n in [1, 2, 5, 16] {
            assert_lanes_match(&numbered_cube(n), &dirs);
        }
    }

    proptest::proptest! {
        #[test]
        fn cube_lanes_equal_the_scalar_lookup(
            dirs in proptest::collection::vec(proptest::array::uniform3(-1.0f32..1.0), 1..40),
            n in 1usize..9,
        ) {
            let dirs: Vec<Vec3> = dirs.into_iter().map(Vec3::from_array).collect();
            assert_lanes_match(&numbered_cube(n), &dirs);
        }
    }

    /// An sRGB 8-bit texture reads every level as the linear float the table gives, on every
    /// texel, the last one (read without the 4-byte load) included, and samples as the
    /// same image converted to floats up front.
    #[test]
    fn srgb8_texels_read_as_their_linear_values() {
        let (w, h) = (7, 5);
        let bytes: Vec<u8> = (0..3 * w * h).map(|i| (i * 37 % 256) as u8).collect();
        let tex = Texture::from_srgb8(w, h, bytes.clone());
        let table = srgb8_table();
        let linear: Vec<Vec3> = bytes
            .chunks_exact(3)
            .map(|c| {
                Vec3::new(
                    table[c[0] as usize],
                    table[c[1] as usize],
                    table[c[2] as usize],
                )
            })
            .collect();
        for (i, &want) in linear.iter().enumerate() {
            assert_eq!(tex.texel_at(i), want, "texel {i}");
        }
        assert_eq!(tex.linear_texels(), linear);
        assert_eq!(tex.texel_bytes(), 3 * w * h);
        let floats = Texture::new(w, h, linear);
        assert_eq!(floats.texel_bytes(), 12 * w * h);
        for k in 0..200 {
            let uv = Vec2::new(k as f32 * 0.0173 - 0.6, k as f32 * 0.0291 - 1.3);
            let (a, b) = (tex.sample_uv(uv), floats.sample_uv(uv));
            assert_eq!(
                a.to_array().map(f32::to_bits),
                b.to_array().map(f32::to_bits)
            );
        }
        // the table is the exact formula, rounded once; its ends are exact
        assert_eq!((table[0], table[255]), (0.0, 1.0));
        for (v, &t) in table.iter().enumerate() {
            assert_eq!(t, crate::image::srgb_decode(v as f64 / 255.0) as f32);
        }
    }

    #[test]
    fn faces_alike_only_when_every_face_has_the_first_size() {
        let mut cm = numbered_cube(3);
        assert!(cm.faces_alike());
        cm.faces[4] = Texture::new(2, 2, vec![Vec3::ONE; 4]);
        assert!(!cm.faces_alike());
    }
}
