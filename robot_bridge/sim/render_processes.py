"""Camera frames rendered in worker processes, so that many cameras use every core.

Render threads share one GIL and about half of a frame's time is Python code, so threads bring about
1.1 cores' worth (50 cameras on 2 cores: 277 frames/s with threads, 259 one after the other). Worker
processes render whole frames while this process renders its own share at the same time.

Why it is built this way:
- Workers are plain ``python -m robot_bridge.sim.render_processes`` processes talking over a pair of
  pipes, not ``multiprocessing``'s spawn or forkserver children: those re-run the user's main script in
  each child, and a robotics script rarely has an ``if __name__ == "__main__"`` guard. A worker whose
  pipe closes (this process ended) exits by itself: no orphans.
- Pixels stay where the worker rendered them, in shared memory: a frame's arrays are views of its slot,
  which takes another frame only once nobody uses them any more (a copy would cost this process about
  0.4 ms a frame, a tenth of a render). Readers keep frames as long as they like; more segments are
  made as needed.
- Workers are fed a frame each time one of theirs is done, and this process renders from the other end
  of the queue in between: the work balances itself, whatever else this process has to do. Once the
  queue is empty, this process takes back the frames a worker holds but has not started, instead of
  waiting for them (50 cameras: that wait was about 7% of the wall time).
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
import secrets
import subprocess
import sys
import threading
import time
import weakref
from collections import OrderedDict, deque
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from robot_bridge.processes import die_with_parent, spawn

log = logging.getLogger(__name__)

ENV_WORKERS = "FAULTMAS_RENDER_PROCESSES"
_SHM_DIR = Path("/dev/shm")          # where POSIX shared memory lives on Linux: workers map it from there
_ALIGN = 64
_READY_SECONDS = 60.0                # a worker that has not started by then is given up
_FRAME_SECONDS = 5.0                 # a frame taking longer than this (plus a margin) means a stalled worker
_SENT_OBJECTS = 16                   # rigs and scenes a worker keeps, by key
IN_FLIGHT = 3                        # frames a worker holds at once: one rendering, the others waiting
SLOTS_PER_SEGMENT = 4                # frames per shared-memory segment (more segments as frames are kept)
Slot = tuple[int, int, int]          # segment key, offset, bytes


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
        self.segments: dict[int, mmap.mmap] = {}
        self.segment_names: list[str] = []
        self.free: list[Slot] = []                          # slots no frame uses
        self.released: deque[Slot] = deque()                # slots freed by the garbage collector (any thread)
        self.in_flight: dict[tuple[int, int], tuple[Any, Slot]] = {}   # (segment, offset) -> frame, slot
        self.recalled: set[tuple[int, int]] = set()         # in flight, asked back (see ``_take_back``)
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
            self.process = spawn(
                [sys.executable, "-m", "robot_bridge.sim.render_processes", str(to_child_r), str(from_child_w)],
                pass_fds=(to_child_r, from_child_w), stdin=subprocess.DEVNULL, env=env)
        finally:
            os.close(to_child_r)
            os.close(from_child_w)
        self.send_conn = Connection(to_child_w, readable=False)
        self.recv_conn = Connection(from_child_r, writable=False)

    def key_of(self, obj: Any) -> int:
        """The key under which the worker knows ``obj`` (by value: equal rigs are one); sends it first
        if the worker does not have it."""
        key = self.sent.get(obj)
        if key is not None:
            self.sent.move_to_end(obj)
            return key
        self.keys += 1
        self.sent[obj] = self.keys
        self.send_conn.send(("object", self.keys, obj))
        if len(self.sent) > _SENT_OBJECTS:
            _, forgotten = self.sent.popitem(last=False)
            self.send_conn.send(("forget", forgotten))
        return self.keys

    def take_slot(self, size: int) -> Slot:
        """A free slot of at least ``size`` bytes; a new segment of ``SLOTS_PER_SEGMENT`` slots if none."""
        while self.released:
            self.free.append(self.released.popleft())
        for i, slot in enumerate(self.free):
            if slot[2] >= size:
                return self.free.pop(i)
        key = len(self.segments) + 1
        name = f"faultmas-render-{os.getpid()}-{self.index}-{key}-{secrets.token_hex(4)}"
        self.segments[key] = _create(name, SLOTS_PER_SEGMENT * size)
        self.segment_names.append(name)
        self.send_conn.send(("segment", key, name, SLOTS_PER_SEGMENT * size))
        self.free.extend((key, i * size, size) for i in range(1, SLOTS_PER_SEGMENT))
        return key, 0, size

    def stop(self) -> None:
        if self.send_conn is not None:
            try:
                self.send_conn.send(("stop",))
            except (OSError, ValueError):   # already gone
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
        for name in self.segment_names:     # the worker unlinks each once mapped, unless it died first
            (_SHM_DIR / name).unlink(missing_ok=True)
        self.segments.clear()               # each is unmapped once no frame uses its pixels any more
        self.free.clear()


class RenderProcesses:
    """Worker processes that render ``DeferredFrame``s; see the module's docstring."""

    def __init__(self, workers: int) -> None:
        self.size = workers
        self._workers = [_Worker(i + 1) for i in range(workers)]
        self._started_at: float | None = None
        self.broken: str | None = None            # why the pool was given up
        self.frames_by_workers = 0
        self.frames_taken_back = 0                # asked back from a worker to render here (see ``_take_back``)
        self.worker_cpu_seconds = 0.0             # CPU time the workers spent rendering
        self._pid = os.getpid()
        self._busy = threading.Lock()             # one thread at a time talks to the workers

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
        """Render ``frames`` (``DeferredFrame``s not rendered yet) here and in the workers at the same
        time. A worker is fed a frame whenever one of its ``IN_FLIGHT`` is done, and this process takes
        frames from the other end of the queue in between, so the work balances itself (this process
        also runs the world between steps). Frames a worker could not render are rendered here, and so
        are all frames of a call made while another thread is using the workers."""
        if os.getpid() != self._pid:        # a forked child must not share the parent's pipes
            self.broken = "a forked process"
        if self.broken is not None or not self.ready() or not self._busy.acquire(blocking=False):
            for frame in frames:
                frame._render()
            return
        try:
            self._render(frames)
        finally:
            self._busy.release()

    def _render(self, frames: Sequence[Any]) -> None:
        todo = deque(frames)
        share = max(1, len(todo) // (self.size + 1))    # a small batch: this process keeps its part
        try:
            for worker in self._workers:
                self._feed(worker, todo, share)
            while todo:
                for worker in self._workers:
                    while worker.in_flight and worker.recv_conn.poll():
                        self._take(worker)
                        self._feed(worker, todo)
                if todo:
                    todo.pop()._render()
            # nothing left here: rather than wait for frames a worker has queued but not started, take
            # them back and render them here, while the workers finish the ones they are on
            while True:
                for worker in self._workers:
                    while worker.in_flight and worker.recv_conn.poll():
                        self._take(worker)
                queued = max(self._workers, key=lambda w: len(w.in_flight) - len(w.recalled))
                if len(queued.in_flight) - len(queued.recalled) < 2:
                    break
                self._take_back(queued)._render()
            for worker in self._workers:
                while worker.in_flight:
                    if not worker.recv_conn.poll(_FRAME_SECONDS + 30.0):
                        raise TimeoutError(f"render process {worker.index} gave no frame in {_FRAME_SECONDS + 30:.0f} s")
                    self._take(worker)
        except (EOFError, OSError, TimeoutError, ValueError) as exc:
            codes = ", ".join(f"render process {w.index} exit code {w.process.poll()}"
                              for w in self._workers if w.process is not None)
            self._give_up(f"{exc!r} ({codes}; None: still running)")
            for worker in self._workers:
                todo.extend(frame for frame, _ in worker.in_flight.values())
                worker.in_flight.clear()
                worker.recalled.clear()
            for frame in todo:
                frame._render()

    def _feed(self, worker: _Worker, todo: deque, most: int = IN_FLIGHT) -> None:
        """Send ``worker`` frames from the front of ``todo`` while it holds fewer than ``IN_FLIGHT``
        (and than ``most``)."""
        while todo and len(worker.in_flight) < min(most, IN_FLIGHT):
            frame = todo.popleft()
            rig, pose, robots, scene, seed = job = frame.job
            slot = worker.take_slot(sum(frame_bytes(job)))
            worker.in_flight[slot[:2]] = (frame, slot)
            rig_key = worker.key_of(rig)
            scene_key = worker.key_of(scene)
            worker.send_conn.send(("frame", slot[0], slot[1], rig_key, pose, robots, scene_key, seed))

    def _take_back(self, worker: _Worker) -> Any:
        """Ask ``worker`` to give back the frame it was sent last (not started yet, most likely), and
        return that frame to render here. The worker answers "given back", or "done" if it had already
        started it; either way ``_take`` settles it."""
        for key in reversed(worker.in_flight):
            if key not in worker.recalled:
                worker.recalled.add(key)
                worker.send_conn.send(("give back", *key))
                self.frames_taken_back += 1
                return worker.in_flight[key][0]
        raise ValueError(f"render process {worker.index} has no frame to give back")

    def _take(self, worker: _Worker) -> None:
        """Receive one answer from ``worker``: a finished frame, whose pixels (views of its slot) go to the
        frame, or a frame given back."""
        reply = worker.recv_conn.recv()
        if reply[0] not in ("done", "given back") or tuple(reply[1:3]) not in worker.in_flight:
            raise ValueError(f"unexpected answer {reply[:2]!r} from render process {worker.index}")
        key, offset = reply[1:3]
        frame, slot = worker.in_flight.pop((key, offset))
        worker.recalled.discard((key, offset))
        if reply[0] == "done":
            self.worker_cpu_seconds += reply[4]
        if reply[0] == "given back" or frame.rendered:     # taken back (and rendered here): the slot is free
            worker.free.append(slot)
            return
        error = reply[3]
        if error is not None:
            worker.free.append(slot)
            log.warning("render process %d failed a frame of %s, rendered here instead: %s",
                        worker.index, frame.robot, error)
            frame._render()
            return
        frame.deliver(*_pixels_in(worker.segments[key], slot, frame.job, worker.released.append))
        self.frames_by_workers += 1


def _pixels_in(segment: mmap.mmap, slot: Slot, job: tuple, release: Callable[[Slot], Any]
               ) -> tuple[np.ndarray, np.ndarray]:
    """A frame's colour and depth images where a worker rendered them, without a copy: both are views
    of one array over the slot, and ``release(slot)`` is called once neither is used any more (the
    frame and everyone who kept its pixels let go), so the slot can take another frame."""
    whole = np.frombuffer(segment, np.uint8, slot[2], slot[1])
    weakref.finalize(whole, release, slot).atexit = False
    image, flat = frame_views(whole, 0, job)          # views whose base is ``whole``
    return image, flat[:image.shape[0] * image.shape[1]].reshape(image.shape[:2])


_shared: list[RenderProcesses] = []
_shared_lock = threading.Lock()


def shared_pool() -> RenderProcesses | None:
    """This process's render workers, started on first use; None if it has none (see ``default_workers``)."""
    with _shared_lock:
        if _shared and _shared[0] is not None and _shared[0]._pid != os.getpid():
            _shared.clear()                 # inherited through fork: not ours to use
        if not _shared:
            workers = default_workers()
            pool = RenderProcesses(workers) if workers > 0 else None
            _shared.append(pool)
            if pool is not None:
                pool.start()
                atexit.register(close_shared_pool)
        return _shared[0]


def close_shared_pool() -> None:
    """End this process's render workers now (they are otherwise ended at exit): for a host that must know its
    children are gone before it exits, such as the test session's check for processes left behind."""
    with _shared_lock:
        pool = _shared[0] if _shared and _shared[0] is not None and _shared[0]._pid == os.getpid() else None
        _shared.clear()
    if pool is not None:
        pool.close()


def _create(name: str, size: int) -> mmap.mmap:
    """A new shared-memory file of ``size`` bytes, mapped. A plain mmap, not ``SharedMemory``, whose
    ``close`` fails (and complains at exit) while frames still use the pixels in it."""
    fd = os.open(_SHM_DIR / name, os.O_RDWR | os.O_CREAT | os.O_EXCL, 0o600)
    try:
        os.ftruncate(fd, size)
        return mmap.mmap(fd, size)
    finally:
        os.close(fd)


# ------------------------------------------------------------------------------------------ the worker
def _attach(name: str, size: int) -> mmap.mmap:
    """Map the segment ``name`` and remove its name: both sides have it now, and nothing is left
    behind in /dev/shm whichever process ends first."""
    path = _SHM_DIR / name
    fd = os.open(path, os.O_RDWR)
    try:
        return mmap.mmap(fd, size)
    finally:
        os.close(fd)
        path.unlink()


def _render_into(segment: mmap.mmap, offset: int, job: tuple) -> None:
    from robot_bridge.sim.camera.pipeline import _render

    rig, pose, robots, scene, seed = job
    _render(rig, pose, robots, scene, np.random.default_rng(seed), count=False,
            out=frame_views(segment, offset, job))


def serve(recv_conn: Connection, send_conn: Connection) -> None:
    """A render worker's loop: objects, segments, frames and requests to give a frame back in;
    ``("done", key, offset, error, cpu)`` or ``("given back", key, offset)`` out; until ``("stop",)`` or
    the pipe closes."""
    import traceback

    import cv2

    import robot_bridge.sim.camera.pipeline  # noqa: F401  (imported before "ready": the first frame is not slow)

    cv2.setNumThreads(1)                    # one core per process: threads would only contend
    objects: dict[int, Any] = {}
    segments: dict[int, mmap.mmap] = {}
    queued: OrderedDict[tuple[int, int], tuple] = OrderedDict()    # frames received and not started
    send_conn.send(("ready", os.getpid()))
    while True:
        # read everything sent so far before starting a frame: a frame may have been asked back
        try:
            while not queued or recv_conn.poll():
                message = recv_conn.recv()
                kind = message[0]
                if kind == "stop":
                    return
                if kind == "object":
                    objects[message[1]] = message[2]
                elif kind == "forget":
                    objects.pop(message[1], None)
                elif kind == "segment":
                    segments[message[1]] = _attach(message[2], message[3])
                elif kind == "frame":
                    queued[message[1], message[2]] = message
                elif kind == "give back" and queued.pop((message[1], message[2]), None) is not None:
                    send_conn.send(("given back", message[1], message[2]))
                # a frame asked back after it was started is answered "done" as usual
        except (EOFError, OSError):
            return
        _, (_, key, offset, rig_key, pose, robots, scene_key, seed) = queued.popitem(last=False)
        started = time.process_time()
        try:
            _render_into(segments[key], offset, (objects[rig_key], pose, robots, objects[scene_key], seed))
            error = None
        except Exception:               # reported, and that frame is rendered by the other side
            error = traceback.format_exc(limit=4)
        send_conn.send(("done", key, offset, error, time.process_time() - started))


if __name__ == "__main__":
    die_with_parent()
    serve(Connection(int(sys.argv[1]), writable=False), Connection(int(sys.argv[2]), readable=False))
