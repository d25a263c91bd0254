"""Side by side with Open3D's RaycastingScene when open3d is installed (it is not a test
dependency: `pip install open3d`, which needs Debian's libusb-1.0-0). Skipped otherwise."""

import pathlib

import numpy as np
import pytest

import whitted

o3d = pytest.importorskip("open3d")

KITTEN = pathlib.Path(__file__).resolve().parents[2] / "meshes" / "kitten.m"


@pytest.fixture(scope="module")
def scenes():
    V, T = whitted.load_mesh(KITTEN)
    ours = whitted.RaycastingScene()
    ours.add_triangles(V, T)
    ours.add_triangles(V + 1.0, T)
    theirs = o3d.t.geometry.RaycastingScene()
    theirs.add_triangles(o3d.core.Tensor(V), o3d.core.Tensor(T))
    theirs.add_triangles(o3d.core.Tensor(V + 1.0), o3d.core.Tensor(T))
    rng = np.random.default_rng(8)
    lo, hi = V.min(0), V.max(0) + 1.0
    o = rng.uniform(lo, hi, (50000, 3))
    d = rng.normal(size=(50000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    rays = np.hstack([o, d]).astype(np.float32).reshape(250, 200, 6)
    points = rng.uniform(lo - 0.05, hi + 0.05, (5000, 3)).astype(np.float32)
    return ours, theirs, rays, points


def numpy_dict(d):
    return {k: v.numpy() for k, v in d.items()}


def test_cast_rays_like_open3d(scenes):
    ours, theirs, rays, _ = scenes
    a = ours.cast_rays(rays)
    b = numpy_dict(theirs.cast_rays(o3d.core.Tensor(rays)))
    assert set(a) == set(b)
    for k in a:
        assert a[k].dtype == b[k].dtype and a[k].shape == b[k].shape, k
    np.testing.assert_array_equal(a["geometry_ids"], b["geometry_ids"])
    np.testing.assert_array_equal(a["primitive_ids"], b["primitive_ids"])
    hit = a["geometry_ids"] != whitted.INVALID_ID
    np.testing.assert_array_equal(a["t_hit"][~hit], b["t_hit"][~hit])
    np.testing.assert_allclose(a["t_hit"][hit], b["t_hit"][hit], rtol=1e-3)
    np.testing.assert_allclose(a["primitive_uvs"], b["primitive_uvs"], atol=1e-3)
    np.testing.assert_allclose(a["primitive_normals"], b["primitive_normals"], atol=1e-4)


def test_occlusions_counts_and_lists_like_open3d(scenes):
    ours, theirs, rays, _ = scenes
    r = o3d.core.Tensor(rays)
    for kw in ({}, {"tnear": 0.01, "tfar": 0.1}):
        np.testing.assert_array_equal(
            ours.test_occlusions(rays, **kw), theirs.test_occlusions(r, **kw).numpy()
        )
    a, b = ours.count_intersections(rays), theirs.count_intersections(r).numpy()
    assert a.dtype == b.dtype
    np.testing.assert_array_equal(a, b)
    a = ours.list_intersections(rays[:10])
    b = numpy_dict(theirs.list_intersections(o3d.core.Tensor(rays[:10])))
    assert set(a) == set(b)
    for k in a:
        assert a[k].dtype == b[k].dtype and a[k].shape == b[k].shape, k
    np.testing.assert_array_equal(a["ray_splits"], b["ray_splits"])


def test_closest_points_and_occupancy_like_open3d(scenes):
    ours, theirs, _, points = scenes
    p = o3d.core.Tensor(points)
    a, b = ours.compute_closest_points(points), numpy_dict(theirs.compute_closest_points(p))
    assert set(a) == set(b)
    for k in a:
        assert a[k].dtype == b[k].dtype and a[k].shape == b[k].shape, k
    np.testing.assert_allclose(ours.compute_distance(points), theirs.compute_distance(p).numpy(), atol=1e-6)
    occ = ours.compute_occupancy(points)
    np.testing.assert_array_equal(occ, theirs.compute_occupancy(p, nsamples=5).numpy())
    sd = ours.compute_signed_distance(points)
    np.testing.assert_array_equal(sd < 0, theirs.compute_signed_distance(p, nsamples=5).numpy() < 0)
