"""Camera frames rendered in worker processes: the same pixels, every frame counted, nothing lost when
a worker dies, and no process or shared memory left behind."""
from __future__ import annotations

import logging

import numpy as np
import pytest

from robot_bridge.sim import camera
from robot_bridge.sim.render_processes import ENV_WORKERS, RenderProcesses, _SHM_DIR, SLOTS_PER_SEGMENT, default_workers, frame_bytes
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
    assert 0 < pool.frames_by_workers - by_workers < len(frames)        # both sides rendered
    for frame in frames:
        rig, pose, robots, scene, seed = frame.job
        rgb, depth = camera.render(rig, pose, robots, scene, np.random.default_rng(seed))
        assert np.array_equal(frame.rgb, rgb) and np.array_equal(frame.depth, depth)


def _same_as_rendered_here(frame) -> bool:
    rig, pose, robots, scene, seed = frame.job
    rgb, depth = camera.render(rig, pose, robots, scene, np.random.default_rng(seed))
    return np.array_equal(frame.rgb, rgb) and np.array_equal(frame.depth, depth)


def test_pixels_kept_by_a_reader_stay_intact_and_a_slot_is_reused_once_nobody_holds_it(pool):
    kept = _unread_frames(4, 0.25)
    pool.render(kept)
    worker = pool._workers[0]
    from_worker = [f for f in kept if f.rgb.base is not None and not f.rgb.base.flags.owndata]
    assert from_worker, "no frame came from the worker"
    held = {(id(f.rgb.base)) for f in from_worker}
    pool.render(_unread_frames(4, 0.25))                    # new frames must not overwrite the kept ones
    assert all(_same_as_rendered_here(f) for f in kept)
    depth_only = from_worker[0].depth                       # a reader keeping just one image holds the slot
    size = sum(frame_bytes(kept[0].job))                    # every frame here has the same size
    del kept, from_worker, held
    slots = sum(len(seg) for seg in worker.segments.values()) // size
    assert len(worker.free) + len(worker.released) == slots - 1, "a slot nobody holds was not given back"
    # Nothing kept: the freed slots serve again. How many frames of a render the worker takes varies
    # with the machine's load, so a render may need more slots at once than the earlier ones did; with
    # reuse, no render needs more than its frames plus the one held. Without reuse, ten renders would
    # add at least one slot each.
    per_render = len(_unread_frames(4, 0.25))
    bound = max(slots, SLOTS_PER_SEGMENT * -(-(per_render + 1) // SLOTS_PER_SEGMENT))
    for _ in range(10):
        pool.render(_unread_frames(4, 0.25))
    assert sum(len(seg) for seg in worker.segments.values()) // size <= bound
    assert depth_only.shape == (480, 640) and depth_only.any()


def test_a_bigger_camera_gets_a_bigger_segment_and_mixed_sizes_render_right():
    from perception.camera import CameraModel
    from robot_bridge.sim.world import CameraMount

    big = camera.CameraRig(camera=CameraModel.from_fov(57.0, 43.0, 1280, 960))
    world = World(seed=12)
    frames: list = []
    for i, mount in enumerate((CameraMount(), CameraMount(rig=big), CameraMount(), CameraMount(rig=big))):
        world.add_robot(f"r{i}", x=0.9 * i, yaw_deg=50.0 * i, camera=mount)
        world.subscribe_camera(f"r{i}", frames.append)
    world.run(0.25)
    pool = RenderProcesses(1)
    pool.start()
    try:
        assert pool.wait_ready(60.0), pool.broken
        pool.render(frames)
        assert pool.frames_by_workers > 0
        big_frame = sum(frame_bytes(frames[1].job))
        assert any(len(seg) >= SLOTS_PER_SEGMENT * big_frame for seg in pool._workers[0].segments.values())
        for frame in frames:
            rig, pose, robots, scene, seed = frame.job
            rgb, depth = camera.render(rig, pose, robots, scene, np.random.default_rng(seed))
            assert frame.rgb.shape == rgb.shape and np.array_equal(frame.rgb, rgb)
            assert np.array_equal(frame.depth, depth)
    finally:
        pool.close()


def test_a_dead_worker_ends_the_pool_with_a_warning_and_its_frames_are_rendered_here(caplog):
    processes = RenderProcesses(1)
    processes.start()
    assert processes.wait_ready(60.0), processes.broken
    worker = processes._workers[0]
    processes.render(_unread_frames(2, 0.1))
    segment_names = list(worker.segment_names)
    worker.process.kill()
    worker.process.wait()
    frames = _unread_frames(4)
    before = camera.frames_rendered()
    with caplog.at_level(logging.WARNING, logger="robot_bridge.sim.render_processes"):
        processes.render(frames)
    assert all(f.rendered for f in frames) and camera.frames_rendered() - before == len(frames)
    assert processes.broken and "render process 1 exit code -9" in processes.broken
    assert any("in this process from now on" in r.getMessage() for r in caplog.records)
    assert segment_names and not any((_SHM_DIR / name).exists() for name in segment_names)   # gone
    processes.render(later := _unread_frames(2, 0.1))                  # broken: all here, quietly
    assert all(f.rendered for f in later)


def test_closing_the_pool_ends_its_processes_and_frees_its_shared_memory():
    processes = RenderProcesses(2)
    processes.start()
    assert processes.wait_ready(60.0), processes.broken
    processes.render(_unread_frames(3, 0.1))
    names = [name for w in processes._workers for name in w.segment_names]
    assert names
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


def test_two_threads_rendering_at_once_get_every_frame_right(pool):
    from concurrent.futures import ThreadPoolExecutor

    batches = [_unread_frames(3, 0.25), _unread_frames(3, 0.25)]
    with ThreadPoolExecutor(2) as threads:
        list(threads.map(pool.render, batches))
    assert pool.broken is None
    assert all(f.rendered and _same_as_rendered_here(f) for batch in batches for f in batch)


def test_frames_a_worker_holds_are_taken_back_and_rendered_here_once(pool):
    """Frames taken back (``_take_back``) whether or not the worker has started them: each frame rendered
    and counted once, with the worker's pixels or this process's, and every slot free again."""
    from collections import deque

    worker = pool._workers[0]
    frames = _unread_frames(3)
    before, back = camera.frames_rendered(), pool.frames_taken_back
    pool._feed(worker, deque(frames))
    assert len(worker.in_flight) == 3
    slots = [slot for _, slot in worker.in_flight.values()]
    for _ in range(3):                          # the last sent first; the first is likely being rendered
        pool._take_back(worker)._render()
    with pytest.raises(ValueError, match="no frame to give back"):
        pool._take_back(worker)
    while worker.in_flight:
        assert worker.recv_conn.poll(30.0), "the worker did not answer"
        pool._take(worker)
    assert not worker.recalled and pool.frames_taken_back - back == 3
    assert camera.frames_rendered() - before == 3                       # rendered here, once each
    assert all(_same_as_rendered_here(f) for f in frames)
    assert all(slot in worker.free for slot in slots)
    pool.render(_unread_frames(4))                                      # and the worker goes on working
    assert pool.broken is None
