use super::*;
use exr::compression::Compression;
use exr::meta::attribute::{ChannelDescription, IntegerBounds, LineOrder, SampleType};
use exr::meta::{BlockDescription, header::Header};
use proptest::prelude::*;

/// Channel types by 16-bit words per sample.
fn sample_type(words: usize, k: usize) -> SampleType {
    match (words, k % 2) {
        (1, _) => SampleType::F16,
        (_, 0) => SampleType::F32,
        _ => SampleType::U32,
    }
}

/// `block` decoded by the exr crate's PIZ decoder (a header of channels `A`, `B`, ... with
/// `words` words per sample).
fn exr_decode(block: Vec<u8>, width: usize, lines: usize, words: &[usize]) -> Vec<u8> {
    let channels = words
        .iter()
        .enumerate()
        .map(|(k, &w)| {
            let name = ((b'A' + k as u8) as char).to_string();
            ChannelDescription::named(name.as_str(), sample_type(w, k))
        })
        .collect();
    let header = Header::new("t".into(), (width, lines), channels).with_encoding(
        Compression::PIZ,
        BlockDescription::ScanLines,
        LineOrder::Increasing,
    );
    Compression::PIZ
        .decompress_image_section_from_le(
            &header,
            block,
            IntegerBounds::new((0, 0), (width, lines)),
            true,
        )
        .expect("the exr crate decodes the block")
}

/// Samples: `pattern` 0 all zero, 1 one value, 2 a ramp of runs, 3 noise.
fn samples(n_words: usize, pattern: u8, seed: u64) -> Vec<u8> {
    let mut s = seed | 1;
    let mut next = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        s
    };
    let mut out = Vec::with_capacity(2 * n_words);
    for i in 0..n_words / 2 {
        let v: u32 = match pattern {
            0 => 0,
            1 => 0x3f40_0000,
            2 => (0.25 + (i / 16) as f32 / 1024.0).to_bits(),
            _ => next() as u32,
        };
        out.extend_from_slice(&v.to_le_bytes());
    }
    if n_words % 2 == 1 {
        out.extend_from_slice(&(next() as u16).to_le_bytes());
    }
    out
}

fn round_trip(width: usize, lines: usize, words: &[usize], pattern: u8, seed: u64) {
    let n = words.iter().sum::<usize>() * width * lines;
    let raw = samples(n, pattern, seed);
    let block = piz_block(&raw, width, lines, words);
    assert!(block.len() <= raw.len());
    let back = exr_decode(block, width, lines, words);
    assert!(back == raw, "{width}x{lines} {words:?} pattern {pattern}");
}

#[test]
fn blocks_decode_to_their_samples() {
    for words in [&[2usize, 2, 2][..], &[1, 1, 1], &[2, 1, 2, 2], &[1]] {
        for (width, lines) in [
            (1, 1),
            (2, 2),
            (3, 32),
            (17, 5),
            (64, 32),
            (333, 31),
            (1920, 32),
        ] {
            for pattern in 0..4 {
                round_trip(width, lines, words, pattern, 7 + width as u64);
            }
        }
    }
}

/// Blocks of a ramp and of noise (values below 2^14 after the table, and above it): within a
/// few bytes of the exr crate's own PIZ blocks, the ramp's less than half its samples.
#[test]
fn rendered_blocks_compress_like_the_exr_crates() {
    for (pattern, words) in [(2u8, [2usize, 2, 2]), (2, [1, 1, 1]), (3, [1, 1, 1])] {
        let (width, lines) = (640, 32);
        let n = words.iter().sum::<usize>() * width * lines;
        let raw = samples(n, pattern, 99);
        let ours = piz_block(&raw, width, lines, &words);
        let channels = words
            .iter()
            .enumerate()
            .map(|(k, &w)| {
                let name = ((b'A' + k as u8) as char).to_string();
                ChannelDescription::named(name.as_str(), sample_type(w, 0))
            })
            .collect();
        let header = Header::new("t".into(), (width, lines), channels).with_encoding(
            Compression::PIZ,
            BlockDescription::ScanLines,
            LineOrder::Increasing,
        );
        let theirs = Compression::PIZ
            .compress_image_section_to_le(
                &header,
                raw.clone(),
                IntegerBounds::new((0, 0), (width, lines)),
            )
            .expect("the exr crate compresses");
        assert!(
            ours.len() as f64 <= theirs.len() as f64 * 1.002 + 16.0,
            "{} against {}",
            ours.len(),
            theirs.len()
        );
        if pattern == 2 {
            assert!(
                ours.len() < raw.len() / 2,
                "{} of {}",
                ours.len(),
                raw.len()
            );
        }
        assert!(exr_decode(ours, width, lines, &words) == raw);
    }
}

/// The in-place construction gives a complete prefix code (Kraft sum 1) of the same total
/// cost as a textbook Huffman tree built with a heap.
#[test]
fn code_lengths_are_optimal() {
    let heap_cost = |w: &[u64]| {
        let mut h: std::collections::BinaryHeap<std::cmp::Reverse<u64>> =
            w.iter().map(|&x| std::cmp::Reverse(x)).collect();
        let mut cost = 0;
        while h.len() > 1 {
            let a = h.pop().unwrap().0;
            let b = h.pop().unwrap().0;
            cost += a + b;
            h.push(std::cmp::Reverse(a + b));
        }
        cost
    };
    let mut s = 12345u64;
    for n in [2usize, 3, 5, 100, 4000] {
        for spread in [1u64, 10, 3000, 1 << 20] {
            let freq: Vec<u32> = (0..n)
                .map(|_| {
                    s = s
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    ((s >> 33) % spread) as u32 + 1
                })
                .collect();
            let mut lengths = vec![9; n];
            code_lengths(&freq, &mut lengths);
            let kraft: f64 = lengths.iter().map(|&l| 0.5f64.powi(l as i32)).sum();
            assert!((kraft - 1.0).abs() < 1e-9, "{n} {spread}: {kraft}");
            let cost: u64 = freq
                .iter()
                .zip(&lengths)
                .map(|(&f, &l)| f as u64 * l as u64)
                .sum();
            let w: Vec<u64> = freq.iter().map(|&f| f as u64).collect();
            assert_eq!(cost, heap_cost(&w), "{n} {spread}");
        }
    }
    // symbols that do not occur get no code
    let mut lengths = [7; 5];
    code_lengths(&[0, 5, 0, 5, 0], &mut lengths);
    assert_eq!(lengths, [0, 1, 0, 1, 0]);
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// Any samples of any shape come back bit for bit.
    #[test]
    fn any_block_round_trips(
        width in 1usize..70,
        lines in 1usize..33,
        words in proptest::collection::vec(1usize..3, 1..5),
        pattern in 0u8..4,
        seed in any::<u64>(),
    ) {
        round_trip(width, lines, &words, pattern, seed);
    }
}

/// The encoder's time on the 32-line blocks of a rendered image, best of 9 passes (a
/// measurement, not a test): `whitted render phong --width 1920 --height 1080
/// --exr-compression none -o /tmp/phong.exr`, then `WHITTED_PIZ_IMAGE=/tmp/phong.exr cargo
/// test --release --lib piz_encoder_time -- --ignored --nocapture`.
#[test]
#[ignore]
fn piz_encoder_time() {
    let Ok(path) = std::env::var("WHITTED_PIZ_IMAGE") else {
        eprintln!("WHITTED_PIZ_IMAGE not set");
        return;
    };
    let image = crate::io::image::load_exr_image(std::path::Path::new(&path)).expect("an EXR");
    let (width, lines) = (image.width, 32);
    // each block's lines, each line's channels B, G, R (the file's order), f32 samples
    let blocks: Vec<Vec<u8>> = image
        .pixels
        .chunks(width * lines)
        .map(|rows| {
            let mut raw = Vec::with_capacity(rows.len() * 12);
            for row in rows.chunks(width) {
                for c in [2, 1, 0] {
                    for p in row {
                        raw.extend_from_slice(&p[c].to_le_bytes());
                    }
                }
            }
            raw
        })
        .collect();
    let mut best = f64::INFINITY;
    let mut bytes = 0;
    for _ in 0..9 {
        let start = std::time::Instant::now();
        bytes = blocks
            .iter()
            .map(|raw| piz_block(raw, width, raw.len() / (12 * width), &[2, 2, 2]).len())
            .sum::<usize>();
        best = best.min(start.elapsed().as_secs_f64());
    }
    eprintln!(
        "{path}: {} blocks, {bytes} bytes, best of 9 {:.2} ms",
        blocks.len(),
        best * 1e3
    );
}

/// Codes put two, three or four at a time make the same bits as one at a time.
#[test]
fn codes_grouped_in_puts_make_the_same_bits() {
    let mut rng = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        rng
    };
    // 300 symbols and the run-length symbol, lengths 1 to 14 (not a prefix code: the bits
    // are compared, not decoded)
    let rle = 300;
    let longs: Vec<u64> = (0..=rle)
        .map(|_| {
            let len = 1 + next() % 14;
            (next() & ((1 << len) - 1)) << 6 | len
        })
        .collect();
    let shorts: Vec<u32> = longs.iter().map(|&c| c as u32).collect();
    // noise with runs of every length up to 300 between
    let mut data = Vec::new();
    while data.len() < 20_000 {
        let s = (next() % rle as u64) as u16;
        let repeat = if next() % 4 == 0 { next() % 300 } else { 0 };
        data.extend(std::iter::repeat_n(s, 1 + repeat as usize));
    }
    let mut one = vec![7u8];
    let bits = emit::<u64, 1>(&data, &longs, rle, &mut one, 1);
    for per in [2, 3, 4] {
        let mut out = vec![7u8];
        let b = match per {
            2 => emit::<u32, 2>(&data, &shorts, rle, &mut out, 1),
            3 => emit::<u32, 3>(&data, &shorts, rle, &mut out, 1),
            _ => emit::<u32, 4>(&data, &shorts, rle, &mut out, 1),
        };
        assert_eq!((b, &out), (bits, &one), "{per} codes a put");
    }
}
