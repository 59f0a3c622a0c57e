"""Frames the world hands out: rendered when first read; the frames of one step side by side (threads or
worker processes).

Moved unchanged from ``robot_bridge/sim/camera.py`` (issue 23); the package's ``__init__`` says how the
camera works.
"""
from __future__ import annotations

import os
import threading
from collections import deque
from concurrent.futures import ThreadPoolExecutor
from time import perf_counter
from typing import Sequence

import numpy as np

from robot_bridge.sim.camera.pipeline import _frames, _frames_lock, render
from robot_bridge.sim.camera.scene import CameraRig, Pose, Scene
from robot_bridge.sim.camera.truth import may_show_robots
from robot_bridge.sim.camera_frame import CameraFrame


class DeferredFrame(CameraFrame):
    """A ``CameraFrame`` whose pixels are rendered the first time ``rgb`` or ``depth`` is read.

    The scene (every robot's pose, the time) is fixed when the frame is taken, and the sensor noise
    comes from a seed drawn then, so the pixels are the same whenever, and whether, they are read;
    a 10 Hz camera whose frames nobody looks at costs a pose snapshot per frame, not a render.
    """

    def __init__(self, robot: str, time: float, pose: Pose, rig: CameraRig, robots: Sequence[Pose],
                 scene: Scene, seed: int) -> None:
        for name, value in (("robot", robot), ("time", time), ("pose", pose), ("camera", rig.camera),
                            ("_job", (rig, pose, tuple(robots), scene, seed)), ("_pixels", None),
                            ("_lock", threading.Lock())):
            object.__setattr__(self, name, value)

    def _render(self) -> tuple[np.ndarray, np.ndarray]:
        pixels = self._pixels
        if pixels is None:
            with self._lock:                # listeners in several threads: render once
                pixels = self._pixels
                if pixels is None:
                    rig, pose, robots, scene, seed = self._job
                    pixels = render(rig, pose, robots, scene, np.random.default_rng(seed))
                    object.__setattr__(self, "_pixels", pixels)
        return pixels

    @property
    def rendered(self) -> bool:
        return self._pixels is not None

    @property
    def may_show_robots(self) -> bool:
        """Whether a robot's markers may be in this frame (``truth.may_show_robots``); False: a detector
        finds nothing in it and need not read its pixels."""
        rig, pose, robots, scene, _ = self._job
        return may_show_robots(rig, pose, robots, scene)

    @property
    def job(self) -> tuple[CameraRig, Pose, tuple[Pose, ...], Scene, int]:
        """What the pixels depend on: rig, camera pose, the robots' poses, scene and noise seed."""
        return self._job

    def deliver(self, rgb: np.ndarray, depth: np.ndarray) -> None:
        """Take pixels rendered elsewhere (a render worker) from this frame's ``job``; counted as rendered."""
        with self._lock:
            if self._pixels is None:
                object.__setattr__(self, "_pixels", (rgb, depth))
                with _frames_lock:
                    _frames[0] += 1

    @property
    def rgb(self) -> np.ndarray:            # type: ignore[override]
        return self._render()[0]

    @property
    def depth(self) -> np.ndarray:          # type: ignore[override]
        return self._render()[1]

    def __reduce__(self):
        return (CameraFrame, (self.robot, self.time, self.pose, self.camera, self.rgb, self.depth))


_pool: list = []


_pool_lock = threading.Lock()


def render_threads() -> int:
    """Threads that render frames side by side: one per core this process may use (at most 4)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:                  # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(cores, 4))


class _Pace:
    """Wall time per frame rendered one by one and side by side (moving averages), to use the faster.

    A second thread pays only when a core is free, and other programs may keep the cores busy. So
    both ways are timed, taking turns for the first ``TRIALS`` calls each (the first call of each,
    which warms caches up, not counted), then the faster one is used and the other is tried again
    every ``EXPLORE`` calls, as the load changes.
    """

    TRIALS = 4
    EXPLORE = 16

    def __init__(self) -> None:
        self.seconds: dict[bool, float | None] = {False: None, True: None}
        self.runs = {False: 0, True: 0}
        self.calls = 0

    def side_by_side(self) -> bool:
        self.calls += 1
        if min(self.runs.values()) < self.TRIALS:
            return self.runs[True] < self.runs[False]
        faster = self.seconds[True] < self.seconds[False]
        return not faster if self.calls % self.EXPLORE == 0 else faster

    def record(self, side_by_side: bool, seconds_per_frame: float) -> None:
        self.runs[side_by_side] += 1
        if self.runs[side_by_side] > 1:
            old = self.seconds[side_by_side]
            self.seconds[side_by_side] = seconds_per_frame if old is None else 0.7 * old + 0.3 * seconds_per_frame


_pace = _Pace()


def render_all(frames: Sequence[CameraFrame]) -> None:
    """Render the pixels of the deferred ``frames`` not rendered yet: shared with render worker
    processes once they have started (``render_processes``), else side by side in threads when that is
    faster (see ``_Pace``).

    Frames due at the same step (one per camera) are independent, and most of a frame's time is in
    OpenCV calls and whole-image numpy loops, which release the GIL. The calling thread renders too;
    pixels do not depend on which thread renders them (noise comes from the frame's seed).
    """
    todo = deque(f for f in frames if isinstance(f, DeferredFrame) and not f.rendered)
    count = len(todo)
    if count >= 2:
        from robot_bridge.sim.render_processes import shared_pool

        processes = shared_pool()
        if processes is not None and processes.ready():
            processes.render(todo)
            return
    helpers = min(count - 1, render_threads() - 1)

    def work() -> None:
        while True:
            try:
                frame = todo.popleft()
            except IndexError:
                return
            frame._render()

    if helpers <= 0:
        work()
        return
    side_by_side = _pace.side_by_side()
    started = perf_counter()
    if side_by_side:
        with _pool_lock:
            if not _pool:
                _pool.append(ThreadPoolExecutor(render_threads() - 1, thread_name_prefix="sim-camera"))
        futures = [_pool[0].submit(work) for _ in range(helpers)]
        work()
        for future in futures:
            future.result()
    else:
        work()
    _pace.record(side_by_side, (perf_counter() - started) / count)


def deferred_frame(robot: str, time: float, pose: Pose, rig: CameraRig, robots: Sequence[Pose], scene: Scene,
                   rng: np.random.Generator) -> DeferredFrame:
    """A frame of the camera at ``pose`` seeing ``robots`` now, rendered when its pixels are read."""
    return DeferredFrame(robot, time, pose, rig, robots, scene, int(rng.integers(0, 2 ** 63)))
