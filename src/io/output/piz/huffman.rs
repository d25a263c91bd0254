//! The Huffman code of a PIZ block (OpenEXR's `hufCompress`): symbol frequencies, optimal
//! code lengths in place (Moffat and Katajainen, after a counting sort), canonical codes, the
//! code-length table and the code's bits.

use super::zeroed;

/// Symbols of the Huffman code: the 65536 values and the run-length symbol after the
/// largest value used.
const SYMBOLS: usize = 65537;
/// Code-length table: lengths 1 to 58, a run of 2 to 5 zero lengths as `59 + run - 2`, a
/// longer run (6 to 261) as 63 and `run - 6` in 8 bits.
const SHORT_ZERO_RUN: u64 = 59;
const LONG_ZERO_RUN: u64 = 63;
const SHORTEST_LONG_RUN: usize = 6;
const LONGEST_LONG_RUN: usize = 255 + SHORTEST_LONG_RUN;
/// The longest code OpenEXR's decoder takes.
const MAX_CODE_BITS: u32 = 58;

/// The Huffman coder's tables, of [`SYMBOLS`] entries each but `present` (one thread's,
/// reused from block to block).
pub(super) struct Tables {
    /// Frequencies (of the even words, while counting).
    freq: Box<[u32; SYMBOLS]>,
    /// Frequencies of the odd words, while counting.
    odd: Box<[u32; SYMBOLS]>,
    /// Code lengths (at most 58).
    lengths: Vec<u8>,
    /// `code << 6 | length`.
    codes: Vec<u64>,
    /// `codes` in 32 bits, when every code fits.
    shorts: Vec<u32>,
    /// The symbols that occur, relative to the first.
    present: Vec<u32>,
    /// The code-length construction's buffers.
    sort: Sorted,
}

/// The symbols that occur sorted by frequency, and the weights that become their code
/// lengths ([`code_lengths_of`]'s buffers, kept from block to block).
#[derive(Default)]
struct Sorted {
    order: Vec<u32>,
    weight: Vec<u32>,
    /// Symbols of frequency [`SMALL`] and more, sorted by comparison.
    large: Vec<(u32, u32)>,
}

impl Tables {
    pub(super) fn new() -> Self {
        Tables {
            freq: zeroed(),
            odd: zeroed(),
            lengths: vec![0; SYMBOLS],
            codes: vec![0; SYMBOLS],
            shorts: vec![0; SYMBOLS],
            present: Vec::new(),
            sort: Sorted::default(),
        }
    }
}

/// MSB-first bits into bytes, as OpenEXR's Huffman coder packs them. The bits not yet
/// whole bytes wait at the top of `acc`; every put stores all 8 bytes of `acc` at the end of
/// `out` and keeps the whole ones, so no branch depends on the data.
struct Bits<'a> {
    out: &'a mut Vec<u8>,
    /// Bytes of `out` written; `out` is 8 bytes longer (or more) while putting.
    len: usize,
    acc: u64,
    /// Bits at the top of `acc` (fewer than 8 between calls).
    n: u32,
}

impl<'a> Bits<'a> {
    fn new(out: &'a mut Vec<u8>) -> Self {
        let len = out.len();
        Bits {
            out,
            len,
            acc: 0,
            n: 0,
        }
    }

    /// The `bits` low bits of `value` (the bits above them zero).
    #[inline(always)]
    fn put(&mut self, bits: u32, value: u64) {
        debug_assert!(bits <= MAX_CODE_BITS && value >> bits == 0);
        if bits > 56 {
            self.put_long(bits, value);
            return;
        }
        if self.out.len() < self.len + 8 {
            self.out.resize(2 * self.len + 64, 0);
        }
        self.n += bits;
        self.acc |= value << (64 - self.n);
        self.out[self.len..self.len + 8].copy_from_slice(&self.acc.to_be_bytes());
        let whole = self.n & !7;
        self.len += (whole / 8) as usize;
        self.acc <<= whole;
        self.n -= whole;
    }

    #[cold]
    fn put_long(&mut self, bits: u32, value: u64) {
        self.put(bits - 32, value >> 32);
        self.put(32, value & 0xffff_ffff);
    }

    /// Pad the last byte with zeros and cut `out` to the bytes written; the bits written
    /// since `start` (a byte of `out`).
    fn finish(self, start: usize) -> usize {
        let bits = (self.len - start) * 8 + self.n as usize;
        let end = self.len + self.n.div_ceil(8) as usize;
        self.out.resize(end.max(self.len + 8), 0);
        self.out[self.len..self.len + 8].copy_from_slice(&self.acc.to_be_bytes());
        self.out.truncate(end);
        bits
    }
}

/// OpenEXR's Huffman coding of `data` (`hufCompress`), appended to `out`: five
/// little-endian u32 (the smallest and largest symbol in the table, the table's bytes, the
/// code's bits, 0), the code-length table, the code.
pub(super) fn huffman(data: &[u16], out: &mut Vec<u8>, tables: &mut Tables) {
    let Tables {
        freq,
        odd,
        lengths,
        codes,
        shorts,
        present,
        sort,
    } = tables;
    if data.is_empty() {
        return;
    }
    // two tables, even and odd words, so that a run of one symbol does not wait on its own
    // stores
    freq.fill(0);
    odd.fill(0);
    let pairs = data.chunks_exact(2);
    if let [last] = pairs.remainder() {
        freq[*last as usize] += 1;
    }
    for pair in pairs {
        freq[pair[0] as usize] += 1;
        odd[pair[1] as usize] += 1;
    }
    for (f, &o) in freq.iter_mut().zip(odd.iter()) {
        *f += o;
    }
    let lo = freq.iter().position(|&f| f != 0).unwrap_or(0);
    let hi = freq.iter().rposition(|&f| f != 0).unwrap_or(0);
    // the run-length symbol, after the largest value, counted once
    let rle = hi + 1;
    freq[rle] = 1;
    // the symbols that occur, relative to `lo`, and their codes
    present_symbols(&freq[lo..=rle], present);
    code_lengths_of(&freq[lo..=rle], present, &mut lengths[lo..=rle], sort);
    let lengths = &lengths[lo..=rle];
    let longest = present.iter().map(|&s| lengths[s as usize]).max();
    let longest = longest.unwrap_or(0) as u32;

    let header = out.len();
    out.extend_from_slice(&[0; 20]);
    let table = out.len();
    pack_lengths(present, lengths, rle + 1 - lo, out);
    let table_bytes = out.len() - table;
    let code_start = out.len();
    let nbits = if longest <= SHORT_CODE_BITS {
        // half the table's bytes in the cache: codes and lengths packed in 32 bits
        canonical(present, lengths, &mut shorts[lo..=rle]);
        // as many codes to a put as surely fit in its 56 bits
        match longest {
            0..=14 => emit::<u32, 4>(data, shorts, rle, out, code_start),
            15..=18 => emit::<u32, 3>(data, shorts, rle, out, code_start),
            _ => emit::<u32, 2>(data, shorts, rle, out, code_start),
        }
    } else {
        canonical(present, lengths, &mut codes[lo..=rle]);
        emit::<u64, 1>(data, codes, rle, out, code_start)
    };
    for (k, v) in [lo, rle, table_bytes, nbits, 0].into_iter().enumerate() {
        out[header + 4 * k..header + 4 * k + 4].copy_from_slice(&(v as u32).to_le_bytes());
    }
}

/// Codes of at most this many bits pack with their length into 32 bits.
const SHORT_CODE_BITS: u32 = 26;

/// A symbol's code and its length packed as `code << 6 | length`.
pub(super) trait Packed: Copy {
    fn unpack(self) -> (u64, u32);
    /// `code << 6 | length` (the code fits).
    fn pack(code: u64, length: u32) -> Self;
}

impl Packed for u64 {
    #[inline(always)]
    fn unpack(self) -> (u64, u32) {
        (self >> 6, (self & 63) as u32)
    }
    #[inline(always)]
    fn pack(code: u64, length: u32) -> Self {
        code << 6 | length as u64
    }
}

impl Packed for u32 {
    #[inline(always)]
    fn unpack(self) -> (u64, u32) {
        ((self >> 6) as u64, self & 63)
    }
    #[inline(always)]
    fn pack(code: u64, length: u32) -> Self {
        (code << 6) as u32 | length
    }
}

/// The code of `data` appended to `out`, runs of a symbol shortened with the run-length
/// symbol `rle` where that is shorter; the bits written. Where no run can start, `PER`
/// codes go in one put (the caller picks the most whose lengths surely fit in 56 bits): the
/// bits are the same for every `PER`.
#[inline(never)]
pub(super) fn emit<C: Packed, const PER: usize>(
    data: &[u16],
    codes: &[C],
    rle: usize,
    out: &mut Vec<u8>,
    start: usize,
) -> usize {
    let mut bits = Bits::new(out);
    let (rcode, rlen) = codes[rle].unpack();
    // symbols looked at together: a multiple of PER
    let chunk = 16 - 16 % PER;
    let n = data.len();
    let mut i = 0;
    while i < n {
        // `chunk` symbols none of which equals the next: no run to look for
        if let Some(run) = data.get(i..i + chunk + 1) {
            let (a, b) = (&run[..chunk], &run[1..]);
            if a.iter().zip(b).all(|(x, y)| x != y) {
                for group in a.chunks_exact(PER) {
                    let (mut c, mut l) = (0, 0);
                    for &s in group {
                        let (code, len) = codes[s as usize].unpack();
                        c = c << len | code;
                        l += len;
                    }
                    bits.put(l, c);
                }
                i += chunk;
                continue;
            }
        }
        let s = data[i];
        let (code, len) = codes[s as usize].unpack();
        // a run of at most 256 copies: the symbol, then the run-length symbol and the
        // repeats in 8 bits where that is shorter
        let end = (i + 256).min(n);
        let mut j = i + 1;
        while j < end && data[j] == s {
            j += 1;
        }
        let run = (j - i - 1) as u32;
        if run == 0 {
            bits.put(len, code);
        } else if len + rlen + 8 < len * run {
            bits.put(len, code);
            bits.put(rlen, rcode);
            bits.put(8, run as u64);
        } else {
            for _ in 0..=run {
                bits.put(len, code);
            }
        }
        i = j;
    }
    bits.finish(start)
}

/// Optimal code lengths (into `lengths`) for the symbols of frequencies `freq` (0 for those
/// that do not occur): the symbols that occur sorted by frequency (a counting sort for the
/// many rare ones), then Moffat and Katajainen's in-place construction over the sorted
/// weights.
#[cfg(test)]
pub(super) fn code_lengths(freq: &[u32], lengths: &mut [u32]) {
    let mut present = Vec::new();
    present_symbols(freq, &mut present);
    let mut short = vec![0u8; lengths.len()];
    code_lengths_of(freq, &present, &mut short, &mut Sorted::default());
    for (l, &s) in lengths.iter_mut().zip(&short) {
        *l = s as u32;
    }
    debug_assert!(lengths.iter().all(|&l| l <= MAX_CODE_BITS));
}

/// The symbols of nonzero frequency in `freq`, in order, into `present` (gathered without a
/// branch).
fn present_symbols(freq: &[u32], present: &mut Vec<u32>) {
    present.clear();
    present.resize(freq.len(), 0);
    let mut k = 0;
    for (s, &f) in freq.iter().enumerate() {
        present[k] = s as u32;
        k += (f != 0) as usize;
    }
    present.truncate(k);
}

/// [`code_lengths`] given the symbols that occur (`present`, in order): their lengths are
/// written, the other entries of `lengths` left as they are.
fn code_lengths_of(freq: &[u32], present: &[u32], lengths: &mut [u8], sort: &mut Sorted) {
    // counting sort of them by frequency, frequencies below `SMALL` by bucket
    let mut count = [0u32; SMALL + 1];
    let Sorted {
        order,
        weight,
        large,
    } = sort;
    large.clear();
    for &s in present {
        let f = freq[s as usize];
        if f as usize >= SMALL {
            large.push((f, s));
        } else {
            count[f as usize] += 1;
        }
    }
    large.sort_unstable();
    let mut start = 0u32;
    for c in count.iter_mut() {
        let n = *c;
        *c = start;
        start += n;
    }
    let n = present.len();
    order.resize(n, 0);
    weight.resize(n, 0);
    for &s in present {
        let f = freq[s as usize];
        if (f as usize) < SMALL {
            let at = count[f as usize] as usize;
            count[f as usize] += 1;
            order[at] = s;
            weight[at] = f;
        }
    }
    for (k, &(f, s)) in large.iter().enumerate() {
        order[start as usize + k] = s;
        weight[start as usize + k] = f;
    }
    minimum_redundancy(&mut weight[..n]);
    for (&s, &l) in order[..n].iter().zip(&weight[..n]) {
        lengths[s as usize] = l as u8;
    }
}

/// Frequencies below this are sorted by counting, the rest by comparison.
const SMALL: usize = 1024;

/// Moffat and Katajainen's in-place minimum-redundancy code ("In-place calculation of
/// minimum-redundancy codes", 1995): `a` holds weights in increasing order and is left
/// holding each one's code length. Three passes: pair the two lightest of leaves and
/// internal nodes, recording parents; depths of the internal nodes from the root down;
/// leaf depths from the counts of internal nodes per level.
fn minimum_redundancy(a: &mut [u32]) {
    let n = a.len();
    match n {
        0 => return,
        1 => {
            a[0] = 1;
            return;
        }
        _ => {}
    }
    a[0] += a[1];
    let (mut root, mut leaf) = (0usize, 2usize);
    for next in 1..n - 1 {
        // the first of the pair
        if leaf >= n || a[root] < a[leaf] {
            a[next] = a[root];
            a[root] = next as u32;
            root += 1;
        } else {
            a[next] = a[leaf];
            leaf += 1;
        }
        // the second
        if leaf >= n || (root < next && a[root] < a[leaf]) {
            a[next] += a[root];
            a[root] = next as u32;
            root += 1;
        } else {
            a[next] += a[leaf];
            leaf += 1;
        }
    }
    a[n - 2] = 0;
    for next in (0..n - 2).rev() {
        a[next] = a[a[next] as usize] + 1;
    }
    let (mut avail, mut used, mut depth) = (1usize, 0usize, 0u32);
    let mut root = n as isize - 2;
    let mut next = n as isize - 1;
    while avail > 0 {
        while root >= 0 && a[root as usize] == depth {
            used += 1;
            root -= 1;
        }
        while avail > used {
            a[next as usize] = depth;
            next -= 1;
            avail -= 1;
        }
        avail = 2 * used;
        depth += 1;
        used = 0;
    }
}

/// The canonical codes for `lengths`, as OpenEXR assigns them from the lengths alone
/// (`hufCanonicalCodeTable`: per length, consecutive codes in symbol order, longer codes
/// below shorter ones): `code << 6 | length` into `codes` for each symbol of `present` (the
/// symbols of nonzero length, in order; the other entries are left as they are).
fn canonical<C: Packed>(present: &[u32], lengths: &[u8], codes: &mut [C]) {
    let mut first = [0u64; 59];
    for &s in present {
        first[lengths[s as usize] as usize] += 1;
    }
    let mut c = 0u64;
    for l in (1..=58).rev() {
        let next = (c + first[l]) >> 1;
        first[l] = c;
        c = next;
    }
    for &s in present {
        let l = lengths[s as usize];
        let code = first[l as usize];
        first[l as usize] += 1;
        codes[s as usize] = C::pack(code, l as u32);
    }
}

/// The code-length table (`hufPackEncTable`) of `n` symbols: 6 bits per length, zero runs
/// shortened; `present` lists the symbols of nonzero length, in order (the others' are 0).
fn pack_lengths(present: &[u32], lengths: &[u8], n: usize, out: &mut Vec<u8>) {
    let mut bits = Bits::new(out);
    let mut next = 0;
    for &s in present {
        let s = s as usize;
        let (gap_bits, gap_code) = zero_run(&mut bits, s - next);
        // the gap's code and the length in one put
        bits.put(gap_bits + 6, gap_code << 6 | lengths[s] as u64);
        next = s + 1;
    }
    let (gap_bits, gap_code) = zero_run(&mut bits, n - next);
    bits.put(gap_bits, gap_code);
    bits.finish(0);
}

/// A run of `gap` zero lengths: the longest runs put at once while more than
/// [`LONGEST_LONG_RUN`] are left, then the rest's code as `(bits, code)` from [`ZERO_RUNS`].
#[inline(always)]
fn zero_run(bits: &mut Bits, mut gap: usize) -> (u32, u64) {
    while gap > LONGEST_LONG_RUN {
        bits.put(
            14,
            LONG_ZERO_RUN << 8 | (LONGEST_LONG_RUN - SHORTEST_LONG_RUN) as u64,
        );
        gap -= LONGEST_LONG_RUN;
    }
    let (b, c) = ZERO_RUNS[gap];
    (b as u32, c as u64)
}

/// The code of each run of 0 to [`LONGEST_LONG_RUN`] zero lengths as `(bits, code)`: none,
/// one length 0, a short run, or the long-run code and the run in 8 bits.
const ZERO_RUNS: [(u8, u16); LONGEST_LONG_RUN + 1] = {
    let mut t = [(0u8, 0u16); LONGEST_LONG_RUN + 1];
    let mut run = 1;
    while run <= LONGEST_LONG_RUN {
        t[run] = if run >= SHORTEST_LONG_RUN {
            (
                14,
                (LONG_ZERO_RUN << 8) as u16 | (run - SHORTEST_LONG_RUN) as u16,
            )
        } else if run >= 2 {
            (6, (SHORT_ZERO_RUN + run as u64 - 2) as u16)
        } else {
            (6, 0)
        };
        run += 1;
    }
    t
};
