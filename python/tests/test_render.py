"""whitted.render and whitted.Scene: images and AOVs as numpy arrays, bad input named."""

import pathlib

import numpy as np
import pytest

import whitted

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_render_builtin_scene():
    img = whitted.render("phong", width=32, height=24)
    assert img.dtype == np.float32 and img.shape == (24, 32, 3)
    assert np.isfinite(img).all() and img.max() > 0
    # deterministic, and threads do not change the image
    np.testing.assert_array_equal(img, whitted.render("phong", width=32, height=24, threads=1))


def test_stages_depth_spp_and_defines():
    a = whitted.render("demo", width=16, height=12, stage="intersection")
    b = whitted.render("demo", width=16, height=12, stage="shadow")
    assert not np.array_equal(a, b)
    c = whitted.render("demo", width=16, height=12, spp=4, depth=2)
    assert c.shape == (12, 16, 3)
    d = whitted.render("demo", width=16, height=12, defines={"image.width": 20})
    assert d.shape == (12, 16, 3)  # width= wins over the define
    e = whitted.Scene("demo", defines={"image.width": 20, "image.height": 10})
    assert (e.width, e.height) == (20, 10)
    assert whitted.render(e).shape == (10, 20, 3)
    f = whitted.Scene("demo", defines=["image.width=8"])
    assert f.width == 8


def test_aovs():
    img, aov = whitted.render("phong", width=16, height=12, aov=["albedo", "normal", "depth", "id"])
    assert img.shape == (12, 16, 3)
    assert aov["albedo"].shape == (12, 16, 3) and aov["normal"].shape == (12, 16, 3)
    assert aov["depth"].dtype == np.float32 and aov["depth"].shape == (12, 16)
    assert aov["id"].dtype == np.uint32 and aov["id"].shape == (12, 16)
    miss = aov["id"] == whitted.INVALID_ID
    assert np.isinf(aov["depth"][miss]).all() and np.isfinite(aov["depth"][~miss]).all()


def test_scene_front_door_and_mesh_files():
    s = whitted.Scene.builtin("phong")
    assert s.triangle_count > 0 and s.width > 0
    s.width, s.height = 8, 6
    assert s.render().shape == (6, 8, 3)
    assert set(whitted.builtin_scenes()) >= {"phong", "demo"}
    m = whitted.Scene(ROOT / "meshes" / "kitten.m")
    img = whitted.render(m, width=16, height=12)
    assert img.shape == (12, 16, 3) and (m.width, m.height) == (1024, 768)


def test_bad_render_input(tmp_path):
    with pytest.raises(ValueError, match="scene: .*no built-in scene 'nope'|scene: .*nope"):
        whitted.Scene.builtin("nope")
    with pytest.raises((OSError, ValueError), match="scene: "):
        whitted.Scene(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[image\nwidth = 3\n")
    with pytest.raises(ValueError, match="scene: .*bad.toml"):
        whitted.Scene(bad)
    with pytest.raises(ValueError, match="stage: unknown stage 'sepia'"):
        whitted.render("demo", width=8, height=6, stage="sepia")
    with pytest.raises(ValueError, match="aov: unknown AOV 'colour'"):
        whitted.render("demo", width=8, height=6, aov=["colour"])
    with pytest.raises(ValueError, match="render: spp 0"):
        whitted.render("demo", width=8, height=6, spp=0)
    with pytest.raises(ValueError, match="width: must be positive"):
        whitted.render("demo", width=0, height=6)
    with pytest.raises(ValueError, match="render: depth"):
        whitted.render("demo", width=8, height=6, depth=10**6)
    with pytest.raises(ValueError, match="defines"):
        whitted.Scene("demo", defines={"render.depth": "deep"})
