"""RaycastingScene: shapes, dtypes and miss values as Open3D gives them, hits as whitted's
engines give them, the nearest-point queries against brute force, and every bad input."""

import math
import pathlib

import numpy as np
import pytest

import whitted

ROOT = pathlib.Path(__file__).resolve().parents[2]
KITTEN = ROOT / "meshes" / "kitten.m"
INVALID = whitted.INVALID_ID


def cube():
    """The unit cube, 12 counter-clockwise triangles (outward normals)."""
    v = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], np.float32)
    quads = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
    t = np.array([[q[0], q[1], q[2]] for q in quads] + [[q[0], q[2], q[3]] for q in quads], np.uint32)
    return v, t


@pytest.fixture(scope="module")
def kitten():
    s = whitted.RaycastingScene()
    assert s.add_mesh(KITTEN) == 0
    return s


def random_rays(n, lo, hi, seed=1):
    rng = np.random.default_rng(seed)
    o = rng.uniform(lo, hi, (n, 3))
    d = rng.normal(size=(n, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    return np.hstack([o, d]).astype(np.float32)


def test_build_info():
    info = whitted.build_info()
    assert info["simd_compiled"] in ("x86-64-v3", "x86-64-v4"), info
    if "avx2" in info["features_cpu"]:
        assert "avx2" in info["features_compiled"], "built without the x86-64-v3 kernels"
        assert info["warning"] is None
    assert "auto" in info["engines"] and info["threads"] >= 1


def test_cast_rays_shapes_dtypes_and_misses():
    s = whitted.RaycastingScene()
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], np.float32)
    t = np.array([[0, 1, 2], [0, 1, 3]], np.uint32)
    assert s.add_triangles(v, t) == 0
    assert s.add_triangles(v + 2, t) == 1
    assert s.INVALID_ID == whitted.RaycastingScene.INVALID_ID == 2**32 - 1
    rays = np.array(
        [[0.2, 0.2, 1, 0, 0, -1], [5, 5, 5, 1, 0, 0], [np.nan, 0, 0, 0, 0, 1], [0.2, 0.5, 0.2, 0, -1, 0]],
        np.float32,
    ).reshape(2, 2, 6)
    r = s.cast_rays(rays)
    assert set(r) == {"t_hit", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"}
    assert r["t_hit"].dtype == np.float32 and r["t_hit"].shape == (2, 2)
    assert r["geometry_ids"].dtype == np.uint32 and r["primitive_ids"].dtype == np.uint32
    assert r["primitive_uvs"].shape == (2, 2, 2) and r["primitive_normals"].shape == (2, 2, 3)
    # hits: the values Open3D 0.20 returns for these rays
    assert r["t_hit"][0, 0] == pytest.approx(1.0) and r["t_hit"][1, 1] == pytest.approx(0.5)
    assert r["geometry_ids"].tolist() == [[0, INVALID], [INVALID, 0]]
    assert r["primitive_ids"].tolist() == [[0, INVALID], [INVALID, 1]]
    np.testing.assert_allclose(r["primitive_uvs"][0, 0], [0.2, 0.2], atol=1e-6)
    np.testing.assert_allclose(r["primitive_uvs"][1, 1], [0.2, 0.2], atol=1e-6)
    np.testing.assert_array_equal(r["primitive_normals"][0, 0], [0, 0, 1])
    np.testing.assert_array_equal(r["primitive_normals"][1, 1], [0, -1, 0])
    # misses (the NaN ray among them)
    assert math.isinf(r["t_hit"][0, 1]) and math.isinf(r["t_hit"][1, 0])
    assert not r["primitive_uvs"][0, 1].any() and not r["primitive_normals"][1, 0].any()
    # the second geometry
    r2 = s.cast_rays([[2.2, 2.2, 3, 0, 0, -1]])
    assert r2["geometry_ids"].tolist() == [1] and r2["primitive_ids"].tolist() == [0]
    # float64 is converted, lists too
    r64 = s.cast_rays(rays.astype(np.float64))
    np.testing.assert_array_equal(r64["t_hit"], r["t_hit"])
    # a single ray [6] gives scalars [] and an empty batch gives empty arrays
    assert s.cast_rays(rays[0, 0])["t_hit"].shape == ()
    empty = s.cast_rays(np.zeros((0, 6), np.float32))
    assert empty["t_hit"].shape == (0,) and empty["primitive_uvs"].shape == (0, 2)


def test_empty_scene_misses():
    s = whitted.RaycastingScene()
    r = s.cast_rays(np.zeros((3, 6), np.float32))
    assert np.isinf(r["t_hit"]).all() and (r["geometry_ids"] == INVALID).all()
    assert not s.test_occlusions(np.zeros((3, 6), np.float32)).any()
    assert (s.count_intersections(np.zeros((3, 6), np.float32)) == 0).all()
    c = s.compute_closest_points(np.zeros((2, 3), np.float32))
    assert (c["geometry_ids"] == INVALID).all() and np.isnan(c["points"]).all()


def test_hits_are_the_engines_bit_for_bit(kitten):
    V, T = whitted.load_mesh(KITTEN)
    rays = random_rays(20000, V.min(0), V.max(0))
    r = kitten.cast_rays(rays)
    ref = kitten.trace(rays, engine="scalar")
    for engine in whitted.build_info()["engines"]:
        e = kitten.trace(rays, engine=engine)
        for k in ("t", "tri", "b1", "b2"):
            np.testing.assert_array_equal(e[k], ref[k], err_msg=f"{engine} {k}")
    hit = ref["tri"] != INVALID
    assert hit.mean() > 0.3
    np.testing.assert_array_equal(r["t_hit"], ref["t"])
    np.testing.assert_array_equal(r["primitive_ids"], ref["tri"])
    np.testing.assert_array_equal(r["primitive_uvs"][:, 0], ref["b1"])
    np.testing.assert_array_equal(r["primitive_uvs"][:, 1], ref["b2"])
    # the normal is the triangle's unit geometric normal
    tri = T[r["primitive_ids"][hit]]
    n = np.cross(V[tri[:, 1]] - V[tri[:, 0]], V[tri[:, 2]] - V[tri[:, 0]])
    n /= np.linalg.norm(n, axis=1)[:, None]
    np.testing.assert_allclose(r["primitive_normals"][hit], n, atol=1e-5)
    # threads do not change answers
    one = kitten.cast_rays(rays, nthreads=1)
    for k in r:
        np.testing.assert_array_equal(one[k], r[k])


def test_occlusions_agree_with_closest_hits(kitten):
    V, _ = whitted.load_mesh(KITTEN)
    rays = random_rays(20000, V.min(0), V.max(0), seed=2)
    t = kitten.cast_rays(rays)["t_hit"]
    for engine in whitted.build_info()["engines"]:
        occ = kitten.test_occlusions(rays, engine=engine)
        assert occ.dtype == np.bool_ and occ.shape == (20000,)
        np.testing.assert_array_equal(occ, np.isfinite(t), err_msg=engine)
    # a window [tnear, tfar] on t
    tnear, tfar = 0.01, 0.05
    occ = kitten.test_occlusions(rays, tnear=tnear, tfar=tfar)
    li = kitten.list_intersections(rays)
    expect = np.zeros(len(rays), bool)
    inside = (li["t_hit"] > tnear) & (li["t_hit"] < tfar)
    expect[li["ray_ids"][inside]] = True
    np.testing.assert_array_equal(occ, expect)
    assert kitten.test_occlusions(rays.reshape(100, 200, 6), nthreads=1).shape == (100, 200)


def test_count_and_list_intersections(kitten):
    V, _ = whitted.load_mesh(KITTEN)
    rays = random_rays(5000, V.min(0), V.max(0), seed=3)
    c = kitten.count_intersections(rays)
    assert c.dtype == np.int32
    li = kitten.list_intersections(rays)
    assert set(li) == {"ray_splits", "ray_ids", "t_hit", "geometry_ids", "primitive_ids", "primitive_uvs"}
    s = li["ray_splits"]
    assert s.dtype == np.uint32 and s.shape == (5001,) and s[0] == 0
    np.testing.assert_array_equal(np.diff(s), c)
    np.testing.assert_array_equal(li["ray_ids"], np.repeat(np.arange(5000), c))
    # sorted by t within each ray, the first being the closest hit
    t = li["t_hit"]
    same = li["ray_ids"][1:] == li["ray_ids"][:-1]
    assert (t[1:][same] >= t[:-1][same]).all()
    first = kitten.cast_rays(rays)
    hit = c > 0
    np.testing.assert_array_equal(t[s[:-1][hit]], first["t_hit"][hit])
    assert li["primitive_uvs"].shape == (len(t), 2)
    # leading shape flattens; counts keep it
    assert kitten.count_intersections(rays.reshape(50, 100, 6)).shape == (50, 100)


def brute_closest(V, T, p):
    """Nearest point of every triangle to every point (numpy, float64, by regions)."""
    a, b, c = (V[T[:, k]].astype(np.float64) for k in range(3))
    best = np.full(len(p), np.inf)
    for i in range(len(p)):
        q = p[i].astype(np.float64)
        # sample-free exact: project and clamp via Ericson on all triangles (vectorised)
        ab, ac, ap = b - a, c - a, q - a
        d1, d2 = (ab * ap).sum(1), (ac * ap).sum(1)
        bp = q - b
        d3, d4 = (ab * bp).sum(1), (ac * bp).sum(1)
        cp = q - c
        d5, d6 = (ab * cp).sum(1), (ac * cp).sum(1)
        va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
        with np.errstate(all="ignore"):
            den = va + vb + vc
            v, w = vb / den, vc / den
            pts = a + ab * v[:, None] + ac * w[:, None]
            cands = [pts]
            for s0, s1 in ((a, b), (a, c), (b, c)):
                e = s1 - s0
                tt = np.clip(((q - s0) * e).sum(1) / (e * e).sum(1), 0, 1)
                cands.append(s0 + e * tt[:, None])
        inside = (va >= 0) & (vb >= 0) & (vc >= 0)
        dist = np.where(inside, np.linalg.norm(cands[0] - q, axis=1), np.inf)
        for cnd in cands[1:]:
            dist = np.minimum(dist, np.linalg.norm(cnd - q, axis=1))
        best[i] = np.nanmin(dist)
    return best


def test_closest_points_against_brute_force():
    V, T = whitted.load_mesh(KITTEN)
    s = whitted.RaycastingScene()
    s.add_triangles(V, T)
    rng = np.random.default_rng(4)
    lo, hi = V.min(0), V.max(0)
    p = rng.uniform(lo - 0.1 * (hi - lo), hi + 0.1 * (hi - lo), (200, 3)).astype(np.float32)
    c = s.compute_closest_points(p)
    assert set(c) == {"points", "geometry_ids", "primitive_ids", "primitive_uvs", "primitive_normals"}
    assert c["points"].dtype == np.float32 and c["primitive_ids"].dtype == np.uint32
    d = s.compute_distance(p)
    assert d.dtype == np.float32 and d.shape == (200,)
    np.testing.assert_allclose(d, brute_closest(V, T, p), rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(c["points"] - p, axis=1), d, rtol=1e-4, atol=1e-6)
    # the point lies on its triangle at its barycentrics
    tri = T[c["primitive_ids"]]
    u, w = c["primitive_uvs"][:, :1], c["primitive_uvs"][:, 1:]
    q = V[tri[:, 0]] * (1 - u - w) + V[tri[:, 1]] * u + V[tri[:, 2]] * w
    np.testing.assert_allclose(q, c["points"], atol=1e-5)
    assert c["primitive_normals"].shape == (200, 3)
    # leading shape; NaN points
    assert s.compute_distance(p.reshape(10, 20, 3)).shape == (10, 20)
    nan = s.compute_closest_points([[np.nan, 0, 0]])
    assert nan["geometry_ids"][0] == INVALID and np.isnan(s.compute_distance([[0, np.nan, 0]])[0])


def test_signed_distance_and_occupancy_on_vertices_and_edges():
    v, t = cube()
    s = whitted.RaycastingScene()
    s.add_triangles(v, t)
    rng = np.random.default_rng(5)
    p = rng.uniform(-0.5, 1.5, (4000, 3)).astype(np.float32)
    truth = ((p > 0) & (p < 1)).all(1)
    occ = s.compute_occupancy(p)
    assert occ.dtype == np.float32
    np.testing.assert_array_equal(occ > 0.5, truth)
    sd = s.compute_signed_distance(p)
    np.testing.assert_array_equal(sd < 0, truth)
    np.testing.assert_allclose(np.abs(sd), s.compute_distance(p))
    # points whose axis-aligned rays would run through the cube's edges and vertices
    grid = np.array([[x, y, z] for x in (0.25, 0.5, 0.75) for y in (0.25, 0.5, 0.75) for z in (0.25, 0.5, 0.75)], np.float32)
    for ns in (1, 3, 5):
        assert (s.compute_occupancy(grid, nsamples=ns) == 1).all(), ns
        assert (s.compute_occupancy(grid + 2, nsamples=ns) == 0).all(), ns
    # the kitten: the centre of mass is inside, far points outside
    k = whitted.RaycastingScene()
    k.add_mesh(KITTEN)
    V, _ = whitted.load_mesh(KITTEN)
    assert k.compute_occupancy(V.mean(0)[None])[0] == 1.0
    assert k.compute_occupancy(V.max(0)[None] + 1)[0] == 0.0
    with pytest.raises(ValueError, match="nsamples"):
        s.compute_occupancy(grid, nsamples=0)


def test_gil_is_released_while_tracing(kitten):
    import threading
    import time

    V, _ = whitted.load_mesh(KITTEN)
    rays = random_rays(400000, V.min(0), V.max(0), seed=6)
    ticks = []
    done = threading.Event()

    def tick():
        while not done.is_set():
            ticks.append(time.perf_counter())
            time.sleep(0.001)

    th = threading.Thread(target=tick, daemon=True)
    th.start()
    try:
        time.sleep(0.01)
        start = len(ticks)
        t0 = time.perf_counter()
        kitten.cast_rays(rays, nthreads=1)
        elapsed = time.perf_counter() - t0
        during = len(ticks) - start
    finally:
        done.set()
        th.join()
    # a held GIL would stop the ticker for the whole call
    assert elapsed < 0.02 or during >= 3, (elapsed, during)


@pytest.mark.parametrize(
    "call",
    ["cast_rays", "test_occlusions", "count_intersections", "list_intersections"],
)
def test_ray_arguments_are_checked(kitten, call):
    f = getattr(kitten, call)
    with pytest.raises(ValueError, match="rays: the last dimension must be 6"):
        f(np.zeros((4, 5), np.float32))
    with pytest.raises(TypeError, match="rays: expected a float array, got dtype object"):
        f(np.array([[object()] * 6]))
    with pytest.raises(TypeError, match="rays"):
        f(np.array([["a"] * 6]))
    with pytest.raises(ValueError, match="nthreads"):
        f(np.zeros((1, 6), np.float32), nthreads=-1)


@pytest.mark.parametrize(
    "call", ["compute_closest_points", "compute_distance", "compute_signed_distance", "compute_occupancy"]
)
def test_point_arguments_are_checked(kitten, call):
    f = getattr(kitten, call)
    with pytest.raises(ValueError, match="query_points: the last dimension must be 3"):
        f(np.zeros((4, 6), np.float32))
    with pytest.raises(TypeError, match="query_points"):
        f(np.array([[None, None, None]]))


def test_geometry_arguments_are_checked(tmp_path):
    s = whitted.RaycastingScene()
    v, t = cube()
    with pytest.raises(ValueError, match="triangles: triangle 0 names vertex 8, but there are 8 vertices"):
        s.add_triangles(v, np.array([[0, 1, 8]]))
    with pytest.raises(ValueError, match="triangles: index -1 is out of range"):
        s.add_triangles(v, np.array([[0, 1, -1]]))
    with pytest.raises(ValueError, match="triangles: expected shape"):
        s.add_triangles(v, np.array([0, 1, 2]))
    with pytest.raises(TypeError, match="triangles: expected an integer array"):
        s.add_triangles(v, t.astype(np.float32))
    with pytest.raises(ValueError, match="vertices: the last dimension must be 3"):
        s.add_triangles(v[:, :2], t)
    bad = v.copy()
    bad[3, 1] = np.nan
    with pytest.raises(ValueError, match="vertices: vertex 3 has a non-finite coordinate"):
        s.add_triangles(bad, t)
    with pytest.raises(OSError, match="path: .*nope.m"):
        s.add_mesh(tmp_path / "nope.m")
    broken = tmp_path / "broken.m"
    broken.write_text("Vertex 1 0 0 0\nFace 1 1 2 3\n")
    with pytest.raises(ValueError, match="path: .*broken.m"):
        s.add_mesh(broken)
    xyz = tmp_path / "mesh.xyz"
    xyz.write_text("0 0 0\n")
    with pytest.raises(ValueError, match="path: .*mesh.xyz"):
        s.add_mesh(xyz)
    # nothing was added by the failures
    assert s.geometry_count == 0
    with pytest.raises(ValueError, match="engine: unknown engine 'warp'"):
        s.cast_rays(np.zeros((1, 6), np.float32), engine="warp")


def test_meshes_from_trimesh_and_every_format(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    box = trimesh.creation.box()
    s = whitted.RaycastingScene()
    assert s.add_triangles(box) == 0
    assert s.cast_rays([[0, 0, 5, 0, 0, -1]])["t_hit"][0] == pytest.approx(4.5)
    for name in ("cube.obj", "tetrahedron.m", "teapot.obj"):
        assert s.add_mesh(ROOT / "meshes" / name) >= 1
    ply = tmp_path / "box.ply"
    box.export(ply)
    gid = s.add_mesh(ply)
    assert s.geometry_count == gid + 1


def test_load_mesh(tmp_path):
    V, T = whitted.load_mesh(KITTEN)
    assert V.dtype == np.float32 and V.shape[1] == 3
    assert T.dtype == np.uint32 and T.shape[1] == 3 and T.max() < len(V)
    with pytest.raises(OSError, match="path: .*missing.obj"):
        whitted.load_mesh(tmp_path / "missing.obj")
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 0\nf 1 2 3\n")
    with pytest.raises(ValueError, match="path: .*bad.obj"):
        whitted.load_mesh(bad)
