//! OpenEXR's PIZ compression of one block of scan lines, written for speed.
//!
//! The format (OpenEXR's `ImfPizCompressor`, which every reader decodes): the block's 16-bit
//! words gathered channel by channel; a bitmap of the values that occur, and each word
//! replaced by its rank among them (so the values span `0..=max`); per channel and per word
//! of a sample, a 2D Haar wavelet over the block (14-bit lifting when `max < 2^14`, else
//! modular 16-bit); then one Huffman code over all the words, with a run-length symbol. What
//! the format leaves to the encoder is the Huffman code itself: any prefix code of at most 58
//! bits per symbol decodes, and this one builds an optimal code in place over the symbols
//! sorted by frequency (Moffat and Katajainen's algorithm, after a counting sort), where the
//! exr crate's encoder pushes every symbol through a binary heap. The bytes need not equal
//! another encoder's; what a reader gets back must equal the block, bit for bit (tested
//! against the exr crate's decoder here and OpenEXR's own in `tests/openexr.rs`).

mod huffman;

use huffman::{Tables, huffman};
#[cfg(test)]
use huffman::{code_lengths, emit};

/// Bytes of the bitmap of 16-bit values.
const BITMAP_BYTES: usize = 65536 / 8;

/// Buffers one thread's blocks reuse (a 4K block would otherwise allocate and clear about
/// 2 MB of tables).
struct Scratch {
    data: Vec<u16>,
    /// Each value's rank (an array, so that a `u16` index needs no bounds check).
    lut: Box<[u16; 65536]>,
    seen: Box<[u8; 65536]>,
    huffman: Tables,
}

/// A zeroed array on the heap (not through the stack).
pub(super) fn zeroed<T: Clone + Default, const N: usize>() -> Box<[T; N]> {
    vec![T::default(); N]
        .into_boxed_slice()
        .try_into()
        .unwrap_or_else(|_| unreachable!("N entries"))
}

thread_local! {
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch {
        data: Vec::new(),
        lut: zeroed(),
        seen: zeroed(),
        huffman: Tables::new(),
    });
}

/// A PIZ block of `lines` scan lines of `width` pixels: `raw` holds, line by line, each
/// channel's samples (little-endian), and `words[c]` is channel `c`'s 16-bit words per
/// sample (1 for half, 2 for f32 and u32). A block that would not shrink is stored raw, as
/// OpenEXR does.
///
/// # Panics
/// If `raw` is not `lines * width * 2 * sum(words)` bytes, or a channel has other than 1 or
/// 2 words per sample.
pub fn piz_block(raw: &[u8], width: usize, lines: usize, words: &[usize]) -> Vec<u8> {
    let per_line: usize = words.iter().sum::<usize>() * width;
    assert_eq!(raw.len(), 2 * per_line * lines, "a whole block of samples");
    assert!(
        words.iter().all(|&w| w == 1 || w == 2),
        "1 or 2 words per sample"
    );
    if raw.is_empty() {
        return Vec::new();
    }
    SCRATCH.with_borrow_mut(|s| encode(raw, width, lines, words, s))
}

fn encode(raw: &[u8], width: usize, lines: usize, words: &[usize], s: &mut Scratch) -> Vec<u8> {
    // the words, channel by channel (each channel's lines one after another), and the
    // bitmap of the values that occur
    // every word is written below: the last block's buffer is reused as it is (clearing it
    // was a 737 KB memset per 4K block)
    let data = &mut s.data;
    data.resize(raw.len() / 2, 0);
    let mut bitmap = [0u8; BITMAP_BYTES];
    // which values occur, a byte each (a store per word where the bitmap would load too)
    let seen = &mut *s.seen;
    seen.fill(0);
    let starts: Vec<usize> = words
        .iter()
        .scan(0, |at, &w| {
            let s = *at;
            *at += w * width * lines;
            Some(s)
        })
        .collect();
    let mut line_at = 0;
    for y in 0..lines {
        for (&w, &start) in words.iter().zip(&starts) {
            let n = w * width;
            let dst = &mut data[start + y * n..start + (y + 1) * n];
            let src = &raw[2 * line_at..2 * (line_at + n)];
            for (d, b) in dst.iter_mut().zip(src.chunks_exact(2)) {
                let v = u16::from_le_bytes([b[0], b[1]]);
                seen[v as usize] = 1;
                *d = v;
            }
            line_at += n;
        }
    }
    for (byte, seen) in bitmap.iter_mut().zip(seen.chunks_exact(8)) {
        *byte = seen.iter().enumerate().fold(0, |b, (i, &s)| b | s << i);
    }
    // zero is always taken to occur, and not stored
    bitmap[0] &= !1;
    let used = bitmap.iter().position(|&b| b != 0);
    let (min_nz, max_nz) = match used {
        Some(lo) => (lo, bitmap.iter().rposition(|&b| b != 0).unwrap_or(lo)),
        None => (BITMAP_BYTES - 1, 0),
    };
    // each value's rank among those that occur (zero's is 0; the entries of values that do
    // not occur are stale and never read)
    let lut = &mut *s.lut;
    lut[0] = 0;
    let mut rank = 1u32;
    for (byte, &bits) in bitmap.iter().enumerate().skip(min_nz) {
        let mut bits = bits;
        while bits != 0 {
            let i = byte * 8 + bits.trailing_zeros() as usize;
            lut[i] = rank as u16;
            rank += 1;
            bits &= bits - 1;
        }
    }
    let max_value = rank - 1;
    for d in data.iter_mut() {
        *d = lut[*d as usize];
    }
    for (&w, &start) in words.iter().zip(&starts) {
        let plane = &mut data[start..start + w * width * lines];
        match (w, max_value < 1 << 14) {
            (1, true) => wavelet::<true, 1>(plane, width, lines),
            (1, false) => wavelet::<false, 1>(plane, width, lines),
            (_, true) => wavelet::<true, 2>(plane, width, lines),
            (_, false) => wavelet::<false, 2>(plane, width, lines),
        }
    }

    let mut out = Vec::with_capacity(raw.len() / 2);
    out.extend_from_slice(&(min_nz as u16).to_le_bytes());
    out.extend_from_slice(&(max_nz as u16).to_le_bytes());
    if min_nz <= max_nz {
        out.extend_from_slice(&bitmap[min_nz..=max_nz]);
    }
    let length_at = out.len();
    out.extend_from_slice(&[0; 4]);
    huffman(data, &mut out, &mut s.huffman);
    let length = (out.len() - length_at - 4) as u32;
    out[length_at..length_at + 4].copy_from_slice(&length.to_le_bytes());
    if out.len() >= raw.len() {
        return raw.to_vec();
    }
    out
}

/// OpenEXR's 14-bit Haar step: the mean and the difference, as signed 16-bit values.
#[inline(always)]
fn enc14(a: u16, b: u16) -> (u16, u16) {
    let (a, b) = (a as i16 as i32, b as i16 as i32);
    (((a + b) >> 1) as u16, (a - b) as u16)
}

/// OpenEXR's modular 16-bit Haar step (values of the full 16 bits), without its branch: a
/// negative difference moves the mean by 2^15, modulo 2^16, which flips its top bit.
#[inline(always)]
fn enc16(a: u16, b: u16) -> (u16, u16) {
    let ao = (a as i32 + 0x8000) & 0xffff;
    let b = b as i32;
    let d = ao - b;
    let m = ((ao + b) >> 1) ^ ((d >> 31) & 0x8000);
    (m as u16, d as u16)
}

/// One 2x2 square of the wavelet, `[top left, top right, bottom left, bottom right]`: the
/// Haar step along the rows, then down the columns.
#[inline(always)]
fn square(enc: fn(u16, u16) -> (u16, u16), [a, b, c, d]: [u16; 4]) -> [u16; 4] {
    let (i00, i01) = enc(a, b);
    let (i10, i11) = enc(c, d);
    let ((m0, d0), (m1, d1)) = (enc(i00, i10), enc(i01, i11));
    [m0, m1, d0, d1]
}

/// Words the wavelet's first level takes at a time.
const LANES: usize = 16;

/// OpenEXR's 2D wavelet encoding (`wav2Encode`) in place, over a plane of `nx` by `ny`
/// samples of `W` words each (each word its own wavelet, as OpenEXR runs one per word
/// offset); `W14` when every value is below 2^14.
fn wavelet<const W14: bool, const W: usize>(d: &mut [u16], nx: usize, ny: usize) {
    let enc = if W14 { enc14 } else { enc16 };
    let row = nx * W;
    let n = nx.min(ny);
    let mut p = 1;
    while 2 * p <= n {
        let p2 = 2 * p;
        // the columns of 2x2 squares, as OpenEXR's pointer loops (`nx - p2` inclusive)
        let squares = (nx - p2) / p2 + 1;
        let odd_column = nx & p != 0;
        let mut y = 0;
        while y + p2 <= ny {
            let (top, bottom) = d[y * row..].split_at_mut(p * row);
            let (top, bottom) = (&mut top[..row], &mut bottom[..row]);
            if p == 1 {
                // 16 words of each corner at a time, in arrays the compiler vectorizes
                let group = 2 * LANES;
                let grouped = squares * W / LANES;
                for (t, b) in top
                    .chunks_exact_mut(group)
                    .zip(bottom.chunks_exact_mut(group))
                    .take(grouped)
                {
                    let corner = |row: &[u16], right: usize| -> [u16; LANES] {
                        std::array::from_fn(|j| row[(j / W) * 2 * W + right * W + j % W])
                    };
                    let (mut a, mut b1) = (corner(t, 0), corner(t, 1));
                    let (mut c, mut d) = (corner(b, 0), corner(b, 1));
                    for j in 0..LANES {
                        [a[j], b1[j], c[j], d[j]] = square(enc, [a[j], b1[j], c[j], d[j]]);
                    }
                    for j in 0..LANES {
                        let at = (j / W) * 2 * W + j % W;
                        (t[at], t[at + W]) = (a[j], b1[j]);
                        (b[at], b[at + W]) = (c[j], d[j]);
                    }
                }
                let rest = grouped * group;
                for (t, b) in top[rest..]
                    .chunks_exact_mut(2 * W)
                    .zip(bottom[rest..].chunks_exact_mut(2 * W))
                    .take(squares - grouped * LANES / W)
                {
                    for k in 0..W {
                        [t[k], t[W + k], b[k], b[W + k]] =
                            square(enc, [t[k], t[W + k], b[k], b[W + k]]);
                    }
                }
            } else {
                for x in (0..squares).map(|i| i * p2 * W) {
                    for k in x..x + W {
                        let k1 = k + p * W;
                        [top[k], top[k1], bottom[k], bottom[k1]] =
                            square(enc, [top[k], top[k1], bottom[k], bottom[k1]]);
                    }
                }
            }
            if odd_column {
                for k in squares * p2 * W..squares * p2 * W + W {
                    (top[k], bottom[k]) = enc(top[k], bottom[k]);
                }
            }
            y += p2;
        }
        // an odd line
        if ny & p != 0 {
            let line = &mut d[y * row..(y + 1) * row];
            for x in (0..squares).map(|i| i * p2 * W) {
                for k in x..x + W {
                    let k1 = k + p * W;
                    (line[k], line[k1]) = enc(line[k], line[k1]);
                }
            }
        }
        p = p2;
    }
}

#[cfg(test)]
#[path = "piz_tests.rs"]
mod tests;
