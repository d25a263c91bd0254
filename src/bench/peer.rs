//! The Embree peer (`rt-bench`): finding it, running it, parsing its output.

use super::*;
use std::path::{Path, PathBuf};

// ---------------------------------------------------------------- the peer's output

/// One kernel line of rt-bench: `  {label} {rays} rays  wall best {b} med {m} | cpu best .. med ..`.
#[derive(Clone, Debug, PartialEq)]
pub struct PeerKernel {
    /// The ray set traced.
    pub workload: Workload,
    /// Rays per call: 1, 8 or 16.
    pub width: u32,
    /// Rays in the set.
    pub rays: usize,
    /// Wall-clock rate of the best pass, Mrays/s.
    pub wall_best: f64,
    /// Wall-clock rate of the median pass, Mrays/s.
    pub wall_median: f64,
    /// CPU-time rate of the best pass, Mrays/s.
    pub cpu_best: f64,
    /// CPU-time rate of the median pass, Mrays/s.
    pub cpu_median: f64,
}

/// What rt-bench printed for one build quality.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PeerReport {
    /// `embree 3.13.5, device config ...` line.
    pub version: String,
    /// Triangles after subdivision (the `mesh` line), if printed.
    pub triangles: Option<usize>,
    /// The `camera` line after `camera ` and up to its first `:`.
    pub camera: String,
    /// Build time in ms, wall best.
    pub build_best_ms: Option<f64>,
    /// Build time in ms, wall median.
    pub build_median_ms: Option<f64>,
    /// Kernel lines, in output order (at least one after a successful parse).
    pub kernels: Vec<PeerKernel>,
    /// Primary rays that hit.
    pub primary_hits: Option<usize>,
    /// The `mismatches` count printed on the `primary hits` line.
    pub mismatches: Option<usize>,
    /// Shadow rays that are occluded.
    pub occluded: Option<usize>,
    /// Incoherent rays that hit.
    pub incoherent_hits: Option<usize>,
    /// Random rays that hit (a peer run with `--random`).
    pub random_hits: Option<usize>,
}

impl PeerReport {
    /// The kernel line for workload `w` at `width` rays per call, if the peer printed one.
    pub fn kernel(&self, w: Workload, width: u32) -> Option<&PeerKernel> {
        self.kernels
            .iter()
            .find(|k| k.workload == w && k.width == width)
    }
}

/// Parse rt-bench's text output (the first build quality only; run it with
/// `--quality medium`). Kernel lines are the 2-space indented ones with `rays  wall best`.
pub fn parse_peer(text: &str) -> Result<PeerReport, String> {
    let mut p = PeerReport::default();
    let num = |s: &str| s.parse::<f64>().map_err(|e| format!("'{s}': {e}"));
    let first_int = |s: &str| -> Option<usize> { s.split_whitespace().next()?.parse().ok() };
    let mut builds = 0;
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("mesh ") {
            // mesh PATH subdivide K: V vertices, T triangles (load ..)
            p.triangles = rest
                .rsplit_once(" vertices, ")
                .and_then(|(_, t)| first_int(t));
        } else if line.starts_with("embree ") {
            p.version = line.to_string();
        } else if let Some(rest) = line.strip_prefix("camera ") {
            p.camera = rest.split(':').next().unwrap_or("").to_string();
        } else if let Some(rest) = line.strip_prefix("build ") {
            builds += 1;
            if builds > 1 {
                break; // a second quality follows; keep the first
            }
            let w: Vec<&str> = rest.split_whitespace().collect();
            let at = |key: &str| w.iter().position(|x| *x == key).and_then(|i| w.get(i + 1));
            p.build_best_ms = at("best").and_then(|s| s.parse().ok());
            p.build_median_ms = at("median").and_then(|s| s.parse().ok());
        } else if let Some(rest) = line.trim_start().strip_prefix("primary hits ") {
            p.primary_hits = first_int(rest);
            p.mismatches = rest
                .rsplit_once("mismatches ")
                .and_then(|(_, m)| first_int(m));
        } else if let Some(rest) = line.trim_start().strip_prefix("occluded ") {
            p.occluded = first_int(rest);
        } else if let Some(rest) = line.trim_start().strip_prefix("incoherent hits ") {
            p.incoherent_hits = first_int(rest);
        } else if let Some(rest) = line.trim_start().strip_prefix("random hits ") {
            p.random_hits = first_int(rest);
        } else if line.starts_with("  ") && line.contains(" rays  wall best ") {
            let (head, tail) = line.split_once(" rays  wall best ").unwrap();
            let head: Vec<&str> = head.split_whitespace().collect();
            if head.len() < 3 {
                return Err(format!("kernel line: {line}"));
            }
            let workload = Workload::from_name(head[0])
                .ok_or_else(|| format!("unknown workload '{}' in: {line}", head[0]))?;
            let width: u32 = head[1]
                .trim_start_matches(|c: char| !c.is_ascii_digit())
                .parse()
                .map_err(|_| format!("kernel width in: {line}"))?;
            let rays: usize = head[head.len() - 1]
                .parse()
                .map_err(|_| format!("ray count in: {line}"))?;
            // "{b} med {m} | cpu best {cb} med {cm} Mrays/s"
            let v: Vec<&str> = tail.split_whitespace().collect();
            if v.len() < 8 {
                return Err(format!("kernel line: {line}"));
            }
            p.kernels.push(PeerKernel {
                workload,
                width,
                rays,
                wall_best: num(v[0])?,
                wall_median: num(v[2])?,
                cpu_best: num(v[6])?,
                cpu_median: num(v[8.min(v.len() - 1)])?,
            });
        }
    }
    if p.kernels.is_empty() {
        return Err("no kernel lines in rt-bench's output".into());
    }
    Ok(p)
}

/// The peer binary: `explicit`, else `$WHITTED_PEER`, else `rt-bench` on `PATH`.
pub fn find_peer(explicit: Option<&Path>) -> Option<PathBuf> {
    if let Some(p) = explicit {
        return Some(p.to_path_buf());
    }
    if let Some(p) = std::env::var_os("WHITTED_PEER").filter(|p| !p.is_empty()) {
        return Some(PathBuf::from(p));
    }
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join("rt-bench"))
            .find(|p| p.is_file())
    })
}

/// Run the peer on `mesh` with the same options (`--quality medium`, `--random random`
/// unless 0) and parse its output.
pub fn run_peer(
    peer: &Path,
    mesh: &Path,
    threads: usize,
    subdivide: u32,
    reps: usize,
    (width, height): (u32, u32),
    random: usize,
) -> Result<(PeerReport, String), String> {
    let mut cmd = std::process::Command::new(peer);
    cmd.arg(mesh)
        .args(["--width", &width.to_string()])
        .args(["--height", &height.to_string()])
        .args(["--threads", &threads.to_string()])
        .args(["--subdivide", &subdivide.to_string()])
        .args(["--reps", &reps.to_string()])
        .args(["--quality", "medium"]);
    if random > 0 {
        cmd.args(["--random", &random.to_string()]);
    }
    let out = cmd
        .output()
        .map_err(|e| format!("{}: {e}", peer.display()))?;
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    if !out.status.success() {
        return Err(format!(
            "{} exited with {}: {}",
            peer.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    parse_peer(&text).map(|p| (p, text))
}

/// One report from the peer's runs of one pass each (`--reps 1`, one per round of `whitted
/// bench`): per kernel and for the build, the best and the median over the runs, as the
/// peer computes them over its passes (`median = sorted[runs / 2]` of the times, so the
/// rate of that pass); the rest from the first run. Runs that traced different ray sets
/// (counts or hits differ) are refused.
pub fn merge_peer(runs: &[PeerReport]) -> Result<PeerReport, String> {
    let first = runs.first().ok_or("no peer runs")?;
    for r in &runs[1..] {
        let key = |p: &PeerReport| {
            let kernels: Vec<_> = p
                .kernels
                .iter()
                .map(|k| (k.workload, k.width, k.rays))
                .collect();
            (
                p.triangles,
                p.primary_hits,
                p.occluded,
                p.incoherent_hits,
                p.random_hits,
                kernels,
            )
        };
        if key(r) != key(first) {
            return Err("the peer's runs traced different ray sets".into());
        }
    }
    // best (highest rate) and median (the median pass's rate) of one figure per run.
    let best_median = |rates: Vec<f64>| {
        let mut v = rates;
        // descending rates = ascending times
        v.sort_by(|a, b| b.total_cmp(a));
        (v[0], v[v.len() / 2])
    };
    let mut merged = first.clone();
    for (i, k) in merged.kernels.iter_mut().enumerate() {
        (k.wall_best, k.wall_median) =
            best_median(runs.iter().map(|r| r.kernels[i].wall_best).collect());
        (k.cpu_best, k.cpu_median) =
            best_median(runs.iter().map(|r| r.kernels[i].cpu_best).collect());
    }
    let builds: Option<Vec<f64>> = runs.iter().map(|r| r.build_best_ms).collect();
    (merged.build_best_ms, merged.build_median_ms) = match builds {
        Some(mut b) => {
            b.sort_by(f64::total_cmp);
            (Some(b[0]), Some(b[b.len() / 2]))
        }
        None => (None, None),
    };
    merged.mismatches = runs.iter().filter_map(|r| r.mismatches).max();
    Ok(merged)
}
