"""The camera's compiled z-buffer loop (robot_bridge/sim/zbuffer.py): the pixels of the numpy path, bit for
bit; used when built, never when its source changed since or with FAULTMAS_PURE_PYTHON=1."""
from __future__ import annotations

import json
import logging
import shutil

import numpy as np
import pytest

from agentspeak import _speedups
from robot_bridge.sim import camera, zbuffer
from robot_bridge.sim.camera import objects
from robot_bridge.sim.render_scenes import random_scene
from tests.robot_bridge.test_camera_render import CAMERA, RIG, _crowd

BUILT = zbuffer.MANIFEST.exists()
needs_build = pytest.mark.skipif(not BUILT, reason="the z-buffer loop is not built (no C compiler)")


@pytest.mark.skipif(not _speedups.c_compiler_available(), reason="no C compiler: numpy draws")
def test_a_machine_with_a_compiler_draws_with_the_compiled_loop():
    assert BUILT, "no _zbuffer.json: run make speedups"
    assert objects._ZBUFFER is not None and zbuffer.load() is not None


@needs_build
@pytest.mark.parametrize("count", [False, True])
def test_the_compiled_loop_gives_the_pixels_counts_and_shadows_of_numpy(monkeypatch, count):
    """Crowded views (dozens of cylinders, near and far, overlapping, caps above and below the camera) and
    random rooms: colour, depth (shadows and noise included) and marker pixel counts are identical."""
    robots, scene = _crowd()
    samples = [(RIG, CAMERA, robots, scene)] + [(s.rig, s.camera_pose, s.robots, s.scene)
                                                for s in map(random_scene, range(24))]
    compiled = zbuffer.load()
    drawn = []
    spy = compiled.draw_cylinders
    monkeypatch.setattr(compiled, "draw_cylinders", lambda *a: (drawn.append(len(a[8])), spy(*a)))
    for rig, pose, robots, scene in samples:
        frames = []
        for loop in (compiled, None):
            monkeypatch.setattr(objects, "_ZBUFFER", loop)
            frames.append(camera._render(rig, pose, robots, scene, np.random.default_rng(5), count=count))
        (rgb, depth, pixels), (rgb_np, depth_np, pixels_np) = frames
        assert np.array_equal(rgb, rgb_np) and np.array_equal(depth, depth_np)
        assert pixels == pixels_np
    assert len(drawn) >= len(samples) and max(drawn) >= 100     # the crowd went through the compiled loop


@needs_build
def test_a_band_outside_the_arrays_is_an_error_not_a_crash():
    disparity, image = np.zeros((4, 5), np.float32), np.zeros((4, 5, 3), np.uint8)
    one = np.ones(1, np.intp)
    columns = np.ones(3, np.float32)
    args = dict(t1=columns, t2=columns * 2, face=np.zeros((3, 3), np.uint8), lo_rows=np.zeros(4, np.float32),
                hi_rows=np.full(4, 9, np.float32), start=one * 0, u0=one * 3, ncols=one * 3, v0=one * 0, v1=one * 4,
                limit_row0=one * 0, cap_rgb=np.zeros((1, 3), np.uint8), label=np.ones(1, np.int16), fb=1.0,
                hits=np.zeros(1, np.int64), written=np.zeros(1, np.int64))
    kernel = zbuffer.load()
    with pytest.raises(ValueError, match="outside"):           # columns 3..5 of a 5-column image
        kernel.draw_cylinders(disparity, image, None, *args.values())
    args["u0"] = one * 2
    kernel.draw_cylinders(disparity, image, None, *args.values())
    assert args["hits"][0] == args["written"][0] == 12 and (disparity[:, 2:] == 1.0).all()


@needs_build
def test_a_loop_built_from_another_source_is_not_used(tmp_path, monkeypatch, caplog):
    source = tmp_path / "_zbuffer.pyx"
    shutil.copy(zbuffer.SOURCE, source)
    monkeypatch.setattr(zbuffer, "SOURCE", source)
    assert zbuffer.load() is not None                            # the same text: used
    source.write_text(source.read_text() + "\n# edited after the build\n")
    with caplog.at_level(logging.WARNING, logger="faultmas.sim"):
        assert zbuffer.load() is None
    assert "make speedups" in caplog.text
    manifest = tmp_path / "_zbuffer.json"
    manifest.write_text(json.dumps({"digest": zbuffer.source_digest(source)}))
    monkeypatch.setattr(zbuffer, "MANIFEST", manifest)
    assert zbuffer.load() is not None                            # rebuilt (its digest recorded): used again
    monkeypatch.setenv(zbuffer.PURE_ENV, "1")
    assert zbuffer.load() is None
