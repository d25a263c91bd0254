"""whitted.trimesh.RayMeshIntersector, checked the way trimesh's own ray tests check its
intersectors (tests/test_ray.py in trimesh), and against trimesh's pure-numpy intersector."""

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from whitted.trimesh import RayMeshIntersector  # noqa: E402


def with_whitted(mesh):
    mesh.ray = RayMeshIntersector(mesh)
    return mesh


def test_returns_arrays_and_hits_on_a_sphere():
    sphere = with_whitted(trimesh.creation.icosphere(subdivisions=3))
    rng = np.random.default_rng(1)
    o = rng.random((10000, 3)) * 2 - 1
    o[:, 2] = -5
    d = np.tile([0, 0, 1.0], (len(o), 1))
    a = sphere.ray.intersects_id(o, d)
    b = sphere.ray.intersects_location(o, d)
    assert all(isinstance(x, np.ndarray) for x in a + b)
    index_tri, index_ray = a
    assert index_tri.dtype == np.int64 and index_ray.dtype == np.int64
    # rays within the sphere's silhouette cross it twice, others not at all
    r = np.hypot(o[:, 0], o[:, 1])
    hits = np.bincount(index_ray, minlength=len(o))
    clear = (r < 0.95) | (r > 1.01)
    assert (hits[clear & (r < 0.95)] == 2).all() and (hits[clear & (r > 1.01)] == 0).all()
    loc, ray, tri = b
    assert loc.shape == (len(ray), 3) and len(tri) == len(ray)
    # locations are on the hit triangle's plane
    n = sphere.face_normals[tri]
    off = ((loc - sphere.triangles[tri, 0]) * n).sum(1)
    assert np.abs(off).max() < 1e-5


def test_empty():
    sphere = with_whitted(trimesh.creation.icosphere())
    rng = np.random.default_rng(2)
    o = rng.random((100, 3))
    o[:, 2] = -5
    d = np.tile([0, 1.0, 0], (100, 1))
    for x in sphere.ray.intersects_id(o, d) + sphere.ray.intersects_location(o, d):
        assert isinstance(x, np.ndarray) and len(x) == 0
    assert not sphere.ray.intersects_any(o, d).any()
    assert (sphere.ray.intersects_first(o, d) == -1).all()
    assert len(sphere.ray.intersects_id(np.zeros((0, 3)), np.zeros((0, 3)))[0]) == 0


def test_contains():
    scale = 1.5
    mesh = with_whitted(trimesh.creation.box())
    mesh.ray.contains_points(mesh.vertices)  # on the surface: either answer
    assert mesh.ray.contains_points(mesh.vertices * (1.0 / scale)).all()
    assert not mesh.ray.contains_points(mesh.vertices * scale).any()
    rng = np.random.default_rng(3)
    way_out = rng.random((30, 3)) * 100 + 1.0 + mesh.bounds[1]
    assert not mesh.ray.contains_points(way_out).any()
    assert mesh.ray.contains_points([mesh.center_mass]).all()
    # mesh.contains goes through mesh.ray
    p = rng.uniform(-1, 1, (2000, 3))
    truth = (np.abs(p) < 0.5).all(1)
    np.testing.assert_array_equal(mesh.contains(p), truth)


def test_on_vertex():
    m = with_whitted(trimesh.creation.box())
    origins = np.zeros_like(m.vertices)
    vectors = m.vertices.copy()
    assert m.ray.intersects_any(ray_origins=origins, ray_directions=vectors).all()
    _, index_ray, _ = m.ray.intersects_location(ray_origins=origins, ray_directions=vectors)
    assert (np.bincount(index_ray, minlength=len(origins)) == 1).all()


def test_on_edge():
    # a cube with one octant cut away (trimesh's 7_8ths_cube), points on its inner edges
    # build it as a voxel union, which stays watertight without a boolean engine
    cubes = []
    for x in (-0.5, 0.5):
        for y in (-0.5, 0.5):
            for z in (-0.5, 0.5):
                if (x, y, z) != (0.5, 0.5, 0.5):
                    c = trimesh.creation.box(extents=[1, 1, 1])
                    c.apply_translation([x, y, z])
                    cubes.append(c)
    m = with_whitted(trimesh.util.concatenate(cubes))
    points = [[4.5, 0, -23], [-0.5, -0.5, -0.5], [0.3, -0.4, -0.3], [0.25, 0.25, -0.25], [0.5, 0.5, 0.5]]
    truth = [False, True, True, True, False]
    # the union's inner faces come in pairs, which parity counts twice: still right
    np.testing.assert_array_equal(m.ray.contains_points(points), truth)


def test_multiple_hits():
    f = 1000.0
    h, w = 256, 256
    dirs = trimesh.util.grid_arange([[-h / 2, -w / 2], [h / 2, w / 2]], step=2.0)
    dirs = np.column_stack((dirs, np.ones(len(dirs)) * f))
    origins = np.tile([0, 0, -15.0], (len(dirs), 1))
    cube = with_whitted(trimesh.creation.box(extents=[2, 2, 2]))
    tri, _ = cube.ray.intersects_id(origins, dirs, multiple_hits=False)
    assert len(np.unique(tri)) == 2
    tri, _ = cube.ray.intersects_id(origins, dirs, multiple_hits=True)
    assert len(np.unique(tri)) > 2
    tri, ray = cube.ray.intersects_id(origins, dirs, multiple_hits=True, max_hits=1)
    assert len(np.unique(ray)) == len(ray)


def test_box_locations():
    mesh = with_whitted(trimesh.creation.box())
    origins = trimesh.util.grid_linspace(mesh.bounds[:, :2] + np.reshape([-0.02, 0.02], (-1, 1)), 100)
    origins = np.column_stack((origins, np.ones(len(origins)) * -100))
    vectors = np.ones((len(origins), 3)) * [0, 0, 1.0]
    pos, ray, _ = mesh.ray.intersects_location(ray_origins=origins, ray_directions=vectors)
    assert len(pos) > 0
    for p, r in zip(pos, ray):
        assert np.allclose(p[:2], origins[r][:2])
        assert np.isclose(p[2], mesh.bounds[:, 2]).any()


def test_duplicate_hits_on_a_large_box():
    mesh = trimesh.creation.box()
    mesh.apply_scale(10000.0)
    with_whitted(mesh)
    tri, _ = mesh.ray.intersects_id([[0.0, 0.0, 4000.0]], [[0.0, 0.0, -1.0]], multiple_hits=True)
    assert len(tri) == 1


def test_agrees_with_trimesh_own_intersector():
    pytest.importorskip("rtree")  # trimesh's numpy intersector needs it
    from trimesh.ray.ray_triangle import RayMeshIntersector as Numpy

    mesh = trimesh.creation.icosphere(subdivisions=2)
    mesh.apply_translation([0.1, -0.2, 0.05])
    rng = np.random.default_rng(7)
    o = rng.uniform(-3, 3, (500, 3))
    d = rng.normal(size=(500, 3))
    ours, theirs = RayMeshIntersector(mesh), Numpy(mesh)
    np.testing.assert_array_equal(ours.intersects_any(o, d), theirs.intersects_any(o, d))
    first = ours.intersects_first(o, d)
    np.testing.assert_array_equal(first, theirs.intersects_first(o, d))
    a = ours.intersects_location(o, d)
    b = theirs.intersects_location(o, d)
    order_a = np.lexsort((a[2], a[1]))
    order_b = np.lexsort((b[2], b[1]))
    np.testing.assert_array_equal(a[1][order_a], b[1][order_b])
    np.testing.assert_array_equal(a[2][order_a], b[2][order_b])
    np.testing.assert_allclose(a[0][order_a], b[0][order_b], atol=1e-5)
    p = rng.uniform(-1.2, 1.2, (1000, 3))
    np.testing.assert_array_equal(ours.contains_points(p), theirs.contains_points(p))


def test_bad_arguments():
    m = RayMeshIntersector(trimesh.creation.box())
    with pytest.raises(ValueError, match="don't match"):
        m.intersects_id(np.zeros((3, 3)), np.zeros((2, 3)))
    with pytest.raises(ValueError, match="ray_origins"):
        m.intersects_first(np.zeros((3, 4)), np.zeros((3, 4)))
    with pytest.raises(ValueError, match="points"):
        m.contains_points(np.zeros((3, 2)))
