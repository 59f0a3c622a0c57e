"""The soak of issue 22 (``make soak``): one team of six robots that stays up and diagnoses fault after fault
for ``--sim-seconds`` of simulated time (default one hour), as a real team between repairs would.

The team is what ``faultmas run --robots 6`` starts (six agent processes over Zenoh, the embedded simulator
served by this process), started once. Its first task is an ordinary team run; then, task after task, this
process plays the fleet manager and the repair crew: it waits until every robot has ended its task or its
diagnosis and every agent is idle, repairs every robot, turns each round (towards the arena's middle when
near a wall), resets the odometry, injects a fault into one robot chosen at random, and tells every robot
``task(N, X, Y, YawDeg)`` (plans/team_robot_tasks.asl: its pose, and go again). Nothing is restarted, so a
leak anywhere in the team adds up over the hour, and an hour of simulated time costs about an hour of wall
time (the simulator runs in real time while the robots stand, faster while they move).

What it watches, after every task: this process (hub, simulator server, world) for RSS, what the RSS is made
of (``soak_memory``: malloc's heap and arenas, other anonymous and file-backed mappings, huge pages, and glibc's
in-use versus freed-but-kept bytes; tests/hardening/memory.py), threads and open descriptors; every agent
(the inspector's summary query) for intentions, events and beliefs once it should be idle (an agent still busy
then has a stuck intention); every agent process for RSS (and its parts) and threads; the
Zenoh declarations of this process's hub; what the simulator keeps that may grow (the camera renderer's
static layers, the trajectory rows kept: both bounded) and the gc-tracked objects. The summary gives the
least-squares slope of each RSS per hour of simulated time, over the run and over its second half (after
the bounded stores filled), and the object types that grew from the second task to the last. A task that ends
neither diagnosed nor arrived within ``--task-timeout`` simulated seconds (what the robots did, whatever the
machine's load: on 2 shared cores the simulator ran at 0.45-0.9x real time) or ``--task-wall-timeout`` wall
seconds (a hang) is named (``timeout``) and the next task starts anyway.

``python -m tests.hardening.soak --sim-seconds 3600 --out soak.jsonl`` (one JSON line per task, then the
summary line); ``--wall-seconds`` caps it, and the summary says which limit ended it."""
from __future__ import annotations

import argparse
import json
import math
import random
import sys
import tempfile
import threading
import time
from dataclasses import replace
from typing import Callable

import psutil

from tests.hardening.memory import memory_breakdown, smaps_breakdown

PROGRAM = "team_robot_tasks.asl"
FINAL = ("arrived", "diagnosed", "undiagnosed")
SENDER = "fleet"
"""The name tasks come from: not a member of the MAS, which the default profile allows for a tell."""


def _team_state(hub, mas: str) -> dict:
    """Every agent's summary (intentions, events, beliefs) through the inspector's queryable."""
    from agents.inspector.keys import state_key

    selector = state_key(mas, "x").rsplit("/x/", 1)[0] + "/*/state?summary"
    states = {}
    for reply in hub.session.get(selector, timeout=5.0):
        if reply.ok is not None:
            state = json.loads(reply.ok.payload.to_bytes())
            states[state["agent"]] = {k: state.get(k) for k in ("intentions", "events", "beliefs", "top")}
    return states


def _agent_processes(launched: dict) -> tuple[dict, dict]:
    """RSS (MiB, and what it is made of) and threads of the agent processes still running, by agent name; and
    the names of those that ended (``launched``: name -> pid, as first seen; not reaped here: the launcher
    reports the status)."""
    found = {}
    for child in psutil.Process().children():
        try:
            argv = child.cmdline()
            if "--name" in argv and child.status() != psutil.STATUS_ZOMBIE:
                name = argv[argv.index("--name") + 1]
                launched.setdefault(name, child.pid)
                found[name] = {"rss_mib": round(child.memory_info().rss / 2 ** 20, 1), "threads": child.num_threads(),
                               "memory": smaps_breakdown(child.pid)}
        except (psutil.Error, OSError):      # ended meanwhile (its smaps gone)
            pass
    return found, {name: pid for name, pid in launched.items() if name not in found}


class TaskLog:
    """The robots' ``.progress`` reports, by task: a robot's reports belong to the task it last announced."""

    def __init__(self, robots: list[str]) -> None:
        self.robots = robots
        self.task = {r: 0 for r in robots}
        self.final: dict[int, dict[str, tuple[str, str]]] = {}
        self.changed = threading.Condition()

    def on_control(self, message: dict) -> None:
        from agents.progress import ProgressReport

        report = ProgressReport.from_message(message)
        if report is None or report.agent not in self.task:
            return
        with self.changed:
            if report.step == "task":
                self.task[report.agent] = int(report.detail)
            elif report.step in FINAL:
                self.final.setdefault(self.task[report.agent], {}).setdefault(report.agent, (report.step, report.detail))
            self.changed.notify_all()

    def wait_done(self, task: int, expired: Callable[[], bool], timeout: float) -> bool:
        """Wait until every robot has ended ``task`` (its destination reached, or a diagnosis), ``expired()``
        (checked twice a second: the task's simulated budget) or ``timeout`` wall seconds."""
        deadline = time.monotonic() + timeout
        with self.changed:
            while len(self.final.get(task, {})) < len(self.robots):
                left = deadline - time.monotonic()
                if left <= 0 or expired():
                    return False
                self.changed.wait(min(0.5, left))
            return True


def _wait_idle(hub, mas: str, robots: list[str], timeout: float) -> tuple[dict, float]:
    """The agents' states once all are idle (no intention, no event), or as they are after ``timeout``."""
    deadline = time.monotonic() + timeout
    while True:
        states = _team_state(hub, mas)
        idle = all(states.get(r, {}).get("intentions") == 0 and states.get(r, {}).get("events") == 0 for r in robots)
        if idle or time.monotonic() >= deadline:
            return states, max(0.0, timeout - (deadline - time.monotonic()))
        time.sleep(0.5)


def _turn_round(world, bridges, robot: str) -> float:
    """Degrees for ``robot`` to face the arena's middle when it stands near a wall, else about."""
    x, y, yaw = world.pose(robot)
    xmin, ymin, xmax, ymax = world.arena
    cx, cy = (xmin + xmax) / 2, (ymin + ymax) / 2
    if min(x - xmin, xmax - x, y - ymin, ymax - y) < 2.0:
        heading = math.degrees(math.atan2(cy - y, cx - x))
    else:
        heading = yaw + 180.0
    return (heading - yaw + 180.0) % 360.0 - 180.0


def _next_task(n: int, world, bridges, hub, mas: str, rng: random.Random, timeout: float) -> tuple[str, str, list]:
    """Repair, turn round, reset odometry, inject one fault, tell every robot task ``n``; also returns the
    robots whose turn did not complete (against another robot, or not within ``timeout`` wall seconds):
    they start from where they are."""
    import concurrent.futures

    from agents.cooperative import TEAM_FAULTS
    from agents.transport.envelope import Envelope
    from robot_bridge.protocol import Action

    robots = list(bridges)
    for robot in robots:
        world.set_fault(robot, "none")
    turns = {r: bridges[r].act(Action("turn", (round(_turn_round(world, bridges, r), 1),))) for r in robots}
    concurrent.futures.wait(list(turns.values()), timeout=timeout)
    unturned = sorted(r for r, f in turns.items() if not f.done() or not f.result().ok)
    for robot in unturned:
        world.cancel_all("preempted", name=robot)
    faulty, fault = rng.choice(robots), rng.choice(TEAM_FAULTS)
    for robot in robots:
        world.reset_odometry(robot)
    world.set_fault(faulty, fault)
    for robot in robots:
        x, y, yaw = world.pose(robot)
        hub.send(Envelope(mas, SENDER, (robot,), "tell", f"task({n}, {x:.3f}, {y:.3f}, {yaw:.1f})"))
    return faulty, fault, unturned


def _kept_by_simulator(world, runner) -> dict:
    """What the simulator holds that may grow with time, so a RSS step can be told from a leak: the camera
    renderers' static layers (bounded, 32 poses each), the trajectory rows kept, Python's gc objects; and the
    camera frames its listeners (the robots' detectors) failed on so far, each dropped with a log line.

    The census runs with the world held still (``WorldRunner.paused``): ``gc.get_objects`` beside the simulator's
    thread took the tuple ``cv2.findContours`` was filling, and OpenCV failed that frame with a SystemError
    (issue 22, docs/reliability.md: 32 to 60 per 1,000 detections in ``tests/hardening/gc_census_race.py``)."""
    import gc

    with runner.paused():
        renderers = _renderers_alive()
        gc_objects = len(gc.get_objects())
    layers = sum(len(r._static) for r in renderers)
    layer_bytes = sum(kept[1].nbytes + kept[2].nbytes for r in renderers for kept in list(r._static.values()))
    rows = sum(len(robot.trajectory) for robot in world._robots.values())
    failed = sum(listener.failures.total for robot in world._robots.values() for listener in robot.camera_listeners)
    return {"static_layers": layers, "static_layers_mib": round(layer_bytes / 2 ** 20, 1),
            "trajectory_rows": rows, "gc_objects": gc_objects, "camera_frames_failed": failed}


def _renderers_alive() -> list:
    """The camera renderers this process made (one per rig and sensor, cached)."""
    import gc

    from robot_bridge.sim.camera.renderer import _Renderer

    return [o for o in gc.get_objects() if isinstance(o, _Renderer)]


def _type_counts() -> dict[str, int]:
    """Live gc-tracked objects by type name (compared first task against last: what grows)."""
    import collections
    import gc

    return dict(collections.Counter(type(o).__qualname__ for o in gc.get_objects()))


def _declared(hub) -> int:
    """Zenoh publishers and subscribers this process's hub holds (per receiver and agent)."""
    return len(hub._publishers) + len(hub._declared)


def _poses(world, robots: list[str]) -> dict[str, list[float]]:
    """Every robot's ground-truth pose (x m, y m, yaw deg) at a task's start: with the seed, the fault and the
    agents' log, what reproduces a task (``tests/hardening/soak_replay.py``)."""
    return {r: [round(v, 3) for v in world.pose(r)] for r in robots}


def _write_paths(path: str, world, robots: list[str], since: float, every: int = 5) -> None:
    """Every robot's ground-truth path since ``since`` (simulated s; every ``every``-th logged point):
    where a task that did not end correct took the robots, beside the agents' lines."""
    paths = {r: [[round(p.time, 2), round(p.x, 3), round(p.y, 3), round(p.yaw_deg, 1)]
                 for p in world.trajectory(r)[::every] if p.time >= since] for r in robots}
    with open(path, "w") as out:
        json.dump(paths, out)


class _Stamped:
    """The agents' lines to a file, each with the simulated time it was read at (the task markers too)."""

    def __init__(self, path: str, world) -> None:
        self.file, self.world, self.lock = open(path, "w"), world, threading.Lock()

    def write(self, text: str) -> None:
        with self.lock:
            for line in text.splitlines(keepends=True):
                self.file.write(f"{self.world.time:9.2f} {line}")
            self.file.flush()

    def flush(self) -> None:
        pass

    def close(self) -> None:
        self.file.close()


def soak(sim_seconds: float, wall_seconds: float | None, task_timeout: float, seed: int, settle: float,
         emit, agent_log: str | None = None, task_wall_timeout: float = 900.0) -> dict:
    from agents.cooperative import build_world, run_agent_processes, team_scenario
    from robot_bridge.sim.runner import shared_runner
    from robot_bridge.sim.server import SimServer

    first = team_scenario(6, 1, seed)
    scenario = replace(first, robots=tuple(replace(r, program=PROGRAM) for r in first.robots))
    robots = [r.name for r in scenario.robots]
    world, bridges = build_world(scenario)
    runner = shared_runner(world)
    log = TaskLog(robots)
    rng = random.Random(seed)
    me = psutil.Process()
    # the rows wait in a file, not in this process's memory: kept as dicts they grew it ~1.2 MiB per simulated hour
    # (about 10 KB a task), which a slope of the soak process's RSS would count as the simulator's
    kept_rows = tempfile.TemporaryFile("w+", encoding="utf-8")
    hub_of: dict = {}
    lines = _Stamped(agent_log, world) if agent_log else None
    poses = _poses(world, robots)
    started = time.monotonic()

    def serve(hub):
        hub_of["hub"] = hub
        hub.on_control(log.on_control)
        return SimServer(hub.session, scenario.mas, bridges).start().stop

    def limit_reached() -> str | None:
        if runner.error is not None:     # the world stands still: no task can end (the soak names it, no hang)
            return f"simulator failed: {runner.error!r}"
        if world.time >= sim_seconds:
            return "sim_seconds"
        if wall_seconds is not None and time.monotonic() - started >= wall_seconds:
            return "wall_seconds"
        return None

    def hold():
        try:
            tasks()
        except Exception as exc:   # the figures so far still count: the summary names what ended it
            import traceback
            traceback.print_exc()
            hold_state["ended_by"] = f"soak error: {exc!r}"

    def tasks():
        nonlocal poses
        hub = hub_of["hub"]
        n, faulty = 0, next((r.name, r.fault, []) for r in scenario.robots if r.fault != "none")
        task_sim, task_wall = 0.0, started
        while True:
            done = log.wait_done(n, lambda: world.time - task_sim >= task_timeout or runner.error is not None,
                                 max(0.0, task_wall_timeout - (time.monotonic() - task_wall)))
            states, waited = _wait_idle(hub, scenario.mas, robots, settle)
            processes, ended_agents = _agent_processes(launched)
            ended = log.final.get(n, {})
            step, detail = ended.get(faulty[0], (None, None))
            diagnosis = detail if step == "diagnosed" else step
            row = {"task": n, "seed": seed, "faulty": faulty[0], "fault": faulty[1], "diagnosis": diagnosis,
                   "unturned": faulty[2], "poses": poses,
                   "outcome": ("correct" if diagnosis == faulty[1] else "wrong") if done else "timeout",
                   "not_ended": sorted(set(robots) - set(ended)),
                   "sim_s": round(world.time - task_sim, 1), "wall_s": round(time.monotonic() - task_wall, 1),
                   "sim_total_s": round(world.time, 1), "wall_total_s": round(time.monotonic() - started, 1),
                   "settle_s": round(waited, 1),
                   "stuck": {a: s for a, s in states.items() if s.get("intentions") or s.get("events")},
                   "missing_agents": sorted(set(robots) - set(states)),
                   "agents": {a: {k: s.get(k) for k in ("intentions", "events", "beliefs")} for a, s in states.items()},
                   "agent_processes": processes, "ended_agents": ended_agents,
                   "soak_rss_mib": round(me.memory_info().rss / 2 ** 20, 1), "soak_memory": memory_breakdown(),
                   "soak_threads": threading.active_count(),
                   "soak_os_threads": me.num_threads(), "soak_fds": me.num_fds(), "hub_declared": _declared(hub),
                   **_kept_by_simulator(world, runner)}
            if n == 1:
                with runner.paused():   # a census beside the simulator's thread fails its OpenCV calls
                    type_counts["first"] = _type_counts()
            if agent_log and row["outcome"] != "correct":
                _write_paths(f"{agent_log}.task{n}.json", world, robots, task_sim)
            kept_rows.write(json.dumps(row) + "\n")
            emit(row)
            why = limit_reached()
            if why is not None or len(row["agent_processes"]) < len(robots):
                with runner.paused():
                    type_counts["last"] = _type_counts()
                hold_state["ended_by"] = why or "an agent process ended"
                return
            n += 1
            task_sim, task_wall = world.time, time.monotonic()
            faulty = _next_task(n, world, bridges, hub, scenario.mas, rng, task_wall_timeout)
            poses = _poses(world, robots)
            if lines is not None:
                lines.write(f"== task {n}: {faulty[0]} {faulty[1]}, poses {json.dumps(poses)}\n")

    hold_state: dict = {}
    type_counts: dict = {}
    launched: dict = {}
    try:
        run = run_agent_processes(scenario, ["--bridge", "zenoh"], task_wall_timeout, world=world, serve=serve, hold=hold,
                                  out=lines)
    finally:
        if lines is not None:
            lines.close()
        for bridge in bridges.values():
            bridge.shutdown()
    kept_rows.seek(0)
    rows = [json.loads(line) for line in kept_rows]
    kept_rows.close()
    summary = summarize(rows, hold_state.get("ended_by", "the first task failed"), run.died, run.frozen, started,
                        task_timeout)
    if "first" in type_counts and "last" in type_counts:
        first, last = type_counts["first"], type_counts["last"]
        growth = {t: last.get(t, 0) - first.get(t, 0) for t in set(first) | set(last)}
        summary["gc_types_grown_task1_to_last"] = dict(sorted(((t, g) for t, g in growth.items() if g > 0),
                                                              key=lambda tg: -tg[1])[:15])
    return summary


def _slope(xs: list[float], ys: list[float]) -> float:
    if len(xs) < 2:
        return 0.0
    import numpy as np
    return float(np.polyfit(xs, ys, 1)[0])


MEMORY_PARTS = ("rss", "heap", "arenas", "anon", "file", "huge", "advised", "malloc.in_use", "malloc.free",
                "malloc.mmapped")


AGENT_MEMORY_PARTS = ("rss", "heap", "arenas", "anon", "file")
"""An agent's row has the smaps parts only (glibc's own account is read in-process, by the soak for itself)."""


def _part(memory: dict, part: str) -> float:
    """``part`` of a row's ``soak_memory`` (``malloc.free``: a field of glibc's account; 0 without it)."""
    for key in part.split("."):
        memory = (memory or {}).get(key)
    return memory or 0.0


def summarize(rows: list[dict], ended_by: str, died, frozen, started: float, task_timeout: float = 240.0) -> dict:
    settled = rows[1:] or rows  # the first task loads the interpreter, models, Zenoh and caches: not a leak
    hours = [r["sim_total_s"] / 3600 for r in settled]
    half_time = (settled[0]["sim_total_s"] + settled[-1]["sim_total_s"]) / 2 if settled else 0.0
    second_half = [r for r in settled if r["sim_total_s"] >= half_time]
    agents = sorted({a for r in rows for a in r["agent_processes"]})

    def first_last(key):
        return [settled[0][key], settled[-1][key]] if settled else None
    per_agent_slope = {a: round(_slope([r["sim_total_s"] / 3600 for r in settled if a in r["agent_processes"]],
                                       [r["agent_processes"][a]["rss_mib"] for r in settled
                                        if a in r["agent_processes"]]), 2) for a in agents}
    return {
        "ended_by": ended_by, "tasks": len(rows),
        "sim_hours": round(rows[-1]["sim_total_s"] / 3600, 3) if rows else 0.0,
        "wall_hours": round((time.monotonic() - started) / 3600, 3),
        "outcomes": {o: sum(r["outcome"] == o for r in rows) for o in ("correct", "wrong", "timeout")},
        "task_sim_s_max": max((r["sim_s"] for r in rows), default=None),
        "task_wall_s_max": max((r["wall_s"] for r in rows), default=None),
        "tasks_longer_than_budget_in_wall_time": sum(r["wall_s"] > task_timeout for r in rows),
        "died": died, "agents_ended": sorted({a for r in rows for a in r["ended_agents"]}), "frozen": frozen,
        "tasks_with_stuck_intentions": sum(bool(r["stuck"]) for r in rows),
        "max_settle_s": max((r["settle_s"] for r in rows), default=None),
        "soak_rss_mib_first_last": first_last("soak_rss_mib"),
        "soak_rss_slope_mib_per_sim_hour": round(_slope(hours, [r["soak_rss_mib"] for r in settled]), 2),
        "soak_rss_slope_second_half_mib_per_sim_hour": round(_slope(
            [r["sim_total_s"] / 3600 for r in second_half], [r["soak_rss_mib"] for r in second_half]), 2),
        "soak_memory_first_last": first_last("soak_memory"),
        "soak_memory_slope_second_half_mib_per_sim_hour": {
            part: round(_slope([r["sim_total_s"] / 3600 for r in second_half],
                               [_part(r["soak_memory"], part) for r in second_half]), 2)
            for part in MEMORY_PARTS} if second_half and "soak_memory" in second_half[0] else None,
        "static_layers_mib_first_last": first_last("static_layers_mib"),
        "gc_objects_first_last": first_last("gc_objects"),
        "soak_threads_first_last": first_last("soak_os_threads"),
        "soak_fds_first_last": first_last("soak_fds"),
        "hub_declared_first_last": first_last("hub_declared"),
        "agent_rss_mib_first_last": {a: [next(r["agent_processes"][a]["rss_mib"] for r in settled if a in r["agent_processes"]),
                                         next(r["agent_processes"][a]["rss_mib"] for r in reversed(settled) if a in r["agent_processes"])]
                                     for a in agents} if settled else {},
        "agent_rss_slope_mib_per_sim_hour": per_agent_slope,
        "agent_rss_slope_second_half_mib_per_sim_hour": {
            a: round(_slope([r["sim_total_s"] / 3600 for r in second_half if a in r["agent_processes"]],
                            [r["agent_processes"][a]["rss_mib"] for r in second_half if a in r["agent_processes"]]), 2)
            for a in agents},
        "agent_memory_slope_second_half_mib_per_sim_hour": {
            a: {part: round(_slope([r["sim_total_s"] / 3600 for r in second_half if a in r["agent_processes"]],
                                   [_part(r["agent_processes"][a].get("memory"), part)
                                    for r in second_half if a in r["agent_processes"]]), 2)
                for part in AGENT_MEMORY_PARTS}
            for a in agents},
        "agent_threads_first_last": {a: [next(r["agent_processes"][a]["threads"] for r in settled if a in r["agent_processes"]),
                                         next(r["agent_processes"][a]["threads"] for r in reversed(settled) if a in r["agent_processes"])]
                                     for a in agents} if settled else {},
        "agent_beliefs_first_last": {a: [settled[0]["agents"].get(a, {}).get("beliefs"),
                                         settled[-1]["agents"].get(a, {}).get("beliefs")] for a in agents} if settled else {},
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sim-seconds", type=float, default=3600.0, help="simulated time to reach (default 1 h)")
    parser.add_argument("--wall-seconds", type=float, default=None,
                        help="also stop after this much wall time (the summary says which limit ended it)")
    parser.add_argument("--task-wall-timeout", type=float, default=900.0,
                        help="wall seconds a task may take before it is named a timeout whatever the simulated "
                             "time (a hang; default 900)")
    parser.add_argument("--task-timeout", type=float, default=240.0,
                        help="simulated seconds a task may take before it is named a timeout (default 240)")
    parser.add_argument("--settle", type=float, default=30.0,
                        help="wall seconds the agents may take to be idle once a task ended (default 30)")
    parser.add_argument("--seed", type=int, default=1000)
    parser.add_argument("--out", default=None, help="also write the JSON lines here")
    parser.add_argument("--agent-log", default=None,
                        help="write the agents' lines here, stamped with simulated time, a marker at each task; "
                             "and the robots' paths of every task that did not end correct to PATH.taskN.json")
    args = parser.parse_args(argv)
    out = open(args.out, "w") if args.out else None

    def emit(row: dict) -> None:
        line = json.dumps(row)
        print(line, flush=True)
        if out:
            out.write(line + "\n")
            out.flush()
    summary = soak(args.sim_seconds, args.wall_seconds, args.task_timeout, args.seed, args.settle, emit,
                   args.agent_log, args.task_wall_timeout)
    emit({"summary": summary})
    if out:
        out.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
