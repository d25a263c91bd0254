"""The package is typed (PEP 561): ``py.typed`` ships with it and every public function,
method and property says the types of its parameters and of what it returns, so that mypy
and pyright check code that calls whitted."""

import inspect
import os
from importlib import resources

import pytest

import whitted
import whitted.trimesh


def public_callables():
    """(name, function) for every public function, method and property getter/setter."""
    for name in whitted.__all__:
        obj = getattr(whitted, name)
        if inspect.isfunction(obj):
            yield name, obj
    classes = [whitted.RaycastingScene, whitted.Scene, whitted.trimesh.RayMeshIntersector]
    for cls in classes:
        for attr, value in vars(cls).items():
            if attr.startswith("_") and attr != "__init__":
                continue
            if isinstance(value, property):
                for part, f in (("get", value.fget), ("set", value.fset)):
                    if f is not None:
                        yield f"{cls.__name__}.{attr} ({part})", f
            elif isinstance(value, (classmethod, staticmethod)):
                yield f"{cls.__name__}.{attr}", value.__func__
            elif inspect.isfunction(value):
                yield f"{cls.__name__}.{attr}", value


def test_the_package_says_it_is_typed():
    assert resources.files("whitted").joinpath("py.typed").is_file()


def test_every_public_callable_is_annotated():
    seen = dict(public_callables())
    # the calls the README and the issue name are among those checked
    for name in [
        "render", "load_mesh", "build_info", "builtin_scenes",
        "RaycastingScene.cast_rays", "RaycastingScene.test_occlusions",
        "RaycastingScene.compute_occupancy", "Scene.render", "Scene.width (set)",
        "RayMeshIntersector.intersects_id", "RayMeshIntersector.contains_points",
    ]:
        assert name in seen, name
    missing = []
    for name, f in seen.items():
        sig = inspect.signature(f)
        for p in sig.parameters.values():
            if p.name in ("self", "cls"):
                continue
            if p.annotation is inspect.Parameter.empty:
                missing.append(f"{name}: parameter {p.name}")
        if sig.return_annotation is inspect.Signature.empty:
            missing.append(f"{name}: return")
    assert not missing, "not annotated: " + ", ".join(missing)


USE = """
import numpy as np
import whitted
import whitted.trimesh

scene = whitted.RaycastingScene()
gid: int = scene.add_triangles(np.zeros((3, 3)), np.array([[0, 1, 2]]))
hits = scene.cast_rays(np.zeros((4, 6), np.float32))
t: np.ndarray = hits["t_hit"]
occluded: np.ndarray = scene.test_occlusions([[0, 0, 0, 0, 0, 1]])
image = whitted.render("phong", width=8, height=8)
s = whitted.Scene.builtin("phong")
s.width = 16
m = whitted.trimesh.RayMeshIntersector(object())
tri, ray = m.intersects_id([[0, 0, 0]], [[0, 0, 1]])
tri2, ray2, where = m.intersects_id([[0, 0, 0]], [[0, 0, 1]], return_locations=True)
"""


def mypy_or_skip():
    try:
        from mypy import api
    except ImportError:
        if os.environ.get("CI") == "true":
            raise AssertionError("mypy is not installed (.ci/run installs it)")
        pytest.skip("mypy is not installed")
    return api


def test_mypy_checks_the_package_and_code_that_uses_it(tmp_path):
    api = mypy_or_skip()
    flags = ["--no-incremental", "--cache-dir", str(tmp_path / "cache")]
    out, err, status = api.run(flags + ["-p", "whitted"])
    assert status == 0, out + err
    good = tmp_path / "use.py"
    good.write_text(USE)
    out, err, status = api.run(flags + [str(good)])
    assert status == 0, out + err
    # the types are whitted's, not Any: a wrong one is caught, on its line
    bad = tmp_path / "bad.py"
    bad.write_text(USE + "wrong: int = scene.cast_rays(np.zeros((1, 6)))\n")
    out, err, status = api.run(flags + [str(bad)])
    line = USE.count("\n") + 1
    assert status == 1 and f"bad.py:{line}: error: Incompatible types" in out, out + err
