//! The engines, one list for `trace`, `bench` and `render`, and `auto`'s choice among them
//! from what a batch of rays is.
//!
//! Every engine returns the same hits bit for bit (`intersect1`'s); they differ in how many
//! rays go down which tree together. `auto` looks at the batch before tracing it
//! ([`choices`]): how far apart the directions and the origins of neighbouring rays are, over
//! a sample of the 16-ray groups the packet engines would form ([`spread`]). Which engine
//! wins for which kind of batch is a measurement (`docs/engines.md`); the rule follows it:
//!
//! | the batch's 16-ray groups | candidates (AVX-512) | candidates (without) |
//! |---|---|---|
//! | one octant, directions within a few degrees (camera, shadow rays to a point light) | `packet16`, `hybrid16` | `hybrid8`, `wide1` |
//! | directions apart, origins close together (bounces off neighbouring hits) | `hybrid16`, `wide1` | `hybrid8`, `wide1` |
//! | directions and origins apart (random rays, lidar, inside/outside tests) | `wide1` | `wide1` |
//!
//! Where two engines are candidates, which is faster depends on the mesh as well (how soon
//! a packet's lanes part), so a batch of at least [`PILOT_MIN`] rays settles it by a pilot
//! ([`pilot`]): runs of 512 rays covering one ray in 512 (at least 8 runs), spread over the
//! batch, each traced by both into the batch's output, the first 192 rays of a run untimed;
//! the rest of the batch is then traced by the one with the smaller total ([`left_over`]: the
//! pilot's results stand, as every engine's are `intersect1`'s; the pilot's cost is the
//! second trace of its rays, 0.2% of a large batch, 2.0% of the bench's 201,702-ray sets,
//! 3.1% at [`PILOT_MIN`]). Smaller batches (and the renderer's tile-sized queues) take the
//! first candidate.

use crate::accel::Accel;
use crate::ray::Ray;

/// Which traversal traces a batch. Every engine returns the same hits bit for bit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Engine {
    /// Chosen per batch from the rays ([`choose`]); in the renderer per queue.
    #[default]
    Auto,
    /// `intersect1` / `occluded1` ray by ray over the binary tree (the reference).
    Scalar,
    /// `intersect8` / `occluded8`: packets of 8 consecutive rays over the binary tree.
    Packet,
    /// `intersect_wide1` / `occluded_wide1`: ray by ray over the 8-wide tree.
    Wide,
    /// `intersect_hybrid8` / `occluded_hybrid8`: packets of 8 over the binary tree that hand
    /// their last few lanes to single-ray traversal of the 8-wide tree.
    Hybrid,
    /// `intersect16` / `occluded16`: packets of 16 over the binary tree (AVX-512; two
    /// `packet8` calls on a CPU without it).
    Packet16,
    /// `intersect_hybrid16` / `occluded_hybrid16`: 16-ray packets down the 8-wide tree
    /// together (any hit, and closest hit when the lanes share an octant), else down the
    /// binary tree, each lane alone once few remain (AVX-512; two `hybrid8` calls without).
    Hybrid16,
}

impl Engine {
    /// Every engine: the ones that trace, the reference first, then `auto` (the bench's
    /// report order).
    pub const ALL: [Engine; 7] = [
        Engine::Scalar,
        Engine::Packet,
        Engine::Wide,
        Engine::Hybrid,
        Engine::Packet16,
        Engine::Hybrid16,
        Engine::Auto,
    ];

    /// The engines that trace: [`Engine::ALL`] without `auto`.
    pub const CONCRETE: [Engine; 6] = {
        let mut c = [Engine::Scalar; 6];
        let mut i = 0;
        while i < c.len() {
            c[i] = Engine::ALL[i];
            i += 1;
        }
        c
    };

    /// The engine's name (`--engine`, tables, JSON).
    pub fn name(self) -> &'static str {
        match self {
            Engine::Auto => "auto",
            Engine::Scalar => "scalar",
            Engine::Packet => "packet8",
            Engine::Wide => "wide1",
            Engine::Hybrid => "hybrid8",
            Engine::Packet16 => "packet16",
            Engine::Hybrid16 => "hybrid16",
        }
    }

    /// The engine called `name`: its [`name`](Engine::name), or `packet`, `wide`, `hybrid`
    /// for the 8-ray and single-ray engines.
    pub fn from_name(name: &str) -> Option<Engine> {
        match name {
            "packet" => Some(Engine::Packet),
            "wide" => Some(Engine::Wide),
            "hybrid" => Some(Engine::Hybrid),
            _ => Engine::ALL.into_iter().find(|e| e.name() == name),
        }
    }

    /// Packet engines are compared with Embree's 8- and 16-wide packets, single-ray ones
    /// with its single rays (`auto` with both).
    pub fn packet(self) -> bool {
        !matches!(self, Engine::Scalar | Engine::Wide)
    }
}

/// How far apart neighbouring rays of a batch are, over a sample of its 16-ray groups.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spread {
    /// Groups sampled.
    pub groups: usize,
    /// Share of the sampled groups whose directions are not all in one octant.
    pub mixed_octants: f32,
    /// Mean over the groups of the largest angle (as `1 - cos`) between a direction and
    /// the group's first.
    pub direction: f32,
    /// Mean over the groups of the largest distance between an origin and the group's
    /// first, over the diagonal of the scene's box.
    pub origin: f32,
}

/// Groups of 16 consecutive rays [`spread`] looks at, at most (spaced evenly over the batch).
pub const SAMPLE_GROUPS: usize = 64;

/// Directions within this `1 - cos` of their group's first (about 8 degrees) count as one
/// beam: camera rays (`1 - cos` about 1e-5 between neighbouring pixels) and shadow rays
/// towards a point light (about 1e-4) are far below it, bounce rays (about 0.9) far above.
pub const BEAM: f32 = 0.01;

/// Origins within this share of the scene's diagonal of their group's first count as
/// together: the hits of a 4x4 pixel block (a group's mean farthest 0.016 of the diagonal on
/// the kitten at 1920x1080, 0.06 at 480x270) are below it, origins anywhere in the box (0.6
/// to 0.8: the farthest of 15 points uniform in the box) far above.
pub const TOGETHER: f32 = 0.2;

/// [`Spread`] of `rays` in a scene of box diagonal `diagonal`.
pub fn spread(rays: &[Ray], diagonal: f32) -> Spread {
    spread_by(rays.len(), |i| rays[i], diagonal)
}

/// [`Spread`] of a batch of `n` rays given by index (`ray_at(i)` for `i < n`; only the
/// sampled groups' rays are asked for): what a caller whose rays are in another layout
/// (a numpy array of rows) passes without making `Ray`s of the whole batch.
pub fn spread_by(count: usize, ray_at: impl Fn(usize) -> Ray, diagonal: f32) -> Spread {
    let groups = count.div_ceil(16);
    let n = groups.min(SAMPLE_GROUPS);
    if n == 0 {
        return Spread::default();
    }
    let (mut mixed, mut dir, mut org) = (0usize, 0.0f64, 0.0f64);
    let scale = if diagonal > 0.0 && diagonal.is_finite() {
        1.0 / diagonal
    } else {
        0.0
    };
    for k in 0..n {
        let g = k * groups / n;
        let rays = g * 16..(g * 16 + 16).min(count);
        let len = rays.len();
        let mut group = [Ray::new(glam::Vec3::ZERO, glam::Vec3::ZERO, 0.0, 0.0); 16];
        for (slot, i) in group.iter_mut().zip(rays) {
            *slot = ray_at(i);
        }
        let group = &group[..len];
        let first = group[0];
        let octant = |r: &Ray| r.dir.cmplt(glam::Vec3::ZERO).bitmask();
        let d0 = first.dir.normalize_or_zero();
        let (mut worst_cos, mut far) = (1.0f32, 0.0f32);
        let mut same = true;
        for r in group {
            same &= octant(r) == octant(&first);
            let c = r.dir.normalize_or_zero().dot(d0);
            // (NaN directions count as apart)
            worst_cos = if c.is_nan() { -1.0 } else { worst_cos.min(c) };
            let dist = (r.origin - first.origin).length() * scale;
            far = if dist.is_nan() { 1.0 } else { far.max(dist) };
        }
        mixed += !same as usize;
        dir += (1.0 - worst_cos) as f64;
        org += far.min(1.0) as f64;
    }
    Spread {
        groups: n,
        mixed_octants: mixed as f32 / n as f32,
        direction: (dir / n as f64) as f32,
        origin: (org / n as f64) as f32,
    }
}

/// What the rays say before any is traced: one engine, or two to try on a pilot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Choice {
    /// This engine, no pilot needed.
    One(Engine),
    /// The first by the rule alone, the second as good where the measurement says so
    /// (`docs/engines.md`); a large batch lets a pilot ([`pilot`]) decide.
    Try([Engine; 2]),
}

impl Choice {
    /// The engine without a pilot.
    pub fn first(self) -> Engine {
        match self {
            Choice::One(e) | Choice::Try([e, _]) => e,
        }
    }
}

/// The candidates for a batch by its [`Spread`] (the table of the module doc):
/// - beams: `packet16` and `hybrid16` (AVX-512), or `hybrid8` and `wide1`. Camera rays
///   from one eye go fastest in 16-ray packets; beams from many origins (shadow rays, the
///   camera rays that hit) go as fast or faster with `hybrid16` on large meshes (1.3M
///   triangles: shadow 6.0 against 4.8 Mrays/s), where the lanes part sooner. Without
///   AVX-512 `packet8` is never far ahead of `hybrid8` (AMD Zen 3: 0.97-1.01x of it on the
///   bench's beams at 20k, 1.3M and 5.2M triangles), while at 5.2M `wide1` leads on the
///   camera rays' hits (2.71 against 2.50 Mrays/s) and their shadow rays (2.97 against
///   2.64), where the packets' lanes part at once;
/// - scattered directions from origins close together: `hybrid16` and `wide1` (AVX-512), or
///   `hybrid8` and `wide1` (on the kitten the hybrid leads, at 1.3M triangles `wide1` by a
///   little);
/// - scattered in both: `wide1` alone (random rays: 1.2x `hybrid16` at 20k triangles and
///   1.1x at 1.3M; packets lose half).
pub fn candidates(s: Spread, avx512: bool) -> Choice {
    if s.groups == 0 {
        return Choice::One(Engine::Wide);
    }
    let (beam, scattered) = if avx512 {
        (
            [Engine::Packet16, Engine::Hybrid16],
            [Engine::Hybrid16, Engine::Wide],
        )
    } else {
        (
            [Engine::Hybrid, Engine::Wide],
            [Engine::Hybrid, Engine::Wide],
        )
    };
    if s.direction < BEAM && s.mixed_octants < 0.5 {
        Choice::Try(beam)
    } else if s.origin < TOGETHER {
        Choice::Try(scattered)
    } else {
        Choice::One(Engine::Wide)
    }
}

/// The candidates for `rays` in `accel` ([`spread`] over the scene's box, then
/// [`candidates`] with the AVX-512 kernels if the CPU runs them).
pub fn choices(accel: &Accel, rays: &[Ray]) -> Choice {
    choices_by(accel, rays.len(), |i| rays[i])
}

/// [`choices`] for a batch of `n` rays given by index ([`spread_by`]).
pub fn choices_by(accel: &Accel, n: usize, ray_at: impl Fn(usize) -> Ray) -> Choice {
    let diagonal = accel.nodes.first().map_or(0.0, |n| {
        (glam::Vec3::from(n.max) - glam::Vec3::from(n.min)).length()
    });
    candidates(
        spread_by(n, ray_at, diagonal),
        crate::accel::packet16::available(),
    )
}

/// The engine for `rays` by the rule alone, without a pilot ([`Choice::first`] of
/// [`choices`]): what `auto` takes for batches under [`PILOT_MIN`] rays.
pub fn choose(accel: &Accel, rays: &[Ray]) -> Engine {
    choices(accel, rays).first()
}

/// [`choose`]'s rule on a measured spread, with or without the AVX-512 kernels.
pub fn choose_by(s: Spread, avx512: bool) -> Engine {
    candidates(s, avx512).first()
}

/// Rays of one pilot block.
pub const PILOT_BLOCK: usize = 64;
/// Blocks of one pilot run: the first [`PILOT_WARM`] warm the caches for the engine, the
/// rest are timed. Runs of 3 blocks (128 rays timed) chose `hybrid8` for the 5.2M-triangle
/// bench's compacted hits on an AMD Zen 3 without AVX-512, at 0.88 of `wide1`: a short run
/// starts with colder caches than a ray amid the batch, which costs the single-ray walk more
/// than the packets. With 6 `auto` was within 5% of the best engine on all five workloads at
/// 20k, 1.3M and 5.2M triangles there (docs/performance.md).
pub const PILOT_RUN: usize = 8;
/// Blocks of a pilot run traced untimed first. With one (64 rays, in runs of 6 blocks) the
/// pilot chose `packet16` for the 5.2M-triangle bench's camera rays on every run on an AMD
/// Zen 5 with AVX-512, where `hybrid16` traced them 1.15x as fast: the cold start costs the
/// binary tree's packets less than the wide tree's walks there. With three (runs of 8, the
/// same 320 rays timed) it chose `hybrid16` in 7 runs of 7, and still `packet16` at 1.3M
/// triangles and on the kitten, where that is the faster (docs/engines.md).
pub const PILOT_WARM: usize = 3;
/// A pilot's runs cover one ray in this many, and there are at least [`PILOT_RUNS_MIN`].
pub const PILOT_SHARE: usize = 512;
/// Runs a pilot makes at least.
pub const PILOT_RUNS_MIN: usize = 8;
/// Batches of fewer rays take the rule's first candidate: their pilot would trace more than
/// 1/32 of them twice over.
pub const PILOT_MIN: usize = 131072;

/// The runs of a pilot over `n` rays: ranges of [`PILOT_RUN`] blocks of [`PILOT_BLOCK`]
/// rays (starting at multiples of 64), evenly spaced over the batch, covering one ray in
/// [`PILOT_SHARE`] and at least [`PILOT_RUNS_MIN`] of them; none under [`PILOT_MIN`] rays.
pub fn pilot_blocks(n: usize) -> Vec<std::ops::Range<usize>> {
    if n < PILOT_MIN {
        return vec![];
    }
    let len = PILOT_RUN * PILOT_BLOCK;
    let blocks = n / PILOT_BLOCK - PILOT_RUN;
    let count = (n / (PILOT_SHARE * len)).max(PILOT_RUNS_MIN);
    (0..count)
        .map(|k| {
            let b = k * blocks / (count - 1);
            b * PILOT_BLOCK..b * PILOT_BLOCK + len
        })
        .collect()
}

/// Time the two candidates on the pilot runs of a batch of `n` rays (`run(engine, rays)`
/// traces those rays with `engine`): both trace every run, `a` first on even runs and `b`
/// first on odd ones, each its first [`PILOT_WARM`] blocks untimed (a run's first rays fetch the nodes its
/// later rays reuse, as in the batch itself: timed alone, 128-ray blocks picked `packet16`
/// for the 5.2M-triangle camera rays, where `hybrid16` traces the batch 1.1x as fast) and
/// the rest timed. The one with the smaller total time wins. Totals, not a median of
/// ratios: runs differ in cost (camera rays that all miss cost a tenth of those that hit the
/// mesh, and the engines rank differently on the two), so the runs that cost most must weigh
/// most. Each run's time counts at most [`PILOT_CLAMP`] times the other engine's on the
/// same run, so a run slowed by a preemption does not decide. With no pilot runs (under
/// [`PILOT_MIN`] rays), `a`.
pub fn pilot(
    two: [Engine; 2],
    n: usize,
    mut run: impl FnMut(Engine, std::ops::Range<usize>),
) -> Engine {
    pilot_by(two, n, |e, r| {
        let warm = r.start + PILOT_WARM * PILOT_BLOCK;
        run(e, r.start..warm);
        let start = std::time::Instant::now();
        run(e, warm..r.end);
        start.elapsed().as_secs_f64()
    })
}

/// [`pilot`]'s decision with the timing given: `time(engine, run)` traces a pilot run with
/// `engine` and returns the seconds its timed part took.
pub fn pilot_by(
    [a, b]: [Engine; 2],
    n: usize,
    mut time: impl FnMut(Engine, &std::ops::Range<usize>) -> f64,
) -> Engine {
    let runs = pilot_blocks(n);
    if runs.is_empty() {
        return a;
    }
    let (mut total_a, mut total_b) = (0.0, 0.0);
    for (k, r) in runs.iter().enumerate() {
        let (ta, tb) = if k % 2 == 0 {
            let ta = time(a, r);
            (ta, time(b, r))
        } else {
            let tb = time(b, r);
            (time(a, r), tb)
        };
        total_a += ta.min(PILOT_CLAMP * tb);
        total_b += tb.min(PILOT_CLAMP * ta);
    }
    if total_b < total_a { b } else { a }
}

/// A pilot run's time counts at most this many times the other candidate's on it.
pub const PILOT_CLAMP: f64 = 3.0;

/// The parts of `range` outside the sorted, disjoint ranges `done`, in order: what is left
/// of a batch's rays once its pilot ([`pilot`]) has traced its runs. Both candidates trace
/// every run into the batch's output, and every engine's hits are `intersect1`'s bit for
/// bit, so the chosen engine need not trace those rays again (`range` may be one chunk of a
/// parallel pass; runs outside it are skipped).
pub fn left_over(
    range: std::ops::Range<usize>,
    done: &[std::ops::Range<usize>],
) -> impl Iterator<Item = std::ops::Range<usize>> + '_ {
    let end = range.end;
    let mut at = range.start;
    done.iter()
        .filter(move |d| d.end > range.start && d.start < range.end)
        .map(Some)
        .chain([None])
        .filter_map(move |d| {
            let stop = d.map_or(end, |d| d.start.max(at));
            let piece = at..stop;
            at = d.map_or(end, |d| d.end.min(end));
            (!piece.is_empty()).then_some(piece)
        })
}
