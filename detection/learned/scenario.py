"""Data for the learned detector from faultmas' own running team: runs of the real ROS 2 nodes with a
varying workload, some with a performance bug injected in one component, each recorded with its truth.

One run: ``robot_bridge.ros2.launch`` starts every node of the robots as its own process (with
``FAULTMAS_PERFBUGS`` pointing at the run's schedule, see :mod:`robot_bridge.ros2.perfbugs`); a
workload node sends patrols of ``move``/``turn``/``rotate``/``stop`` actions on ``jason/actions``
in phases of changing intensity; the recorder taps every topic of the team and samples every node's
process. Profiles (``PROFILES``) say how many runs of which length; ``generate`` writes a data set
directory: ``manifest.json`` (runs, faults, components, channels and their columns) and ``run-NNN.npz``.

With an ``AgentTeam`` (``faultmas experiment perfbugs --agents``) the team's AgentSpeak agents run too,
one process each over Zenoh, driving their robots through the ROS 2 bridge beside the workload: the
recorder then also taps every faultmas Zenoh key (``zenoh_events``) and samples the agents'
processes, so the agents are components (``faulty_agent``...) with their keys as channels. Detection
never imports ``agents/``: the experiments layer hands the team in (``experiments.perfbugs_agents``).
"""
from __future__ import annotations

import json
import random
import sys
import tempfile
import threading
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable, Protocol, TextIO

from robot_bridge.ros2.perfbugs import ENV_VAR, KINDS, PerfBug, agent_component, component_name, write_schedule

ROBOTS = ("faulty", "helper")
WARMUP_S = 8.0
"""Seconds after all nodes are up before ticks count (imports, discovery, first messages)."""


@dataclass(frozen=True)
class Profile:
    name: str
    fault_free_runs: int
    faulty_runs: int
    duration_s: float
    camera: bool
    fault_length_s: tuple[float, float]
    kinds: tuple[str, ...] = KINDS
    faults: tuple[tuple[str, str], ...] = ()
    """Fixed (kind, component) per faulty run; empty: kinds in turn, in a random node of a random robot."""

    @property
    def runs(self) -> int:
        return self.fault_free_runs + self.faulty_runs


PROFILES: dict[str, Profile] = {
    # a quarter of an hour in all; the tests read it. The camera (rendering 640x480 at 10 Hz per robot)
    # is off so that a run fits a shared 2-core machine; every kind once, mostly in a motion decomposer
    # (its inputs and outputs change with the workload, so the model has something to learn).
    "smoke": Profile("smoke", fault_free_runs=8, faulty_runs=7, duration_s=60.0, camera=False,
                     fault_length_s=(30.0, 40.0),
                     faults=(("memory_leak", "helper_motion_decomposer"), ("wasted_cpu", "helper_motion_decomposer"),
                             ("thread_leak", "faulty_motion_decomposer"), ("added_latency", "helper_motion_decomposer"),
                             ("algorithmic_slowdown", "helper_motion_decomposer"), ("fd_leak", "faulty_kobuki_sim"),
                             ("delayed_communication", "helper_motion_decomposer"))),
    # the data set: >= 10 fault-free and >= 20 faulty runs of >= 4 min, every kind 3 times
    "paper": Profile("paper", fault_free_runs=12, faulty_runs=21, duration_s=240.0, camera=True,
                     fault_length_s=(40.0, 90.0)),
}


FAULTY_IDS = 100
"""Faulty runs are numbered from here, fault-free ones from 0: a profile can grow either kind of run
and the runs already recorded keep their ids."""


AGENT_SHARE = 3
"""With the agents, every third faulty run has its bug in an agent's process (``faulty_agent`` or
``helper_agent``): with 21 faulty runs, each of the 7 kinds once in an agent (j = 2, 5, ... 20 walk
through all kinds mod 7), the rest in the robots' nodes as without agents."""


def run_plan(profile: Profile, seed: int = 0, agents: bool = False) -> list[dict]:
    """Which runs to make: id, seed, and for a faulty run its (component node, kind); reproducible.
    ``agents``: the agents run too, and every ``AGENT_SHARE``-th faulty run's bug is in an agent."""
    rng = random.Random(seed)
    runs = [{"id": i, "seed": seed * 1000 + i, "kind": None} for i in range(profile.fault_free_runs)]
    nodes = ["kobuki_sim", "fault_injector", "motion_decomposer"] + (
        ["camera_sim", "visual_synthesizer"] if profile.camera else [])
    for j in range(profile.faulty_runs):
        if profile.faults:
            kind, component = profile.faults[j % len(profile.faults)]
        else:
            kind, component = profile.kinds[j % len(profile.kinds)], component_name(rng.choice(ROBOTS), rng.choice(nodes))
        if agents and j % AGENT_SHARE == AGENT_SHARE - 1:
            component = agent_component(ROBOTS[(j // AGENT_SHARE) % len(ROBOTS)])
        runs.append({"id": FAULTY_IDS + j, "seed": seed * 1000 + FAULTY_IDS + j, "kind": kind, "component": component})
    return runs


class Workload:
    """Patrols on every robot's ``jason/actions``: random motions in phases (busy, calm, idle)."""

    PHASES = (("busy", 0.8), ("calm", 3.0), ("idle", 8.0))          # mean gap between actions, s

    def __init__(self, node, robots: tuple[str, ...], seed: int) -> None:
        from std_msgs.msg import String

        self.rng = random.Random(seed)
        self.node = node
        self.publishers = {r: node.create_publisher(String, f"/{r}/jason/actions", 10) for r in robots}
        self.next_at = {r: 0.0 for r in robots}
        self.sign = {r: 1.0 for r in robots}
        self.phase, self.phase_end, self.id = self.PHASES[0], 0.0, 0
        self._string = String
        self.timer = node.create_timer(0.1, self._tick)

    def _tick(self) -> None:
        from robot_bridge.ros2.wire import ActionRequest

        now = time.monotonic()
        if now >= self.phase_end:
            self.phase = self.rng.choice(self.PHASES)
            self.phase_end = now + self.rng.uniform(8.0, 20.0)
        for robot, publisher in self.publishers.items():
            if now < self.next_at[robot]:
                continue
            self.next_at[robot] = now + self.rng.expovariate(1.0 / self.phase[1])
            choice = self.rng.random()
            if choice < 0.4:
                self.sign[robot] *= -1.0             # back and forth: the robots stay where they are
                name, params = "move", [f"{self.sign[robot] * self.rng.uniform(0.1, 0.6):.2f}"]
            elif choice < 0.75:
                name, params = "turn", [f"{self.rng.uniform(-180, 180):.0f}"]
            elif choice < 0.9:
                name, params = "rotate", [f"{self.rng.uniform(20, 60):.0f}"]
            else:
                name, params = "stop", []
            self.id += 1
            publisher.publish(self._string(data=ActionRequest(robot, name, tuple(params), self.id).to_json()))


class RunningAgents(Protocol):
    endpoint: str
    """A Zenoh endpoint (loopback) of the agents' hub, for the recorder's tap to connect to."""
    pids: dict[str, int]
    """Agent name → process id."""
    fault: str
    """The robot fault the agents' scenario injects (``fault_injector``); ``none`` for none."""

    def stop(self) -> None: ...


class AgentTeam(Protocol):
    """Starts a team's agents over Zenoh for one run, once the ROS 2 nodes are up."""

    def robot_fault(self, seed: int) -> str:
        """The fault of the first robot's ``fault_injector`` in the run with ``seed`` (the agents' scenario)."""

    def start(self, domain_id: int, seed: int, env: dict[str, str] | None = None) -> RunningAgents:
        """``env``: added to the agents' processes' environment (the run's perf-bug schedule)."""


def _domain_id(seed: int) -> int:
    return 100 + (seed + int(time.time())) % 100        # 100..199 (DOMAINS): clear of the tests' ids


DISCOVERY_S = 60.0
"""How long the recorder waits for the graph to show every node of the plan with all its topics."""


def settled_graph(probe, expected: set[str], what: str, timeout_s: float = DISCOVERY_S):
    """``discover`` once every node in ``expected`` is in the graph and two looks a second apart agree.

    Discovery has no fixed delay: on a busy host a fixed wait missed nodes, and a run recorded without
    them would silently lack components. A graph that does not settle in ``timeout_s`` fails the run."""
    from detection.learned.ros_tap import discover

    deadline, last = time.monotonic() + timeout_s, None
    while True:
        time.sleep(1.0)
        components, topic_types = discover(probe, [f"/{r}" for r in ROBOTS])
        now = ({n: c.to_dict() for n, c in components.items()}, topic_types)
        if expected <= set(components) and now == last:
            return components, topic_types
        if time.monotonic() >= deadline:
            missing = sorted(expected - set(components))
            raise RuntimeError(f"{what}: the ROS 2 graph did not settle in {timeout_s:.0f} s"
                               + (f" (nodes not seen: {', '.join(missing)})" if missing else " (topics still changing)"))
        last = now


def record_run(run: dict, profile: Profile, out_dir: Path, progress: Callable[[str], None],
               agents: AgentTeam | None = None, domain_id: int | None = None) -> dict:
    """Launch the team, run the workload for ``profile.duration_s`` and record; returns the run's manifest
    entry. With ``agents`` the team's agents run over Zenoh as well and are recorded as components.
    ``domain_id``: the ROS domain (default: one of 101..200 from the seed and the clock)."""
    from detection.learned.record import RunRecorder
    from detection.learned.ros_tap import RawTap
    from detection.learned.zenoh_events import (CHANNEL_TYPE, ZenohEventTap, adopt_bridge_nodes, agent_component,
                                                merge_zenoh)
    from robot_bridge.ros2.launch import Supervisor, plan
    from robot_bridge.ros2.runtime import RosContext

    rng = random.Random(run["seed"])
    domain = domain_id if domain_id is not None else _domain_id(run["seed"])
    robot_fault = agents.robot_fault(run["seed"]) if agents is not None else "none"
    team: RunningAgents | None = None
    zenoh_tap: ZenohEventTap | None = None
    with tempfile.TemporaryDirectory(prefix="faultmas-perfbugs-") as tmp:
        schedule = Path(tmp) / "schedule.json"
        write_schedule(schedule, [])               # filled once the start time is known (nodes read it at start)
        supervisor = Supervisor(plan(list(ROBOTS), fault=robot_fault, camera=profile.camera, seed=run["seed"]),
                                domain, extra_env={ENV_VAR: str(schedule)})
        bugs: list[PerfBug] = []
        supervisor.start()
        try:
            missing = supervisor.wait_ready(90.0)
            if missing or supervisor.dead():
                raise RuntimeError(f"run {run['id']}: nodes did not come up (missing {sorted(missing)})")
            pids = {component_name(s.robot, s.node): p.pid for s, p in zip(supervisor.specs, supervisor.processes)}
            if agents is not None:
                team = agents.start(domain, run["seed"], env={ENV_VAR: str(schedule)})
            with RosContext(domain_id=domain) as ros:
                import rclpy
                probe = ros.add(rclpy.create_node("faultmas_perfbugs_recorder", context=ros.context))
                if team is not None:
                    _wait_for_bridge_nodes(probe, team, run["id"])
                components, topic_types = settled_graph(probe, set(pids), f"run {run['id']}")
                if team is not None:
                    components = adopt_bridge_nodes(components, team.pids)
                agent_pids = {agent_component(a): pid for a, pid in team.pids.items()} if team else {}
                pids.update(agent_pids)
                recorder = RunRecorder({name: pids[name] for name in {*components, *agent_pids}})
                tap = RawTap(probe, topic_types, recorder.on_event)
                if team is not None:
                    zenoh_tap = ZenohEventTap(recorder.on_json, connect=[team.endpoint])
                Workload(probe, ROBOTS, run["seed"])
                time.sleep(WARMUP_S)
                recorder.start()
                began = time.time()
                if run["kind"]:          # the nodes' hooks re-read the schedule: the times count from now
                    start = began + rng.uniform(8.0, max(9.0, profile.duration_s - profile.fault_length_s[1] - 5.0))
                    length = rng.uniform(*profile.fault_length_s)
                    bugs = [PerfBug(run["component"], run["kind"], start, min(start + length, began + profile.duration_s))]
                    write_schedule(schedule, bugs)
                end = began + profile.duration_s
                while time.time() < end:
                    if supervisor.dead():
                        raise RuntimeError(f"run {run['id']}: a node died: {supervisor.dead()}")
                    if recorder.lost:    # an agent's process too: its counters would be missing, not healthy
                        raise RuntimeError(f"run {run['id']}: a process ended during the run: {', '.join(recorder.lost)}")
                    time.sleep(min(5.0, max(0.0, end - time.time())))
                    progress(f"run {run['id']}: {time.time() - began:4.0f}/{profile.duration_s:.0f} s, "
                             f"{tap.received} messages" + (f", {zenoh_tap.received} on Zenoh" if zenoh_tap else ""))
                recorder.stop()
        finally:
            if zenoh_tap is not None:
                zenoh_tap.close()
            if team is not None:
                team.stop()
            supervisor.stop()
    counts = recorder.save(out_dir / f"run-{run['id']:03d}.npz")
    channels = {t: {"type": topic_types[t], "columns": tap.encoders[t].columns, "events": counts.get(t, 0)}
                for t in topic_types}
    entry = {"id": run["id"], "seed": run["seed"], "file": f"run-{run['id']:03d}.npz", "start": began,
             "duration_s": profile.duration_s, "faults": [b.to_dict() for b in bugs],
             "components": {n: c.to_dict() for n, c in components.items()},
             "channels": channels, "dropped": tap.dropped, "lost_processes": recorder.lost}
    if team is not None:                 # only then: runs without agents keep their layout
        agent_components = zenoh_tap.channels.components(team.pids)
        merge_zenoh(components, agent_components)
        entry["components"] = {n: c.to_dict() for n, c in components.items()}
        channels.update({k: {"type": CHANNEL_TYPE, "columns": recorder.columns[k], "events": counts.get(k, 0)}
                         for k in recorder.columns})
        entry["agents"] = {"agents": sorted(team.pids), "robot_fault": team.fault,
                           "silent": sorted(set(map(agent_component, team.pids)) - set(agent_components)),
                           "dropped": zenoh_tap.dropped}
    return entry


def _wait_for_bridge_nodes(probe, team: RunningAgents, run_id: int, timeout: float = 90.0) -> None:
    from detection.learned.zenoh_events import wait_for_bridge_nodes

    if wait_for_bridge_nodes(probe, team.pids, timeout):
        raise RuntimeError(f"run {run_id}: the agents' ROS 2 nodes did not come up within {timeout:.0f} s")


DOMAINS = range(100, 200)
"""The ROS domain ids the generation takes (one per run being recorded); tests use others."""
LOCKS = Path(tempfile.gettempdir())


def allocate_domain(start: int = 0) -> tuple[int, object]:
    """A ROS domain id of ``DOMAINS`` no other run on this host records in, and the open lock file that
    holds it (close it when the run is over). Runs recorded at once must not share a domain: each would
    see the other's nodes. A lock (``flock``), not a random pick, so two workers never collide."""
    import fcntl
    for k in range(len(DOMAINS)):
        domain = DOMAINS[(start + k) % len(DOMAINS)]
        handle = open(LOCKS / f"faultmas-perfbugs-domain-{domain}.lock", "w")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return domain, handle
        except OSError:
            handle.close()
    raise RuntimeError(f"every ROS domain id of {DOMAINS.start}..{DOMAINS.stop - 1} is in use by a recording")


def _interleaved(runs: list[dict]) -> list[dict]:
    """Fault-free and faulty runs in an even mix, so that a generation cut short leaves both kinds."""
    groups = [[r for r in runs if not r["kind"]], [r for r in runs if r["kind"]]]
    return sorted(runs, key=lambda r: next((i + 0.5) / len(g) for g in groups if r in g for i in [g.index(r)]))


def _lock_dir(out_dir: Path) -> Path:
    """Where the workers of one data set claim runs (in the temp directory: the data set stays clean)."""
    import hashlib
    folder = LOCKS / f"faultmas-perfbugs-{hashlib.sha1(str(out_dir.resolve()).encode()).hexdigest()[:12]}"
    folder.mkdir(exist_ok=True)
    return folder


def _read_manifest(path: Path, profile: Profile, seed: int) -> dict:
    return json.loads(path.read_text()) if path.exists() else \
        {"format": 1, "profile": asdict(profile), "seed": seed, "runs": []}


def generate(out_dir: str | Path, profile_name: str, seed: int = 0, out: TextIO = sys.stderr,
             only: list[int] | None = None, agents: AgentTeam | None = None, jobs: int = 1) -> Path:
    """Make (or complete) the data set of ``profile_name`` in ``out_dir``; runs already there are kept.
    ``agents``: the team's agents run (and are recorded) too; see ``record_run``. ``jobs``: runs
    recorded at once, each by its own process in its own ROS domain (``allocate_domain``); any number
    of generations may share ``out_dir``: each run is claimed by a lock file and the manifest is
    merged under a lock after every run. A run that fails is reported and left for the next
    generation; ``RuntimeError`` at the end lists them."""
    import fcntl
    import signal

    profile = PROFILES[profile_name]
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    manifest_path = out_dir / "manifest.json"
    manifest = _read_manifest(manifest_path, profile, seed)
    if threading.current_thread() is threading.main_thread():      # SIGTERM stops the nodes too
        signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    if manifest["runs"] and bool(manifest.get("agents")) != (agents is not None):
        raise ValueError(f"{manifest_path}: its runs were recorded {'with' if manifest.get('agents') else 'without'} "
                         "the agents; record the other kind into another directory (--data)")
    workers = []
    if jobs > 1:                       # the others in processes of their own (a run's recorder keeps real time)
        import multiprocessing
        spawn = multiprocessing.get_context("spawn")
        workers = [spawn.Process(target=_worker, args=(out_dir, profile_name, seed, only, agents, f"w{k}"),
                                 daemon=True, name=f"perfbugs-generate-{k}") for k in range(2, jobs + 1)]
        for worker in workers:
            worker.start()
            time.sleep(20.0)           # staggered: two teams starting at once starve each other's discovery
    locks = _lock_dir(out_dir)
    done = {r["id"] for r in manifest["runs"]}
    todo = _interleaved([r for r in run_plan(profile, seed, agents is not None)
                         if r["id"] not in done and (only is None or r["id"] in only)])
    failed: list[str] = []
    for n, run in enumerate(todo, 1):
        claim = open(locks / f"run-{run['id']:03d}.lock", "w")
        try:
            fcntl.flock(claim, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            claim.close()
            continue                   # another worker records it
        try:
            if run["id"] in {r["id"] for r in _read_manifest(manifest_path, profile, seed)["runs"]}:
                continue               # recorded meanwhile by another worker
            what = f"{run['kind']} in {run['component']}" if run["kind"] else "fault-free"
            print(f"[{n}/{len(todo)}] run {run['id']} ({what})", file=out, flush=True)
            domain, domain_lock = allocate_domain(run["seed"])
            try:
                entry = record_run(run, profile, out_dir, lambda text: print(f"  {text}", file=out, flush=True),
                                   agents, domain_id=domain)
            except (RuntimeError, TimeoutError, OSError) as exc:
                print(f"  run {run['id']} failed, left for the next generation: {exc}", file=out, flush=True)
                failed.append(f"run {run['id']}: {exc}")
                continue
            finally:
                domain_lock.close()
            with open(locks / "manifest.lock", "w") as lock:        # merged: other workers write it too
                fcntl.flock(lock, fcntl.LOCK_EX)
                manifest = _read_manifest(manifest_path, profile, seed)
                if agents is not None:
                    manifest["agents"] = True          # only then: manifests without agents keep their keys
                manifest["runs"] = sorted([*[r for r in manifest["runs"] if r["id"] != entry["id"]], entry],
                                          key=lambda r: r["id"])
                partial = manifest_path.with_suffix(".json.part")
                partial.write_text(json.dumps(manifest, indent=1))
                partial.replace(manifest_path)    # after every run: an interrupted generation resumes where it was
        finally:
            claim.close()
    for worker in workers:
        worker.join()
        if worker.exitcode:
            failed.append(f"worker {worker.name} ended with exit code {worker.exitcode}")
    if failed:
        raise RuntimeError(f"{len(failed)} run(s) not recorded ({'; '.join(failed)}); "
                           "run the generation again to record them")
    return out_dir


def _worker(out_dir: Path, profile_name: str, seed: int, only, agents, label: str) -> None:
    """One more recording process of ``generate(jobs=N)``: takes the runs nobody has claimed."""
    from robot_bridge.processes import die_with_multiprocessing_parent
    die_with_multiprocessing_parent()           # a worker never outlives the generation that started it
    out = _Prefixed(sys.stderr, label)
    try:
        generate(out_dir, profile_name, seed, out, only, agents)
    except RuntimeError as exc:
        print(f"error: {exc}", file=out, flush=True)
        sys.exit(1)


class _Prefixed:
    """A text stream that marks each line with the worker's label (two workers print to one terminal)."""

    def __init__(self, stream: TextIO, label: str) -> None:
        self.stream, self.label = stream, label

    def write(self, text: str) -> int:
        return self.stream.write("".join(f"[{self.label}] {line}" if line.strip() else line
                                         for line in text.splitlines(keepends=True)))

    def flush(self) -> None:
        self.stream.flush()
