//! The `whitted` command line: parse arguments, load, render, save.

use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::Ordering;
use whitted::io::scene::{MAX_DEPTH, SceneFile, SearchPath, build_scene, check_size};
use whitted::render::{Settings, Stage, World};
use whitted::{Error, Result, scenes};

#[derive(Parser)]
#[command(
    name = "whitted",
    version,
    about = "A data-oriented SIMD Whitted ray tracer over triangle meshes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a built-in scene (phong, vertex_color, texture, cubemap, refraction, demo) or a
    /// scene file; with no scene, the demo (needs no files).
    Render(RenderArgs),
    /// Print a scene as editable TOML: a built-in scene, a .toml file (with `-D` applied), or
    /// the scene `render` gives a mesh file.
    Scene {
        /// phong, vertex_color, texture, cubemap, refraction, demo, a .toml scene file, or a
        /// .m, .obj, .ply, .stl, .gltf or .glb mesh.
        name: String,
        /// Override a scene value by its TOML path before printing (as for `render`).
        #[arg(short = 'D', value_name = "KEY=VALUE")]
        define: Vec<String>,
    },
    /// Describe a built-in scene, a scene file, a mesh, an image or a cube-map folder after
    /// validating it.
    Info {
        /// A built-in scene name, a .toml scene, a .m, .obj, .ply, .stl, .gltf or .glb mesh, an
        /// image, or a cube-map folder.
        file: String,
        /// Print one JSON object instead of `key: value` lines.
        #[arg(long)]
        json: bool,
        /// Override a scene value by its TOML path before validating (scenes only).
        #[arg(short = 'D', value_name = "KEY=VALUE")]
        define: Vec<String>,
    },
    /// Trace a binary ray file against a mesh and write the closest hits (see the README).
    TraceRays(TraceArgs),
    /// Join EXR parts (`render --tile/--crop/--pixel-bounds`) into the image they share, after
    /// checking they cover it exactly.
    Merge(MergeArgs),
    /// Intersection throughput on the Embree peer's workloads, beside rt-bench when found.
    #[command(mut_arg("meshes", |a| a.help(
        "Meshes (.m, .obj, .ply, .stl, .gltf or .glb); default meshes/kitten.m from the current \
         folder, the WHITTED_ASSETS folders or the copy whitted ships"
    )))]
    Bench(whitted::bench::Options),
}

#[derive(clap::Args)]
struct MergeArgs {
    /// The parts, EXR files with the whole image as display window and the part as data window.
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// The merged image, `.exr` or `.png`.
    #[arg(long, short = 'o')]
    outfile: PathBuf,
    /// EXR output in 16-bit floats (implied when every part is 16-bit).
    #[arg(long)]
    half: bool,
    /// EXR compression: piz (default), zip, zips, rle or none (all lossless).
    #[arg(long, default_value = "piz")]
    exr_compression: String,
    /// No summary line.
    #[arg(long, short = 'q')]
    quiet: bool,
}

fn cmd_merge(args: MergeArgs) -> Result<()> {
    let opts = parse_exr_options(args.half, &args.exr_compression)?;
    let start = std::time::Instant::now();
    let display = whitted::io::merge::merge(&args.parts, &args.outfile, opts)?;
    if !args.quiet {
        eprintln!(
            "merged {} parts into {}x{} in {:.2} s -> {}",
            args.parts.len(),
            display.x1,
            display.y1,
            start.elapsed().as_secs_f64(),
            args.outfile.display()
        );
    }
    Ok(())
}

#[derive(clap::Args)]
struct TraceArgs {
    /// The mesh: .m, .obj, .ply, .stl, .gltf or .glb.
    mesh: PathBuf,
    /// Input rays: little-endian f32 `ox oy oz dx dy dz tnear tfar`, 32 bytes each.
    #[arg(long)]
    rays: PathBuf,
    /// Output hits: `u32 triangle, f32 t, f32 b1, f32 b2`, 16 bytes each.
    #[arg(long)]
    hits: PathBuf,
    /// auto (chosen from the rays: how far apart neighbouring directions and origins are),
    /// packet8 (intersect8), wide1 (intersect_wide1, the 8-wide tree), hybrid8
    /// (intersect_hybrid8), packet16 (intersect16, AVX-512), hybrid16 (intersect_hybrid16) or
    /// scalar (intersect1); all write the same bytes. `packet`, `wide` and `hybrid` name the
    /// 8-ray and single-ray engines too.
    #[arg(long, default_value = "auto")]
    engine: String,
    /// Skip back faces.
    #[arg(long)]
    cull: bool,
    /// Midpoint subdivision levels (each x4 triangles; face order: 4 children per face).
    #[arg(long, default_value_t = 0)]
    subdivide: u32,
    /// Worker threads (default: all cores).
    #[arg(long, short = 't', visible_alias = "nthreads")]
    threads: Option<usize>,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Built-in scene name, a `.toml` scene file, or a mesh (`.obj`, `.ply`, `.stl`, `.gltf`,
    /// `.glb`, `.m`) to render alone (framed from the canonical direction, canonical lights or its emitters).
    scene: Option<String>,
    /// Render one stage of the assignment: intersection, diffuse, specular, shadow, reflection.
    #[arg(long)]
    stage: Option<String>,
    /// Image width in pixels (overrides the scene's `[image] width`; default 1024).
    #[arg(long, allow_negative_numbers = true)]
    width: Option<i64>,
    /// Image height in pixels (overrides the scene's `[image] height`; default 768).
    #[arg(long, allow_negative_numbers = true)]
    height: Option<i64>,
    /// Recursion depth for reflection and refraction (overrides the scene and stage).
    #[arg(long, allow_negative_numbers = true)]
    depth: Option<u32>,
    /// Samples per pixel, 1 to 4096 (stratified, deterministic).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    spp: i64,
    /// Worker threads (default: all cores).
    #[arg(long, short = 't', visible_alias = "nthreads")]
    threads: Option<usize>,
    /// Output image, `.png` (sRGB 8-bit) or `.exr` (linear float). Default: SCENE.png.
    #[arg(long, short = 'o')]
    outfile: Option<PathBuf>,
    /// No progress bar and no summary.
    #[arg(long, short = 'q')]
    quiet: bool,
    /// Midpoint-subdivide every mesh K times (x4 triangles per level), to scale the work.
    #[arg(long, default_value_t = 0)]
    subdivide: u32,
    /// auto (wavefront renderer, fastest kernel per queue, default), packet8, wide1, hybrid8,
    /// packet16 or hybrid16 (wavefront, that kernel for every queue; the 16-ray kernels need
    /// AVX-512, else they trace as packet and hybrid) or scalar (the recursive reference).
    #[arg(long, default_value = "auto")]
    engine: String,
    /// Print BVH build time, rays per queue, and time and Mrays/s per phase.
    #[arg(long)]
    stats: bool,
    /// Override a scene value by its TOML path, e.g. `-D camera.vfov=30`,
    /// `-D 'light[0].intensity=[1,1,1]'`, `-D 'light[+]={position=[0,5,5], intensity=[1,1,1]}'`
    /// (appends a light), `-D background.cubemap=textures/cubemap` (replaces the colour);
    /// repeatable, applied in order.
    #[arg(short = 'D', value_name = "KEY=VALUE")]
    define: Vec<String>,
    /// Extra first-hit layers in the EXR beside the beauty image: any of albedo, normal,
    /// depth, id (comma-separated; needs `-o file.exr`).
    #[arg(long, value_name = "LIST")]
    aov: Option<String>,
    /// Render only a crop window, as fractions of the image: x0,x1,y0,y1 or x0 x1 y0 y1
    /// (pbrt's --cropwindow; pixels ceil(width x0)..ceil(width x1), the same in y).
    #[arg(
        long,
        visible_alias = "cropwindow",
        value_name = "X0,X1,Y0,Y1",
        group = "part",
        num_args = 1..=4,
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    crop: Option<Vec<String>>,
    /// Render only these pixels: x0,x1,y0,y1 or x0 x1 y0 y1, exclusive ends (pbrt's
    /// --pixelbounds).
    #[arg(
        long,
        visible_alias = "pixelbounds",
        value_name = "X0,X1,Y0,Y1",
        group = "part",
        num_args = 1..=4,
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    pixel_bounds: Option<Vec<String>>,
    /// Render the I-th (0-based) of N bands of rows, split on the 16-pixel tile grid the same
    /// way for every I (for array jobs; `whitted merge` joins the parts).
    #[arg(long, value_name = "I/N", group = "part")]
    tile: Option<String>,
    /// EXR output in 16-bit floats instead of 32-bit.
    #[arg(long)]
    half: bool,
    /// EXR compression: piz (default), zip, zips, rle or none (all lossless).
    #[arg(long, default_value = "piz")]
    exr_compression: String,
}

impl RenderArgs {
    /// The part of the image asked for (the whole image by default).
    fn part(&self) -> Result<whitted::render::part::Part> {
        use whitted::render::part::Part;
        let part = match (&self.crop, &self.pixel_bounds, &self.tile) {
            (Some(c), _, _) => Part::parse_crop(&c.join(",")),
            (_, Some(p), _) => Part::parse_pixel_bounds(&p.join(",")),
            (_, _, Some(t)) => Part::parse_tile(t),
            _ => Ok(Part::Full),
        };
        part.map_err(Error::Usage)
    }
}

fn parse_exr_options(half: bool, compression: &str) -> Result<whitted::io::output::ExrOptions> {
    use whitted::io::output::{ExrCompression, ExrOptions};
    let compression = ExrCompression::from_name(compression).ok_or_else(|| {
        Error::Usage(format!(
            "unknown EXR compression '{compression}' ({})",
            ExrCompression::NAMES.join(", ")
        ))
    })?;
    Ok(ExrOptions { compression, half })
}

/// `--subdivide k` on meshes of `triangles` in all: refused before anything is allocated when
/// it would pass the scene's triangle cap.
fn check_subdivided_triangles(k: u32, triangles: u64) -> Result<()> {
    use whitted::io::scene::MAX_SCENE_TRIANGLES;
    let made = triangles.saturating_mul(1u64 << (2 * k.min(16)));
    if made > MAX_SCENE_TRIANGLES {
        return Err(Error::Usage(format!(
            "--subdivide {k} would make {made} triangles from {triangles}, over the cap of \
             {MAX_SCENE_TRIANGLES}"
        )));
    }
    Ok(())
}

fn set_threads(threads: Option<usize>) -> Result<()> {
    if let Some(n) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build_global()
            .map_err(|e| Error::Usage(format!("--threads {n}: {e}")))?;
    }
    Ok(())
}

fn parse_engine(name: &str) -> Result<whitted::trace::Engine> {
    whitted::trace::Engine::from_name(name).ok_or_else(|| {
        Error::Usage(format!(
            "unknown engine '{name}' (auto, packet8, wide1, hybrid8, packet16, hybrid16, scalar)"
        ))
    })
}

fn check_subdivide(k: u32) -> Result<()> {
    if k > whitted::io::scene::MAX_SUBDIVIDE {
        return Err(Error::Usage(format!(
            "--subdivide {k} is over the cap of {}",
            whitted::io::scene::MAX_SUBDIVIDE
        )));
    }
    Ok(())
}

fn cmd_trace_rays(args: TraceArgs) -> Result<()> {
    let engine = parse_engine(&args.engine)?;
    check_subdivide(args.subdivide)?;
    set_threads(args.threads)?;
    let (mesh, warnings) = whitted::io::load_mesh(&args.mesh)?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    check_subdivided_triangles(args.subdivide, mesh.triangles.len() as u64)?;
    let mesh = mesh.subdivide(args.subdivide);
    let tris: Vec<[glam::Vec3; 3]> = mesh
        .triangles
        .iter()
        .map(|t| t.map(|i| mesh.positions[i as usize]))
        .collect();
    let accel = whitted::accel::Accel::build(&tris, whitted::accel::BuildQuality::default());
    let rays = whitted::io::rays::read_rays(&args.rays)?;
    let start = std::time::Instant::now();
    let cpu = cpu_time::ProcessTime::now();
    // (auto's choice is timed: it is part of every auto batch)
    let (hits, chosen) = whitted::trace::trace_rays_with(&accel, &rays, engine, args.cull);
    let secs = start.elapsed().as_secs_f64();
    let cpu = cpu.elapsed().as_secs_f64();
    whitted::io::rays::save_hits(&args.hits, &hits)?;
    println!(
        "{} rays, {} hits, {:.3} s, {:.2} Mrays/s, CPU {:.3} s ({} engine, {} triangles, BVH {:.1} ms)",
        rays.len(),
        hits.iter().filter(|h| h.is_some()).count(),
        secs,
        rays.len() as f64 / secs.max(1e-9) / 1e6,
        cpu,
        if engine == chosen {
            chosen.name().to_string()
        } else {
            format!("{} -> {}", engine.name(), chosen.name())
        },
        tris.len(),
        accel.build_time.as_secs_f64() * 1e3
    );
    Ok(())
}

/// `--crop 0,0.5,0,1` as `--crop=0,0.5,0,1`: a comma list is the option's whole value, so the
/// scene after it stays the scene (the space-separated `--crop 0 0.5 0 1` takes four words),
/// and a list starting with a minus sign gets whitted's range error, not clap's.
fn attach_hyphen_values(args: impl Iterator<Item = std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    let mut out: Vec<std::ffi::OsString> = Vec::new();
    for a in args {
        let takes_list = out.last().and_then(|o| o.to_str()).is_some_and(|o| {
            matches!(
                o,
                "--crop" | "--cropwindow" | "--pixel-bounds" | "--pixelbounds"
            )
        });
        match a.to_str() {
            Some(v) if takes_list && v.contains(',') => {
                let flag = out.pop().expect("the flag");
                out.push(format!("{}={v}", flag.to_string_lossy()).into());
            }
            _ => out.push(a),
        }
    }
    out
}

fn main() -> ExitCode {
    whitted::accel::pages::keep_freed_memory();
    let cli = Cli::parse_from(attach_hyphen_values(std::env::args_os()));
    whitted::cpu::warn_if_slow_build();
    let result = match cli.command {
        Command::Render(args) => cmd_render(args),
        Command::Scene { name, define } => cmd_scene(&name, &define),
        Command::Info { file, json, define } => whitted::info::print(&file, &define, json),
        Command::TraceRays(args) => cmd_trace_rays(args),
        Command::Merge(args) => cmd_merge(args),
        Command::Bench(opts) => whitted::bench::run(&opts),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// A built-in scene by name, or a scene file; returns it with its path (for messages) and
/// the folder its relative paths start from.
fn load_scene_file(arg: &str) -> Result<(SceneFile, PathBuf, Option<PathBuf>)> {
    if let Some(s) = scenes::builtin(arg) {
        return Ok((s, PathBuf::from(format!("<built-in scene {arg}>")), None));
    }
    let path = PathBuf::from(arg);
    if !arg.ends_with(".toml") && !path.exists() {
        return Err(Error::Usage(format!(
            "'{arg}' is neither a built-in scene ({}) nor a .toml file",
            scenes::NAMES.join(", ")
        )));
    }
    let file = SceneFile::load(&path)?;
    let dir = path.parent().map(Path::to_path_buf);
    Ok((file, path, dir))
}

fn cmd_scene(name: &str, define: &[String]) -> Result<()> {
    if whitted::io::mesh_scene::is_mesh_file(Path::new(name)) {
        let (s, warnings) = whitted::io::mesh_scene::scene_for_mesh(Path::new(name), 1024, 768)?;
        for w in warnings {
            eprintln!("warning: {w}");
        }
        let s = s.with_overrides(define)?;
        let materials = if s.materials.is_empty() {
            "Materials: none in the file, so whitted's default material."
        } else {
            "Materials: the file's, mapped from MTL."
        };
        print!(
            "# whitted scene for the mesh '{name}': `whitted render {name}` renders this.\n# Lights: the canonical ones scaled to the model, or none when its materials emit\n# (emitters light the scene themselves). {materials}\n{}",
            s.to_toml()
        );
        return Ok(());
    }
    let (s, _, _) = load_scene_file(name)?;
    let s = s.with_overrides(define)?;
    print!(
        "# whitted scene '{name}'. Relative paths resolve against this file's folder, the\n# current folder, the folders of WHITTED_ASSETS, then whitted's own data folder.\n{}",
        s.to_toml()
    );
    Ok(())
}

fn cmd_render(args: RenderArgs) -> Result<()> {
    let name = args.scene.clone().unwrap_or_else(|| "demo".into());
    let size_arg = |flag: &str, v: Option<i64>| match v {
        Some(n) if n <= 0 => Err(Error::Usage(format!(
            "{flag} {n}: the image size must be > 0 pixels"
        ))),
        v => Ok(v.map(|n| n as u64)),
    };
    let (width, height) = (
        size_arg("--width", args.width)?,
        size_arg("--height", args.height)?,
    );
    let (file, path, dir) = if whitted::io::mesh_scene::is_mesh_file(Path::new(&name)) {
        // A mesh alone: framed for the requested size; build_scene reports the warnings.
        let size = (width.unwrap_or(1024), height.unwrap_or(768));
        check_size(size.0, size.1).map_err(|m| Error::Usage(format!("--width/--height: {m}")))?;
        let (file, _) = whitted::io::mesh_scene::scene_for_mesh(Path::new(&name), size.0, size.1)?;
        (file, PathBuf::from(&name), None)
    } else {
        load_scene_file(&name)?
    };
    let mut file = file.with_overrides(&args.define)?;
    if let Some(w) = width {
        file.image.width = w;
    }
    if let Some(h) = height {
        file.image.height = h;
    }
    let (w, h) = if args.width.is_some() || args.height.is_some() {
        check_size(file.image.width, file.image.height)
            .map_err(|m| Error::Usage(format!("--width/--height: {m}")))?
    } else {
        file.image_size(&path)
            .map_err(|e| whitted::io::scene::name_overrides(e, &args.define))?
    };
    let stage = match &args.stage {
        None => None,
        Some(s) => Some(Stage::from_name(s).ok_or_else(|| {
            Error::Usage(format!(
                "unknown stage '{s}' (intersection, diffuse, specular, shadow, reflection)"
            ))
        })?),
    };
    if let Some(d) = args.depth
        && d > MAX_DEPTH
    {
        return Err(Error::Usage(format!(
            "--depth {d} is over the cap of {MAX_DEPTH}"
        )));
    }
    if !(1..=4096).contains(&args.spp) {
        return Err(Error::Usage(format!(
            "--spp {}: samples per pixel must be in 1..=4096",
            args.spp
        )));
    }
    let spp = args.spp as u32;
    let out = args.outfile.clone().unwrap_or_else(|| {
        let stem = Path::new(&name)
            .file_stem()
            .map_or("render".into(), |s| s.to_string_lossy().into_owned());
        PathBuf::from(format!("{stem}.png"))
    });
    if !matches!(
        out.extension().and_then(|e| e.to_str()),
        Some("png" | "exr" | "PNG" | "EXR")
    ) {
        return Err(Error::Usage(format!(
            "{}: output must be .png or .exr",
            out.display()
        )));
    }
    let aovs = match &args.aov {
        None => None,
        Some(list) => {
            let aovs = whitted::aov::Aov::parse_list(list)
                .map_err(|m| Error::Usage(format!("--aov {list}: {m}")))?;
            if whitted::io::extension(&out) != "exr" {
                return Err(Error::Usage(format!(
                    "--aov {list}: AOV layers are written into an EXR beside the beauty image; {} is not .exr (use -o {}.exr)",
                    out.display(),
                    out.with_extension("").display()
                )));
            }
            Some(aovs)
        }
    };
    check_subdivide(args.subdivide)?;
    let engine = parse_engine(&args.engine)?;
    set_threads(args.threads)?;

    let part_arg = args.part()?;
    let part = part_arg.bounds(w, h).map_err(Error::Usage)?;
    let exr = parse_exr_options(args.half, &args.exr_compression)?;
    // A value set by -D names the argument too.
    let load_start = std::time::Instant::now();
    let (mut scene, warnings) = build_scene(&file, &path, &SearchPath::for_scene(dir.as_deref()))
        .map_err(|e| whitted::io::scene::name_overrides(e, &args.define))?;
    check_subdivided_triangles(args.subdivide, scene.stored_triangle_count() as u64)?;
    for o in &mut scene.objects {
        o.mesh = o.mesh.subdivide(args.subdivide);
    }
    for w in warnings {
        eprintln!("warning: {w}");
    }
    let settings = Settings {
        stage,
        depth: args.depth,
        spp,
        engine,
    };
    let load_time = load_start.elapsed();
    let world = World::new(scene);
    // what is rendered: the image, or a part of it
    let what = if part_arg.is_full() {
        format!("{w}x{h} {name}")
    } else {
        format!(
            "{}x{} part ({part}) of {w}x{h} {name}",
            part.width(),
            part.height()
        )
    };
    let bar = if args.quiet {
        ProgressBar::hidden()
    } else {
        let b = ProgressBar::new(part.area());
        let prefix = if part_arg.is_full() {
            String::new()
        } else {
            format!("part {part} ")
        };
        b.set_style(
            ProgressStyle::with_template(&format!(
                "{{spinner}} {prefix}[{{elapsed_precise}}] {{wide_bar}} {{percent}}% ETA {{eta}}"
            ))
            .expect("template"),
        );
        b
    };
    // Rows stream into the file as bands finish, AOV layers (if any) captured band by band
    // beside them; a failed render leaves no file behind.
    let times = whitted::io::output::OutputTimes::default();
    let capture = |b| whitted::render::aov::capture_part(&world, aovs.as_deref().unwrap_or(&[]), b);
    let aov_source = aovs.as_deref().map(|aovs| whitted::io::output::AovSource {
        aovs,
        capture: &capture,
    });
    let mut stats = None;
    let write_start = std::time::Instant::now();
    let wrote = whitted::io::output::write_streamed_with(
        &out,
        (w, h),
        part,
        exr,
        aov_source.as_ref(),
        &times,
        &mut |sink| {
            let s = whitted::render::render_rows(&world, &settings, part, &|n| bar.inc(n), sink)?;
            let over = s.budget_error(&world, &settings);
            stats = Some(s);
            match over {
                None => Ok(()),
                Some(msg) => Err(Error::scene(&path, msg)),
            }
        },
    );
    bar.finish_and_clear();
    wrote?;
    let stats = stats.expect("the render ran");
    let write_wall = write_start.elapsed();
    if !args.quiet {
        let r = &stats.rays;
        let total = r.total();
        let secs = stats.time.as_secs_f64();
        eprintln!(
            "{what} in {:.2} s (BVH {:.1} ms, {} triangles): {} rays (primary {}, shadow {}, reflection {}, refraction {}), {:.2} Mrays/s -> {}",
            secs,
            world.build_time().as_secs_f64() * 1e3,
            world.triangles(),
            total,
            r.primary.load(Ordering::Relaxed),
            r.shadow.load(Ordering::Relaxed),
            r.reflection.load(Ordering::Relaxed),
            r.refraction.load(Ordering::Relaxed),
            total as f64 / secs / 1e6,
            out.display()
        );
    }
    if args.stats {
        print!(
            "{}",
            whitted::render::report::stats_text(&world, &stats, engine)
        );
        print_times(load_time, &stats, &times, write_wall);
    }
    Ok(())
}

/// `--stats`, where the time went: loading (scene file, meshes, textures), rendering, and the
/// output's thread time (layout and compression, AOV capture, writing) and the wall time it
/// added after the render's last band.
fn print_times(
    load: std::time::Duration,
    stats: &whitted::render::RenderStats,
    times: &whitted::io::output::OutputTimes,
    write_wall: std::time::Duration,
) {
    let secs = |a: &std::sync::atomic::AtomicU64| a.load(Ordering::Relaxed) as f64 * 1e-9;
    println!(
        "load              {:.1} ms (scene, meshes, textures)",
        load.as_secs_f64() * 1e3
    );
    println!(
        "trace/shade       {:.3} s wall (the render, output overlapping it)",
        stats.time.as_secs_f64()
    );
    println!(
        "output            {:.3} thread-s layout+compression, {:.3} AOVs, {:.3} writing; {:.3} s wall after the last band",
        secs(&times.encode_ns),
        secs(&times.aov_ns),
        secs(&times.write_ns),
        write_wall.saturating_sub(stats.time).as_secs_f64()
    );
}
