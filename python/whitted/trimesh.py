"""A trimesh ray backend: ``mesh.ray = whitted.trimesh.RayMeshIntersector(mesh)``.

The interface is trimesh's (``trimesh.ray.ray_pyembree.RayMeshIntersector``): the same
methods, arguments and return types. Directions are normalised first, as trimesh does, so
distances along rays are lengths. ``multiple_hits`` lists every crossing in order along each
ray from whitted's all-hits walk, with hits at the same point (a ray through an edge or a
vertex, which meets each triangle there) reported once, the lowest triangle index first.
trimesh itself is not imported here: any object with ``vertices``, ``faces`` and
(optionally) ``scale`` works.
"""

from __future__ import annotations

from typing import Any, Literal, Optional, Tuple, Union, overload

import numpy as np
from numpy.typing import ArrayLike

from . import RaycastingScene

__all__ = ["RayMeshIntersector"]


def _unitize(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=1)
    out = np.zeros_like(v)
    ok = n > 0
    out[ok] = v[ok] / n[ok, None]
    return out


class RayMeshIntersector:
    """trimesh's ray queries on whitted's BVH. The BVH is built at the first query; make a
    new intersector after changing the mesh."""

    def __init__(self, mesh: Any, scale_to_box: bool = True) -> None:
        self.mesh = mesh
        self._scale_to_box = scale_to_box
        self._scene: Optional[RaycastingScene] = None

    @property
    def scene(self) -> RaycastingScene:
        """The ``RaycastingScene`` holding the mesh (one geometry)."""
        if self._scene is None:
            s = RaycastingScene()
            s.add_triangles(
                np.asarray(self.mesh.vertices, dtype=np.float64),
                np.asarray(self.mesh.faces, dtype=np.int64).reshape(-1, 3),
            )
            self._scene = s
        return self._scene

    def _rays(self, ray_origins, ray_directions):
        o = np.asarray(ray_origins, dtype=np.float64)
        d = np.asarray(ray_directions, dtype=np.float64)
        if o.shape != d.shape:
            raise ValueError("Ray origin and direction don't match!")
        if o.size == 0:
            o = o.reshape(0, 3)
            d = d.reshape(0, 3)
        if o.ndim != 2 or o.shape[1] != 3:
            raise ValueError(f"ray_origins: expected shape (n, 3), got {o.shape}")
        d = _unitize(d)
        return o, d, np.hstack((o, d)).astype(np.float32)

    def _tolerance(self) -> float:
        scale = getattr(self.mesh, "scale", None)
        if scale is None or not np.isfinite(scale) or scale <= 0:
            v = np.asarray(self.mesh.vertices, dtype=np.float64)
            scale = float(np.ptp(v, axis=0).max()) if len(v) else 1.0
        return max(1e-8, 1e-6 * float(scale))

    @overload
    def intersects_id(
        self, ray_origins: ArrayLike, ray_directions: ArrayLike, multiple_hits: bool = ...,
        max_hits: int = ..., return_locations: Literal[False] = ...,
    ) -> Tuple[np.ndarray, np.ndarray]: ...

    @overload
    def intersects_id(
        self, ray_origins: ArrayLike, ray_directions: ArrayLike, multiple_hits: bool = ...,
        max_hits: int = ..., *, return_locations: Literal[True],
    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]: ...

    def intersects_id(
        self, ray_origins: ArrayLike, ray_directions: ArrayLike, multiple_hits: bool = True,
        max_hits: int = 100, return_locations: bool = False,
    ) -> Union[Tuple[np.ndarray, np.ndarray], Tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Triangles hit by each ray: ``index_tri`` and ``index_ray`` (int64 ``(m,)``), and
        ``locations`` (float64 ``(m, 3)``) when ``return_locations``. With
        ``multiple_hits`` every crossing (at most ``max_hits`` per ray) in order along each
        ray, else the first hit of each ray that hits."""
        o, d, rays = self._rays(ray_origins, ray_directions)
        if not multiple_hits:
            r = self.scene.cast_rays(rays)
            index_ray = np.nonzero(r["geometry_ids"] != RaycastingScene.INVALID_ID)[0]
            index_tri = r["primitive_ids"][index_ray].astype(np.int64)
            t = r["t_hit"][index_ray].astype(np.float64)
        else:
            li = self.scene.list_intersections(rays)
            index_ray = li["ray_ids"].astype(np.int64)
            index_tri = li["primitive_ids"].astype(np.int64)
            t = li["t_hit"].astype(np.float64)
            if len(t):
                # one hit per point: the triangles around an edge or vertex a ray passes
                # through are met at the same t
                same_ray = np.r_[False, index_ray[1:] == index_ray[:-1]]
                close = np.r_[False, np.diff(t) <= self._tolerance()]
                keep = ~(same_ray & close)
                index_ray, index_tri, t = index_ray[keep], index_tri[keep], t[keep]
                # at most max_hits per ray: the rank of each hit within its ray
                starts = np.r_[0, np.nonzero(index_ray[1:] != index_ray[:-1])[0] + 1]
                counts = np.diff(np.r_[starts, len(index_ray)])
                rank = np.arange(len(index_ray)) - np.repeat(starts, counts)
                keep = rank < int(max_hits)
                index_ray, index_tri, t = index_ray[keep], index_tri[keep], t[keep]
        index_ray = index_ray.astype(np.int64)
        if return_locations:
            locations = o[index_ray] + d[index_ray] * t[:, None]
            return index_tri, index_ray, locations.reshape(-1, 3)
        return index_tri, index_ray

    def intersects_location(
        self, ray_origins: ArrayLike, ray_directions: ArrayLike, multiple_hits: bool = True
    ) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Where rays hit: ``locations`` (float64 ``(m, 3)``), ``index_ray``, ``index_tri``."""
        index_tri, index_ray, locations = self.intersects_id(
            ray_origins, ray_directions, multiple_hits=multiple_hits, return_locations=True
        )
        return locations, index_ray, index_tri

    def intersects_first(self, ray_origins: ArrayLike, ray_directions: ArrayLike) -> np.ndarray:
        """Index of the first triangle each ray hits, -1 for none: int64 ``(n,)``."""
        _, _, rays = self._rays(ray_origins, ray_directions)
        r = self.scene.cast_rays(rays)
        first = r["primitive_ids"].astype(np.int64)
        first[r["geometry_ids"] == RaycastingScene.INVALID_ID] = -1
        return first

    def intersects_any(self, ray_origins: ArrayLike, ray_directions: ArrayLike) -> np.ndarray:
        """Whether each ray hits the surface: bool ``(n,)``."""
        _, _, rays = self._rays(ray_origins, ray_directions)
        return self.scene.test_occlusions(rays)

    def contains_points(self, points: ArrayLike) -> np.ndarray:
        """Whether each point is inside the (closed) mesh: bool ``(n,)``, by a majority of
        ray parity votes in 5 directions (``RaycastingScene.compute_occupancy``). Points on
        the surface may go either way."""
        p = np.asarray(points, dtype=np.float64)
        if p.size == 0:
            return np.zeros(0, dtype=bool)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"points: expected shape (n, 3), got {p.shape}")
        return self.scene.compute_occupancy(p, nsamples=5) > 0.5

    def __getstate__(self):
        state = self.__dict__.copy()
        state["_scene"] = None
        return state

    def __copy__(self, *args):
        return RayMeshIntersector(self.mesh, scale_to_box=self._scale_to_box)

    def __deepcopy__(self, *args):
        return self.__copy__()
