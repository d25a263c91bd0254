//! `whitted._whitted`: the native half of the Python package. The Python half
//! (`python/whitted/__init__.py`) checks shapes and dtypes, flattens the arrays and names the
//! arguments in its errors; this half takes flat contiguous arrays, releases the GIL and runs
//! whitted's engines on a rayon pool of the requested size.

use glam::Vec3;
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, OnceLock};
use whitted::accel::{Accel, BuildQuality};
use whitted::ray::Ray;
use whitted::trace::{self, Engine, trace_rays};
use whitted::{Error, query};

/// Open3D's marker for "no geometry / no primitive".
const INVALID_ID: u32 = u32::MAX;

fn value_error(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// A whitted error as a Python exception: files the system refused to read are `OSError`,
/// the rest `ValueError`; `what` (an argument's name) leads the message.
fn whitted_error(what: &str, e: Error) -> PyErr {
    let msg = format!("{what}: {e}");
    match e {
        Error::Io { .. } => PyOSError::new_err(msg),
        _ => PyValueError::new_err(msg),
    }
}

/// Run `f` on a pool of `nthreads` threads (0: rayon's global pool, one per core). Pools are
/// kept per size, so repeated calls do not start threads each time.
fn on_pool<T: Send>(nthreads: usize, f: impl FnOnce() -> T + Send) -> PyResult<T> {
    if nthreads == 0 {
        return Ok(f());
    }
    static POOLS: OnceLock<Mutex<HashMap<usize, Arc<rayon::ThreadPool>>>> = OnceLock::new();
    let pool = {
        let mut pools = POOLS
            .get_or_init(Default::default)
            .lock()
            .unwrap_or_else(|p| p.into_inner());
        match pools.get(&nthreads) {
            Some(p) => p.clone(),
            None => {
                let p = rayon::ThreadPoolBuilder::new()
                    .num_threads(nthreads)
                    .build()
                    .map(Arc::new)
                    .map_err(|e| value_error(format!("nthreads: {e}")))?;
                pools.insert(nthreads, p.clone());
                p
            }
        }
    };
    Ok(pool.install(f))
}

/// The engine for a batch: the one named, or with `""` whitted's `Auto`, which chooses once
/// per batch from the rays ([`batch_engine`]; `whitted::engine`: 16-ray packets for beams
/// such as camera rays, the hybrid for rays scattered from nearby origins, one ray at a
/// time down the 8-wide tree for rays from anywhere in any direction).
fn pick_engine(name: &str) -> PyResult<Engine> {
    if name.is_empty() {
        Ok(Engine::Auto)
    } else {
        engine_named(name)
    }
}

fn engine_named(name: &str) -> PyResult<Engine> {
    Engine::from_name(name).ok_or_else(|| {
        value_error(format!(
            "engine: unknown engine '{name}' ({})",
            Engine::ALL.map(Engine::name).join(", ")
        ))
    })
}

/// Rays per parallel work item of the ray queries (a multiple of 16, as the engines' own).
const CHUNK: usize = 4096;

/// An output column of `n` entries, on huge pages where the kernel has them, filled with
/// `fill` by the pool's threads (which also take the pages' first-touch faults). Faulting
/// the columns in on 4 KiB pages (2M camera rays: 64 MB, 16,000 faults) held `cast_rays`
/// on two threads to 1.33x one; filling them on one thread, even on huge pages, still left
/// 2M camera rays at about 72 Mrays/s on two threads against about 91 filled in parallel
/// (AMD EPYC Zen 5, 2026-12-07, medians of 11 calls in alternating runs).
fn column<T: Clone + Send + Sync>(n: usize, fill: T) -> Vec<T> {
    use rayon::prelude::*;
    let mut v = Vec::with_capacity(n);
    whitted::accel::pages::advise_huge(&v);
    // filled by the pool's threads, which also take the pages' first-touch faults
    v.par_extend(rayon::iter::repeat_n(fill, n));
    v
}

/// The ray of one `[ox, oy, oz, dx, dy, dz]` row, accepting `tnear < t < tfar`.
#[inline(always)]
fn row_ray(r: &[f32], tnear: f32, tfar: f32) -> Ray {
    Ray::new(
        Vec3::new(r[0], r[1], r[2]),
        Vec3::new(r[3], r[4], r[5]),
        tnear,
        tfar,
    )
}

/// Rays from `[ox, oy, oz, dx, dy, dz]` rows, accepting `tnear < t < tfar`.
fn rays_of(flat: &[f32], tnear: f32, tfar: f32) -> Vec<Ray> {
    flat.chunks_exact(6)
        .map(|r| row_ray(r, tnear, tfar))
        .collect()
}

/// The rows of `flat` as rays into `buf` (cleared first): a chunk's rays, made in a buffer
/// the worker thread reuses from chunk to chunk.
fn fill_rays(buf: &mut Vec<Ray>, flat: &[f32], tnear: f32, tfar: f32) {
    buf.clear();
    buf.extend(flat.chunks_exact(6).map(|r| row_ray(r, tnear, tfar)));
}

/// The engine for a whole batch of rows (`auto`'s choice made once, with its pilot on a
/// large batch, on a thread of the current pool), which every chunk then traces with.
fn batch_engine(
    engine: Engine,
    accel: &Accel,
    flat: &[f32],
    tnear: f32,
    tfar: f32,
    any_hit: bool,
) -> Engine {
    let ray_at = |i: usize| row_ray(&flat[6 * i..6 * i + 6], tnear, tfar);
    rayon::scope(|_| trace::resolve_by(engine, accel, flat.len() / 6, ray_at, any_hit, false))
}

fn points_of(flat: &[f32]) -> Vec<Vec3> {
    flat.chunks_exact(3)
        .map(|p| Vec3::new(p[0], p[1], p[2]))
        .collect()
}

/// Triangles of several geometries in one BVH. Triangle `i` of the concatenation belongs to
/// the geometry whose range `start[g]..start[g + 1]` holds it.
#[pyclass(module = "whitted._whitted")]
struct Raycaster {
    tris: Vec<[Vec3; 3]>,
    /// Unit geometric normal per triangle, `cross(v1 - v0, v2 - v0)` normalised (0 when
    /// degenerate), as Open3D reports it.
    normals: Vec<[f32; 3]>,
    /// First triangle of each geometry.
    start: Vec<u32>,
    /// The BVH over `tris`, built at the first query after a change.
    accel: Option<Arc<Accel>>,
}

impl Raycaster {
    fn accel(&mut self, py: Python<'_>) -> Arc<Accel> {
        if self.accel.is_none() {
            let tris = &self.tris;
            self.accel = Some(Arc::new(
                py.detach(|| Accel::build(tris, BuildQuality::Binned)),
            ));
        }
        self.accel.clone().unwrap_or_default()
    }

    /// `(geometry id, primitive id)` of concatenated triangle `tri`.
    fn ids(start: &[u32], tri: u32) -> (u32, u32) {
        let g = start.partition_point(|&s| s <= tri) - 1;
        (g as u32, tri - start[g])
    }

    fn add(&mut self, positions: &[Vec3], triangles: &[[u32; 3]]) -> u32 {
        self.start.push(self.tris.len() as u32);
        for t in triangles {
            let v = t.map(|i| positions[i as usize]);
            let n = (v[1] - v[0]).cross(v[2] - v[0]).normalize_or_zero();
            self.tris.push(v);
            self.normals.push(n.to_array());
        }
        self.accel = None;
        (self.start.len() - 1) as u32
    }
}

type Arr<'py, T> = Bound<'py, PyArray1<T>>;

#[pymethods]
impl Raycaster {
    #[new]
    fn new() -> Self {
        Raycaster {
            tris: Vec::new(),
            normals: Vec::new(),
            start: Vec::new(),
            accel: None,
        }
    }

    /// Add a geometry from flat `vertices` (`3 n` floats) and `triangles` (`3 m` indices);
    /// returns its id.
    fn add_triangles(
        &mut self,
        vertices: PyReadonlyArray1<'_, f32>,
        triangles: PyReadonlyArray1<'_, u32>,
    ) -> PyResult<u32> {
        let v = vertices.as_slice()?;
        let t = triangles.as_slice()?;
        if v.len() % 3 != 0 || t.len() % 3 != 0 {
            return Err(value_error(
                "vertices and triangles must hold whole rows of 3",
            ));
        }
        if let Some(i) = v.iter().position(|x| !x.is_finite()) {
            return Err(value_error(format!(
                "vertices: vertex {} has a non-finite coordinate ({})",
                i / 3,
                v[i]
            )));
        }
        let n = (v.len() / 3) as u32;
        if let Some(i) = t.iter().position(|&x| x >= n) {
            return Err(value_error(format!(
                "triangles: triangle {} names vertex {}, but there are {n} vertices",
                i / 3,
                t[i]
            )));
        }
        if self.tris.len() + t.len() / 3 >= INVALID_ID as usize {
            return Err(value_error("triangles: too many triangles in one scene"));
        }
        let positions = points_of(v);
        let tris: Vec<[u32; 3]> = t.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Ok(self.add(&positions, &tris))
    }

    /// Add the mesh in a file whitted reads (`.m`, `.obj`, `.ply`, `.stl`, `.gltf`, `.glb`);
    /// returns its id and the loader's warnings.
    fn add_mesh(&mut self, py: Python<'_>, path: PathBuf) -> PyResult<(u32, Vec<String>)> {
        let (mesh, warnings) = py
            .detach(|| whitted::io::load_mesh(&path))
            .map_err(|e| whitted_error("path", e))?;
        if self.tris.len() + mesh.triangles.len() >= INVALID_ID as usize {
            return Err(value_error("path: too many triangles in one scene"));
        }
        Ok((self.add(&mesh.positions, &mesh.triangles), warnings))
    }

    /// Number of geometries.
    fn geometry_count(&self) -> usize {
        self.start.len()
    }

    /// Number of triangles over all geometries.
    fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// Closest hits: `(t_hit, geometry_ids, primitive_ids, primitive_uvs, primitive_normals)`
    /// flat, misses as Open3D gives them (`inf`, `INVALID_ID`, zeros).
    #[allow(clippy::type_complexity)]
    #[pyo3(signature = (rays, nthreads=0, engine=""))]
    fn cast_rays<'py>(
        &mut self,
        py: Python<'py>,
        rays: PyReadonlyArray1<'py, f32>,
        nthreads: usize,
        engine: &str,
    ) -> PyResult<(
        Arr<'py, f32>,
        Arr<'py, u32>,
        Arr<'py, u32>,
        Arr<'py, f32>,
        Arr<'py, f32>,
    )> {
        let flat = rays.as_slice()?;
        let engine = pick_engine(engine)?;
        let accel = self.accel(py);
        let (start, normals) = (&self.start, &self.normals);
        let out = py.detach(|| {
            on_pool(nthreads, || {
                use rayon::prelude::*;
                let n = flat.len() / 6;
                let engine = batch_engine(engine, &accel, flat, 0.0, f32::INFINITY, false);
                let mut t = column(n, f32::INFINITY);
                let mut g = column(n, INVALID_ID);
                let mut p = column(n, INVALID_ID);
                let mut uv = column(2 * n, 0f32);
                let mut nrm = column(3 * n, 0f32);
                // chunk by chunk: the chunk's rays and hits stay in cache between the
                // conversion, the engine and the scatter into the output columns
                t.par_chunks_mut(CHUNK)
                    .zip(g.par_chunks_mut(CHUNK))
                    .zip(p.par_chunks_mut(CHUNK))
                    .zip(uv.par_chunks_mut(2 * CHUNK))
                    .zip(nrm.par_chunks_mut(3 * CHUNK))
                    .zip(flat.par_chunks(6 * CHUNK))
                    .for_each_init(
                        || (Vec::with_capacity(CHUNK), Vec::with_capacity(CHUNK)),
                        |(rays, hits), (((((t, g), p), uv), nrm), rows)| {
                            fill_rays(rays, rows, 0.0, f32::INFINITY);
                            hits.resize(rays.len(), None);
                            trace::intersect_into(&accel, rays, engine, false, hits);
                            for (i, h) in hits.iter().enumerate() {
                                if let Some(h) = h {
                                    t[i] = h.t;
                                    (g[i], p[i]) = Raycaster::ids(start, h.tri);
                                    uv[2 * i..2 * i + 2].copy_from_slice(&[h.b1, h.b2]);
                                    nrm[3 * i..3 * i + 3].copy_from_slice(&normals[h.tri as usize]);
                                }
                            }
                        },
                    );
                (t, g, p, uv, nrm)
            })
        })?;
        Ok((
            out.0.into_pyarray(py),
            out.1.into_pyarray(py),
            out.2.into_pyarray(py),
            out.3.into_pyarray(py),
            out.4.into_pyarray(py),
        ))
    }

    /// Whether each ray hits anything with `tnear < t < tfar`.
    #[pyo3(signature = (rays, tnear=0.0, tfar=f32::INFINITY, nthreads=0, engine=""))]
    fn test_occlusions<'py>(
        &mut self,
        py: Python<'py>,
        rays: PyReadonlyArray1<'py, f32>,
        tnear: f32,
        tfar: f32,
        nthreads: usize,
        engine: &str,
    ) -> PyResult<Arr<'py, bool>> {
        let flat = rays.as_slice()?;
        let engine = pick_engine(engine)?;
        let accel = self.accel(py);
        let out = py.detach(|| {
            on_pool(nthreads, || {
                use rayon::prelude::*;
                let engine = batch_engine(engine, &accel, flat, tnear, tfar, true);
                let mut out = vec![false; flat.len() / 6];
                out.par_chunks_mut(CHUNK)
                    .zip(flat.par_chunks(6 * CHUNK))
                    .for_each_init(Vec::new, |rays, (out, rows)| {
                        fill_rays(rays, rows, tnear, tfar);
                        trace::occluded_into(&accel, rays, engine, false, out);
                    });
                out
            })
        })?;
        Ok(out.into_pyarray(py))
    }

    /// Closest hits as whitted's engines return them: `(t, triangle, b1, b2)`, the triangle
    /// indexing the concatenation of all geometries (`INVALID_ID` and `inf` on misses).
    #[allow(clippy::type_complexity)]
    #[pyo3(signature = (rays, engine="auto", nthreads=0))]
    fn trace<'py>(
        &mut self,
        py: Python<'py>,
        rays: PyReadonlyArray1<'py, f32>,
        engine: &str,
        nthreads: usize,
    ) -> PyResult<(Arr<'py, f32>, Arr<'py, u32>, Arr<'py, f32>, Arr<'py, f32>)> {
        let engine = engine_named(engine)?;
        let accel = self.accel(py);
        let flat = rays.as_slice()?;
        let hits = py.detach(|| {
            on_pool(nthreads, || {
                trace_rays(&accel, &rays_of(flat, 0.0, f32::INFINITY), engine, false)
            })
        })?;
        let t = hits.iter().map(|h| h.map_or(f32::INFINITY, |h| h.t));
        let tri = hits.iter().map(|h| h.map_or(INVALID_ID, |h| h.tri));
        let b1 = hits.iter().map(|h| h.map_or(0.0, |h| h.b1));
        let b2 = hits.iter().map(|h| h.map_or(0.0, |h| h.b2));
        Ok((
            t.collect::<Vec<_>>().into_pyarray(py),
            tri.collect::<Vec<_>>().into_pyarray(py),
            b1.collect::<Vec<_>>().into_pyarray(py),
            b2.collect::<Vec<_>>().into_pyarray(py),
        ))
    }

    /// How many triangles each ray hits at `t > 0`.
    #[pyo3(signature = (rays, nthreads=0))]
    fn count_intersections<'py>(
        &mut self,
        py: Python<'py>,
        rays: PyReadonlyArray1<'py, f32>,
        nthreads: usize,
    ) -> PyResult<Arr<'py, i32>> {
        let accel = self.accel(py);
        let flat = rays.as_slice()?;
        let out = py.detach(|| {
            on_pool(nthreads, || {
                use rayon::prelude::*;
                rays_of(flat, 0.0, f32::INFINITY)
                    .par_iter()
                    .map(|r| query::count_hits(&accel, r) as i32)
                    .collect::<Vec<i32>>()
            })
        })?;
        Ok(out.into_pyarray(py))
    }

    /// Every hit at `t > 0`, sorted by `t` within each ray: `(ray_splits, ray_ids, t_hit,
    /// geometry_ids, primitive_ids, primitive_uvs)`, flat.
    #[allow(clippy::type_complexity)]
    #[pyo3(signature = (rays, nthreads=0))]
    fn list_intersections<'py>(
        &mut self,
        py: Python<'py>,
        rays: PyReadonlyArray1<'py, f32>,
        nthreads: usize,
    ) -> PyResult<(
        Arr<'py, u32>,
        Arr<'py, u32>,
        Arr<'py, f32>,
        Arr<'py, u32>,
        Arr<'py, u32>,
        Arr<'py, f32>,
    )> {
        let accel = self.accel(py);
        let flat = rays.as_slice()?;
        let start = &self.start;
        let out = py.detach(|| {
            on_pool(nthreads, || {
                use rayon::prelude::*;
                let per_ray: Vec<Vec<query::AnyHit>> = rays_of(flat, 0.0, f32::INFINITY)
                    .par_iter()
                    .map(|r| query::all_hits(&accel, r))
                    .collect();
                let total: usize = per_ray.iter().map(Vec::len).sum();
                let mut splits = Vec::with_capacity(per_ray.len() + 1);
                let (mut ids, mut t, mut g, mut p, mut uv) = (
                    Vec::with_capacity(total),
                    Vec::with_capacity(total),
                    Vec::with_capacity(total),
                    Vec::with_capacity(total),
                    Vec::with_capacity(2 * total),
                );
                splits.push(0u32);
                for (i, hits) in per_ray.iter().enumerate() {
                    for h in hits {
                        let (gi, pi) = Raycaster::ids(start, h.tri);
                        ids.push(i as u32);
                        t.push(h.t);
                        g.push(gi);
                        p.push(pi);
                        uv.extend([h.b1, h.b2]);
                    }
                    splits.push(t.len() as u32);
                }
                (splits, ids, t, g, p, uv)
            })
        })?;
        Ok((
            out.0.into_pyarray(py),
            out.1.into_pyarray(py),
            out.2.into_pyarray(py),
            out.3.into_pyarray(py),
            out.4.into_pyarray(py),
            out.5.into_pyarray(py),
        ))
    }

    /// Nearest surface points: `(points, geometry_ids, primitive_ids, primitive_uvs,
    /// primitive_normals, distance)`, flat; NaN points give NaN and `INVALID_ID`.
    #[allow(clippy::type_complexity)]
    #[pyo3(signature = (points, nthreads=0))]
    fn compute_closest_points<'py>(
        &mut self,
        py: Python<'py>,
        points: PyReadonlyArray1<'py, f32>,
        nthreads: usize,
    ) -> PyResult<(
        Arr<'py, f32>,
        Arr<'py, u32>,
        Arr<'py, u32>,
        Arr<'py, f32>,
        Arr<'py, f32>,
        Arr<'py, f32>,
    )> {
        let accel = self.accel(py);
        let flat = points.as_slice()?;
        let (start, normals) = (&self.start, &self.normals);
        let out = py.detach(|| {
            on_pool(nthreads, || {
                use rayon::prelude::*;
                let found: Vec<Option<query::Closest>> = points_of(flat)
                    .par_iter()
                    .map(|&p| query::closest_point(&accel, p))
                    .collect();
                let n = found.len();
                let (mut q, mut g, mut pr, mut uv, mut nrm, mut d) = (
                    Vec::with_capacity(3 * n),
                    Vec::with_capacity(n),
                    Vec::with_capacity(n),
                    Vec::with_capacity(2 * n),
                    Vec::with_capacity(3 * n),
                    Vec::with_capacity(n),
                );
                for c in &found {
                    match c {
                        Some(c) => {
                            let (gi, pi) = Raycaster::ids(start, c.tri);
                            q.extend(c.point.to_array());
                            g.push(gi);
                            pr.push(pi);
                            uv.extend([c.b1, c.b2]);
                            nrm.extend(normals[c.tri as usize]);
                            d.push(c.dist2.sqrt() as f32);
                        }
                        None => {
                            q.extend([f32::NAN; 3]);
                            g.push(INVALID_ID);
                            pr.push(INVALID_ID);
                            uv.extend([0.0; 2]);
                            nrm.extend([0.0; 3]);
                            d.push(f32::NAN);
                        }
                    }
                }
                (q, g, pr, uv, nrm, d)
            })
        })?;
        Ok((
            out.0.into_pyarray(py),
            out.1.into_pyarray(py),
            out.2.into_pyarray(py),
            out.3.into_pyarray(py),
            out.4.into_pyarray(py),
            out.5.into_pyarray(py),
        ))
    }

    /// Whether each point is inside, by a majority of `nsamples` ray parity votes
    /// (`whitted::query::inside`).
    #[pyo3(signature = (points, nthreads=0, nsamples=3))]
    fn compute_inside<'py>(
        &mut self,
        py: Python<'py>,
        points: PyReadonlyArray1<'py, f32>,
        nthreads: usize,
        nsamples: u32,
    ) -> PyResult<Arr<'py, bool>> {
        let accel = self.accel(py);
        let flat = points.as_slice()?;
        let out = py.detach(|| {
            on_pool(nthreads, || {
                use rayon::prelude::*;
                points_of(flat)
                    .par_iter()
                    .map(|&p| query::inside(&accel, p, nsamples))
                    .collect::<Vec<bool>>()
            })
        })?;
        Ok(out.into_pyarray(py))
    }
}

/// A scene ready to render: a built-in name, a TOML scene file or a mesh file, with `-D`
/// style overrides applied (`Scene` of the Rust front door).
#[pyclass(module = "whitted._whitted", name = "Scene")]
struct PyScene {
    scene: whitted::Scene,
    /// The loaders' warnings.
    #[pyo3(get)]
    warnings: Vec<String>,
    /// What was loaded (name or path).
    #[pyo3(get)]
    source: String,
}

#[pymethods]
impl PyScene {
    #[new]
    #[pyo3(signature = (source, defines=Vec::new()))]
    fn new(py: Python<'_>, source: &str, defines: Vec<String>) -> PyResult<Self> {
        use whitted::io::scene::{SceneFile, SearchPath, build_scene};
        let load = || -> whitted::Result<(whitted::Scene, Vec<String>)> {
            let path = Path::new(source);
            let (file, label, dir, mut warnings) =
                if let Some(file) = whitted::scenes::builtin(source) {
                    let label = PathBuf::from(format!("<built-in scene {source}>"));
                    (file, label, None, Vec::new())
                } else if whitted::io::mesh_scene::is_mesh_file(path) {
                    let (file, w) = whitted::io::mesh_scene::scene_for_mesh(path, 1024, 768)?;
                    (file, path.to_path_buf(), None, w)
                } else {
                    let file = SceneFile::load(path)?;
                    (file, path.to_path_buf(), path.parent(), Vec::new())
                };
            let file = file.with_overrides(&defines)?;
            let (scene, w) = build_scene(&file, &label, &SearchPath::for_scene(dir))?;
            warnings.extend(w);
            Ok((scene, warnings))
        };
        let (scene, warnings) = py.detach(load).map_err(|e| {
            let named = whitted::io::scene::overrides_named(&e.to_string(), &defines);
            if named.is_empty() {
                whitted_error("scene", e)
            } else {
                whitted_error(&format!("defines ({})", named.join(", ")), e)
            }
        })?;
        Ok(PyScene {
            scene,
            warnings,
            source: source.to_string(),
        })
    }

    /// Image width in pixels.
    #[getter]
    fn width(&self) -> u32 {
        self.scene.width
    }
    #[setter]
    fn set_width(&mut self, w: u32) {
        self.scene.width = w;
    }
    /// Image height in pixels.
    #[getter]
    fn height(&self) -> u32 {
        self.scene.height
    }
    #[setter]
    fn set_height(&mut self, h: u32) {
        self.scene.height = h;
    }
    /// Triangles over all objects.
    #[getter]
    fn triangle_count(&self) -> usize {
        self.scene.triangle_count()
    }

    /// Render: `(pixels, height, width, aovs)` with `pixels` flat linear RGB and `aovs` a dict
    /// of flat arrays by name.
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (spp=1, depth=None, stage=None, threads=0, aov=Vec::new(), engine="auto"))]
    fn render<'py>(
        &self,
        py: Python<'py>,
        spp: u32,
        depth: Option<u32>,
        stage: Option<&str>,
        threads: usize,
        aov: Vec<String>,
        engine: &str,
    ) -> PyResult<(Arr<'py, f32>, usize, usize, Bound<'py, PyDict>)> {
        use whitted::aov::Aov;
        let stage = match stage {
            None => None,
            Some(s) => Some(whitted::Stage::from_name(s).ok_or_else(|| {
                value_error(format!(
                    "stage: unknown stage '{s}' (intersection, diffuse, specular, shadow, \
                     reflection)"
                ))
            })?),
        };
        let aovs = if aov.is_empty() {
            Vec::new()
        } else {
            Aov::parse_list(&aov.join(",")).map_err(|m| value_error(format!("aov: {m}")))?
        };
        let settings = whitted::Settings {
            stage,
            depth,
            spp,
            engine: engine_named(engine)?,
        };
        let scene = self.scene.clone();
        let (image, layers) = py
            .detach(|| {
                on_pool(threads, || -> whitted::Result<_> {
                    whitted::io::scene::check_size(scene.width as u64, scene.height as u64)
                        .map_err(Error::Usage)?;
                    let world = whitted::render::World::new(scene);
                    let image = world.render_image(&settings)?;
                    let layers = (!aovs.is_empty()).then(|| whitted::aov::capture(&world, &aovs));
                    Ok((image, layers))
                })
            })?
            .map_err(|e| whitted_error("render", e))?;
        let pixels: Vec<f32> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
        let dict = PyDict::new(py);
        if let Some(l) = layers {
            let flat3 =
                |v: Vec<Vec3>| -> Vec<f32> { v.iter().flat_map(|p| p.to_array()).collect() };
            if let Some(a) = l.albedo {
                dict.set_item("albedo", flat3(a).into_pyarray(py))?;
            }
            if let Some(n) = l.normal {
                dict.set_item("normal", flat3(n).into_pyarray(py))?;
            }
            if let Some(d) = l.depth {
                dict.set_item("depth", d.into_pyarray(py))?;
            }
            if let Some(i) = l.id {
                dict.set_item("id", i.into_pyarray(py))?;
            }
        }
        Ok((pixels.into_pyarray(py), image.height, image.width, dict))
    }
}

/// What this build was compiled with and what the CPU has.
#[pyfunction]
fn build_info(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    use whitted::cpu;
    let d = PyDict::new(py);
    let compiled = cpu::compiled_features();
    let have = cpu::cpu_features();
    d.set_item("version", env!("CARGO_PKG_VERSION"))?;
    d.set_item("simd_compiled", cpu::level(&compiled))?;
    d.set_item("simd_cpu", cpu::level(&have))?;
    d.set_item("features_compiled", compiled)?;
    d.set_item("features_cpu", have)?;
    d.set_item("avx512_kernels", whitted::accel::packet16::available())?;
    d.set_item("warning", cpu::slow_build_warning())?;
    d.set_item("engines", Engine::ALL.map(Engine::name).to_vec())?;
    d.set_item("threads", rayon::current_num_threads())?;
    d.set_item("debug_build", cfg!(debug_assertions))?;
    Ok(d)
}

/// A mesh file whitted reads, as flat `(vertices, triangles, warnings)`.
#[pyfunction]
#[allow(clippy::type_complexity)]
fn load_mesh<'py>(
    py: Python<'py>,
    path: PathBuf,
) -> PyResult<(Arr<'py, f32>, Arr<'py, u32>, Vec<String>)> {
    let (mesh, warnings) = py
        .detach(|| whitted::io::load_mesh(&path))
        .map_err(|e| whitted_error("path", e))?;
    let v: Vec<f32> = mesh.positions.iter().flat_map(|p| p.to_array()).collect();
    let t: Vec<u32> = mesh.triangles.iter().flatten().copied().collect();
    Ok((v.into_pyarray(py), t.into_pyarray(py), warnings))
}

/// The slow-build warning (`whitted::cpu::take_slow_build_warning`) the first time, then
/// `None`; the package turns it into a `RuntimeWarning` at import.
#[pyfunction]
fn take_warning() -> Option<String> {
    whitted::cpu::take_slow_build_warning()
}

/// Names of the built-in scenes.
#[pyfunction]
fn builtin_scenes() -> Vec<&'static str> {
    whitted::scenes::NAMES.to_vec()
}

#[pymodule]
fn _whitted(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Raycaster>()?;
    m.add_class::<PyScene>()?;
    m.add_function(wrap_pyfunction!(build_info, m)?)?;
    m.add_function(wrap_pyfunction!(builtin_scenes, m)?)?;
    m.add_function(wrap_pyfunction!(load_mesh, m)?)?;
    m.add_function(wrap_pyfunction!(take_warning, m)?)?;
    m.add("INVALID_ID", INVALID_ID)?;
    Ok(())
}
