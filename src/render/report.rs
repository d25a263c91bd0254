//! `whitted render --stats`: where a render's time went, as text.

use super::RenderStats;
use crate::engine::Engine;
use crate::world::World;
use std::fmt::Write;
use std::sync::atomic::Ordering;

/// `writeln!` into a `String`, which cannot fail.
macro_rules! w {
    ($out:expr, $($arg:tt)*) => {{
        let _ = writeln!($out, $($arg)*);
    }};
}

/// `--stats`: BVH build, rays per queue, time and Mrays/s per phase (thread time, summed over
/// worker threads, so per-phase Mrays/s is per thread), total.
pub fn stats_text(world: &World, stats: &RenderStats, engine: Engine) -> String {
    let mut out = String::new();
    let r = &stats.rays;
    let load = |a: &std::sync::atomic::AtomicU64| a.load(Ordering::Relaxed);
    let (primary, shadow, refl, refr) = (
        load(&r.primary),
        load(&r.shadow),
        load(&r.reflection),
        load(&r.refraction),
    );
    w!(out, "engine            {engine:?}");
    match &world.instanced {
        None => w!(
            out,
            "BVH build         {:.1} ms ({} triangles, depth {})",
            world.accel.build_time.as_secs_f64() * 1e3,
            world.accel.tris.len(),
            world.accel.depth
        ),
        Some(i) => w!(
            out,
            "BVH build         {:.1} ms ({} triangles in {} instances of {} meshes, {} stored; top level {} nodes)",
            i.build_time.as_secs_f64() * 1e3,
            i.tracer.triangles,
            i.tracer.instances.len(),
            i.tracer.meshes.len(),
            i.geometries
                .iter()
                .map(|g| g.triangles.len())
                .sum::<usize>(),
            i.tracer.top_nodes()
        ),
    }
    w!(
        out,
        "rays              primary {primary}, shadow {shadow}, reflection {refl}, refraction {refr}"
    );
    let (repeated, repeated_shadow) = (load(&r.repeated), load(&r.repeated_shadow));
    if repeated > 0 {
        w!(
            out,
            "repeated rays     {repeated} reflection and refraction, {repeated_shadow} shadow: each is another ray bit for bit and takes its answer untraced"
        );
    }
    if engine != Engine::Scalar {
        let rays_of = [primary, primary + refl + refr, shadow, refl + refr];
        for (k, name) in RenderStats::PHASES.iter().enumerate() {
            let secs = load(&stats.phase_ns[k]) as f64 * 1e-9;
            let what = if *name == "shade" {
                "hits+misses shaded"
            } else {
                "rays"
            };
            w!(
                out,
                "phase {name:<11} {secs:8.3} thread-s  {:8.2} M{what}/thread-s",
                rays_of[k] as f64 / secs.max(1e-12) / 1e6
            );
        }
    } else {
        w!(
            out,
            "phases            (only the wavefront engines time their phases)"
        );
    }
    let secs = stats.time.as_secs_f64();
    w!(
        out,
        "total             {secs:.3} s wall, {:.2} Mrays/s",
        r.total() as f64 / secs.max(1e-12) / 1e6
    );
    out
}
