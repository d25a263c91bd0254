//! Writing renders as they are made: rows stream into `.exr` (display and data windows,
//! ZIP/ZIPS/PIZ/RLE/none, f32 or f16, AOV layers beside the beauty image) or `.png` (sRGB
//! 8-bit), always through a temporary file beside the target that is renamed into place only
//! once complete. EXR blocks are compressed as parallel tasks while the render goes on, and
//! written in order as they finish.

use crate::aov::{Aov, AovImages};
use crate::error::{Error, Result};
use crate::image::{PixelBounds, srgb8};
use exr::prelude::f16;
use glam::Vec3;
use rayon::prelude::*;
use std::io::{Seek, Write};
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

mod atomic;
mod piz;
mod writeback;

pub(crate) use atomic::write_atomically;

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

/// The EXR compressions whitted writes (all lossless). PIZ is the default: whitted's encoder
/// makes the smallest files and costs less CPU time than ZIP (docs/output.md).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExrCompression {
    /// Raw samples.
    None,
    /// Run-length encoding of bytes, one scan line per block: no gain on float renders.
    Rle,
    /// zlib over single scan lines (OpenEXR's ZIPS), through libdeflate.
    Zips,
    /// zlib over blocks of 16 scan lines (OpenEXR's ZIP), through libdeflate.
    Zip,
    /// wavelet + Huffman over blocks of 32 scan lines (OpenEXR's PIZ), whitted's encoder.
    Piz,
}

/// libdeflate's compression level for ZIP and ZIPS blocks: the fastest level whose files stay
/// within 15% of PIZ's on `phong` at 1080p and 4K (level 1 is 23% larger at 4K; docs/output.md).
pub const ZIP_LEVEL: i32 = 4;

impl ExrCompression {
    /// The names `--exr-compression` takes, the default first.
    pub const NAMES: [&'static str; 5] = ["piz", "zip", "zips", "rle", "none"];

    /// The compression of a name in [`Self::NAMES`].
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "none" => ExrCompression::None,
            "rle" => ExrCompression::Rle,
            "zips" => ExrCompression::Zips,
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
            ExrCompression::Zips => C::ZIP1,
            ExrCompression::Zip => C::ZIP16,
            ExrCompression::Piz => C::PIZ,
        }
    }
}

/// AOV layers written beside the beauty image of a streamed EXR: which, and how to capture
/// them over a rectangle of the image (called once per batch of rows, with the part's
/// columns; it returns an [`AovImages`] of the rectangle's size).
pub struct AovSource<'a> {
    /// The layers, each written as the channels of [`crate::io::aov::CHANNELS`].
    pub aovs: &'a [Aov],
    /// Capture the layers over a rectangle of the image.
    pub capture: &'a (dyn Fn(PixelBounds) -> AovImages + Sync),
}

/// Where the time of a streamed write went (nanoseconds, summed over threads): laying out
/// and compressing blocks, capturing AOVs, writing chunks.
#[derive(Debug, Default)]
pub struct OutputTimes {
    /// Laying samples out in the file's order and compressing them.
    pub encode_ns: AtomicU64,
    /// Capturing AOV layers ([`AovSource::capture`]).
    pub aov_ns: AtomicU64,
    /// Handing compressed chunks to the file (in order, under a lock).
    pub write_ns: AtomicU64,
}

impl OutputTimes {
    fn add(counter: &AtomicU64, since: Instant) {
        counter.fetch_add(since.elapsed().as_nanos() as u64, Ordering::Relaxed);
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
    size: (u32, u32),
    part: PixelBounds,
    exr: ExrOptions,
    produce: &mut dyn FnMut(&mut RowSink) -> Result<()>,
) -> Result<()> {
    write_streamed_with(
        path,
        size,
        part,
        exr,
        None,
        &OutputTimes::default(),
        produce,
    )
}

/// [`write_streamed`] with AOV layers beside the beauty image (`.exr` only: with `aovs` a
/// `.png` path is an error), adding where the time went to `times`.
pub fn write_streamed_with(
    path: &Path,
    (width, height): (u32, u32),
    part: PixelBounds,
    exr: ExrOptions,
    aovs: Option<&AovSource>,
    times: &OutputTimes,
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
            write_exr(file, path, (width, height), part, exr, aovs, times, produce)
        }),
        "png" if aovs.is_some() => Err(Error::Usage(format!(
            "{}: AOV layers need an .exr file",
            path.display()
        ))),
        "png" => write_atomically(path, |file| write_png(file, path, part, produce)),
        _ => Err(Error::Usage(format!(
            "{}: unknown output format (use .png or .exr)",
            path.display()
        ))),
    }
}

/// Where one channel's samples come from.
#[derive(Clone, Copy, Debug)]
enum Source {
    /// The beauty image's component (0 R, 1 G, 2 B).
    Beauty(usize),
    Albedo(usize),
    Normal(usize),
    Depth,
    Id,
}

impl Source {
    /// Bytes per sample in the file: 2 for floats written as `half`, else 4 (`id` is always
    /// a u32).
    fn bytes(self, half: bool) -> usize {
        if half && !matches!(self, Source::Id) {
            2
        } else {
            4
        }
    }
}

/// The file's channels, in its (byte-wise sorted) order: name and source.
fn channel_layout(aovs: &[Aov]) -> Vec<(&'static str, Source)> {
    use crate::io::aov::CHANNELS;
    let mut v = vec![
        ("R", Source::Beauty(0)),
        ("G", Source::Beauty(1)),
        ("B", Source::Beauty(2)),
    ];
    for &a in aovs {
        let names = CHANNELS[a as usize].1;
        for (k, &name) in names.iter().enumerate() {
            v.push((
                name,
                match a {
                    Aov::Albedo => Source::Albedo(k),
                    Aov::Normal => Source::Normal(k),
                    Aov::Depth => Source::Depth,
                    Aov::Id => Source::Id,
                },
            ));
        }
    }
    v.sort_by(|a, b| a.0.cmp(b.0));
    v
}

/// The rows of one batch: beauty pixels and, with AOVs, the layers over the same rows.
struct Rows<'a> {
    beauty: &'a [Vec3],
    aovs: Option<&'a AovImages>,
}

/// Float samples into `dst`, little-endian, as f16 (`half`) or f32.
fn put(dst: &mut [u8], samples: impl Iterator<Item = f32>, half: bool) {
    if half {
        for (d, x) in dst.chunks_exact_mut(2).zip(samples) {
            d.copy_from_slice(&f16::from_f32(x).to_le_bytes());
        }
    } else {
        for (d, x) in dst.chunks_exact_mut(4).zip(samples) {
            d.copy_from_slice(&x.to_le_bytes());
        }
    }
}

/// One block's bytes in the file's layout: for each row, each channel's samples in turn,
/// little-endian (f16 or f32; `id` u32).
fn encode_block(
    rows: &Rows,
    (r0, r1): (usize, usize),
    width: usize,
    layout: &[(&str, Source)],
    half: bool,
) -> Vec<u8> {
    let size: usize = layout.iter().map(|(_, s)| s.bytes(half)).sum();
    let mut out = vec![0u8; (r1 - r0) * width * size];
    let mut at = 0;
    // the next `width` samples of a channel, `bytes` each
    let mut take = |bytes: usize| {
        at += width * bytes;
        at - width * bytes..at
    };
    for r in r0..r1 {
        let span = r * width..(r + 1) * width;
        for &(_, source) in layout {
            let a = rows.aovs;
            let bytes = source.bytes(half);
            let dst = &mut out[take(bytes)];
            match source {
                Source::Beauty(c) => put(dst, rows.beauty[span.clone()].iter().map(|p| p[c]), half),
                Source::Albedo(c) => {
                    let v = a
                        .and_then(|a| a.albedo.as_deref())
                        .expect("albedo captured");
                    put(dst, v[span.clone()].iter().map(|p| p[c]), half)
                }
                Source::Normal(c) => {
                    let v = a
                        .and_then(|a| a.normal.as_deref())
                        .expect("normal captured");
                    put(dst, v[span.clone()].iter().map(|p| p[c]), half)
                }
                Source::Depth => {
                    let v = a.and_then(|a| a.depth.as_deref()).expect("depth captured");
                    put(dst, v[span.clone()].iter().copied(), half)
                }
                Source::Id => {
                    let v = a.and_then(|a| a.id.as_deref()).expect("id captured");
                    for (d, i) in dst.chunks_exact_mut(4).zip(&v[span.clone()]) {
                        d.copy_from_slice(&i.to_le_bytes());
                    }
                }
            }
        }
    }
    out
}

thread_local! {
    /// Each thread's libdeflate compressor (its tables are reused from block to block).
    static DEFLATE: std::cell::RefCell<libdeflater::Compressor> = std::cell::RefCell::new(
        libdeflater::Compressor::new(
            libdeflater::CompressionLvl::new(ZIP_LEVEL).expect("a valid libdeflate level"),
        ),
    );
}

/// OpenEXR's ZIP (and ZIPS) block: the little-endian bytes split into the even-indexed ones
/// then the odd, each byte replaced by its difference from the one before plus 128 (mod 256),
/// then zlib. A block that would not shrink is stored raw, as OpenEXR does (a reader takes a
/// block of the raw size as uncompressed).
pub fn zip_block(raw: &[u8]) -> Vec<u8> {
    let n = raw.len();
    if n == 0 {
        return Vec::new();
    }
    let half = n.div_ceil(2);
    let mut split = vec![0u8; n];
    let (even, odd) = split.split_at_mut(half);
    for ((pair, e), o) in raw.chunks_exact(2).zip(even.iter_mut()).zip(odd.iter_mut()) {
        *e = pair[0];
        *o = pair[1];
    }
    if n % 2 == 1 {
        even[half - 1] = raw[n - 1];
    }
    let mut predicted = vec![0u8; n];
    predicted[0] = split[0];
    for ((d, &cur), &prev) in predicted[1..]
        .iter_mut()
        .zip(&split[1..])
        .zip(&split[..n - 1])
    {
        *d = cur.wrapping_sub(prev).wrapping_add(128);
    }
    DEFLATE.with(|c| {
        let mut c = c.borrow_mut();
        let mut out = vec![0u8; c.zlib_compress_bound(n)];
        match c.zlib_compress(&predicted, &mut out) {
            Ok(len) if len < n => {
                out.truncate(len);
                out
            }
            _ => raw.to_vec(),
        }
    })
}

/// The compressed chunks waiting to be written in order, and the writer they go to.
struct InOrder<'w, C> {
    chunks: &'w mut C,
    ready: std::collections::BTreeMap<usize, exr::block::chunk::Chunk>,
    next: usize,
    error: Option<exr::error::Error>,
}

/// Scan-line blocks of `part` laid out and compressed as parallel tasks (while `produce`
/// goes on rendering) and written in increasing y as they finish.
#[allow(clippy::too_many_arguments)]
fn write_exr<W: Write + Seek + Send>(
    out: W,
    path: &Path,
    (width, height): (u32, u32),
    part: PixelBounds,
    opts: ExrOptions,
    aovs: Option<&AovSource>,
    times: &OutputTimes,
    produce: &mut dyn FnMut(&mut RowSink) -> Result<()>,
) -> Result<()> {
    use exr::block::chunk::{Chunk, CompressedBlock, CompressedScanLineBlock};
    use exr::block::{BlockIndex, UncompressedBlock, writer::ChunksWriter};
    use exr::math::Vec2;
    use exr::meta::attribute::{ChannelDescription, IntegerBounds, LineOrder, SampleType};
    use exr::meta::{BlockDescription, header::Header};

    let layout = channel_layout(aovs.map_or(&[], |a| a.aovs));
    let float = if opts.half {
        SampleType::F16
    } else {
        SampleType::F32
    };
    let channels = layout
        .iter()
        .map(|&(name, source)| {
            let sample = match source {
                Source::Id => SampleType::U32,
                _ => float,
            };
            ChannelDescription::named(name, sample)
        })
        .collect();
    let (pw, ph) = (part.width() as usize, part.height() as usize);
    let compression = opts.compression;
    // 16-bit words per sample of each channel, in the file's order (PIZ's blocks)
    let words: Vec<usize> = layout.iter().map(|(_, s)| s.bytes(opts.half) / 2).collect();
    let mut header = Header::new("rgb".into(), (pw, ph), channels)
        .with_encoding(
            compression.to_exr(),
            BlockDescription::ScanLines,
            LineOrder::Increasing,
        )
        .with_display_window(IntegerBounds::new(
            (0, 0),
            (width as usize, height as usize),
        ))
        .with_position(Vec2(part.x0 as i32, part.y0 as i32));
    header.own_attributes.layer_name = None;
    let lines = compression.to_exr().scan_lines_per_block();
    let exr_err = |e: exr::error::Error| Error::image(path, format!("cannot write EXR: {e}"));

    // our own error (from `produce`), carried through the exr crate's closure
    let mut failure: Option<Error> = None;
    let written = exr::block::write(
        out,
        std::iter::once(header).collect(),
        true,
        |meta, chunks| {
            let headers = &meta.headers;
            let state = Mutex::new(InOrder {
                chunks,
                ready: Default::default(),
                next: 0,
                error: None,
            });
            // Compress block `k` (its bytes laid out) and write every chunk that is next in
            // order.
            let compress_and_write = |k: usize, rows: usize, data: Vec<u8>| {
                let t = Instant::now();
                let y = part.y0 as i32 + (k * lines) as i32;
                // whitted's own encoders, else the exr crate's
                let ours = match compression {
                    ExrCompression::Piz => Some(piz::piz_block(&data, pw, rows, &words)),
                    ExrCompression::Zip | ExrCompression::Zips => Some(zip_block(&data)),
                    ExrCompression::Rle | ExrCompression::None => None,
                };
                let chunk = if let Some(compressed_pixels_le) = ours {
                    Ok(Chunk {
                        layer_index: 0,
                        compressed_block: CompressedBlock::ScanLine(CompressedScanLineBlock {
                            y_coordinate: y,
                            compressed_pixels_le,
                        }),
                    })
                } else {
                    let index = BlockIndex {
                        layer: 0,
                        pixel_position: Vec2(0, k * lines),
                        pixel_size: Vec2(pw, rows),
                        level: Vec2(0, 0),
                    };
                    UncompressedBlock { index, data }.compress_to_chunk(headers)
                };
                OutputTimes::add(&times.encode_ns, t);
                let t = Instant::now();
                let mut guard = state.lock().unwrap_or_else(|e| e.into_inner());
                let s = &mut *guard;
                match chunk {
                    Ok(c) => {
                        s.ready.insert(k, c);
                    }
                    Err(e) => {
                        s.error.get_or_insert(e);
                    }
                }
                while let Some(c) = s.ready.remove(&s.next) {
                    if s.error.is_none()
                        && let Err(e) = s.chunks.write_chunk(s.next, c)
                    {
                        s.error = Some(e);
                    }
                    s.next += 1;
                }
                OutputTimes::add(&times.write_ns, t);
            };
            let write_error = |state: &Mutex<InOrder<_>>| {
                let s = state.lock().unwrap_or_else(|e| e.into_inner());
                s.error.as_ref().map(|e| format!("cannot write EXR: {e}"))
            };

            let mut produced = Ok(());
            let mut rendered = 0usize;
            rayon::in_place_scope(|scope| {
                // part rows `done..` are not laid out yet; those that do not fill a block
                // wait in `pending`
                let mut pending: Vec<Vec3> = Vec::new();
                let mut done = 0usize;
                // Lay out the blocks of `lines` rows at the front of `src` (part rows from
                // `done` on; with `last`, a short final block too) in parallel and hand each
                // to a task that compresses and writes it; the number of rows taken.
                let emit = |src: &[Vec3], done: usize, last: bool| -> usize {
                    let rows = src.len() / pw;
                    let blocks = if last {
                        rows.div_ceil(lines)
                    } else {
                        rows / lines
                    };
                    let taken = (blocks * lines).min(rows);
                    if taken == 0 {
                        return 0;
                    }
                    let layers = aovs.map(|a| {
                        let t = Instant::now();
                        let y0 = part.y0 + done as u32;
                        let img = (a.capture)(PixelBounds {
                            x0: part.x0,
                            x1: part.x1,
                            y0,
                            y1: y0 + taken as u32,
                        });
                        OutputTimes::add(&times.aov_ns, t);
                        img
                    });
                    let batch = Rows {
                        beauty: &src[..taken * pw],
                        aovs: layers.as_ref(),
                    };
                    let laid_out: Vec<Vec<u8>> = (0..blocks)
                        .into_par_iter()
                        .map(|b| {
                            let t = Instant::now();
                            let r0 = b * lines;
                            let rows = (r0, (r0 + lines).min(rows));
                            let data = encode_block(&batch, rows, pw, &layout, opts.half);
                            OutputTimes::add(&times.encode_ns, t);
                            data
                        })
                        .collect();
                    for (b, data) in laid_out.into_iter().enumerate() {
                        let k = done / lines + b;
                        let n = lines.min(rows - b * lines);
                        let task = &compress_and_write;
                        scope.spawn(move |_| task(k, n, data));
                    }
                    taken
                };
                produced = produce(&mut |y, rows| {
                    debug_assert_eq!(rows.len() % pw, 0);
                    let expected = part.y0 as usize + done + pending.len() / pw;
                    if y as usize != expected {
                        return Err(Error::image(
                            path,
                            format!("rows from {y} given where {expected} was next"),
                        ));
                    }
                    if let Some(msg) = write_error(&state) {
                        return Err(Error::image(path, msg));
                    }
                    let mut rows = rows;
                    if !pending.is_empty() {
                        // the waiting rows (less than a block) completed from the front of
                        // the batch and emitted on their own: only that block is copied
                        let take = (lines * pw - pending.len()).min(rows.len());
                        pending.extend_from_slice(&rows[..take]);
                        rows = &rows[take..];
                        if pending.len() == lines * pw {
                            done += emit(&pending, done, false);
                            pending.clear();
                        }
                    }
                    if pending.is_empty() {
                        // straight from the caller's rows; the rest of a block waits
                        let n = emit(rows, done, false);
                        pending.extend_from_slice(&rows[n * pw..]);
                        done += n;
                    }
                    Ok(())
                });
                rendered = done + pending.len() / pw;
                // only the part's last block may be short (the exr crate sizes a block from
                // its position; PIZ indexes out of range on a short one anywhere else)
                if produced.is_ok() && rendered == ph {
                    emit(&pending, done, true);
                }
            });
            if let Err(e) = produced {
                failure = Some(e);
                return Err(exr::error::Error::Aborted);
            }
            if rendered != ph {
                failure = Some(Error::image(
                    path,
                    format!("{rendered} of the part's {ph} rows were rendered"),
                ));
                return Err(exr::error::Error::Aborted);
            }
            let s = state.into_inner().unwrap_or_else(|e| e.into_inner());
            match s.error {
                Some(e) => Err(e),
                None => Ok(()),
            }
        },
    );
    match (failure, written) {
        (Some(e), _) => Err(e),
        (None, r) => r.map_err(exr_err),
    }
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
mod tests;
