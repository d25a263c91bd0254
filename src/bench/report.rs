//! What one run measured, as text tables and as JSON.

use super::*;
use std::path::PathBuf;

/// Everything measured on one mesh.
#[derive(Clone, Debug)]
pub struct Report {
    /// The mesh file as given.
    pub mesh: PathBuf,
    /// Midpoint subdivision levels applied.
    pub subdivide: u32,
    /// Vertices after subdivision.
    pub vertices: usize,
    /// Triangles after subdivision.
    pub triangles: usize,
    /// Tracing threads (at least 1).
    pub threads: usize,
    /// Rounds (1..=64): one timed build and one timed pass per engine and workload each,
    /// alternating with the peer's runs.
    pub reps: usize,
    /// The camera and light the workloads were generated from.
    pub framing: Framing,
    /// Image width of the camera workloads, pixels.
    pub width: u32,
    /// Image height of the camera workloads, pixels.
    pub height: u32,
    /// BVH build time (seconds; on a pool of `threads`).
    pub build: Timing,
    /// Bytes of the 8-wide tree and its triangle blocks.
    pub wide_bytes: usize,
    /// Bytes of everything traversal reads ([`crate::accel::Accel::bytes`]: both trees, the SoA columns,
    /// the blocks).
    pub accel_bytes: usize,
    /// Peak resident memory of the process while this mesh was benchmarked (subdivision,
    /// builds, workloads, every engine's results; not the peer, a process of its own), bytes;
    /// `None` where the system does not say (not Linux).
    pub peak_resident: Option<u64>,
    /// Whether the peak was reset before this mesh ([`super::reset_peak_resident`]); if
    /// not, `peak_resident` is the process's peak since it started, earlier meshes included.
    pub peak_reset: bool,
    /// The 8-wide collapse (plan and block fill), the fastest of the timed builds' (ms).
    pub collapse_ms: f64,
    /// The BVH2 builder (`binned`, or the obvhs preset `fast` / `medium` / `slow`).
    pub builder: &'static str,
    /// Every engine on every workload.
    pub measured: Vec<Measured>,
    /// The peer's figures, or why there are none.
    pub peer: Result<PeerReport, String>,
}

impl Report {
    /// The measurement of engine `e` on workload `w`, if taken.
    pub fn get(&self, w: Workload, e: Engine) -> Option<&Measured> {
        self.measured
            .iter()
            .find(|m| m.workload == w && m.engine == e)
    }

    /// Rays on which some engine's results differ from the scalar reference's (0: all agree).
    pub fn mismatches(&self) -> usize {
        let mut n = 0;
        for w in Workload::ALL {
            let Some(s) = self.get(w, Engine::Scalar) else {
                continue;
            };
            for e in ENGINES {
                let Some(p) = self.get(w, e) else { continue };
                let r = (&s.results, &p.results);
                n += r.0.tri.iter().zip(&r.1.tri).filter(|(a, b)| a != b).count()
                    + r.0
                        .t
                        .iter()
                        .zip(&r.1.t)
                        .filter(|(a, b)| a.to_bits() != b.to_bits())
                        .count()
                    + r.0
                        .occluded
                        .iter()
                        .zip(&r.1.occluded)
                        .filter(|(a, b)| a != b)
                        .count();
            }
        }
        n
    }

    /// The fastest concrete engine on `w` (CPU-time best, else wall-clock best) and its
    /// rate (`auto` traces with one of them, so it is not among the candidates).
    pub fn best_engine(&self, w: Workload) -> Option<(Engine, f64)> {
        Engine::CONCRETE
            .iter()
            .filter_map(|&e| {
                let m = self.get(w, e)?;
                let (b, _, c) = m.timing.rate(m.rays);
                Some((e, c.unwrap_or(b)))
            })
            .max_by(|a, b| a.1.total_cmp(&b.1))
    }
}

fn fmt_v3(v: [f64; 3]) -> String {
    format!("({:.4} {:.4} {:.4})", v[0], v[1], v[2])
}

/// The report's `memory:` line: what traversal reads, and the peak resident size with what
/// it covers (this mesh when the peak was reset before it, else the whole process so far).
pub fn memory_line(accel_bytes: usize, triangles: usize, peak: Option<u64>, reset: bool) -> String {
    let mb = |b: f64| b / (1024.0 * 1024.0);
    let peak = match peak {
        None => "not available".to_string(),
        Some(b) if reset => format!(
            "{:.1} MiB (this mesh: subdivision, builds, workloads, results; not the peer's)",
            mb(b as f64)
        ),
        Some(b) => format!(
            "{:.1} MiB (the process's since it started, earlier meshes included: the system refused the reset of the peak; not the peer's)",
            mb(b as f64)
        ),
    };
    format!(
        "memory: BVH2 + SoA triangles + wide tree {:.1} MiB ({:.1} bytes/triangle); peak resident {peak}",
        mb(accel_bytes as f64),
        accel_bytes as f64 / triangles.max(1) as f64,
    )
}

/// The report as text tables.
pub fn format_report(r: &Report) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let fr = &r.framing;
    let _ = writeln!(
        s,
        "whitted bench {} subdivide {}: {} vertices, {} triangles | threads {}, rounds {} | {} | {}",
        r.mesh.display(),
        r.subdivide,
        r.vertices,
        r.triangles,
        r.threads,
        r.reps,
        if cfg!(target_feature = "avx2") {
            "AVX2 build"
        } else {
            "no AVX2 in this build (f32x8 runs as two SSE halves)"
        },
        if crate::accel::packet16::available() {
            "packet16 on AVX-512"
        } else {
            "no AVX-512 (packet16 and hybrid16 run as two packet8 and hybrid8 calls)"
        }
    );
    let _ = writeln!(
        s,
        "camera {}: eye {} look_at {} L1 {}, {}x{} vfov 36, eps {:.4e}",
        if fr.canonical { "canonical" } else { "framed" },
        fmt_v3(fr.eye),
        fmt_v3(fr.look),
        fmt_v3(fr.light),
        r.width,
        r.height,
        fr.eps
    );
    let peer = r.peer.as_ref().ok();
    let _ = write!(
        s,
        "BVH build ({} BVH2 + 8-wide collapse, threads {}): best {:.2} ms, median {:.2} ms (collapse best {:.2} ms), wide tree {:.1} bytes/triangle",
        match r.builder {
            "binned" => "binned SAH",
            b => b,
        },
        r.threads,
        r.build.wall_best * 1e3,
        r.build.wall_median * 1e3,
        r.collapse_ms,
        r.wide_bytes as f64 / r.triangles.max(1) as f64
    );
    match peer {
        Some(p) => {
            let _ = writeln!(
                s,
                " | Embree MEDIUM (threads {}): best {:.2} ms, median {:.2} ms",
                r.threads,
                p.build_best_ms.unwrap_or(f64::NAN),
                p.build_median_ms.unwrap_or(f64::NAN)
            );
        }
        None => s.push('\n'),
    }
    let _ = writeln!(
        s,
        "{}",
        memory_line(r.accel_bytes, r.triangles, r.peak_resident, r.peak_reset)
    );
    for cpu in [false, true] {
        let _ = writeln!(
            s,
            "\n{} Mrays/s, best (median) of {} round{}, one pass each{}{}:",
            if cpu { "CPU-time" } else { "Wall-clock" },
            r.reps,
            if r.reps == 1 { "" } else { "s" },
            if r.peer.is_ok() {
                ", alternating with the peer's"
            } else {
                ""
            },
            if cpu {
                " (rays per CPU-second of the tracing threads; steadier on a busy machine)"
            } else {
                ""
            }
        );
        let _ = write!(s, "{:<18} {:>8} |", "workload", "rays");
        for e in ENGINES {
            let _ = write!(s, " {:>15}", e.name());
        }
        let _ = write!(s, " | {:>17}", "auto chose / best");
        if peer.is_some() {
            let _ = write!(
                s,
                " | {:>15} {:>15} {:>15} | {:>22}",
                "Embree x1", "x8", "x16", "best whitted / Embree"
            );
        }
        s.push('\n');
        for w in Workload::ALL {
            let Some(sc) = r.get(w, Engine::Scalar) else {
                continue;
            };
            let ours = |e: Engine| -> Option<(f64, f64)> {
                let m = r.get(w, e)?;
                let n = m.rays as f64 / 1e6;
                if cpu {
                    Some((n / m.timing.cpu_best?, n / m.timing.cpu_median?))
                } else {
                    Some((n / m.timing.wall_best, n / m.timing.wall_median))
                }
            };
            let theirs = |width: u32| -> Option<(f64, f64)> {
                let k = peer?.kernel(w, width)?;
                Some(if cpu {
                    (k.cpu_best, k.cpu_median)
                } else {
                    (k.wall_best, k.wall_median)
                })
            };
            let cell = |v: Option<(f64, f64)>| match v {
                Some((b, m)) => format!("{b:.2} ({m:.2})"),
                None => "-".into(),
            };
            let _ = write!(s, "{:<18} {:>8} |", w.name(), sc.rays);
            for e in ENGINES {
                let _ = write!(s, " {:>15}", cell(ours(e)));
            }
            let best_ours = Engine::CONCRETE
                .iter()
                .filter_map(|&e| Some((e, ours(e)?.0)))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            let auto = r
                .get(w, Engine::Auto)
                .and_then(|m| Some((m.chosen?, ours(Engine::Auto)?.0)));
            let _ = match auto.zip(best_ours) {
                Some(((c, a), (_, b))) => {
                    write!(s, " | {:>17}", format!("{} {:.2}", c.name(), a / b))
                }
                None => write!(s, " | {:>17}", "-"),
            };
            if peer.is_some() {
                let _ = write!(
                    s,
                    " | {:>15} {:>15} {:>15} |",
                    cell(theirs(1)),
                    cell(theirs(8)),
                    cell(theirs(16))
                );
                let best_theirs = [1, 8, 16]
                    .iter()
                    .filter_map(|&k| Some((k, theirs(k)?.0)))
                    .max_by(|a, b| a.1.total_cmp(&b.1));
                let _ = match best_ours.zip(best_theirs) {
                    Some(((e, a), (k, b))) => {
                        write!(s, " {:>22}", format!("{:.2} ({} / x{k})", a / b, e.name()))
                    }
                    None => write!(s, " {:>22}", "-"),
                };
            }
            s.push('\n');
        }
    }
    let count = |w: Workload| r.get(w, Engine::Scalar).map_or(0, |m| m.results.count());
    let _ = write!(
        s,
        "\nchecks: primary hits {}, occluded {}, incoherent hits {}, random hits {}",
        count(Workload::Primary),
        count(Workload::Shadow),
        count(Workload::Incoherent),
        count(Workload::Random)
    );
    if let Some(p) = peer {
        let o = |v: Option<usize>| v.map_or("-".into(), |v| v.to_string());
        let _ = write!(
            s,
            " (Embree {}, {}, {}, {})",
            o(p.primary_hits),
            o(p.occluded),
            o(p.incoherent_hits),
            o(p.random_hits)
        );
    }
    let _ = writeln!(s, "; packet-vs-scalar mismatches {}", r.mismatches());
    let _ = writeln!(
        s,
        "note: primary rays are the peer's bit for bit; the shadow and incoherent rays are built from whitted's own\n      hits (t, Ng), so they match Embree's sets to ~1 ulp per ray, not bit for bit. Ratios use the best pass."
    );
    match &r.peer {
        Ok(p) => {
            let _ = writeln!(
                s,
                "peer: {} (run in this invocation, --quality medium)",
                p.version
            );
        }
        Err(e) => {
            let _ = writeln!(s, "peer: {e}; whitted's figures only");
        }
    }
    s
}

/// The report as JSON.
pub fn report_json(r: &Report) -> serde_json::Value {
    use serde_json::json;
    let t = |t: &Timing| {
        json!({"wall_best_s": t.wall_best, "wall_median_s": t.wall_median,
               "cpu_best_s": t.cpu_best, "cpu_median_s": t.cpu_median})
    };
    let rate = |n: usize, t: &Timing| {
        let (b, m, c) = t.rate(n);
        json!({"wall_best": b, "wall_median": m, "cpu_best": c,
               "cpu_median": t.cpu_median.map(|s| n as f64 / s / 1e6)})
    };
    let peer = r.peer.as_ref().ok();
    let workloads: Vec<serde_json::Value> = Workload::ALL
        .iter()
        .filter_map(|&w| {
            let sc = r.get(w, Engine::Scalar)?;
            let mut ratios = serde_json::Map::new();
            let mut mrays = serde_json::Map::new();
            for e in ENGINES {
                if let Some(m) = r.get(w, e) {
                    mrays.insert(e.name().into(), rate(m.rays, &m.timing));
                }
            }
            if let Some(p) = peer {
                for e in ENGINES {
                    let Some(m) = r.get(w, e) else { continue };
                    for width in if e.packet() { &[8, 16][..] } else { &[1][..] } {
                        let width = *width;
                        let Some(k) = p.kernel(w, width) else {
                            continue;
                        };
                        let (b, _, c) = m.timing.rate(m.rays);
                        ratios.insert(
                            format!("{}_vs_x{width}", e.name()),
                            json!({"wall_best": b / k.wall_best,
                                   "cpu_best": c.map(|c| c / k.cpu_best)}),
                        );
                    }
                }
            }
            let embree: Vec<_> = peer
                .map(|p| {
                    p.kernels
                        .iter()
                        .filter(|k| k.workload == w)
                        .map(|k| {
                            json!({"width": k.width, "rays": k.rays,
                                   "wall_best": k.wall_best, "wall_median": k.wall_median,
                                   "cpu_best": k.cpu_best, "cpu_median": k.cpu_median})
                        })
                        .collect()
                })
                .unwrap_or_default();
            Some(json!({
                "workload": w.name(),
                "rays": sc.rays,
                "hits": sc.results.count(),
                "checksum": format!("{:016x}", sc.results.checksum()),
                "whitted_mrays": mrays,
                "best_engine": r.best_engine(w).map(|b| b.0.name()),
                "auto_chose": r.get(w, Engine::Auto).and_then(|m| m.chosen).map(Engine::name),
                "embree_mrays": embree,
                "ratio": ratios,
            }))
        })
        .collect();
    let fr = &r.framing;
    json!({
        "mesh": r.mesh.display().to_string(),
        "subdivide": r.subdivide,
        "vertices": r.vertices,
        "triangles": r.triangles,
        "threads": r.threads,
        "reps": r.reps,
        "rounds": r.reps,
        "avx2": cfg!(target_feature = "avx2"),
        "avx512": crate::accel::packet16::available(),
        "camera": {"canonical": fr.canonical, "eye": fr.eye, "look_at": fr.look, "light": fr.light,
                   "width": r.width, "height": r.height, "eps": fr.eps},
        "build": t(&r.build),
        "workloads": workloads,
        "packet_scalar_mismatches": r.mismatches(),
        "engine_mismatches": r.mismatches(),
        "wide_bytes": r.wide_bytes,
        "accel_bytes": r.accel_bytes,
        "peak_resident_bytes": r.peak_resident,
        "peak_resident_scope": if r.peak_reset { "mesh" } else { "process" },
        "collapse_ms": r.collapse_ms,
        "builder": r.builder,
        "secondary_rays_from": "whitted's own primary hits (match Embree's sets to ~1 ulp)",
        "peer": match &r.peer {
            Ok(p) => json!({"version": p.version, "build_best_ms": p.build_best_ms,
                            "build_median_ms": p.build_median_ms, "primary_hits": p.primary_hits,
                            "occluded": p.occluded, "incoherent_hits": p.incoherent_hits,
                            "random_hits": p.random_hits}),
            Err(e) => json!({"error": e}),
        },
    })
}
