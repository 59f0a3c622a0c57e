"""Why ``cv2.findContours`` raised ``SystemError: Objects/tupleobject.c:117: bad argument to internal function``
in the soak (issue 22): an experiment, not part of ``make test`` (``python -m tests.hardening.gc_census_race``).

One thread detects robots in a real frame of the simulator's camera as the simulator's thread does
(``perception.detect.detect_all``, whose ``cv2.findContours`` builds its tuple of contours item by item); another
thread, as the soak's main thread did after every task, takes a census of the live objects
(``gc.get_objects()``) or collects garbage (``gc.collect()``). The binding makes the tuple (``PyTuple_New``,
tracked by the collector at once), then converts each contour to a numpy array with the GIL released; the census
runs in that window, finds the half-built tuple among the live objects and holds a reference to it, and
``PyTuple_SetItem`` refuses a tuple whose reference count is not 1. ``gc.get_objects`` documents the hazard
("some of them could be still under construction").

``--setup detector`` (the detector in a loop: the mechanism) or ``world`` (the soak in small: a world stepped by
its runner, frames through ``SimBridge``'s detector); ``--mode census`` (the soak before the fix), ``collect``,
``quiescent`` (the census with the world held still, ``WorldRunner.paused``: what the soak does now), ``none``.
Prints one line per setup and mode: detections or frames, how many failed, per 1,000.
"""
from __future__ import annotations

import argparse
import gc
import sys
import threading
import time


def _world():
    """A watcher with a camera and three robots in view (six markers: several contours per mask)."""
    from robot_bridge.sim.world import World

    world = World(seed=3, noise=False)
    world.add_robot("watcher", camera=True)
    for i, (x, y) in enumerate(((2.0, 0.6), (2.5, -0.5), (3.2, 0.2))):
        world.add_robot(f"r{i}", x=x, y=y, yaw_deg=90.0)
    return world


def _disturb(mode: str, runner) -> None:
    """One census (or collection) as ``mode`` says."""
    if mode == "census":
        len([type(o) for o in gc.get_objects()])
    elif mode == "collect":
        gc.collect()
    elif mode == "quiescent":
        with runner.paused():
            len([type(o) for o in gc.get_objects()])
    else:
        time.sleep(0.01)


def run_detector(mode: str, seconds: float) -> dict:
    """``detect_all`` on one frame in a loop for ``seconds`` beside a thread disturbing the collector as ``mode``
    says (the mechanism, at full rate); counts SystemErrors."""
    from perception.detect import detect_all

    frame = _world().camera_frame("watcher")
    rgb, depth, camera = frame.rgb, frame.depth, frame.camera
    found = len(detect_all(rgb, depth, camera).all)
    stop = threading.Event()
    counts = {"detections": 0, "system_errors": 0, "other_errors": 0, "disturbances": 0}
    first: list[str] = []

    def detect() -> None:
        while not stop.is_set():
            try:
                detect_all(rgb, depth, camera)
                counts["detections"] += 1
            except SystemError as exc:
                counts["system_errors"] += 1
                first[:] = first or [repr(exc)]
            except Exception as exc:    # noqa: BLE001 (counted and shown: what else goes wrong)
                counts["other_errors"] += 1
                first[:] = first or [repr(exc)]

    def disturb() -> None:
        while not stop.is_set():
            _disturb(mode, None)
            counts["disturbances"] += 1

    elapsed = _run_threads([detect, disturb], seconds, stop)
    return {"setup": "detector loop", "mode": mode, "seconds": round(elapsed, 1), "robots_in_frame": found,
            **counts, "per_1000": round(1000 * counts["system_errors"] / max(1, counts["detections"]), 1),
            "first_error": first[0] if first else ""}


def run_world(mode: str, seconds: float) -> dict:
    """The soak in small: a world stepped by its runner (the watcher turning, so flat out), its camera's frames
    through ``SimBridge``'s detector, beside a thread taking censuses as ``mode`` says (``quiescent``: with
    ``WorldRunner.paused``, as the soak does now). Counts the frames the detector failed on (the world's
    record of its listener's failures)."""
    from robot_bridge import Action
    from robot_bridge.sim.bridge import SimBridge

    world = _world()
    bridge = SimBridge("watcher", world=world, camera=True)
    bridge.setup()
    detect, detections = bridge._detect, [0]

    def counted(rgb, depth, camera):
        detections[0] += 1
        return detect(rgb, depth, camera)

    bridge._detect = counted       # the real detector, its calls counted
    bridge.act(Action("rotate", (30.0,)))
    runner = bridge._runner
    listener = world._robots["watcher"].camera_listeners[0]
    stop = threading.Event()
    counts = {"disturbances": 0}

    def disturb() -> None:
        while not stop.is_set():
            _disturb(mode, runner)
            counts["disturbances"] += 1

    frames_before = world.time
    elapsed = _run_threads([disturb], seconds, stop)
    frames = round((world.time - frames_before) * 10)   # the camera's rate: 10 Hz simulated
    failed = listener.failures.total
    bridge.shutdown()
    error = listener.failures.last_error
    return {"setup": "world + runner + SimBridge", "mode": mode, "seconds": round(elapsed, 1), "frames": frames,
            "detections": detections[0], "failed": failed,
            "per_1000": round(1000 * failed / max(1, detections[0]), 1),
            "runner_alive": runner.error is None, **counts, "first_error": error}


def _run_threads(targets, seconds: float, stop: threading.Event) -> float:
    threads = [threading.Thread(target=t) for t in targets]
    started = time.monotonic()
    for thread in threads:
        thread.start()
    time.sleep(seconds)
    stop.set()
    for thread in threads:
        thread.join()
    return time.monotonic() - started


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--setup", choices=("detector", "world"), action="append",
                        help="the detector in a loop (the mechanism), or a world stepped by its runner (the soak)")
    parser.add_argument("--mode", choices=("census", "collect", "quiescent", "none"), action="append",
                        help="what the other thread does: gc.get_objects (the soak before the fix), gc.collect, "
                             "gc.get_objects with the world held still (the fix; world setup only), nothing")
    parser.add_argument("--seconds", type=float, default=20.0, help="per setup and mode (default 20)")
    args = parser.parse_args(argv)
    for setup in args.setup or ["detector", "world"]:
        for mode in args.mode or ["census", "collect", "quiescent", "none"]:
            if setup == "detector" and mode == "quiescent":
                continue    # there is no runner to pause in the bare loop
            print((run_detector if setup == "detector" else run_world)(mode, args.seconds), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
