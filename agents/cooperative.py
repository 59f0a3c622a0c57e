"""The cooperative fault-diagnosis run: robots on the embedded simulator, one agent each, timed steps.

A ``Scenario`` says where the robots stand, which are faulty and how; ``run_scenario`` runs it either
with one OS process per agent talking over Zenoh (``processes=True``, the main job: the simulator is
served to them by ``robot_bridge.sim.server``) or with every agent in this process (the evaluation's
fast path: same plans, same simulator, no network). Agents report their steps with ``.progress``;
a ``ProgressLog`` stamps each with simulated and wall time and ends the run once every robot has
finished its task or its diagnosis.

Fault ``none`` is the paper's false alarm: nothing is broken, but the robot is held for a moment while
it starts (a transient stall, injected as ``both_actuators`` and cleared as soon as the robot reports the
fault), so it raises an alarm that the diagnosis must dismiss.
"""
from __future__ import annotations

import math
import signal
import random
import threading
import time
from dataclasses import dataclass, field
from importlib import resources
from typing import Callable, TextIO

FAULTS = ("none", "encoders", "both_actuators", "left_actuator", "right_actuator", "stuck_wheels")
EXPECTED = {"none": "none", "encoders": "encoders", "both_actuators": "both_actuators",
            "stuck_wheels": "stuck_wheels", "left_actuator": "left_actuator", "right_actuator": "right_actuator"}
"""The outcome the plans must reach for each injected fault. Stuck wheels and dead motors both leave the
robot still, but the model tells them apart by the motors' over-current flags (docs/cooperative.md)."""
FINAL_STEPS = ("arrived", "diagnosed", "undiagnosed")
DEATH_GRACE = 5.0
"""Seconds a run goes on after a robot it waits for died (its process ended with a signal or an error)."""
STEP_NAMES = ("fault_detection", "robot_detection", "diagnosis", "total")


@dataclass(frozen=True)
class RobotSetup:
    name: str
    x: float
    y: float
    yaw_deg: float
    fault: str = "none"
    program: str = "helper.asl"
    false_alarm: bool = False
    """A transient stall at the start (fault ``none`` of a robot that must raise an alarm)."""

    @property
    def under_test(self) -> bool:
        return self.fault != "none" or self.false_alarm


@dataclass(frozen=True)
class Scenario:
    robots: tuple[RobotSetup, ...]
    seed: int = 1
    destination: float = 1.0
    lighting: float = 1.0
    mas: str = "coop"

    @property
    def under_test(self) -> list[RobotSetup]:
        return [r for r in self.robots if r.under_test]


def paper_scenario(fault: str = "encoders", seed: int = 1) -> Scenario:
    """The paper's set-up: Faulty and Helper side by side, 1.5 m apart, both facing the same way."""
    return Scenario((RobotSetup("faulty", 0.0, 0.0, 0.0, fault, "faulty.asl", fault == "none"),
                     RobotSetup("helper", 0.0, -1.5, 0.0)), seed=seed)


def random_pair_scenario(fault: str, seed: int) -> Scenario:
    """The evaluation's set-up, as issue 7 asks: the helper 1-3 m away at any bearing, both robots with
    any heading, lighting 0.6-1.4. End-on, the faulty robot's two cylinders hide each other from any
    marker detector; the plans deal with it (the faulty robot turns to show its side, the helper steps
    away and looks again), except for a robot that can neither move nor be seen (see the eval note)."""
    rng = random.Random(seed)
    distance = rng.uniform(1.0, 3.0)
    bearing = rng.uniform(-180.0, 180.0)              # where the helper stands, seen from the faulty robot
    faulty_yaw = rng.uniform(-180.0, 180.0)
    hx, hy = distance * math.cos(math.radians(bearing)), distance * math.sin(math.radians(bearing))
    return Scenario((RobotSetup("faulty", 0.0, 0.0, faulty_yaw, fault, "faulty.asl", fault == "none"),
                     RobotSetup("helper", hx, hy, rng.uniform(-180.0, 180.0))),
                    seed=seed, lighting=rng.uniform(0.6, 1.4))


TEAM_FAULTS = ("encoders", "both_actuators", "left_actuator", "right_actuator")
"""The faults a team run draws from when none is given (``none`` needs a robot that raises a false alarm)."""
TEAM_MARGIN = 0.8
"""Metres kept between a robot's start and the arena's walls (its 0.5 m task leg must fit)."""


def team_scenario(robots: int, faulty: int, seed: int, fault: str | None = None,
                  arena: tuple[float, float, float, float] = (-5.0, -5.0, 5.0, 5.0)) -> Scenario:
    """``robots`` robots at random places over the whole arena, at least 1.6 m apart, with any heading;
    ``faulty`` of them with ``fault`` (random faults when None); every robot runs ``team_robot.asl`` (its
    own task, and help for the others when free). Robots may start far beyond each other's camera range:
    a help request says where the robot is (``start_pose`` + odometry, see plans/geometry.asl)."""
    if not 2 <= robots <= 12 or not 1 <= faulty < robots:
        raise ValueError(f"--robots must be 2..12 and --faulty 1..robots-1, got {robots} and {faulty}")
    if fault is not None and fault not in FAULTS:
        raise ValueError(f"unknown fault {fault!r}; expected one of {', '.join(FAULTS)}")
    rng = random.Random(seed)
    xmin, ymin, xmax, ymax = arena
    spots: list[tuple[float, float]] = []
    while len(spots) < robots:
        x = rng.uniform(xmin + TEAM_MARGIN, xmax - TEAM_MARGIN)
        y = rng.uniform(ymin + TEAM_MARGIN, ymax - TEAM_MARGIN)
        if all(math.hypot(x - a, y - b) >= 1.6 for a, b in spots):
            spots.append((x, y))
    broken = set(rng.sample(range(robots), faulty))
    setups = tuple(RobotSetup(f"robot{i + 1}", x, y, rng.uniform(-180.0, 180.0),
                              (fault or rng.choice(TEAM_FAULTS)) if i in broken else "none", "team_robot.asl",
                              false_alarm=i in broken and fault == "none")
                   for i, (x, y) in enumerate(spots))
    return Scenario(setups, seed=seed, destination=0.5)


def _wrap(deg: float) -> float:
    return (deg + 180.0) % 360.0 - 180.0


# ---- the steps, as reported by the agents ---------------------------------------------------------
@dataclass
class Mark:
    agent: str
    step: str
    detail: str
    sim: float
    wall: float


@dataclass
class RobotResult:
    name: str
    fault: str
    expected: str
    diagnosis: str | None
    steps_sim: dict[str, float | None]
    steps_wall: dict[str, float | None]

    @property
    def correct(self) -> bool:
        return self.diagnosis == self.expected


@dataclass
class RunResult:
    scenario: Scenario
    robots: list[RobotResult]
    marks: list[Mark]
    finished: bool
    """Every robot ended its task or its diagnosis before the time limit."""
    world: object = None
    died: list[tuple[str, int]] = field(default_factory=list)
    """Agent processes that ended on their own with a non-zero status (negative: killed by that signal),
    in the order seen: the run ends at once and names them (issue 22). Robot processes (ROS 2 nodes) are
    named ``robot/node``."""
    frozen: list[tuple[str, float]] = field(default_factory=list)
    """(process, seconds) of the processes seen stopped (SIGSTOP) during the run, continued since or not:
    named in its summary (a freeze explains a timeout)."""

    @property
    def outcome(self) -> str:
        """'died', 'correct', 'wrong' or 'timeout': what ended the run, for people and exit codes (a helper
        that died while another finished its work is named in ``died`` but does not fail the run)."""
        if self.died and not self.finished:
            return "died"
        if not self.finished:
            return "timeout"
        return "correct" if self.correct else "wrong"

    @property
    def correct(self) -> bool:
        return self.finished and all(r.correct for r in self.robots)


class ProgressLog:
    """``.progress`` reports stamped with simulated and wall time; calls ``on_done`` once all robots
    have reported a final step, and clears a false alarm's transient stall once the fault is seen."""

    def __init__(self, scenario: Scenario, world, on_done: Callable[[], None],
                 echo: Callable[[Mark], None] | None = None, clock: Callable[[], float] | None = None) -> None:
        self.scenario, self.world, self.on_done, self.echo = scenario, world, on_done, echo
        self.clock = clock or (lambda: world.time)
        """Simulated seconds now (the world's clock; real-time robots pass a wall clock)."""
        self.marks: list[Mark] = []
        self.start = time.monotonic()
        self._lock = threading.Lock()
        self._final: set[str] = set()
        self.done = threading.Event()
        self.died: list[tuple[str, int]] = []  # (agent, exit status) of processes that died (processes only)
        self.frozen: list[tuple[str, float]] = []  # (process, seconds) seen stopped (SIGSTOP) during the run
        self.ended = False

    def end(self) -> None:
        """The run is over: later reports are still echoed (a team held up for the inspector, or given task
        after task as issue 22's soak does) but no longer kept, so a team held for days does not grow by
        them (~280 bytes a report, ~30 reports a task) and the run's result stays the run's."""
        with self._lock:
            self.ended = True

    def record(self, report) -> None:
        """Takes an ``agents.progress.ProgressReport`` (from any thread)."""
        mark = Mark(report.agent, report.step, report.detail, self.clock(), time.monotonic() - self.start)
        with self._lock:
            ended = self.ended
        if ended:
            if self.echo is not None:
                self.echo(mark)
            return
        with self._lock:
            self.marks.append(mark)
            if report.step in FINAL_STEPS:
                self._final.add(report.agent)
            complete = self._final >= {r.name for r in self.scenario.robots if r.under_test} and \
                self._final | {r.name for r in self.scenario.robots if r.program == "helper.asl"} >= \
                {r.name for r in self.scenario.robots}
        setup = next((r for r in self.scenario.robots if r.name == report.agent), None)
        if report.step == "fault_detected" and setup is not None and setup.false_alarm and self.world:
            self.world.set_fault(report.agent, "none")      # the transient stall is over
        if self.echo is not None:
            self.echo(mark)
        if complete and not self.done.is_set():
            self.done.set()
            self.on_done()

    def needed(self, agent: str) -> bool:
        """Whether the run still waits for ``agent``: under test (or not a helper) and no final step yet."""
        robot = next((r for r in self.scenario.robots if r.name == agent), None)
        with self._lock:
            return robot is not None and (robot.under_test or robot.program != "helper.asl") \
                and agent not in self._final

    def results(self) -> list[RobotResult]:
        return [self._result(r) for r in self.scenario.robots if r.under_test or r.program != "helper.asl"]

    def _first(self, agent: str, steps: tuple[str, ...], detail: str | None = None) -> Mark | None:
        return next((m for m in self.marks if m.agent == agent and m.step in steps
                     and (detail is None or m.detail == detail)), None)

    def _result(self, robot: RobotSetup) -> RobotResult:
        started = self._first(robot.name, ("started",))
        detected = self._first(robot.name, ("fault_detected",))
        final = self._first(robot.name, ("diagnosed", "undiagnosed"))
        found = next((m for m in self.marks if m.step == "robot_found" and m.detail == robot.name), None)
        searches = [m for m in self.marks if m.step == "searching" and m.detail == robot.name
                    and found is not None and m.agent == found.agent and m.wall <= found.wall]
        searching = searches[-1] if searches else None      # the search that succeeded
        diagnosis_from = found or detected
        pairs = {"fault_detection": (started, detected), "robot_detection": (searching, found),
                 "diagnosis": (diagnosis_from, final), "total": (started, final)}
        sim = {k: (b.sim - a.sim if a and b else None) for k, (a, b) in pairs.items()}
        wall = {k: (b.wall - a.wall if a and b else None) for k, (a, b) in pairs.items()}
        if final is not None and final.step == "diagnosed":
            diagnosis = final.detail
        elif final is not None:
            diagnosis = "undiagnosed"
        else:
            diagnosis = "none" if self._first(robot.name, ("arrived",)) else None
        return RobotResult(robot.name, robot.fault, EXPECTED[robot.fault], diagnosis, sim, wall)


# ---- running ---------------------------------------------------------------------------------------
def plans_dir():
    return resources.files("plans")


PROCESS_BUSY_CAP = 4.0
"""Simulated seconds per wall second at most while robots move, when the agents run in processes of their own
(idle, the world runs at real time as always): fast enough for short runs, slow enough that a command sent
over Zenoh arrives long before a simulated deadline passes (a 3 s move deadline is 0.75 s of wall time,
against milliseconds of latency; always real time tripled the runs' wall time)."""


def build_world(scenario: Scenario, speed: float = 0.0, busy_cap: float | None = None):
    """The world and one ``SimBridge`` (with camera) per robot, set up; ``busy_cap``: see ``WorldRunner``."""
    from robot_bridge.sim.bridge import SimBridge
    from robot_bridge.sim.world import World

    world = World(seed=scenario.seed, lighting=scenario.lighting)
    bridges = {}
    for r in scenario.robots:
        fault = "both_actuators" if r.false_alarm else r.fault
        bridges[r.name] = SimBridge(r.name, world=world, x=r.x, y=r.y, yaw_deg=r.yaw_deg, fault=fault,
                                    camera=True, speed=speed)
    for bridge in bridges.values():
        bridge.setup()
    if busy_cap is not None:
        from robot_bridge.sim.runner import shared_runner
        shared_runner(world, speed).busy_cap = busy_cap
    return world, bridges


def run_scenario(scenario: Scenario, *, processes: bool = True, timeout: float = 120.0,
                 out: TextIO | None = None, err: TextIO | None = None,
                 echo: Callable[[Mark], None] | None = None,
                 on_mark: Callable[[Mark, Callable[[str], None]], None] | None = None,
                 inspector=None, sim_timeout: float | None = None, secure: bool = False) -> RunResult:
    """Run ``scenario`` to the end (or ``timeout`` wall seconds, or ``sim_timeout`` simulated seconds);
    agents' lines go to ``out``. A limit in simulated time measures what the robots did, whatever the
    machine's load (the agents wait in simulated time too); the wall limit guards against a hung run.

    ``inspector``: an ``agents.inspector.live.LiveInspector`` that serves the web view on the run's hub
    (only with ``processes``) and holds the agents alive at the end.

    ``on_mark(mark, kill)``: called on every step; ``kill(name)`` SIGKILLs that agent's process (for
    robustness tests: a helper or a faulty robot that dies mid-way); a true return ends the run.
    Only with ``processes``.
    """
    # Agents in processes of their own see the world over Zenoh, some wall milliseconds late, and count
    # their deadlines in its simulated time: a world stepping flat out while one robot moves spent another
    # robot's whole 3 s move deadline (0.1 s of wall time) before its command arrived. So it is paced then
    # (PROCESS_BUSY_CAP); in-process agents keep the flat-out world (``faultmas eval``).
    world, bridges = build_world(scenario, busy_cap=PROCESS_BUSY_CAP if processes else None)
    try:
        if processes:
            finished = _run_processes(scenario, world, bridges, timeout, out, err, echo, on_mark, inspector,
                                      sim_timeout, secure)
        else:
            finished = _run_in_process(scenario, world, bridges, timeout, out, echo, sim_timeout)
    finally:
        for bridge in bridges.values():
            bridge.shutdown()
    log = finished
    return RunResult(scenario, log.results(), log.marks, log.done.is_set(), world, list(log.died), list(log.frozen))


def _beliefs(scenario: Scenario, robot: RobotSetup) -> list[str]:
    """What a robot is told at launch: its task, and its start pose in the team's shared frame (as a
    localisation's initial pose), so that its help requests can say where it is."""
    return [f"destination({scenario.destination})",
            f"start_pose({round(robot.x, 3)}, {round(robot.y, 3)}, {round(robot.yaw_deg, 1)})"]


def _stop_at_sim_time(world, sim_timeout: float | None, stop: Callable[[], None]) -> Callable[[], None]:
    """Call ``stop`` once ``world`` has run ``sim_timeout`` simulated seconds (checked every 0.2 s of wall
    time, in a thread); returns what cancels the watch."""
    if sim_timeout is None:
        return lambda: None
    done = threading.Event()
    limit = world.time + sim_timeout

    def watch() -> None:
        while not done.wait(0.2):
            if world.time >= limit:
                stop()
                return
    threading.Thread(target=watch, name="sim-timeout", daemon=True).start()
    return done.set


def _run_in_process(scenario, world, bridges, timeout, out, echo, sim_timeout=None) -> ProgressLog:
    from agents.robot_arch import RobotArch
    from agentspeak.parser import parse_program, parse_term
    from agentspeak.runtime import LocalRuntime

    def printer(name: str, text: str) -> None:
        if out is not None:
            out.write(f"[{name}] {text}\n")

    runtime = LocalRuntime(printer=printer)
    log = ProgressLog(scenario, world, lambda: runtime.stop(0.2), echo)
    programs: dict[str, object] = {}
    for r in scenario.robots:
        path = plans_dir().joinpath(r.program)
        if r.program not in programs:
            programs[r.program] = parse_program(path.read_text(), str(path))
        beliefs = [parse_term(b) for b in _beliefs(scenario, r)]
        runtime.add_agent(r.name, program=programs[r.program], source_file=str(path), extra_beliefs=beliefs,
                          arch=RobotArch(runtime, bridges[r.name], on_progress=log.record))
    cancel = _stop_at_sim_time(world, sim_timeout, runtime.stop)
    try:
        runtime.run(timeout=timeout, stop_when_idle=False)
    finally:
        cancel()
    return log


def _run_processes(scenario, world, bridges, timeout, out, err, echo, on_mark=None, inspector=None,
                   sim_timeout=None, secure=False) -> ProgressLog:
    from robot_bridge.sim.server import SimServer

    def serve(hub) -> Callable[[], None]:
        # the secure profile: the hub holds the environment's key, the server signs what the robots send
        stop_sim = SimServer(hub.session, scenario.mas, bridges, sealed=hub.sealed_channel()).start().stop
        if inspector is None:
            return stop_sim
        stop_inspector = inspector.serve(hub, world)
        return lambda: (stop_inspector(), stop_sim())
    extra = ["--bridge", "zenoh"] + (["--allow-pause"] if inspector is not None and inspector.allow_pause else [])
    return run_agent_processes(scenario, extra, timeout, world=world, out=out, err=err, echo=echo,
                               on_mark=on_mark, serve=serve, hold=inspector.hold if inspector is not None else None,
                               sim_timeout=sim_timeout, secure=secure)


def write_project(scenario: Scenario, directory, secure: bool = False) -> "Path":
    """The scenario's MAS as a ``.mas2j`` file in ``directory``: one agent per robot, its plans and
    its launch beliefs (``_beliefs``). ``secure``: the secure profile (docs/reliability.md, "Identity"):
    a key pair per robot in ``directory/keys`` (made for this run, gone with the directory), listed in the
    project, so every agent signs what it sends and refuses what no member signed."""
    from pathlib import Path

    project_file = Path(directory) / f"{scenario.mas}.mas2j"
    key = environment = ""
    if secure:
        from agents.transport.identity import generate_keys
        keys = Path(directory) / "keys"
        generate_keys(keys, [r.name for r in scenario.robots] + ["environment"])
        key = f', key="{keys}"'
        # the run's own process serves the robots (the simulator): it holds the environment's key and signs
        # percepts, action results and the clock; the agents reach it through the zenoh bridge
        environment = f'  environment: zenoh("key={keys / "environment.pub"}")\n'
    lines = [f'    {r.name} {plans_dir().joinpath(r.program)} [beliefs="{", ".join(_beliefs(scenario, r))}"{key}];'
             for r in scenario.robots]
    project_file.write_text(f"MAS {scenario.mas} {{\n{environment}  agents:\n" + "\n".join(lines) + "\n}\n")
    return project_file


def run_agent_processes(scenario: Scenario, extra_args: list[str], timeout: float, *, world=None,
                        clock: Callable[[], float] | None = None, out: TextIO | None = None,
                        err: TextIO | None = None, echo: Callable[[Mark], None] | None = None,
                        on_mark: Callable[[Mark, Callable[[str], None]], bool | None] | None = None,
                        serve: Callable[[object], Callable[[], None]] | None = None,
                        hold: Callable[[], None] | None = None,
                        others: Callable[[], list[tuple[str, int]]] | None = None,
                        other_processes: Callable[[], dict] | None = None,
                        sim_timeout: float | None = None, secure: bool = False) -> ProgressLog:
    """One ``faultmas agent run ... EXTRA_ARGS`` process per robot of ``scenario`` over a Zenoh hub on
    loopback; ``serve(hub)`` starts what the robots need on the hub (returns its stop). The progress
    reports the agents publish are recorded until every robot is done, ``on_mark`` says stop, or ``timeout``;
    then ``hold()`` runs (the agents still alive) before they are stopped. ``others()``: the robot processes
    (e.g. ROS 2 nodes) that ended, as (name, status): one ends the run as an agent's death does, named;
    ``other_processes()``: {name: Popen} of them, watched with the agents for freezes (``ProgressLog.frozen``)."""
    import contextlib
    import os
    import sys
    import tempfile
    from pathlib import Path

    from agents.distributed import Launcher
    from agents.progress import ProgressReport
    from agents.transport import ZenohOptions, ZenohTransport, loopback_endpoint
    from agentspeak.mas2j import load_mas2j

    discard = open(os.devnull, "w") if out is None else None    # None: the agents' lines are not shown
    out = out if out is not None else discard
    err = err or sys.stderr
    with tempfile.TemporaryDirectory(prefix="faultmas-run-") as tmp, discard or contextlib.nullcontext():
        project_file = write_project(scenario, Path(tmp), secure=secure)
        project = load_mas2j(str(project_file))
        from agents.transport.identity import ENVIRONMENT, project_identity
        # None: the default profile; secure: the hub serves the robots, so it holds the environment's key
        hub = ZenohTransport(scenario.mas, ZenohOptions(listen=(loopback_endpoint(),)),
                             identity=project_identity(project, [ENVIRONMENT] if secure else [])).open()
        stop_serving = serve(hub) if serve is not None else None
        launcher = Launcher(project, hub, out, err, extra_args=extra_args)

        def kill(name: str, signum: int = signal.SIGKILL) -> None:
            """SIGKILL ``name``'s process (an agent, or a robot process of ``other_processes``), or send it
            ``signum`` (SIGSTOP, SIGCONT: a freeze, for chaos tests)."""
            child = launcher.children.get(name) or (other_processes() if other_processes else {}).get(name)
            if child is not None and child.poll() is None:
                child.send_signal(signum)

        def observe(mark: Mark) -> None:
            if echo is not None:
                echo(mark)
            if on_mark is not None and on_mark(mark, kill):
                launcher.stop_requested.set()
        log = ProgressLog(scenario, world, launcher.stop_requested.set, observe, clock)

        def on_control(message: dict) -> None:
            report = ProgressReport.from_message(message)
            if report is None:
                return
            if hub.identity is not None and not ProgressReport.proved(message):
                # the secure profile: a report not signed by the robot it names (an outsider's, or a
                # member's forged for another) must not decide the run's outcome
                reason = "unsigned" if message.get("by") is None else "bad_signature"   # signed, by another
                hub.report_control_refused(message, reason)
                return
            log.record(report)
        hub.on_control(on_control)
        from robot_bridge.processes import FreezeWatch
        watch = FreezeWatch(lambda: {**launcher.children, **(other_processes() if other_processes else {})})
        cancel_sim_watch = _stop_at_sim_time(world, sim_timeout, launcher.stop_requested.set) \
            if world is not None else (lambda: None)
        try:
            launcher.start()
            started = time.monotonic()
            with watch:
                ended = launcher.wait(timeout, stop_when_idle=False, fatal=log.needed, others=others)
            cancel_sim_watch()
            if ended == "failed":
                # a robot the run waits for died: the others get a lease or two to notice and react
                # (a helper releases it), then the run ends and names it, long before its timeout
                left = timeout - (time.monotonic() - started)
                launcher.stop_requested.wait(max(0.0, min(DEATH_GRACE, left)))
            launcher._check_children()
            log.died.extend(launcher.failures)
            log.frozen.extend(watch.report())  # named whatever the outcome: a freeze explains a timeout
            if hold is not None and not log.died:
                log.end()
                hold()
        finally:
            cancel_sim_watch()
            launcher.stop_all()
            if stop_serving is not None:
                stop_serving()
            hub.close()
    return log
