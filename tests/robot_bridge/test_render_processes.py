"""Camera frames rendered in worker processes: the same pixels, every frame counted, nothing lost when
a worker dies, and no process or shared memory left behind."""
from __future__ import annotations

import logging

import numpy as np
import pytest

from robot_bridge.sim import camera
from robot_bridge.sim.render_processes import ENV_WORKERS, RenderProcesses, _SHM_DIR, default_workers
from robot_bridge.sim.world import World


def _unread_frames(cameras: int, seconds: float = 0.25) -> list:
    """Deferred frames of ``cameras`` rotating robots, nobody having read their pixels yet."""
    world = World(seed=11)
    frames: list = []
    for i in range(cameras):
        name = f"r{i}"
        world.add_robot(name, x=0.8 * i, y=0.3 * (i % 2), yaw_deg=40.0 * i, camera=True)
        world.command(name, "rotate", (30.0,))
        world.subscribe_camera(name, frames.append)
    world.run(seconds)
    assert frames and not any(f.rendered for f in frames)
    return frames


@pytest.fixture(scope="module")
def pool():
    if not _SHM_DIR.is_dir():
        pytest.skip(f"no {_SHM_DIR}")
    processes = RenderProcesses(1)
    processes.start()
    assert processes.wait_ready(60.0), processes.broken
    yield processes
    processes.close()


def test_frames_rendered_by_a_worker_process_are_the_frames_rendered_here(pool):
    frames = _unread_frames(4)
    before, by_workers = camera.frames_rendered(), pool.frames_by_workers
    pool.render(frames)
    assert all(f.rendered for f in frames)
    assert camera.frames_rendered() - before == len(frames)            # each frame counted once
    assert pool.frames_by_workers - by_workers == len(frames) // 2      # every other camera is the worker's
    for frame in frames:
        rig, pose, robots, scene, seed = frame.job
        rgb, depth = camera.render(rig, pose, robots, scene, np.random.default_rng(seed))
        assert np.array_equal(frame.rgb, rgb) and np.array_equal(frame.depth, depth)
        assert frame.rgb.flags.owndata or frame.rgb.base is not None and frame.rgb.base.flags.owndata


def test_a_camera_stays_with_its_renderer_and_a_bigger_batch_gets_a_bigger_segment():
    pool = RenderProcesses(1)
    pool.start()
    try:
        assert pool.wait_ready(60.0), pool.broken
        pool.render(_unread_frames(2, 0.1))
        owners = dict(pool._owner)
        size = pool._workers[0].segment.size
        many = _unread_frames(8, 0.1)                                   # r0, r1 again, and six more
        pool.render(many)
        assert {name: pool._owner[name] for name in owners} == owners
        assert pool._workers[0].segment.size > size
        for frame in many:
            rig, pose, robots, scene, seed = frame.job
            assert np.array_equal(frame.depth, camera.render(rig, pose, robots, scene, np.random.default_rng(seed))[1])
    finally:
        pool.close()


def test_a_dead_worker_ends_the_pool_with_a_warning_and_its_frames_are_rendered_here(caplog):
    processes = RenderProcesses(1)
    processes.start()
    assert processes.wait_ready(60.0), processes.broken
    worker = processes._workers[0]
    segment_name = None
    processes.render(_unread_frames(2, 0.1))
    segment_name = worker.segment.name
    worker.process.kill()
    worker.process.wait()
    frames = _unread_frames(4)
    before = camera.frames_rendered()
    with caplog.at_level(logging.WARNING, logger="robot_bridge.sim.render_processes"):
        processes.render(frames)
    assert all(f.rendered for f in frames) and camera.frames_rendered() - before == len(frames)
    assert processes.broken and "render process 1" in processes.broken
    assert any("in this process from now on" in r.getMessage() for r in caplog.records)
    assert not (_SHM_DIR / segment_name).exists()                      # its shared memory is gone
    processes.render(later := _unread_frames(2, 0.1))                  # broken: all here, quietly
    assert all(f.rendered for f in later)


def test_closing_the_pool_ends_its_processes_and_frees_its_shared_memory():
    processes = RenderProcesses(2)
    processes.start()
    assert processes.wait_ready(60.0), processes.broken
    processes.render(_unread_frames(3, 0.1))
    names = [w.segment.name for w in processes._workers]
    procs = [w.process for w in processes._workers]
    processes.close()
    assert all(p.poll() is not None for p in procs)
    assert not any((_SHM_DIR / name).exists() for name in names)


@pytest.mark.parametrize("value, expected", [("0", 0), ("2", 2), (" 3 ", 3), ("-1", 0)])
def test_the_number_of_workers_comes_from_the_environment(monkeypatch, value, expected):
    monkeypatch.setenv(ENV_WORKERS, value)
    assert default_workers() == expected


def test_a_malformed_number_of_workers_means_none_and_says_so(monkeypatch, caplog):
    monkeypatch.setenv(ENV_WORKERS, "many")
    with caplog.at_level(logging.WARNING, logger="robot_bridge.sim.render_processes"):
        assert default_workers() == 0
    assert "'many' is not a whole number" in caplog.text
