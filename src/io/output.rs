//! Writing renders as they are made: rows stream into `.exr` (display and data windows,
//! PIZ/ZIP/RLE, f32 or f16) or `.png` (sRGB 8-bit), always through a temporary file beside the
//! target that is renamed into place only once complete.

use crate::error::{Error, Result};
use crate::image::{PixelBounds, srgb8};
use exr::prelude::f16;
use glam::Vec3;
use rayon::prelude::*;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// How EXR pixels are stored.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ExrOptions {
    /// How scan-line blocks are compressed.
    pub compression: ExrCompression,
    /// 16-bit floats (`--half`) instead of 32-bit.
    pub half: bool,
}

impl Default for ExrOptions {
    fn default() -> Self {
        ExrOptions {
            compression: ExrCompression::Piz,
            half: false,
        }
    }
}

/// The EXR compressions whitted writes (all lossless). PIZ is the default: on 32-bit renders
/// it made files 13-17% smaller than ZIP and wrote them in 60% of the CPU time (README,
/// "Output"); ZIP makes the smaller `--half` files.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExrCompression {
    /// Raw samples.
    None,
    /// Run-length encoding of bytes, one scan line per block: no gain on float renders.
    Rle,
    /// zlib over blocks of 16 scan lines.
    Zip,
    /// wavelet + Huffman over blocks of 32 scan lines.
    Piz,
}

impl ExrCompression {
    /// The names `--exr-compression` takes, the default first.
    pub const NAMES: [&'static str; 4] = ["piz", "zip", "rle", "none"];

    /// The compression of a name in [`Self::NAMES`].
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "none" => ExrCompression::None,
            "rle" => ExrCompression::Rle,
            "zip" => ExrCompression::Zip,
            "piz" => ExrCompression::Piz,
            _ => return None,
        })
    }

    fn to_exr(self) -> exr::compression::Compression {
        use exr::compression::Compression as C;
        match self {
            ExrCompression::None => C::Uncompressed,
            ExrCompression::Rle => C::RLE,
            ExrCompression::Zip => C::ZIP16,
            ExrCompression::Piz => C::PIZ,
        }
    }
}

/// Where the rows of a render go: `(y, rows)` gets whole rows from row `y` on, each
/// `part.width()` pixels, in increasing `y` with no gap (what `render::render_rows` gives).
pub type RowSink<'a> = dyn FnMut(u32, &[Vec3]) -> Result<()> + 'a;

/// Write an image of `width x height` pixels of which `part` is rendered, while `produce`
/// hands its rows to the sink it is given. `.exr`: display window the whole image, data window
/// `part`, rows compressed and written as soon as a block of scan lines is complete. `.png`:
/// just the part, rows encoded as they come. Either way the file appears at `path` only when
/// complete: an error from `produce` or from writing leaves whatever was at `path` untouched
/// and no temporary file behind.
pub fn write_streamed(
    path: &Path,
    (width, height): (u32, u32),
    part: PixelBounds,
    exr: ExrOptions,
    produce: &mut dyn FnMut(&mut RowSink) -> Result<()>,
) -> Result<()> {
    if part.is_empty() || !PixelBounds::full(width, height).contains(&part) {
        return Err(Error::Usage(format!(
            "{}: the part {part} is not a non-empty part of the {width}x{height} image",
            path.display()
        )));
    }
    match crate::io::extension(path).as_str() {
        "exr" => write_atomically(path, |file| {
            write_exr(file, path, (width, height), part, exr, produce)
        }),
        "png" => write_atomically(path, |file| write_png(file, path, part, produce)),
        _ => Err(Error::Usage(format!(
            "{}: unknown output format (use .png or .exr)",
            path.display()
        ))),
    }
}

/// Run `write` on a new temporary file beside `path` (`.NAME.PID-K.tmp` in the same folder,
/// so the rename cannot cross file systems), then rename it over `path`. On any error the
/// temporary file is removed and `path` keeps what it held. A process killed mid-write leaves
/// `path` untouched too, and its hidden temporary file behind.
pub fn write_atomically(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> Result<()>,
) -> Result<()> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path
        .file_name()
        .ok_or_else(|| Error::Usage(format!("{}: not a file name", path.display())))?;
    if path.is_dir() {
        return Err(Error::Usage(format!(
            "{}: is a folder, not an image file",
            path.display()
        )));
    }
    let tmp: PathBuf = path.with_file_name(format!(
        ".{}.{}-{}.tmp",
        name.to_string_lossy(),
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let file = File::create_new(&tmp).map_err(|e| Error::io(path, e))?;
    let mut out = BufWriter::with_capacity(1 << 20, file);
    let result = write(&mut out)
        .and_then(|()| out.flush().map_err(|e| Error::io(path, e)))
        .and_then(|()| std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e)));
    if result.is_err() {
        drop(out);
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Scan-line blocks of `part` compressed in parallel and written in increasing y.
fn write_exr<W: Write + Seek>(
    out: W,
    path: &Path,
    (width, height): (u32, u32),
    part: PixelBounds,
    opts: ExrOptions,
    produce: &mut dyn FnMut(&mut RowSink) -> Result<()>,
) -> Result<()> {
    use exr::block::{BlockIndex, UncompressedBlock, writer::ChunksWriter};
    use exr::math::Vec2;
    use exr::meta::attribute::{ChannelDescription, IntegerBounds, LineOrder, SampleType};
    use exr::meta::{BlockDescription, header::Header};

    let sample = if opts.half {
        SampleType::F16
    } else {
        SampleType::F32
    };
    // channels in the file's (alphabetical) order
    let channels = ["B", "G", "R"]
        .map(|name| ChannelDescription::named(name, sample))
        .into_iter()
        .collect();
    let (pw, ph) = (part.width() as usize, part.height() as usize);
    let mut header = Header::new("rgb".into(), (pw, ph), channels)
        .with_encoding(
            opts.compression.to_exr(),
            BlockDescription::ScanLines,
            LineOrder::Increasing,
        )
        .with_display_window(IntegerBounds::new(
            (0, 0),
            (width as usize, height as usize),
        ))
        .with_position(Vec2(part.x0 as i32, part.y0 as i32));
    header.own_attributes.layer_name = None;
    let lines = opts.compression.to_exr().scan_lines_per_block();
    let exr_err = |e: exr::error::Error| Error::image(path, format!("cannot write EXR: {e}"));

    // our own error (from `produce`), carried through the exr crate's closure
    let mut failure: Option<Error> = None;
    let written = exr::block::write(
        out,
        std::iter::once(header).collect(),
        true,
        |meta, chunks| {
            // part rows `done..` are not written yet; those that do not fill a block wait in
            // `pending`
            let mut pending: Vec<Vec3> = Vec::new();
            let mut done = 0usize;
            let headers = &meta.headers;
            // Encode and compress the blocks of `lines` rows at the front of `src` (part rows
            // from `done` on; with `last`, a short final block too) in parallel, write them in
            // order; the number of rows written.
            let mut emit = |src: &[Vec3], done: usize, last: bool| -> exr::error::Result<usize> {
                let rows = src.len() / pw;
                let blocks = if last {
                    rows.div_ceil(lines)
                } else {
                    rows / lines
                };
                let compressed: Vec<exr::error::Result<exr::block::chunk::Chunk>> = (0..blocks)
                    .into_par_iter()
                    .map(|b| {
                        let r0 = b * lines;
                        let n = lines.min(rows - r0);
                        let index = BlockIndex {
                            layer: 0,
                            pixel_position: Vec2(0, done + r0),
                            pixel_size: Vec2(pw, n),
                            level: Vec2(0, 0),
                        };
                        let data = encode_lines(&src[r0 * pw..(r0 + n) * pw], pw, opts.half);
                        UncompressedBlock { index, data }.compress_to_chunk(headers)
                    })
                    .collect();
                for (b, chunk) in compressed.into_iter().enumerate() {
                    chunks.write_chunk(done / lines + b, chunk?)?;
                }
                Ok((blocks * lines).min(rows))
            };
            let mut exr_error = None;
            let produced = produce(&mut |y, rows| {
                debug_assert_eq!(rows.len() % pw, 0);
                let expected = part.y0 as usize + done + pending.len() / pw;
                if y as usize != expected {
                    return Err(Error::image(
                        path,
                        format!("rows from {y} given where {expected} was next"),
                    ));
                }
                let written = if pending.is_empty() {
                    // straight from the caller's rows; the rest of a block waits
                    emit(rows, done, false).inspect(|&n| pending.extend_from_slice(&rows[n * pw..]))
                } else {
                    pending.extend_from_slice(rows);
                    emit(&pending, done, false).inspect(|&n| {
                        pending.drain(..n * pw);
                    })
                };
                match written {
                    Ok(n) => {
                        done += n;
                        Ok(())
                    }
                    Err(e) => {
                        let msg = format!("cannot write EXR: {e}");
                        exr_error = Some(e);
                        Err(Error::image(path, msg))
                    }
                }
            });
            if let Err(e) = produced {
                failure = Some(e);
                return Err(exr_error.unwrap_or(exr::error::Error::Aborted));
            }
            // only the part's last block may be short (the exr crate sizes a block from its
            // position; PIZ indexes out of range on a short one anywhere else)
            let rendered = done + pending.len() / pw;
            if rendered != ph {
                failure = Some(Error::image(
                    path,
                    format!("{rendered} of the part's {ph} rows were rendered"),
                ));
                return Err(exr::error::Error::Aborted);
            }
            emit(&pending, done, true)?;
            Ok(())
        },
    );
    match (failure, written) {
        (Some(e), _) => Err(e),
        (None, r) => r.map_err(exr_err),
    }
}

/// One block's bytes: for each row, all B samples, then G, then R, native-endian.
fn encode_lines(rows: &[Vec3], width: usize, half: bool) -> Vec<u8> {
    let size = if half { 2 } else { 4 };
    let mut out = Vec::with_capacity(rows.len() * 3 * size);
    for row in rows.chunks_exact(width) {
        for c in [2, 1, 0] {
            if half {
                for p in row {
                    out.extend_from_slice(&f16::from_f32(p[c]).to_ne_bytes());
                }
            } else {
                for p in row {
                    out.extend_from_slice(&p[c].to_ne_bytes());
                }
            }
        }
    }
    out
}

/// The part as an 8-bit sRGB PNG, rows deflated as they come (the image crate's defaults:
/// fast compression, adaptive filters, as whitted wrote PNGs before).
fn write_png<W: Write>(
    out: W,
    path: &Path,
    part: PixelBounds,
    produce: &mut dyn FnMut(&mut RowSink) -> Result<()>,
) -> Result<()> {
    let png_err = |e: png::EncodingError| Error::image(path, format!("cannot write PNG: {e}"));
    let mut encoder = png::Encoder::new(out, part.width(), part.height());
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    encoder.set_compression(png::Compression::Fast);
    encoder.set_filter(png::Filter::Adaptive);
    let mut writer = encoder.write_header().map_err(png_err)?;
    let mut stream = writer.stream_writer().map_err(png_err)?;
    let mut next = part.y0;
    let mut bytes = Vec::new();
    produce(&mut |y, rows| {
        if y != next {
            return Err(Error::image(
                path,
                format!("rows from {y} given where {next} was next"),
            ));
        }
        bytes.clear();
        bytes.extend(rows.iter().flat_map(|p| p.to_array().map(srgb8)));
        stream
            .write_all(&bytes)
            .map_err(|e| Error::image(path, format!("cannot write PNG: {e}")))?;
        next += (rows.len() / part.width() as usize) as u32;
        Ok(())
    })?;
    if next != part.y1 {
        return Err(Error::image(
            path,
            format!(
                "{} of the part's {} rows were rendered",
                next - part.y0,
                part.height()
            ),
        ));
    }
    stream.finish().map_err(png_err)?;
    writer.finish().map_err(png_err)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("whitted-out-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn listing(d: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    /// A write that fails midway (after real bytes went out) leaves the old image as it was
    /// and no temporary file; one that succeeds replaces it and leaves nothing else either.
    #[test]
    fn failed_writes_leave_the_old_file_and_no_temporary() {
        for (ext, compression) in [
            ("exr", ExrCompression::Piz),
            ("exr", ExrCompression::Zip),
            ("exr", ExrCompression::Rle),
            ("exr", ExrCompression::None),
            ("png", ExrCompression::Piz),
        ] {
            let opts = ExrOptions {
                compression,
                half: false,
            };
            let d = dir(&format!("atomic-{ext}-{compression:?}"));
            let path = d.join(format!("render.{ext}"));
            std::fs::write(&path, b"the good image").unwrap();
            let part = PixelBounds::full(64, 48);
            let row = vec![Vec3::splat(0.5); 64 * 16];
            let mut fail_after_one_band = |sink: &mut RowSink| -> Result<()> {
                sink(0, &row)?;
                Err(Error::Usage("the render failed midway".into()))
            };
            let r = write_streamed(&path, (64, 48), part, opts, &mut fail_after_one_band);
            assert!(r.unwrap_err().to_string().contains("failed midway"));
            assert_eq!(std::fs::read(&path).unwrap(), b"the good image");
            assert_eq!(listing(&d), [format!("render.{ext}")]);

            // too few rows is an error too, not a short image
            let r = write_streamed(&path, (64, 48), part, opts, &mut |s| s(0, &row));
            assert!(
                r.unwrap_err()
                    .to_string()
                    .contains("16 of the part's 48 rows")
            );
            assert_eq!(std::fs::read(&path).unwrap(), b"the good image");
            assert_eq!(listing(&d), [format!("render.{ext}")]);

            write_streamed(&path, (64, 48), part, opts, &mut |s| {
                (0..3).try_for_each(|b| s(b * 16, &row))
            })
            .unwrap();
            assert_ne!(std::fs::read(&path).unwrap(), b"the good image");
            assert_eq!(listing(&d), [format!("render.{ext}")]);
        }
    }

    #[test]
    fn an_unwritable_target_is_one_error_naming_it() {
        let d = dir("unwritable");
        let missing = d.join("no/such/folder/x.exr");
        let e = write_streamed(
            &missing,
            (8, 8),
            PixelBounds::full(8, 8),
            ExrOptions::default(),
            &mut |s| s(0, &[Vec3::ZERO; 64]),
        )
        .unwrap_err();
        assert!(e.to_string().contains("no/such/folder/x.exr"), "{e}");
        let e = write_streamed(
            &d,
            (8, 8),
            PixelBounds::full(8, 8),
            ExrOptions::default(),
            &mut |s| s(0, &[Vec3::ZERO; 64]),
        );
        assert!(e.is_err());
    }

    /// Rows given in any batch sizes make the same file, whatever the compression's block
    /// height, and read back as written (f32 exactly; f16 to its rounding).
    #[test]
    fn exr_rows_in_any_batches_read_back_exactly() {
        let d = dir("batches");
        let (w, h) = (37u32, 45u32);
        let part = PixelBounds {
            x0: 3,
            x1: 40,
            y0: 5,
            y1: 50,
        };
        let px =
            |x: u32, y: u32| Vec3::new(x as f32 * 0.1, y as f32 * 1e-3, -(x as f32 + y as f32));
        let rows: Vec<Vec3> = (part.y0..part.y1)
            .flat_map(|y| (part.x0..part.x1).map(move |x| px(x, y)))
            .collect();
        for compression in ExrCompression::NAMES.map(|n| ExrCompression::from_name(n).unwrap()) {
            for half in [false, true] {
                let opts = ExrOptions { compression, half };
                let mut files = Vec::new();
                for batch in [1usize, 7, 16, 45] {
                    let path = d.join(format!("{compression:?}-{half}-{batch}.exr"));
                    write_streamed(&path, (w + 10, h + 10), part, opts, &mut |s| {
                        for (k, c) in rows.chunks(batch * w as usize).enumerate() {
                            s(part.y0 + (k * batch) as u32, c)?;
                        }
                        Ok(())
                    })
                    .unwrap();
                    files.push(std::fs::read(&path).unwrap());
                }
                assert!(files.windows(2).all(|f| f[0] == f[1]), "{compression:?}");
                let path = d.join(format!("{compression:?}-{half}-1.exr"));
                let img = exr::prelude::read_first_rgba_layer_from_file(
                    &path,
                    |res, _| vec![Vec3::ZERO; res.0 * res.1],
                    |v: &mut Vec<Vec3>, p, (r, g, b, _): (f32, f32, f32, f32)| {
                        v[p.1 * 37 + p.0] = Vec3::new(r, g, b)
                    },
                )
                .unwrap();
                let layer = &img.layer_data;
                assert_eq!(layer.attributes.layer_position.0, 3);
                assert_eq!(layer.attributes.layer_position.1, 5);
                assert_eq!(layer.size.0, 37);
                assert_eq!(img.attributes.display_window.size.0, 47);
                let round = |v: Vec3| {
                    if half {
                        Vec3::from(v.to_array().map(|c| f16::from_f32(c).to_f32()))
                    } else {
                        v
                    }
                };
                let want: Vec<Vec3> = rows.iter().copied().map(round).collect();
                assert_eq!(layer.channel_data.pixels, want, "{compression:?} {half}");
            }
        }
    }
}
