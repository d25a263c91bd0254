//! Throughput on the Embree peer's workloads (`whitted bench`, `benches/`), side by side with it.
//!
//! The peer is `rt-bench` (`shared/peers/embree`). Its workloads are reproduced here from its
//! source, step for step in the same f64 arithmetic and order:
//! - the mesh: loaded, then midpoint-subdivided with the peer's vertex numbering and child
//!   order ([`subdivide_like_peer`]), so both trace the very same triangles;
//! - the camera: the canonical kitten view, or the same view scaled onto another mesh's box;
//! - **primary**: 1920x1080 pixel-centre rays in 4x4 pixel blocks (an 8-ray packet is the top
//!   or bottom 4x2 half of a block), bit for bit the peer's rays;
//! - **primary-hits-only**: the primary rays that hit, in block order;
//! - **shadow**: from each primary hit towards the light L1, origin pushed `eps` off the
//!   surface on the light's side, `tfar` one ulp short of the light (any hit);
//! - **incoherent**: one uniform hemisphere direction about the geometric normal per hit
//!   (splitmix64, seed 1234567), origin pushed `eps` to the viewer's side (closest hit);
//! - **random**: `--random N` rays (262,144 unless told), origins uniform in the mesh's box and
//!   directions uniform on the sphere (splitmix64, seed 7654321), bit for bit the peer's rays
//!   ([`random_rays`]; closest hit).
//!
//! The secondary sets are built from whitted's *own* primary hits (`t` and the triangle's
//! normal). Embree computes `t` with a different (unpublished) formula, so these two sets agree
//! with Embree's to about one ulp per ray, not bit for bit; fed Embree's `(prim, t, Ng)` the
//! same code reproduces Embree's sets exactly ([`secondary_rays`]).

mod kernels;
mod peer;
mod report;
mod timing;
mod workloads;

pub use kernels::*;
pub use peer::*;
pub use report::*;
pub use timing::*;
pub use workloads::*;

use crate::accel::BuildQuality;
use std::path::{Path, PathBuf};

// ---------------------------------------------------------------- `whitted bench`

/// Options of `whitted bench`.
#[cfg_attr(feature = "cli", derive(clap::Args))]
#[derive(Clone, Debug, Default)]
pub struct Options {
    /// Meshes (`.m`, `.obj`, `.ply`, `.stl`, `.gltf` or `.glb`); default `meshes/kitten.m` from
    /// the current folder, the `WHITTED_ASSETS` folders or the copy whitted ships (the search
    /// path of scene files).
    pub meshes: Vec<PathBuf>,
    /// Tracing threads (also the peer's `--threads`); 1 traces on the calling thread.
    #[cfg_attr(feature = "cli", arg(long, short = 't', default_value_t = 1))]
    pub threads: usize,
    /// Midpoint subdivision levels (x4 triangles each, the peer's vertex and child order).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 0))]
    pub subdivide: u32,
    /// Image width of the camera workloads (also the peer's `--width`).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = WIDTH))]
    pub width: u32,
    /// Image height of the camera workloads (also the peer's `--height`).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = HEIGHT))]
    pub height: u32,
    /// Rounds (best and median are taken over them). Each round times one build and one pass
    /// of every engine on every workload, then runs the peer for one build and one pass of
    /// each of its kernels; every timed call, on both sides, follows an untimed warm-up.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 5))]
    pub reps: usize,
    /// Rays of the random workload (origins anywhere in the mesh's box, directions anywhere;
    /// also the peer's `--random`); 0 leaves it out. Default 262144.
    #[cfg_attr(feature = "cli", arg(long, value_name = "N"))]
    pub random: Option<usize>,
    /// Print one JSON object instead of tables.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
    /// The Embree peer binary (default: `$WHITTED_PEER`, else `rt-bench` on `PATH`).
    #[cfg_attr(feature = "cli", arg(long))]
    pub peer: Option<PathBuf>,
    /// Do not run the peer even when it is found.
    #[cfg_attr(feature = "cli", arg(long))]
    pub no_peer: bool,
    /// whitted's BVH builder: binned (its own), or the obvhs presets fast, medium or slow
    /// (default: the renderer's). The peer always builds at Embree's MEDIUM.
    #[cfg_attr(feature = "cli", arg(long))]
    pub quality: Option<String>,
}

/// Cap of `whitted bench --subdivide` (levels; each multiplies the triangles by 4).
pub const MAX_SUBDIVIDE: u32 = 6;
/// Cap of the triangle count after subdivision (the mesh's count times `4^subdivide`).
pub const MAX_TRIANGLES: u64 = 1 << 25;
/// Cap of `whitted bench --width x --height` (8K is 2^25).
pub const MAX_PIXELS: u64 = 1 << 26;
/// Cap of `whitted bench --random`.
pub const MAX_RANDOM: usize = 1 << 26;

/// Load, subdivide, build, generate and time one mesh (and run the peer on it).
pub fn bench_mesh(path: &Path, opts: &Options) -> crate::Result<Report> {
    let (mesh, _warnings) = crate::io::load_mesh(path)?;
    if opts.subdivide > MAX_SUBDIVIDE
        || (mesh.triangles.len() as u64) << (2 * opts.subdivide.min(MAX_SUBDIVIDE)) > MAX_TRIANGLES
    {
        return Err(crate::Error::Usage(format!(
            "--subdivide {}: over the cap ({MAX_SUBDIVIDE} levels, {MAX_TRIANGLES} triangles)",
            opts.subdivide
        )));
    }
    // 0 (the `Default` of `Options`) means the peer's default size.
    let width = if opts.width == 0 { WIDTH } else { opts.width };
    let height = if opts.height == 0 {
        HEIGHT
    } else {
        opts.height
    };
    if width as u64 * height as u64 > MAX_PIXELS {
        return Err(crate::Error::Usage(format!(
            "--width {width} --height {height}: over the cap of {MAX_PIXELS} pixels"
        )));
    }
    let random = opts.random.unwrap_or(RANDOM_RAYS);
    if random > MAX_RANDOM {
        return Err(crate::Error::Usage(format!(
            "--random {random}: over the cap of {MAX_RANDOM} rays"
        )));
    }
    // (the peak reported covers this mesh from here on: its subdivision, build, workloads
    // and every engine's results, not what earlier meshes of the same run held)
    let peak_reset = reset_peak_resident();
    let mesh = subdivide_like_peer(&mesh, opts.subdivide);
    let tris = triangles(&mesh);
    let threads = opts.threads.max(1);
    let reps = opts.reps.clamp(1, 64);
    let quality = match opts.quality.as_deref() {
        None => BuildQuality::default(),
        Some(q) => BuildQuality::ALL
            .into_iter()
            .find(|b| b.name() == q)
            .ok_or_else(|| {
                crate::Error::Usage(format!(
                    "--quality {q}: expected binned, fast, medium or slow"
                ))
            })?,
    };
    let peer_path = if opts.no_peer {
        Err("not run (--no-peer)".to_string())
    } else {
        find_peer(opts.peer.as_deref())
            .ok_or_else(|| "rt-bench not found (PATH, --peer or WHITTED_PEER)".to_string())
    };
    // Rounds: whitted's build and every engine's pass over every workload, then the peer's
    // run, one timed call each after a warm-up on both sides, `reps` times over. A noisy
    // stretch on a shared machine then falls on both sides' passes alike (timed one side
    // after the other, a burst during whitted's half moved the 1.3M shadow ratio from 1.05
    // to 0.90 between two runs while Embree's figure stayed within 0.5%).
    let mut build = Samples::default();
    let mut collapse = std::time::Duration::MAX;
    let mut measuring = Measuring::default();
    let mut work: Option<Workloads> = None;
    let mut accel = crate::accel::Accel::default();
    let mut peer_runs = peer_path.as_ref().map(|_| vec![]).map_err(Clone::clone);
    let mut peak_resident = None;
    let mut peer_random = random;
    for round in 0..reps {
        // (the previous round's tree and results freed first, as in each timed build; the
        // results are recorded again by this round's passes)
        measuring.forget_results();
        drop(std::mem::take(&mut accel));
        let (a, c) = sample_build(&tris, 1, quality, threads, &mut build);
        accel = a;
        collapse = collapse.min(c);
        let work = work
            .get_or_insert_with(|| Workloads::generate_with(&mesh, &accel, width, height, random));
        measuring.round(&accel, work, threads, 1);
        if round == 0 {
            // (the first round's: a later round's build also runs beside the workloads,
            // which a single build-then-trace does not have)
            peak_resident = peak_resident_bytes();
        }
        if let (Ok(p), Ok(runs)) = (&peer_path, &mut peer_runs) {
            let run =
                |random| run_peer(p, path, threads, opts.subdivide, 1, (width, height), random);
            let mut got = run(peer_random);
            if round == 0 && peer_random > 0 && got.is_err() {
                // an rt-bench older than `--random` refuses the flag: whitted alone on that set
                if let Ok(r) = run(0) {
                    peer_random = 0;
                    got = Ok(r);
                }
            }
            match got {
                Ok((r, _)) => runs.push(r),
                Err(e) => peer_runs = Err(e),
            }
        }
    }
    let work = work.expect("at least one round");
    let measured = measuring.finish();
    let peer = peer_runs.and_then(|runs| merge_peer(&runs));
    let build = build.timing();
    Ok(Report {
        mesh: path.to_path_buf(),
        subdivide: opts.subdivide,
        vertices: mesh.positions.len(),
        triangles: mesh.triangles.len(),
        threads,
        reps,
        framing: work.framing,
        width: work.width,
        height: work.height,
        build,
        wide_bytes: accel.wide.bytes(),
        accel_bytes: accel.bytes(),
        peak_resident,
        peak_reset,
        collapse_ms: collapse.as_secs_f64() * 1e3,
        builder: quality.name(),
        measured,
        peer,
    })
}

/// `whitted bench`: every mesh, tables or one JSON object on stdout.
pub fn run(opts: &Options) -> crate::Result<()> {
    crate::cpu::warn_if_slow_build();
    let mut meshes = opts.meshes.clone();
    if meshes.is_empty() {
        // the kitten, found as a scene file finds it: the current folder, the WHITTED_ASSETS
        // folders, then the copy whitted ships.
        meshes.push(crate::io::scene::SearchPath::for_scene(None).resolve("meshes/kitten.m")?);
    }
    let mut reports = vec![];
    for m in &meshes {
        let r = bench_mesh(m, opts)?;
        if opts.json {
            reports.push(report_json(&r));
        } else {
            println!("{}", format_report(&r));
        }
    }
    if opts.json {
        println!("{}", serde_json::json!({ "whitted_bench": reports }));
    }
    Ok(())
}
