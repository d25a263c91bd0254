//! Timing passes and builds: best and median, wall clock and CPU time; peak memory.

use super::*;
use crate::accel::{Accel, BuildQuality};
use glam::Vec3;
use std::time::Instant;

/// Best and median of timed passes (the peer's `median = sorted[reps / 2]`), wall-clock and
/// CPU seconds (of this thread with one thread, of all the process's threads otherwise).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Timing {
    /// Shortest wall-clock pass, seconds.
    pub wall_best: f64,
    /// Median wall-clock pass, seconds.
    pub wall_median: f64,
    /// Least CPU time of a pass, seconds; `None` when any pass had no CPU reading.
    pub cpu_best: Option<f64>,
    /// Median CPU time of a pass, seconds; `None` like `cpu_best`.
    pub cpu_median: Option<f64>,
}

impl Timing {
    fn of(samples: &Samples) -> Timing {
        let mut wall = samples.wall.clone();
        wall.sort_by(f64::total_cmp);
        let mut cpu: Option<Vec<f64>> = samples.cpu.iter().copied().collect();
        if let Some(c) = &mut cpu {
            c.sort_by(f64::total_cmp);
        }
        let m = wall.len() / 2;
        Timing {
            wall_best: wall[0],
            wall_median: wall[m],
            cpu_best: cpu.as_ref().map(|c| c[0]),
            cpu_median: cpu.as_ref().map(|c| c[m]),
        }
    }

    /// Millions of items per second for `n` items: `(wall best, wall median, cpu best)`.
    pub fn rate(&self, n: usize) -> (f64, f64, Option<f64>) {
        let r = |s: f64| n as f64 / s / 1e6;
        (r(self.wall_best), r(self.wall_median), self.cpu_best.map(r))
    }
}

/// CPU time in seconds: this thread's (`all = false`) or the whole process's, from
/// `clock_gettime(CLOCK_THREAD_CPUTIME_ID / CLOCK_PROCESS_CPUTIME_ID)`, the clocks the peer
/// reads (nanosecond resolution; `/proc/.../schedstat`, read before, advances only at
/// scheduler ticks, 4 ms here, so 20-50 ms passes were quantised by up to 20%).
/// `None` where the clock is missing.
pub fn cpu_seconds(all: bool) -> Option<f64> {
    let t = if all {
        cpu_time::ProcessTime::try_now().ok()?.as_duration()
    } else {
        cpu_time::ThreadTime::try_now().ok()?.as_duration()
    };
    Some(t.as_secs_f64())
}

/// The timed calls of one measurement, possibly gathered over several rounds: wall-clock
/// and CPU seconds per call.
#[derive(Clone, Debug, Default)]
pub struct Samples {
    wall: Vec<f64>,
    cpu: Vec<Option<f64>>,
}

impl Samples {
    /// Best and median of the calls so far (at least one).
    pub fn timing(&self) -> Timing {
        Timing::of(self)
    }

    /// Timed calls so far.
    pub fn len(&self) -> usize {
        self.wall.len()
    }

    /// Whether no call was timed yet.
    pub fn is_empty(&self) -> bool {
        self.wall.is_empty()
    }

    /// One untimed warm-up call of `f`, then `reps` timed calls (at least one), each after an
    /// untimed call of `before`; CPU time of this thread (`threads <= 1`) or the process.
    pub fn take(
        &mut self,
        reps: usize,
        threads: usize,
        mut before: impl FnMut(),
        mut f: impl FnMut(),
    ) {
        before();
        f();
        for _ in 0..reps.max(1) {
            before();
            let c0 = cpu_seconds(threads > 1);
            let t0 = Instant::now();
            f();
            self.wall.push(t0.elapsed().as_secs_f64());
            let c1 = cpu_seconds(threads > 1);
            self.cpu.push(c0.zip(c1).map(|(a, b)| b - a));
        }
    }
}

/// Time `f` after one untimed warm-up call: `reps` timed calls.
pub fn time_reps(reps: usize, threads: usize, f: impl FnMut()) -> Timing {
    time_reps_after(reps, threads, || {}, f)
}

/// [`time_reps`] with `before` called, untimed, before each call of `f`.
pub fn time_reps_after(
    reps: usize,
    threads: usize,
    before: impl FnMut(),
    f: impl FnMut(),
) -> Timing {
    let mut s = Samples::default();
    s.take(reps, threads, before, f);
    s.timing()
}

/// One engine on one set.
#[derive(Clone, Debug)]
pub struct Measured {
    /// The ray set.
    pub workload: Workload,
    /// The engine.
    pub engine: Engine,
    /// Rays in the set.
    pub rays: usize,
    /// Time per pass over the whole set.
    pub timing: Timing,
    /// What the last pass found, per ray.
    pub results: Results,
    /// For `auto`, the engine it chose for the set.
    pub chosen: Option<Engine>,
}

/// Time every engine on every workload (`reps` passes after a warm-up each), on the calling
/// thread (`threads <= 1`) or on a pool of `threads`: one [`Measuring::round`].
pub fn measure(accel: &Accel, work: &Workloads, threads: usize, reps: usize) -> Vec<Measured> {
    let mut m = Measuring::default();
    m.round(accel, work, threads, reps);
    m.finish()
}

/// Every engine on every workload, timed in rounds (`whitted bench` alternates them with the
/// peer's): each round adds its passes to the samples of the rounds before.
#[derive(Default)]
pub struct Measuring {
    /// Per workload and engine, in [`measure`]'s order.
    sets: Vec<Set>,
}

/// One engine on one workload, over the rounds so far.
struct Set {
    workload: Workload,
    engine: Engine,
    rays: usize,
    samples: Samples,
    /// The last round's results (`None` after [`Measuring::forget_results`]).
    results: Option<Results>,
    /// `auto`'s choice.
    chosen: Option<Engine>,
}

impl Measuring {
    /// One round: each engine on each workload, a warm-up pass then `passes` timed ones. The
    /// workloads must be the same from round to round (`accel` may be rebuilt in between).
    pub fn round(&mut self, accel: &Accel, work: &Workloads, threads: usize, passes: usize) {
        let pool = (threads > 1).then(|| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool")
        });
        let first = self.sets.is_empty();
        let mut i = 0;
        for (workload, rays) in work.sets() {
            let packets = Packets::new(rays);
            for engine in ENGINES {
                if first {
                    self.sets.push(Set {
                        workload,
                        engine,
                        rays: rays.len(),
                        samples: Samples::default(),
                        results: None,
                        chosen: None,
                    });
                }
                let set = &mut self.sets[i];
                assert_eq!(
                    (set.workload, set.engine),
                    (workload, engine),
                    "the same workloads"
                );
                let mut out = Out::new(accel, engine, workload.any_hit(), rays);
                set.samples.take(
                    passes,
                    threads,
                    || {},
                    || pass(accel, rays, &packets, &mut out, pool.as_ref()),
                );
                set.results = Some(results_of(&out, rays.len()));
                set.chosen = out.chosen();
                i += 1;
            }
        }
    }

    /// Drop the results kept so far (the next round records them again), so that what
    /// runs between rounds, such as the next build, does not hold them: at 1.3M triangles
    /// they are about 120 MB, most of it the camera rays' hits for each engine.
    pub fn forget_results(&mut self) {
        for set in &mut self.sets {
            set.results = None;
        }
    }

    /// Best and median over every round so far, with the last round's results (empty if
    /// they were forgotten since).
    pub fn finish(self) -> Vec<Measured> {
        self.sets
            .into_iter()
            .map(|s| Measured {
                workload: s.workload,
                engine: s.engine,
                rays: s.rays,
                timing: s.samples.timing(),
                results: s.results.unwrap_or_default(),
                chosen: s.chosen,
            })
            .collect()
    }
}

/// BVH build time over `tris` with `quality`, best and median of `reps` builds after a
/// warm-up, on a pool of `threads` (whitted's builder splits large subtrees across them; the
/// obvhs presets build on one). Each build starts with the previous one freed, untimed, as the
/// peer releases its previous scene before each timed commit (timing the drop of the old tree
/// with the new build, as before, added its unmapping to whitted's figure). Also the shortest
/// 8-wide collapse of those builds (`Accel::collapse_time`; the last build's alone swung from
/// 62 to 802 ms at 1.3M triangles while the best build stayed).
pub fn time_build(
    tris: &[[Vec3; 3]],
    reps: usize,
    quality: BuildQuality,
    threads: usize,
) -> (Accel, Timing, std::time::Duration) {
    let mut samples = Samples::default();
    let (accel, collapse) = sample_build(tris, reps, quality, threads, &mut samples);
    (accel, samples.timing(), collapse)
}

/// [`time_build`]'s builds, their times added to `samples`: the last build and the shortest
/// collapse of the timed ones.
pub fn sample_build(
    tris: &[[Vec3; 3]],
    reps: usize,
    quality: BuildQuality,
    threads: usize,
    samples: &mut Samples,
) -> (Accel, std::time::Duration) {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.max(1))
        .build()
        .expect("thread pool");
    pool.install(|| {
        let accel = std::cell::RefCell::new(Accel::default());
        let collapse = std::cell::Cell::new(std::time::Duration::MAX);
        samples.take(
            reps,
            threads,
            || drop(accel.take()),
            || {
                let a = Accel::build(tris, quality);
                collapse.set(collapse.get().min(a.collapse_time));
                *accel.borrow_mut() = a;
            },
        );
        (accel.into_inner(), collapse.get())
    })
}

/// Start a new peak of resident memory for [`peak_resident_bytes`] (Linux: `5` written to
/// `/proc/self/clear_refs` resets `VmHWM` to the current resident size). Returns whether it
/// did: where the write is refused (a locked-down container) or elsewhere than Linux, the
/// peak stays the process's since it started.
pub fn reset_peak_resident() -> bool {
    #[cfg(target_os = "linux")]
    return std::fs::write("/proc/self/clear_refs", "5").is_ok();
    #[cfg(not(target_os = "linux"))]
    false
}

/// The process's peak resident memory (bytes) since it started or since the last
/// [`reset_peak_resident`]: `VmHWM` of `/proc/self/status`; `None` where that is not
/// readable (not Linux).
pub fn peak_resident_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    parse_vm_hwm(&status)
}

/// The `VmHWM:` line of a `/proc/<pid>/status` text, in bytes.
pub fn parse_vm_hwm(status: &str) -> Option<u64> {
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let mut f = line["VmHWM:".len()..].split_whitespace();
    let kb: u64 = f.next()?.parse().ok()?;
    (f.next() == Some("kB")).then_some(kb * 1024)
}
