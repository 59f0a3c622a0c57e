"""Start every node of every robot as a subprocess and stop them cleanly (``ros2 launch`` is not a wheel).

``Supervisor`` runs ``python -m robot_bridge.ros2.<node> --robot R --domain-id N --ros-args ...``
per node, polls the ROS graph until every node is up, watches for a node that dies, and on
``stop()`` sends SIGINT, then SIGTERM, then SIGKILL, each after a timeout. Children run in their
own process groups, so a Ctrl-C reaches the supervisor only and the shutdown order stays ours.
"""
from __future__ import annotations

import math
import os
import subprocess
import sys
import time
from dataclasses import dataclass, field
from typing import Sequence

from robot_bridge.processes import spawn, stop_processes
from robot_bridge.ros2.runtime import loopback_env

SPACING_M = 1.5
"""Robots start on a line along +x. The last one faces +x and sees the others with its camera; they
stand side-on to it (facing +y), since a robot seen from behind hides one marker behind the other."""


@dataclass(frozen=True)
class NodeSpec:
    """One node process: which robot, which node module, and its ROS parameters."""

    robot: str
    node: str
    params: tuple[tuple[str, str], ...] = ()

    def argv(self, domain_id: int | None) -> list[str]:
        cmd = [sys.executable, "-m", f"robot_bridge.ros2.{self.node}", "--robot", self.robot]
        if domain_id is not None:
            cmd += ["--domain-id", str(domain_id)]
        if self.params:
            cmd.append("--ros-args")
            for name, value in self.params:
                cmd += ["-p", f"{name}:={value}"]
        return cmd


def plan(robots: Sequence[str], fault: str = "none", camera: bool = True, seed: int = 0) -> list[NodeSpec]:
    """The nodes of a simulated team; ``fault`` is injected into the first robot."""
    if not robots or any(not r.isidentifier() for r in robots) or len(set(robots)) != len(robots):
        raise ValueError(f"robots must be distinct names made of letters, digits and _, got {list(robots)!r}")
    from robot_bridge.sim.faults import Fault
    Fault.parse(fault)                                    # fail here, not in a child process
    team = "[" + ", ".join(robots) + "]"
    specs = []
    for i, robot in enumerate(robots):
        x = SPACING_M * (len(robots) - 1 - i)
        yaw = 0.0 if i == len(robots) - 1 else math.pi / 2
        specs.append(NodeSpec(robot, "kobuki_sim", (("x", repr(float(x))), ("yaw", repr(yaw)),
                                                    ("seed", str(seed + i)))))
        specs.append(NodeSpec(robot, "fault_injector", (("fault", fault if i == 0 else "none"),)))
        specs.append(NodeSpec(robot, "motion_decomposer"))
        if camera:
            specs.append(NodeSpec(robot, "camera_sim", (("robots", team), ("seed", str(seed + i)))))
            specs.append(NodeSpec(robot, "visual_synthesizer", (("robots", team),)))
    return specs


@dataclass
class Supervisor:
    """Owns the node processes of one launch."""

    specs: list[NodeSpec]
    domain_id: int | None = None
    processes: list[subprocess.Popen] = field(default_factory=list)
    extra_env: dict[str, str] = field(default_factory=dict)
    """Added to the nodes' environment (e.g. ``FAULTMAS_PERFBUGS``, see ``robot_bridge.ros2.perfbugs``)."""

    def start(self) -> None:
        env = loopback_env()
        env.update(self.extra_env)
        if self.domain_id is not None:
            env["ROS_DOMAIN_ID"] = str(self.domain_id)
        for spec in self.specs:
            self.processes.append(spawn(spec.argv(self.domain_id), env=env, start_new_session=True))

    def expected(self) -> set[tuple[str, str]]:
        return {(spec.node, f"/{spec.robot}") for spec in self.specs}

    def dead(self) -> list[tuple[NodeSpec, int]]:
        """Nodes that have exited, with their exit codes."""
        return [(spec, proc.returncode) for spec, proc in zip(self.specs, self.processes)
                if proc.poll() is not None]

    def wait_ready(self, timeout: float = 30.0) -> set[tuple[str, str]]:
        """Poll the ROS graph until every node is there; returns the ones still missing."""
        import rclpy

        from robot_bridge.ros2.runtime import RosContext
        missing = self.expected()
        with RosContext(domain_id=self.domain_id) as ros:
            probe = ros.add(rclpy.create_node("faultmas_launch_probe", context=ros.context))
            deadline = time.monotonic() + timeout
            while missing and time.monotonic() < deadline and not self.dead():
                missing = self.expected() - set(probe.get_node_names_and_namespaces())
                if missing:
                    time.sleep(0.1)
        return missing

    def stop(self, grace: float = 5.0) -> list[int]:
        """SIGINT, then SIGTERM, then SIGKILL, ``grace`` seconds apart; returns the exit codes."""
        stop_processes(self.processes, grace)
        return [p.wait() for p in self.processes]


def run(robots: Sequence[str], fault: str = "none", domain_id: int | None = None, camera: bool = True,
        duration: float | None = None, ready_timeout: float = 60.0, out=sys.stdout) -> int:
    """Launch, report readiness, then wait for Ctrl-C (or ``duration`` seconds); 0 on a clean run."""
    supervisor = Supervisor(plan(robots, fault, camera), domain_id)
    supervisor.start()
    try:
        result = _watch(supervisor, robots, domain_id, duration, ready_timeout, out)
    except KeyboardInterrupt:
        result = 0
    try:
        codes = supervisor.stop()
    except KeyboardInterrupt:                 # a second Ctrl-C: no more grace
        codes = supervisor.stop(grace=0.0)
    unclean = [f"{s.robot}/{s.node}={c}" for s, c in zip(supervisor.specs, codes) if c not in (0, -2, 130)]
    if unclean:
        print(f"faultmas ros: stopped; unclean exits: {', '.join(unclean)}", file=out, flush=True)
        return result or 1
    print("faultmas ros: all nodes stopped", file=out, flush=True)
    return result


def _watch(supervisor: Supervisor, robots: Sequence[str], domain_id: int | None, duration: float | None,
           ready_timeout: float, out) -> int:
    missing = supervisor.wait_ready(ready_timeout)
    dead = supervisor.dead()
    if dead or missing:
        for spec, code in dead:
            print(f"error: {spec.node} of {spec.robot} exited with code {code}", file=sys.stderr)
        for node, namespace in sorted(missing):
            print(f"error: {namespace}/{node} did not appear within {ready_timeout:g} s", file=sys.stderr)
        return 1
    domain = domain_id if domain_id is not None else os.environ.get("ROS_DOMAIN_ID", "0")
    print(f"faultmas ros: {len(supervisor.specs)} nodes of {', '.join(robots)} up in domain {domain}; "
          "Ctrl-C stops them", file=out, flush=True)
    end = None if duration is None else time.monotonic() + duration
    while end is None or time.monotonic() < end:
        dead = supervisor.dead()
        if dead:
            spec, code = dead[0]
            print(f"error: {spec.node} of {spec.robot} exited with code {code}; stopping", file=sys.stderr)
            return 1
        time.sleep(0.2)
    return 0
