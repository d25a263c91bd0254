"""whitted from Python: an Open3D-style ``RaycastingScene``, a trimesh ray backend
(``whitted.trimesh.RayMeshIntersector``) and renders as numpy arrays.

Arrays go in and come out as numpy arrays: rays ``[..., 6]`` (origin, direction), points
``[..., 3]``, float32 (other float dtypes are converted), any leading shape. The work runs in
whitted's Rust engines with the GIL released.
"""

from __future__ import annotations

import os
import warnings as _warnings
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
from numpy.typing import ArrayLike

from . import _whitted  # type: ignore[attr-defined]  # (the compiled module: no stub)

__all__ = [
    "RaycastingScene",
    "Scene",
    "render",
    "build_info",
    "builtin_scenes",
    "load_mesh",
    "INVALID_ID",
]

# Once per process: the CPU has AVX2 and this build lacks it (the kernels run ~2x slower).
_slow = _whitted.take_warning()
if _slow:
    _warnings.warn(_slow, RuntimeWarning, stacklevel=2)

#: Marker for "no geometry" / "no primitive" in id arrays (``2**32 - 1``), as in Open3D.
INVALID_ID: int = _whitted.INVALID_ID


def builtin_scenes() -> List[str]:
    """The names of the built-in scenes (``"demo"``, ``"phong"``, ...)."""
    return list(_whitted.builtin_scenes())


def load_mesh(path: Union[str, os.PathLike]) -> Tuple[np.ndarray, np.ndarray]:
    """A mesh file whitted reads (``.m``, ``.obj``, ``.ply``, ``.stl``, ``.gltf``, ``.glb``) as
    ``(vertices [N, 3] float32, triangles [M, 3] uint32)``."""
    v, t, _ = _whitted.load_mesh(os.fspath(path))
    return v.reshape(-1, 3), t.reshape(-1, 3)


def build_info() -> Dict[str, Any]:
    """What this build was compiled with and what the CPU has.

    Keys: ``version``; ``simd_compiled`` and ``simd_cpu`` (``"x86-64-v3"`` is AVX2 + FMA,
    ``"x86-64-v4"`` adds AVX-512F); ``features_compiled`` and ``features_cpu``;
    ``avx512_kernels`` (whether the 16-wide AVX-512 engines run on this CPU);
    ``warning`` (a string when the CPU has AVX2 and the build lacks it, else ``None``);
    ``engines``; ``threads`` (the default pool's size); ``debug_build``.
    """
    return dict(_whitted.build_info())


def _floats(a, name: str, last: int) -> Tuple[np.ndarray, Tuple[int, ...]]:
    """``a`` as a flat contiguous float32 array of rows of ``last``, and its leading shape."""
    try:
        arr = np.asarray(a)
    except Exception as e:  # ragged lists and the like
        raise ValueError(f"{name}: not convertible to a numeric array ({e})") from None
    if arr.dtype == object or not (
        np.issubdtype(arr.dtype, np.floating) or np.issubdtype(arr.dtype, np.integer)
    ):
        raise TypeError(f"{name}: expected a float array, got dtype {arr.dtype}")
    if arr.ndim < 1 or arr.shape[-1] != last:
        raise ValueError(
            f"{name}: the last dimension must be {last}, got shape {tuple(arr.shape)}"
        )
    lead = tuple(arr.shape[:-1])
    flat = np.ascontiguousarray(arr, dtype=np.float32).reshape(-1)
    return flat, lead


def _indices(a, name: str) -> np.ndarray:
    try:
        arr = np.asarray(a)
    except Exception as e:
        raise ValueError(f"{name}: not convertible to an integer array ({e})") from None
    if arr.dtype == object or not np.issubdtype(arr.dtype, np.integer):
        raise TypeError(f"{name}: expected an integer array, got dtype {arr.dtype}")
    if arr.ndim != 2 or arr.shape[-1] != 3:
        raise ValueError(f"{name}: expected shape [M, 3], got {tuple(arr.shape)}")
    if arr.size and (arr.min() < 0 or arr.max() >= 2**32 - 1):
        bad = int(arr.min()) if arr.min() < 0 else int(arr.max())
        raise ValueError(f"{name}: index {bad} is out of range")
    return np.ascontiguousarray(arr, dtype=np.uint32).reshape(-1)


def _threads(nthreads) -> int:
    n = int(nthreads)
    if n < 0:
        raise ValueError(f"nthreads: must be 0 (all cores) or positive, got {n}")
    return n


class RaycastingScene:
    """Triangle meshes in one BVH, queried with numpy arrays; shaped like Open3D's
    ``open3d.t.geometry.RaycastingScene`` (names, shapes, dtypes and miss values), with
    numpy arrays in place of Open3D tensors.

    ``nthreads`` is accepted for Open3D's signature (the BVH build uses every core). Every
    query takes ``nthreads`` (0: one thread per core). ``cast_rays`` and ``test_occlusions``
    also take ``engine``, whitted's traversal: ``"auto"``, ``"packet8"``, ``"wide1"``,
    ``"hybrid8"``, ``"packet16"``, ``"hybrid16"`` or ``"scalar"`` (``"packet"``, ``"wide"``
    and ``"hybrid"`` name the first three too), all giving the same hits; by default
    (``None``) ``"auto"``, which chooses from the rays (16-ray packets for camera rays, the
    single-ray wide walk for rays from anywhere in any direction).
    """

    INVALID_ID: int = _whitted.INVALID_ID

    def __init__(self, nthreads: int = 0) -> None:
        _threads(nthreads)
        self._r = _whitted.Raycaster()
        #: The loaders' warnings from ``add_mesh``, in order.
        self.warnings: list = []

    def add_triangles(self, vertices: Any, triangles: Optional[ArrayLike] = None) -> int:
        """Add a mesh: ``vertices`` ``[N, 3]`` floats and ``triangles`` ``[M, 3]`` indices
        (counter-clockwise is the front). Returns the geometry id (0, 1, ...). An Open3D
        ``TriangleMesh`` or a trimesh ``Trimesh`` is accepted in place of the two arrays."""
        if triangles is None:
            if hasattr(vertices, "faces") and hasattr(vertices, "vertices"):  # trimesh
                vertices, triangles = vertices.vertices, vertices.faces
            elif hasattr(vertices, "vertex") and hasattr(vertices, "triangle"):  # open3d.t
                vertices, triangles = (
                    vertices.vertex.positions.numpy(),
                    vertices.triangle.indices.numpy(),
                )
            else:
                raise TypeError("triangles: missing (pass vertices and triangles)")
        v, _ = _floats(vertices, "vertices", 3)
        t = _indices(triangles, "triangles")
        return self._r.add_triangles(v, t)

    def add_mesh(self, path: Union[str, os.PathLike]) -> int:
        """Add the mesh in a file whitted reads (``.m``, ``.obj``, ``.ply``, ``.stl``, ``.gltf``,
        ``.glb``); returns its geometry id. Loader warnings are appended to ``self.warnings``."""
        gid, warnings = self._r.add_mesh(os.fspath(path))
        self.warnings.extend(warnings)
        return gid

    def cast_rays(
        self, rays: ArrayLike, nthreads: int = 0, engine: Optional[str] = None
    ) -> Dict[str, np.ndarray]:
        """Closest hits of ``rays`` ``[..., 6]``: a dict of ``t_hit`` ``[...]`` (float32,
        ``inf`` on a miss), ``geometry_ids`` and ``primitive_ids`` ``[...]`` (uint32,
        ``INVALID_ID``), ``primitive_uvs`` ``[..., 2]`` (barycentric weights of the
        triangle's second and third vertex, 0 on a miss) and ``primitive_normals``
        ``[..., 3]`` (unit geometric normal, 0 on a miss). ``t`` is in units of the ray's
        direction; hits need ``t > 0``. Rays with a NaN miss."""
        flat, lead = _floats(rays, "rays", 6)
        t, g, p, uv, n = self._r.cast_rays(flat, _threads(nthreads), engine or "")
        return {
            "t_hit": t.reshape(lead),
            "geometry_ids": g.reshape(lead),
            "primitive_ids": p.reshape(lead),
            "primitive_uvs": uv.reshape(lead + (2,)),
            "primitive_normals": n.reshape(lead + (3,)),
        }

    def test_occlusions(
        self, rays: ArrayLike, tnear: float = 0.0, tfar: float = np.inf, nthreads: int = 0,
        engine: Optional[str] = None,
    ) -> np.ndarray:
        """Whether each ray hits anything with ``tnear < t < tfar``: bool ``[...]``."""
        flat, lead = _floats(rays, "rays", 6)
        return self._r.test_occlusions(
            flat, float(tnear), float(tfar), _threads(nthreads), engine or ""
        ).reshape(lead)

    def count_intersections(self, rays: ArrayLike, nthreads: int = 0) -> np.ndarray:
        """How many triangles each ray crosses at ``t > 0``: int32 ``[...]``."""
        flat, lead = _floats(rays, "rays", 6)
        return self._r.count_intersections(flat, _threads(nthreads)).reshape(lead)

    def list_intersections(self, rays: ArrayLike, nthreads: int = 0) -> Dict[str, np.ndarray]:
        """Every hit at ``t > 0``, sorted by ``t`` within each ray (rays in flattened
        order): ``ray_splits`` (uint32, ``[R + 1]``: ray ``i``'s hits are
        ``ray_splits[i]:ray_splits[i+1]``), ``ray_ids``, ``t_hit``, ``geometry_ids``,
        ``primitive_ids`` (``[K]``) and ``primitive_uvs`` (``[K, 2]``)."""
        flat, _ = _floats(rays, "rays", 6)
        s, r, t, g, p, uv = self._r.list_intersections(flat, _threads(nthreads))
        return {
            "ray_splits": s,
            "ray_ids": r,
            "t_hit": t,
            "geometry_ids": g,
            "primitive_ids": p,
            "primitive_uvs": uv.reshape(-1, 2),
        }

    def compute_closest_points(
        self, query_points: ArrayLike, nthreads: int = 0
    ) -> Dict[str, np.ndarray]:
        """The nearest surface point to each of ``query_points`` ``[..., 3]``: ``points``
        ``[..., 3]``, ``geometry_ids``, ``primitive_ids`` ``[...]``, ``primitive_uvs``
        ``[..., 2]`` and ``primitive_normals`` ``[..., 3]`` (NaN and ``INVALID_ID`` for a NaN
        point or an empty scene)."""
        flat, lead = _floats(query_points, "query_points", 3)
        q, g, p, uv, n, _ = self._r.compute_closest_points(flat, _threads(nthreads))
        return {
            "points": q.reshape(lead + (3,)),
            "geometry_ids": g.reshape(lead),
            "primitive_ids": p.reshape(lead),
            "primitive_uvs": uv.reshape(lead + (2,)),
            "primitive_normals": n.reshape(lead + (3,)),
        }

    def compute_distance(self, query_points: ArrayLike, nthreads: int = 0) -> np.ndarray:
        """Distance from each point to the surface: float32 ``[...]``."""
        flat, lead = _floats(query_points, "query_points", 3)
        return self._r.compute_closest_points(flat, _threads(nthreads))[5].reshape(lead)

    def _inside(self, flat, nthreads, nsamples) -> np.ndarray:
        n = int(nsamples)
        if n < 1:
            raise ValueError(f"nsamples: must be at least 1, got {n}")
        return self._r.compute_inside(flat, _threads(nthreads), n)

    def compute_signed_distance(
        self, query_points: ArrayLike, nthreads: int = 0, nsamples: int = 3
    ) -> np.ndarray:
        """Distance to the surface, negative inside: float32 ``[...]``. Inside is decided
        by ``nsamples`` rays in fixed directions, each voting by the parity of its
        crossings, the majority winning (see ``compute_occupancy``)."""
        flat, lead = _floats(query_points, "query_points", 3)
        d = self._r.compute_closest_points(flat, _threads(nthreads))[5]
        inside = self._inside(flat, nthreads, nsamples)
        return np.where(inside, -d, d).astype(np.float32).reshape(lead)

    def compute_occupancy(
        self, query_points: ArrayLike, nthreads: int = 0, nsamples: int = 3
    ) -> np.ndarray:
        """1.0 inside the (closed) surface, 0.0 outside: float32 ``[...]``.

        Each of ``nsamples`` rays (fixed directions off the axes) counts its crossings; odd
        votes inside and the majority decides. A ray through an edge or a vertex can count
        the triangles there twice and vote wrong; with 3 or more directions the others
        outvote it. Open3D's default is one ray; whitted's is 3."""
        flat, lead = _floats(query_points, "query_points", 3)
        return self._inside(flat, nthreads, nsamples).astype(np.float32).reshape(lead)

    def trace(
        self, rays: ArrayLike, engine: str = "auto", nthreads: int = 0
    ) -> Dict[str, np.ndarray]:
        """whitted's own closest-hit record for ``rays`` ``[..., 6]``: ``t``, ``tri`` (index
        into all geometries' triangles in order of addition), ``b1``, ``b2``, exactly as the
        Rust engine ``engine`` returns them."""
        flat, lead = _floats(rays, "rays", 6)
        t, tri, b1, b2 = self._r.trace(flat, engine, _threads(nthreads))
        return {
            "t": t.reshape(lead),
            "tri": tri.reshape(lead),
            "b1": b1.reshape(lead),
            "b2": b2.reshape(lead),
        }

    @property
    def triangle_count(self) -> int:
        """Triangles in all geometries."""
        return self._r.triangle_count()

    @property
    def geometry_count(self) -> int:
        """Geometries added."""
        return self._r.geometry_count()


Defines = Optional[Union[Mapping[str, Any], Iterable[str]]]
"""Scene-file overrides: ``{"render.depth": 3}`` or ``["render.depth=3"]``."""


def _defines(defines: Defines) -> List[str]:
    if defines is None:
        return []
    if isinstance(defines, Mapping):
        out = []
        for k, v in defines.items():
            if isinstance(v, bool):
                v = "true" if v else "false"
            elif isinstance(v, (list, tuple)):
                v = "[" + ", ".join(repr(x) if isinstance(x, str) else str(x) for x in v) + "]"
            elif isinstance(v, str) and not (v.startswith('"') or v.startswith("[")):
                v = '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
            out.append(f"{k}={v}")
        return out
    return [str(d) for d in defines]


class Scene:
    """A scene to render: a built-in name (``builtin_scenes()``), a TOML scene file or a
    mesh file (``.m``, ``.obj``, ``.ply``, ``.stl``, ``.gltf``, ``.glb``, framed at 1024x768),
    with ``defines`` overriding scene-file keys as the command line's ``-D`` does
    (``{"render.depth": 3}`` or ``["render.depth=3"]``). ``width`` and ``height`` may be changed
    after loading."""

    def __init__(self, source: Union[str, os.PathLike], defines: Defines = None) -> None:
        self._s = _whitted.Scene(os.fspath(source), _defines(defines))

    @classmethod
    def builtin(cls, name: str) -> "Scene":
        if name not in builtin_scenes():
            raise ValueError(
                f"scene: no built-in scene '{name}' (try {', '.join(builtin_scenes())})"
            )
        return cls(name)

    @classmethod
    def load(cls, path: Union[str, os.PathLike], defines: Defines = None) -> "Scene":
        return cls(path, defines)

    @property
    def width(self) -> int:
        return self._s.width

    @width.setter
    def width(self, w: int) -> None:
        self._s.width = int(w)

    @property
    def height(self) -> int:
        return self._s.height

    @height.setter
    def height(self, h: int) -> None:
        self._s.height = int(h)

    @property
    def triangle_count(self) -> int:
        return self._s.triangle_count

    @property
    def warnings(self) -> List[str]:
        return list(self._s.warnings)

    def render(
        self, spp: int = 1, depth: Optional[int] = None, threads: int = 0,
        stage: Optional[str] = None, aov: Union[str, Sequence[str]] = (), engine: str = "auto",
    ) -> Union[np.ndarray, Tuple[np.ndarray, Dict[str, np.ndarray]]]:
        """Render: linear float32 ``[H, W, 3]``, or ``(image, aovs)`` when ``aov`` names
        layers (``"albedo"``, ``"normal"`` ``[H, W, 3]``, ``"depth"`` float32 ``[H, W]``,
        ``"id"`` uint32 ``[H, W]``)."""
        if isinstance(aov, str):
            aov = [aov]
        for name, x in (("spp", spp), ("threads", threads)):
            if int(x) < 0:
                raise ValueError(f"{name}: must not be negative, got {x}")
        if depth is not None and int(depth) < 0:
            raise ValueError(f"depth: must not be negative, got {depth}")
        pixels, h, w, layers = self._s.render(
            int(spp), None if depth is None else int(depth), stage, int(threads),
            list(aov), engine,
        )
        image = pixels.reshape(h, w, 3)
        if not aov:
            return image
        out = {}
        for k, v in layers.items():
            out[k] = v.reshape((h, w, 3) if k in ("albedo", "normal") else (h, w))
        return image, out


def render(
    scene: Union[str, os.PathLike, Scene] = "demo", width: Optional[int] = None,
    height: Optional[int] = None, spp: int = 1, depth: Optional[int] = None,
    threads: int = 0, stage: Optional[str] = None, defines: Defines = None,
    aov: Union[str, Sequence[str]] = (), engine: str = "auto",
) -> Union[np.ndarray, Tuple[np.ndarray, Dict[str, np.ndarray]]]:
    """Render ``scene`` (a built-in name, a scene file, a mesh file or a ``Scene``) and
    return linear float32 ``[H, W, 3]``, or ``(image, aovs)`` when ``aov`` names layers.
    ``width``/``height`` default to the scene's; ``defines`` override scene-file keys."""
    if isinstance(scene, Scene):
        if defines:
            raise ValueError("defines: apply them when loading the Scene")
        s = scene
    else:
        s = Scene(scene, defines)
    for name, x in (("width", width), ("height", height)):
        if x is not None and int(x) <= 0:
            raise ValueError(f"{name}: must be positive, got {x}")
    size = (s.width, s.height)
    try:
        if width is not None:
            s.width = width
        if height is not None:
            s.height = height
        return s.render(
            spp=spp, depth=depth, threads=threads, stage=stage, aov=aov, engine=engine
        )
    finally:
        # a Scene passed in keeps its own size
        s.width, s.height = size
