//! `whitted merge`: join EXR parts (from `--tile`, `--crop`, `--pixel-bounds`) into the
//! image they share, after checking they cover its display window exactly once; rows are read
//! and written in bands, so memory stays at a band per part whatever the image size.

use crate::error::{Error, Result};
use crate::image::PixelBounds;
use crate::io::output::{ExrOptions, RowSink, write_streamed};
use exr::block::UncompressedBlock;
use exr::meta::attribute::SampleType;
use glam::Vec3;
use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

/// Rows of the merged image produced at a time: about 16 MB of f32 pixels.
const BATCH_BYTES: usize = 16 << 20;

/// What an EXR part's header says: its display window (the whole image) and data window
/// (the part), both as pixel bounds with exclusive ends.
#[derive(Clone, Debug, PartialEq)]
pub struct PartHeader {
    /// The file.
    pub path: PathBuf,
    /// The display window: the whole image.
    pub display: PixelBounds,
    /// The data window: the pixels the file holds.
    pub data: PixelBounds,
    /// Whether every one of R, G, B is stored as a 16-bit float.
    pub half: bool,
    /// Index of R, G and B in the file's channel list.
    channels: [usize; 3],
}

type Decoder = exr::block::reader::SequentialBlockDecompressor<
    exr::block::reader::AllChunksReader<BufReader<File>>,
>;

fn open(path: &Path) -> Result<(PartHeader, Decoder)> {
    use exr::block::reader::ChunksReader;
    let bad = |e: exr::error::Error| Error::image(path, format!("cannot read EXR: {e}"));
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    if !meta.is_file() {
        return Err(Error::Usage(format!(
            "{}: not a regular file",
            path.display()
        )));
    }
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let reader = exr::block::read(BufReader::new(file), true).map_err(bad)?;
    let headers = reader.headers();
    if headers.len() != 1 {
        return Err(Error::image(
            path,
            format!("{} layers; a part has one", headers.len()),
        ));
    }
    let h = &headers[0];
    if h.deep {
        return Err(Error::image(path, "deep data is not a render part"));
    }
    let window = |pos: exr::math::Vec2<i32>, size: exr::math::Vec2<usize>, what: &str| {
        let (x0, y0) = (pos.0 as i64, pos.1 as i64);
        let (x1, y1) = (x0 + size.0 as i64, y0 + size.1 as i64);
        if x0 < 0 || y0 < 0 || x1 > u32::MAX as i64 || y1 > u32::MAX as i64 {
            return Err(Error::image(
                path,
                format!("{what} window at ({x0}, {y0}) is not in the positive quadrant"),
            ));
        }
        Ok(PixelBounds {
            x0: x0 as u32,
            x1: x1 as u32,
            y0: y0 as u32,
            y1: y1 as u32,
        })
    };
    let dw = &h.shared_attributes.display_window;
    let display = window(dw.position, dw.size, "display")?;
    if (display.x0, display.y0) != (0, 0) {
        return Err(Error::image(
            path,
            format!(
                "display window starts at ({}, {}); parts of a render start at (0, 0)",
                display.x0, display.y0
            ),
        ));
    }
    crate::io::scene::check_size(display.x1 as u64, display.y1 as u64)
        .map_err(|e| Error::image(path, format!("display window: {e}")))?;
    let data = window(h.own_attributes.layer_position, h.layer_size, "data")?;
    if data.is_empty() || !display.contains(&data) {
        return Err(Error::image(
            path,
            format!(
                "data window {data} reaches outside the display window {}x{}",
                display.x1, display.y1
            ),
        ));
    }
    let find = |name: &str| {
        h.channels
            .list
            .iter()
            .position(|c| c.name.eq(name))
            .ok_or_else(|| Error::image(path, format!("no {name} channel; a part holds R, G, B")))
    };
    let channels = [find("R")?, find("G")?, find("B")?];
    if let Some(c) = h
        .channels
        .list
        .iter()
        .find(|c| c.sampling.0 != 1 || c.sampling.1 != 1)
    {
        return Err(Error::image(
            path,
            format!("channel {} is subsampled; a part holds every pixel", c.name),
        ));
    }
    let half = channels
        .iter()
        .all(|&c| h.channels.list[c].sample_type == SampleType::F16);
    let header = PartHeader {
        path: path.to_path_buf(),
        display,
        data,
        half,
        channels,
    };
    let decoder = reader
        .all_chunks(true)
        .map_err(bad)?
        .sequential_decompressor(true);
    Ok((header, decoder))
}

/// Read a part's header (for `whitted info` and [`check_coverage`]).
pub fn read_part_header(path: &Path) -> Result<PartHeader> {
    open(path).map(|(h, _)| h)
}

/// Check that `parts` share one display window, and that their data windows cover it with
/// no pixel missing and none twice. The error names every missing range and overlap (a few,
/// then a count). Returns the display window.
pub fn check_coverage(parts: &[PartHeader]) -> Result<PixelBounds> {
    let first = parts
        .first()
        .ok_or_else(|| Error::Usage("merge: no parts given".into()))?;
    let display = first.display;
    for p in parts {
        if p.display != display {
            return Err(Error::Usage(format!(
                "merge: {} has a {}x{} display window, {} has {}x{}: parts of different images",
                p.path.display(),
                p.display.x1,
                p.display.y1,
                first.path.display(),
                display.x1,
                display.y1
            )));
        }
    }
    let mut problems = Vec::new();
    for (i, a) in parts.iter().enumerate() {
        for b in &parts[i + 1..] {
            let o = a.data.intersect(&b.data);
            if !o.is_empty() {
                problems.push(format!(
                    "{} and {} overlap at {o}",
                    a.path.display(),
                    b.path.display()
                ));
            }
        }
    }
    for m in missing(display, parts.iter().map(|p| p.data)) {
        problems.push(format!("missing {m}"));
    }
    if problems.is_empty() {
        return Ok(display);
    }
    const SHOWN: usize = 6;
    let more = problems.len().saturating_sub(SHOWN);
    problems.truncate(SHOWN);
    let mut msg = format!(
        "merge: the {} parts do not cover the {}x{} image exactly: {}",
        parts.len(),
        display.x1,
        display.y1,
        problems.join("; ")
    );
    if more > 0 {
        msg.push_str(&format!("; and {more} more"));
    }
    Err(Error::Usage(msg))
}

/// The pixels of `display` that no rectangle covers, as rectangles: a sweep over the rows
/// between consecutive rectangle edges, gaps found per stretch of rows, and a gap that runs
/// on over the next stretch joined to it.
fn missing(display: PixelBounds, rects: impl Iterator<Item = PixelBounds>) -> Vec<PixelBounds> {
    let rects: Vec<PixelBounds> = rects.filter(|r| !r.is_empty()).collect();
    let mut ys: Vec<u32> = rects.iter().flat_map(|r| [r.y0, r.y1]).collect();
    ys.extend([display.y0, display.y1]);
    ys.sort_unstable();
    ys.dedup();
    let mut out: Vec<PixelBounds> = Vec::new();
    let mut open: Vec<PixelBounds> = Vec::new(); // gaps that reach the current stretch's top
    for w in ys.windows(2) {
        let (ya, yb) = (w[0], w[1]);
        let mut spans: Vec<(u32, u32)> = rects
            .iter()
            .filter(|r| r.y0 <= ya && r.y1 >= yb)
            .map(|r| (r.x0, r.x1))
            .collect();
        spans.sort_unstable();
        let mut gaps = Vec::new();
        let mut x = display.x0;
        for (x0, x1) in spans {
            if x0 > x {
                gaps.push((x, x0));
            }
            x = x.max(x1);
        }
        if x < display.x1 {
            gaps.push((x, display.x1));
        }
        let mut next_open = Vec::new();
        for (x0, x1) in gaps {
            match open
                .iter()
                .position(|g| g.x0 == x0 && g.x1 == x1 && g.y1 == ya)
            {
                Some(k) => {
                    let mut g = open.swap_remove(k);
                    g.y1 = yb;
                    next_open.push(g);
                }
                None => next_open.push(PixelBounds {
                    x0,
                    x1,
                    y0: ya,
                    y1: yb,
                }),
            }
        }
        out.append(&mut open);
        open = next_open;
    }
    out.append(&mut open);
    out.sort_unstable_by_key(|g| (g.y0, g.x0));
    out
}

/// One part being read: blocks of scan lines decoded in increasing y into `rows`, which hold
/// the part's full-width rows from `rows_y0` on.
struct PartReader {
    header: PartHeader,
    decoder: Decoder,
    rows: Vec<Vec3>,
    rows_y0: u32,
}

impl PartReader {
    /// Decode blocks until rows up to `y` (exclusive, clipped to the part) are held.
    fn fill_to(&mut self, y: u32) -> Result<()> {
        let data = self.header.data;
        let (w, y) = (data.width() as usize, y.min(data.y1));
        while (self.rows_y0 + (self.rows.len() / w) as u32) < y {
            let path = &self.header.path;
            let block = self
                .decoder
                .next()
                .ok_or_else(|| Error::image(path, "ends before its last rows"))?
                .map_err(|e| Error::image(path, format!("cannot read EXR: {e}")))?;
            let next = self.rows_y0 + (self.rows.len() / w) as u32;
            let at = block.index.pixel_position;
            if at.0 != 0 || block.index.pixel_size.0 != w || data.y0 + at.1 as u32 != next {
                return Err(Error::image(
                    path,
                    format!(
                        "a block at ({}, {}) where rows from {} were next: merge reads scan-line \
                         parts written in increasing y (as whitted writes them)",
                        at.0,
                        at.1,
                        next - data.y0
                    ),
                ));
            }
            let channels = &self.decoder.meta_data().headers[0].channels;
            decode_block(&block, channels, &self.header, &mut self.rows)?;
        }
        Ok(())
    }

    /// Drop the rows above `y`.
    fn discard_before(&mut self, y: u32) {
        let w = self.header.data.width() as usize;
        let n = (y.saturating_sub(self.rows_y0) as usize).min(self.rows.len() / w.max(1));
        self.rows.drain(..n * w);
        self.rows_y0 += n as u32;
    }
}

/// Append a block's rows to `out` as RGB.
fn decode_block(
    block: &UncompressedBlock,
    channels: &exr::meta::attribute::ChannelList,
    header: &PartHeader,
    out: &mut Vec<Vec3>,
) -> Result<()> {
    let (w, lines) = (block.index.pixel_size.0, block.index.pixel_size.1);
    let line_bytes = channels.bytes_per_pixel * w;
    if block.data.len() != line_bytes * lines {
        return Err(Error::image(&header.path, "a block of the wrong size"));
    }
    // byte offset of each channel's samples within a line, and its sample type
    let mut offsets = Vec::with_capacity(channels.list.len());
    let mut at = 0;
    for c in &channels.list {
        offsets.push((at, c.sample_type));
        at += c.sample_type.bytes_per_sample() * w;
    }
    let start = out.len();
    out.resize(start + w * lines, Vec3::ZERO);
    for (line, px) in block
        .data
        .chunks_exact(line_bytes.max(1))
        .zip(out[start..].chunks_exact_mut(w.max(1)))
    {
        for (k, &c) in header.channels.iter().enumerate() {
            let (off, ty) = offsets[c];
            let bytes = &line[off..];
            for (x, p) in px.iter_mut().enumerate() {
                p[k] = match ty {
                    SampleType::F16 => {
                        exr::prelude::f16::from_ne_bytes([bytes[2 * x], bytes[2 * x + 1]]).to_f32()
                    }
                    SampleType::F32 => {
                        f32::from_ne_bytes(bytes[4 * x..4 * x + 4].try_into().expect("4 bytes"))
                    }
                    SampleType::U32 => {
                        u32::from_ne_bytes(bytes[4 * x..4 * x + 4].try_into().expect("4 bytes"))
                            as f32
                    }
                };
            }
        }
    }
    Ok(())
}

/// Merge `parts` into `out` (`.exr` or `.png`). The EXR is 16-bit when `half` is set or every
/// part is 16-bit (so a merge of `--half` parts keeps their bits), else 32-bit.
pub fn merge(parts: &[PathBuf], out: &Path, mut opts: ExrOptions) -> Result<PixelBounds> {
    let mut readers = Vec::with_capacity(parts.len());
    for p in parts {
        let (header, decoder) = open(p)?;
        readers.push(PartReader {
            rows_y0: header.data.y0,
            header,
            decoder,
            rows: Vec::new(),
        });
    }
    let headers: Vec<PartHeader> = readers.iter().map(|r| r.header.clone()).collect();
    let display = check_coverage(&headers)?;
    opts.half |= headers.iter().all(|h| h.half);
    let w = display.width() as usize;
    let batch = (BATCH_BYTES / (w * std::mem::size_of::<Vec3>())).max(1) as u32;
    write_streamed(
        out,
        (display.x1, display.y1),
        display,
        opts,
        &mut |sink: &mut RowSink| {
            let mut rows = Vec::new();
            for ya in (0..display.y1).step_by(batch as usize) {
                let yb = (ya + batch).min(display.y1);
                rows.clear();
                rows.resize((yb - ya) as usize * w, Vec3::ZERO);
                for r in readers.iter_mut() {
                    let d = r.header.data;
                    let (y0, y1) = (ya.max(d.y0), yb.min(d.y1));
                    if y0 >= y1 {
                        continue;
                    }
                    r.fill_to(y1)?;
                    let pw = d.width() as usize;
                    for y in y0..y1 {
                        let src = (y - r.rows_y0) as usize * pw;
                        let dst = (y - ya) as usize * w + d.x0 as usize;
                        rows[dst..dst + pw].copy_from_slice(&r.rows[src..src + pw]);
                    }
                    r.discard_before(y1);
                }
                sink(ya, &rows)?;
            }
            Ok(())
        },
    )?;
    Ok(display)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(x0: u32, x1: u32, y0: u32, y1: u32) -> PixelBounds {
        PixelBounds { x0, x1, y0, y1 }
    }

    #[test]
    fn missing_ranges_are_found_and_joined_over_rows() {
        let d = b(0, 100, 0, 80);
        assert!(missing(d, [d].into_iter()).is_empty());
        assert_eq!(
            missing(d, [b(0, 100, 0, 20), b(0, 100, 40, 80)].into_iter()),
            [b(0, 100, 20, 40)]
        );
        // a hole in the middle, over rows split by another rectangle's edge
        let r = [
            b(0, 30, 0, 80),
            b(60, 100, 0, 50),
            b(60, 100, 50, 80),
            b(30, 60, 0, 10),
        ];
        assert_eq!(missing(d, r.into_iter()), [b(30, 60, 10, 80)]);
        assert_eq!(missing(d, std::iter::empty()), [d]);
    }
}
