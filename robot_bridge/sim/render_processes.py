"""Camera frames rendered in worker processes, so that many cameras use every core.

Render threads share one GIL and about half of a frame's time is Python code, so threads bring about
1.1 cores' worth (50 cameras on 2 cores: 277 frames/s with threads, 259 one after the other). Worker
processes render whole frames while this process renders its own share at the same time.

Why it is built this way:
- Workers are plain ``python -m robot_bridge.sim.render_processes`` processes talking over a pair of
  pipes, not ``multiprocessing``'s spawn or forkserver children: those re-run the user's main script in
  each child, and a robotics script rarely has an ``if __name__ == "__main__"`` guard. A worker whose
  pipe closes (this process ended) exits by itself: no orphans.
- Pixels come back through one shared-memory segment per worker and are copied out at once, so a
  frame's arrays are its own, to keep as long as its reader likes (a copy costs about 0.2 ms, a render
  about 3 ms).
- A camera's frames always go to the same renderer, where its static layers stay cached.
- Pixels do not depend on which process renders a frame: only on the scene and the frame's seed.
- Anything wrong with a worker (it dies, stalls or fails a frame) ends the pool with a warning and the
  frames are rendered here instead: nothing is lost and nothing hangs.
- ``FAULTMAS_RENDER_PROCESSES`` sets the number of workers (0: none); by default one per usable core
  but one (this process renders too), at most 3, and none on one core.
"""
from __future__ import annotations

import atexit
import logging
import mmap
import os
import subprocess
import sys
import threading
import time
from collections import OrderedDict
from multiprocessing.connection import Connection
from multiprocessing.shared_memory import SharedMemory
from pathlib import Path
from typing import Any, Sequence

import numpy as np

log = logging.getLogger(__name__)

ENV_WORKERS = "FAULTMAS_RENDER_PROCESSES"
_SHM_DIR = Path("/dev/shm")          # where POSIX shared memory lives on Linux: workers map it from there
_ALIGN = 64
_READY_SECONDS = 60.0                # a worker that has not started by then is given up
_FRAME_SECONDS = 5.0                 # a frame taking longer than this (plus a margin) means a stalled worker
_SENT_OBJECTS = 16                   # rigs and scenes a worker keeps, by key


def default_workers() -> int:
    """Worker processes to use: ``FAULTMAS_RENDER_PROCESSES`` if set, else usable cores - 1 (at most 3)."""
    value = os.environ.get(ENV_WORKERS)
    if value is not None and value.strip():
        try:
            return max(0, int(value))
        except ValueError:
            log.warning("%s=%r is not a whole number: no render processes", ENV_WORKERS, value)
            return 0
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:                  # not on Linux
        cores = os.cpu_count() or 1
    return max(0, min(cores - 1, 3))


def _aligned(n: int) -> int:
    return (n + _ALIGN - 1) // _ALIGN * _ALIGN


def frame_bytes(job: tuple) -> tuple[int, int]:
    """Bytes of a frame's colour image and of its depth buffer (with the registration spill)."""
    rig, _, _, scene, _ = job
    h, w = rig.camera.height, rig.camera.width
    return _aligned(h * w * 3), _aligned(4 * (h * w + max(0, int(scene.depth.registration_px))))


def frame_views(buffer: Any, offset: int, job: tuple) -> tuple[np.ndarray, np.ndarray]:
    """The colour image (H x W x 3 uint8) and the flat depth buffer (float32) of the frame stored at ``offset``."""
    rig = job[0]
    h, w = rig.camera.height, rig.camera.width
    image_bytes, depth_bytes = frame_bytes(job)
    image = np.ndarray((h, w, 3), np.uint8, buffer, offset)
    flat = np.ndarray((depth_bytes // 4,), np.float32, buffer, offset + image_bytes)
    return image, flat


# ------------------------------------------------------------------------------------------ this side
class _Worker:
    """One render process: its pipes, its shared-memory segment and what it has been sent."""

    def __init__(self, index: int) -> None:
        self.index = index
        self.process: subprocess.Popen | None = None
        self.send_conn: Connection | None = None
        self.recv_conn: Connection | None = None
        self.ready = False
        self.segment: SharedMemory | None = None
        self.sent: OrderedDict[Any, int] = OrderedDict()     # rig or scene (frozen, hashable) -> its key there
        self.keys = 0

    def start(self) -> None:
        to_child_r, to_child_w = os.pipe()
        from_child_r, from_child_w = os.pipe()
        root = str(Path(__file__).resolve().parents[2])     # where robot_bridge, perception live
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH", "")) if p)
        env[ENV_WORKERS] = "0"              # a worker never starts workers of its own
        try:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "robot_bridge.sim.render_processes", str(to_child_r), str(from_child_w)],
                pass_fds=(to_child_r, from_child_w), stdin=subprocess.DEVNULL, env=env)
        finally:
            os.close(to_child_r)
            os.close(from_child_w)
        self.send_conn = Connection(to_child_w, readable=False)
        self.recv_conn = Connection(from_child_r, writable=False)

    def key_of(self, obj: Any) -> tuple[int, Any | None]:
        """The key under which the worker knows ``obj`` (by value: equal rigs are one), and ``obj``
        itself if it must be sent first."""
        key = self.sent.get(obj)
        if key is not None:
            self.sent.move_to_end(obj)
            return key, None
        self.keys += 1
        self.sent[obj] = self.keys
        if len(self.sent) > _SENT_OBJECTS:
            _, forgotten = self.sent.popitem(last=False)
            self.send_conn.send(("forget", forgotten))
        return self.keys, obj

    def ensure_segment(self, size: int) -> None:
        if self.segment is not None and self.segment.size >= size:
            return
        old = self.segment
        self.segment = SharedMemory(create=True, size=max(size, 2 * old.size if old is not None else size))
        if old is not None:                 # the worker keeps its mapping until it maps the new one
            old.close()
            old.unlink()
        self.send_conn.send(("segment", self.segment.name, self.segment.size))

    def stop(self) -> None:
        for conn in (self.send_conn, self.recv_conn):
            if conn is not None:
                try:
                    if conn is self.send_conn:
                        conn.send(("stop",))
                except (OSError, ValueError):
                    pass
        if self.process is not None:
            try:
                self.process.wait(timeout=2.0)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
        for conn in (self.send_conn, self.recv_conn):
            if conn is not None:
                conn.close()
        self.send_conn = self.recv_conn = None
        if self.segment is not None:
            self.segment.close()
            self.segment.unlink()
            self.segment = None


class RenderProcesses:
    """Worker processes that render ``DeferredFrame``s; see the module's docstring."""

    def __init__(self, workers: int) -> None:
        self.size = workers
        self._workers = [_Worker(i + 1) for i in range(workers)]
        self._owner: dict[str, int] = {}          # camera (robot name) -> renderer: 0 here, i worker i
        self._started_at: float | None = None
        self.broken: str | None = None            # why the pool was given up
        self.frames_by_workers = 0
        self._pid = os.getpid()

    # -- life
    def start(self) -> None:
        """Start the workers (they import numpy and OpenCV for a second or so; ``ready`` says when)."""
        if self._started_at is not None:
            return
        self._started_at = time.monotonic()
        if not _SHM_DIR.is_dir():
            self._give_up(f"no {_SHM_DIR} to share pixels through")
            return
        try:
            for worker in self._workers:
                worker.start()
        except OSError as exc:
            self._give_up(f"a render process did not start: {exc}")

    def ready(self) -> bool:
        """True once every worker has started (without waiting)."""
        return self.wait_ready(0.0)

    def wait_ready(self, timeout: float) -> bool:
        """Wait up to ``timeout`` seconds for every worker to start; False if not (or the pool broke)."""
        if self.broken is not None or self._started_at is None:
            return False
        deadline = time.monotonic() + timeout
        for worker in self._workers:
            while not worker.ready:
                left = deadline - time.monotonic()
                try:
                    if not worker.recv_conn.poll(max(0.0, left)):
                        if time.monotonic() - self._started_at > _READY_SECONDS:
                            self._give_up(f"render process {worker.index} did not start in {_READY_SECONDS:.0f} s")
                        return False
                    reply = worker.recv_conn.recv()
                except (EOFError, OSError) as exc:
                    self._give_up(f"render process {worker.index} ended while starting "
                                  f"(exit code {worker.process.poll()}): {exc!r}")
                    return False
                worker.ready = reply[0] == "ready"
        return True

    def close(self) -> None:
        for worker in self._workers:
            worker.stop()

    def _give_up(self, why: str) -> None:
        if self.broken is None:
            self.broken = why
            log.warning("rendering camera frames in this process from now on: %s", why)
        self.close()

    # -- work
    def render(self, frames: Sequence[Any]) -> None:
        """Render ``frames`` (``DeferredFrame``s not rendered yet): the workers' shares there, the
        rest here, at the same time. Frames a worker could not render are rendered here."""
        if os.getpid() != self._pid:        # a forked child must not share the parent's pipes
            self.broken = "a forked process"
        if self.broken is not None or not self.ready():
            for frame in frames:
                frame._render()
            return
        shares: list[list[Any]] = [[] for _ in range(self.size + 1)]
        for frame in frames:
            owner = self._owner.get(frame.robot)
            if owner is None:
                owner = self._owner[frame.robot] = len(self._owner) % (self.size + 1)
            shares[owner].append(frame)
        sent: list[tuple[_Worker, list[tuple[Any, int]]]] = []
        for worker in self._workers:
            share = shares[worker.index]
            if share:
                placed = self._send(worker, share)
                if placed is None:
                    shares[0].extend(share)
                else:
                    sent.append((worker, placed))
        for frame in shares[0]:
            frame._render()
        for worker, placed in sent:
            self._collect(worker, placed)

    def _send(self, worker: _Worker, share: list[Any]) -> list[tuple[Any, int]] | None:
        placed, jobs, offset = [], [], 0
        for frame in share:
            job = frame.job
            image_bytes, depth_bytes = frame_bytes(job)
            placed.append((frame, offset))
            jobs.append((offset, job))
            offset += image_bytes + depth_bytes
        try:
            worker.ensure_segment(offset)
            batch = []
            for offset, (rig, pose, robots, scene, seed) in jobs:
                rig_key, rig_new = worker.key_of(rig)
                scene_key, scene_new = worker.key_of(scene)
                for key, obj in ((rig_key, rig_new), (scene_key, scene_new)):
                    if obj is not None:
                        worker.send_conn.send(("object", key, obj))
                batch.append((offset, rig_key, pose, robots, scene_key, seed))
            worker.send_conn.send(("batch", batch))
        except (OSError, ValueError) as exc:
            self._give_up(f"render process {worker.index} cannot be reached: {exc!r}")
            return None
        return placed

    def _collect(self, worker: _Worker, placed: list[tuple[Any, int]]) -> None:
        failed: dict[int, str] = {}
        timeout = 30.0 + _FRAME_SECONDS * len(placed)
        try:
            if self.broken is not None or not worker.recv_conn.poll(timeout):
                raise TimeoutError(f"no answer in {timeout:.0f} s" if self.broken is None else self.broken)
            kind, failed = worker.recv_conn.recv()
            if kind != "done":
                raise ValueError(f"unexpected answer {kind!r}")
        except (EOFError, OSError, TimeoutError, ValueError) as exc:
            code = worker.process.poll() if worker.process is not None else None
            self._give_up(f"render process {worker.index} failed (exit code {code}): {exc!r}")
            for frame, _ in placed:
                frame._render()
            return
        for i, (frame, offset) in enumerate(placed):
            if i in failed:
                log.warning("render process %d failed a frame of %s, rendered here instead: %s",
                            worker.index, frame.robot, failed[i])
                frame._render()
                continue
            frame.deliver(*_copied(worker.segment.buf, offset, frame.job))
            self.frames_by_workers += 1


def _copied(buffer: Any, offset: int, job: tuple) -> tuple[np.ndarray, np.ndarray]:
    """A frame's colour and depth images copied out of a segment (whose views end with this call, so
    that the segment can be closed later)."""
    image, flat = frame_views(buffer, offset, job)
    h, w = image.shape[:2]
    return image.copy(), flat[:h * w].reshape(h, w).copy()


_shared: list[RenderProcesses] = []
_shared_lock = threading.Lock()


def shared_pool() -> RenderProcesses | None:
    """This process's render workers, started on first use; None if it has none (see ``default_workers``)."""
    with _shared_lock:
        if _shared and _shared[0]._pid != os.getpid():
            _shared.clear()                 # inherited through fork: not ours to use
        if not _shared:
            workers = default_workers()
            pool = RenderProcesses(workers) if workers > 0 else None
            _shared.append(pool)
            if pool is not None:
                pool.start()
                atexit.register(pool.close)
        return _shared[0]


# ------------------------------------------------------------------------------------------ the worker
def _attach(name: str, size: int) -> mmap.mmap:
    fd = os.open(_SHM_DIR / name, os.O_RDWR)
    try:
        return mmap.mmap(fd, size)
    finally:
        os.close(fd)


def _render_into(segment: mmap.mmap, offset: int, job: tuple) -> None:
    from robot_bridge.sim import camera

    rig, pose, robots, scene, seed = job
    camera._render(rig, pose, robots, scene, np.random.default_rng(seed), count=False,
                   out=frame_views(segment, offset, job))


def serve(recv_conn: Connection, send_conn: Connection) -> None:
    """A render worker's loop: objects, segments and batches in, ``("done", failed)`` out, until
    ``("stop",)`` or the pipe closes."""
    import traceback

    import cv2

    from robot_bridge.sim import camera  # noqa: F401  (imported before "ready": the first frame is not slow)

    cv2.setNumThreads(1)                    # one core per process: threads would only contend
    objects: dict[int, Any] = {}
    segment: mmap.mmap | None = None
    send_conn.send(("ready", os.getpid()))
    while True:
        try:
            message = recv_conn.recv()
        except (EOFError, OSError):
            return
        kind = message[0]
        if kind == "stop":
            return
        if kind == "object":
            objects[message[1]] = message[2]
        elif kind == "forget":
            objects.pop(message[1], None)
        elif kind == "segment":
            if segment is not None:
                try:
                    segment.close()
                except BufferError:         # a view survived a failed frame: leave the mapping be
                    pass
            segment = _attach(message[1], message[2])
        elif kind == "batch":
            failed: dict[int, str] = {}
            for i, (offset, rig_key, pose, robots, scene_key, seed) in enumerate(message[1]):
                try:
                    _render_into(segment, offset, (objects[rig_key], pose, robots, objects[scene_key], seed))
                except Exception:           # reported, and that frame is rendered by the other side
                    failed[i] = traceback.format_exc(limit=4)
            send_conn.send(("done", failed))


if __name__ == "__main__":
    serve(Connection(int(sys.argv[1]), writable=False), Connection(int(sys.argv[2]), readable=False))
