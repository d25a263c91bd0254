"""Rays per second from Python, in one process: whitted's RaycastingScene beside Open3D's
(0.20) and embreex's, on the kitten.

Workloads: the canonical 1920x1080 camera rays (pixel centres in 4x4 blocks, as whitted's
Rust bench makes them) and 2^20 random rays (origins uniform in the bounding box, directions
uniform on the sphere). Calls: closest hit (``cast_rays``) and any hit
(``test_occlusions``), at 1 and 2 threads. Each timing covers one whole call from a numpy
float32 ``[N, 6]`` array to numpy results: Open3D's tensor from the array and ``.numpy()``
of every output are inside it, as is embreex's split into origins and directions. Rounds
alternate the contenders (A B C A B C ...) so drift hits all alike; the median round is
printed.

    pip install ./python open3d embreex   # open3d needs Debian's libusb-1.0-0
    python python/benches/rays.py [--rounds 5] [--mesh meshes/kitten.m]

embreex traces on one thread whatever is asked (its ``run`` is a loop over rays), so its
rows are 1-thread figures.
"""

from __future__ import annotations

import argparse
import datetime
import pathlib
import platform
import statistics
import time

import numpy as np

import whitted

ROOT = pathlib.Path(__file__).resolve().parents[2]

# The canonical view of SCENES.md for the kitten (src/bench/workloads.rs)
EYE = np.array([1.6, 0.9, 4.4])
LOOK = np.array([0.0, -0.15, 0.0])
KC = np.array([-0.0096955, 0.0, -0.009271])
KR = 1.3328798140238487


def camera_rays(V: np.ndarray, w: int = 1920, h: int = 1080) -> np.ndarray:
    """Pixel-centre rays of the canonical camera, framed to the mesh's box as whitted's
    bench frames it, in 4x4 blocks (blocks row-major, pixels row-major within a block)."""
    lo, hi = V.min(0).astype(np.float64), V.max(0).astype(np.float64)
    c = 0.5 * (lo + hi)
    r = 0.5 * np.linalg.norm(hi - lo)
    sc = r / KR
    canonical = abs(sc - 1) < 1e-5 and (np.abs(c - KC) < 1e-5).all()
    eye, look = (EYE, LOOK) if canonical else (c + (EYE - KC) * sc, c + (LOOK - KC) * sc)
    f = look - eye
    f /= np.linalg.norm(f)
    right = np.cross(f, [0.0, 1.0, 0.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, f)
    th = np.tan(36 * np.pi / 360)
    asp = w / h
    Y, X = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    y, x = Y.ravel(), X.ravel()
    order = np.lexsort((x, y, x // 4, y // 4))
    y, x = y[order].astype(np.float64), x[order].astype(np.float64)
    px = (2 * (x + 0.5) / w - 1) * th * asp
    py = (1 - 2 * (y + 0.5) / h) * th
    d = f + px[:, None] * right + py[:, None] * up
    d /= np.linalg.norm(d, axis=1)[:, None]
    o = np.broadcast_to(eye, d.shape)
    return np.hstack([o, d]).astype(np.float32)


def random_rays(V: np.ndarray, n: int = 1 << 20, seed: int = 1234567) -> np.ndarray:
    rng = np.random.default_rng(seed)
    o = rng.uniform(V.min(0), V.max(0), (n, 3))
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return np.hstack([o, d]).astype(np.float32)


def contenders(V, T, threads):
    """name -> {call -> f(rays)} for the libraries that import here."""
    out = {}
    for engine in (None, "auto", "hybrid16", "wide"):
        s = whitted.RaycastingScene()
        s.add_triangles(V, T)
        s.cast_rays(np.zeros((1, 6), np.float32))  # build the BVH outside the timing
        out[f"whitted {engine or 'default'}"] = {
            "cast_rays": lambda r, s=s, e=engine: s.cast_rays(r, nthreads=threads, engine=e),
            "test_occlusions": lambda r, s=s, e=engine: s.test_occlusions(
                r, nthreads=threads, engine=e
            ),
        }
    try:
        import open3d as o3d

        s = o3d.t.geometry.RaycastingScene(nthreads=threads)
        s.add_triangles(o3d.core.Tensor(V), o3d.core.Tensor(T))
        s.cast_rays(o3d.core.Tensor(np.zeros((1, 6), np.float32)))

        def o3d_cast(r, s=s):
            res = s.cast_rays(o3d.core.Tensor.from_numpy(r), nthreads=threads)
            return {k: v.numpy() for k, v in res.items()}

        def o3d_occ(r, s=s):
            return s.test_occlusions(o3d.core.Tensor.from_numpy(r), nthreads=threads).numpy()

        out[f"open3d {o3d.__version__}"] = {"cast_rays": o3d_cast, "test_occlusions": o3d_occ}
    except ImportError as e:
        print(f"(open3d not measured: {e})")
    if threads == 1:
        try:
            from embreex import rtcore_scene as rtcs
            from embreex.mesh_construction import TriangleMesh

            scene = rtcs.EmbreeScene()
            TriangleMesh(scene, V[T.astype(np.int64)].astype(np.float32))
            scene.run(np.zeros((1, 3), np.float32), np.ones((1, 3), np.float32))

            def emb_cast(r, scene=scene):
                o, d = np.ascontiguousarray(r[:, :3]), np.ascontiguousarray(r[:, 3:])
                return scene.run(o, d, output=1)

            def emb_any(r, scene=scene):
                o, d = np.ascontiguousarray(r[:, :3]), np.ascontiguousarray(r[:, 3:])
                return scene.run(o, d) != -1

            out["embreex"] = {"cast_rays": emb_cast, "test_occlusions": emb_any}
        except ImportError as e:
            print(f"(embreex not measured: {e})")
    return out


def cpu_name() -> str:
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mesh", default=str(ROOT / "meshes" / "kitten.m"))
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--threads", default="1,2")
    args = ap.parse_args()

    V, T = whitted.load_mesh(args.mesh)
    info = whitted.build_info()
    print(
        f"# {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, {cpu_name()}, "
        f"whitted built for {info['simd_compiled']} (CPU {info['simd_cpu']}, AVX-512 kernels "
        f"{'on' if info['avx512_kernels'] else 'off'}), {len(T)} triangles"
    )
    workloads = {
        "camera 1920x1080": camera_rays(V),
        "random 2^20": random_rays(V),
    }
    rows = []
    for threads in [int(x) for x in args.threads.split(",")]:
        cs = contenders(V, T, threads)
        for wname, rays in workloads.items():
            for call in ("cast_rays", "test_occlusions"):
                times = {name: [] for name in cs}
                for _ in range(args.rounds):
                    for name, fs in cs.items():
                        t0 = time.perf_counter()
                        fs[call](rays)
                        times[name].append(time.perf_counter() - t0)
                o3d_name = next((n for n in cs if n.startswith("open3d")), None)
                base = statistics.median(times[o3d_name]) if o3d_name else None
                for name in cs:
                    med = statistics.median(times[name])
                    mrays = len(rays) / med / 1e6
                    ratio = f"{base / med:.2f}x" if base else "-"
                    rows.append((threads, wname, call, name, mrays, ratio))
                    print(f"{threads} | {wname} | {call} | {name} | {mrays:.2f} | {ratio}", flush=True)
    print()
    print("| threads | rays | call | library | Mrays/s | vs Open3D |")
    print("|---|---|---|---|---:|---:|")
    for threads, wname, call, name, mrays, ratio in rows:
        print(f"| {threads} | {wname} | `{call}` | {name} | {mrays:.2f} | {ratio} |")


if __name__ == "__main__":
    main()
