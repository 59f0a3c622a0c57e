"""Paces a ``World`` against wall time in a background thread: how simulated time relates to the agents'.

* ``speed > 0``: simulated time runs ``speed`` times faster than wall time, always (``speed=1``: real time).
* ``speed = 0`` (the default, "as fast as possible"): while any robot has a motion running or a wheel
  turning, the world steps as fast as the CPU allows; while everything is at rest it advances at wall-time
  pace (1x), so idle periods still pass (a camera keeps its rate, an agent's ``.wait(500)`` sees about
  0.5 simulated seconds go by) instead of freezing or racing ahead.

The simulated clock is the world's (``World.time``); actions complete in simulated time, and agents on
the world's robots count their waits and deadlines in it too (``SimBridge.clock``, ``robot_bridge.clock``). With ``speed=0`` a ``move(1)`` that takes 5 simulated seconds
typically completes within tens of wall milliseconds. For results that must not depend on the machine,
drive the world directly (``World.step``/``run_until``) instead of through a runner.
"""
from __future__ import annotations

import logging
import threading
import time
import weakref
from contextlib import ExitStack, contextmanager
from typing import Iterator

from robot_bridge.sim import allocator
from robot_bridge.sim.world import World

log = logging.getLogger(__name__)


class WorldRunner:
    """Steps one world in a daemon thread; several bridges share it through ``acquire``/``release``."""

    def __init__(self, world: World, speed: float = 0.0) -> None:
        if speed < 0:
            raise ValueError(f"speed must be >= 0 (0 = as fast as possible), got {speed!r}")
        self.world, self.speed = world, speed
        self.busy_cap: float | None = None
        """With ``speed=0``: at most this many simulated seconds per wall second while robots move (None:
        flat out). Agents in other processes, whose commands arrive some wall milliseconds late and whose
        deadlines count in simulated time, need it: flat out, one robot's move spent another's whole move
        deadline before its command arrived."""
        _every_runner.add(self)
        self._users = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._mutex = threading.Lock()
        self._gate = threading.Condition()
        self._pausers = 0
        self._stepping = False
        self._waiting = False
        self._owed = False
        """A pause ended while the thread waited to step: the next pause waits for that step (pausers taking
        turns back to back would hold the world still for ever)."""
        self.error: BaseException | None = None
        """What ended the thread, if something did (a failure of the world itself, not of a camera listener's:
        those cost a frame, see ``World.subscribe_camera``); the bridges then fail actions with it."""

    def acquire(self) -> None:
        """One more user: start the thread on the first."""
        with self._mutex:
            self._users += 1
            if self._thread is None:
                self._stop.clear()
                self._thread = threading.Thread(target=self._run, name="faultmas-sim", daemon=True)
                self._thread.start()

    def release(self) -> None:
        """One user fewer: stop and join the thread after the last."""
        with self._mutex:
            self._users = max(0, self._users - 1)
            thread = self._thread if self._users == 0 else None
            if thread is not None:
                self._thread = None
                self._stop.set()
                with self.world.changed:
                    self.world.changed.notify_all()
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=5.0)

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    @contextmanager
    def paused(self) -> Iterator[None]:
        """Hold the world still: wait for the step under way to end, keep the thread from starting another
        until the block ends (simulated time stands meanwhile, as when everything is at rest).

        For what must not run beside the simulator's thread: a census of the live objects
        (``gc.get_objects``) holds references to every object under construction, and the tuple
        ``cv2.findContours`` is filling, with the GIL released, in the camera detector is one of them: OpenCV
        then fails that frame with ``SystemError: ... bad argument to internal function`` (issue 22, see
        docs/reliability.md, ``tests/hardening/gc_census_race.py``)."""
        if threading.current_thread() is self._thread:   # asked from within a step (a listener): nothing else steps
            yield
            return
        with self._gate:
            self._gate.wait_for(lambda: not self._owed, timeout=1.0)   # a pause after a pause: one step between
            self._pausers += 1
            while self._stepping:
                self._gate.wait()
        try:
            yield
        finally:
            with self._gate:
                self._pausers -= 1
                self._owed = self._pausers == 0 and self._waiting
                self._gate.notify_all()

    def _step(self, world: World) -> None:
        """One step, unless someone holds the world still (``paused``)."""
        with self._gate:
            self._waiting = True
            while self._pausers and not self._stop.is_set():
                self._gate.wait(0.05)
            self._waiting = False
            if self._stop.is_set():
                self._owed = False
                self._gate.notify_all()
                return
            self._stepping = True
        try:
            world.step()
        finally:
            with self._gate:
                self._stepping = False
                if self._pausers or self._owed:
                    self._owed = False
                    self._gate.notify_all()

    def _run(self) -> None:
        world, dt = self.world, self.world.dt
        anchor_wall, anchor_sim, flat_out = time.monotonic(), world.time, False
        next_trim = anchor_wall + allocator.TRIM_EVERY_S
        try:
            while not self._stop.is_set():
                if time.monotonic() >= next_trim:  # served for hours: what malloc keeps freed goes back
                    allocator.trim()
                    next_trim = time.monotonic() + allocator.TRIM_EVERY_S
                fast = self.speed == 0 and world.busy()
                cap = self.busy_cap
                if fast and cap is None:
                    self._step(world)
                    flat_out = True
                    continue
                rate = self.speed or (cap if fast else 1.0)
                if flat_out != fast:  # the pace changes: re-anchor so idle time is not "caught up" at once
                    anchor_wall, anchor_sim, flat_out = time.monotonic(), world.time, fast
                due = anchor_sim + (time.monotonic() - anchor_wall) * rate
                if world.time + dt <= due:
                    self._step(world)
                    continue
                with world.changed:  # a new command (or shutdown) wakes us early
                    world.changed.wait(timeout=min(0.05, (world.time + dt - due) / rate))
        except BaseException as exc:  # keep the failure for the bridges to report
            self.error = exc
            log.critical("the simulator's thread failed at %.2f s simulated: %r; every action now fails "
                         "(shutdown: simulator failed)", world.time, exc, exc_info=exc)
            world.cancel_all("shutdown")   # logged above with its traceback: not raised again for a second one


_every_runner: "weakref.WeakSet[WorldRunner]" = weakref.WeakSet()
"""Every runner of this process, for ``all_paused``."""


@contextmanager
def all_paused() -> Iterator[None]:
    """Every world of this process held still (``WorldRunner.paused``) for the block: where a census of the live
    objects (``gc.get_objects``, ``agents.memory_trace``) may run without failing the simulator's camera frames."""
    with ExitStack() as stack:
        for runner in list(_every_runner):
            stack.enter_context(runner.paused())
        yield


_shared: "weakref.WeakValueDictionary[int, WorldRunner]" = weakref.WeakValueDictionary()
"""Runners by world id; a runner lives as long as some bridge holds it."""
_shared_lock = threading.Lock()


def shared_runner(world: World, speed: float = 0.0) -> WorldRunner:
    """The one runner of ``world`` (created with ``speed`` by whoever asks first)."""
    with _shared_lock:
        runner = _shared.get(id(world))
        if runner is None or runner.world is not world:
            runner = _shared[id(world)] = WorldRunner(world, speed)
        elif runner.speed != speed:
            raise ValueError(f"world already runs at speed {runner.speed:g}, not {speed:g}")
        return runner
