"""``faultmas run --bridge ros2``: the same plans and agent processes, the robots as ROS 2 nodes.

The ROS 2 side is ``robot_bridge.ros2``'s simulated Turtlebots (``kobuki_sim``, ``fault_injector``,
``motion_decomposer``, ``camera_sim``, ``visual_synthesizer`` per robot, as ``faultmas ros launch``
starts them), on a ROS domain id of its own and discovery kept on this host. Each agent process
drives its robot through ``Ros2Bridge``. The nodes run in real time, so the simulated seconds of
the latency table equal its wall seconds. Only the paper's two robots: ``launch.plan`` places
Faulty side-on 1.5 m in front of Helper, as the paper did. A false alarm needs the simulator's
transient stall, which the ROS nodes do not model: with ``--fault none`` Faulty simply arrives.
"""
from __future__ import annotations

import os
import random
from typing import Callable, TextIO

from agents.cooperative import Mark, RunResult, Scenario, run_agent_processes


def free_domain_id() -> int:
    """A ROS domain id unlikely to be in use by another run on this host (1..100)."""
    return random.Random(os.getpid() ^ int.from_bytes(os.urandom(4), "little")).randint(1, 100)


def run_on_ros2(scenario: Scenario, timeout: float = 180.0, out: TextIO | None = None,
                echo: Callable[[Mark], None] | None = None, domain_id: int | None = None,
                on_mark: Callable | None = None) -> RunResult:
    """The run; a robot node that dies ends it, named ``robot/node`` in ``died`` (outcome 'died').
    ``on_mark(mark, kill)``: as ``run_agent_processes``'s, ``kill`` also takes ``robot/node`` names."""
    from robot_bridge.ros2.launch import Supervisor, plan
    from robot_bridge.ros2.runtime import loopback_env

    names = [r.name for r in scenario.robots]
    if names != ["faulty", "helper"]:
        raise ValueError("--bridge ros2 runs the paper's two robots (faulty and helper) only")
    domain = domain_id if domain_id is not None else free_domain_id()
    os.environ.update(loopback_env())                  # the agent processes inherit it
    supervisor = Supervisor(plan(names, scenario.robots[0].fault), domain)
    supervisor.start()
    try:
        missing = supervisor.wait_ready(90.0)
        if missing or supervisor.dead():
            raise RuntimeError(f"ROS 2 nodes did not come up: missing {sorted(missing)}, "
                               f"dead {[(s.node, c) for s, c in supervisor.dead()]}")
        log = run_agent_processes(scenario, ["--bridge", "ros2", "--bridge-option", f"domain_id={domain}"],
                                  timeout, clock=log_clock(), out=out, echo=echo, on_mark=on_mark,
                                  others=lambda: [(f"{spec.robot}/{spec.node}", code) for spec, code in supervisor.dead()],
                                  other_processes=lambda: node_processes(supervisor))
    finally:
        supervisor.stop()
    return RunResult(scenario, log.results(), log.marks, log.done.is_set(), None, list(log.died), list(log.frozen))


def node_processes(supervisor) -> dict:
    """{``robot/node``: its process} of a launch (for chaos tests and the freeze check)."""
    return {f"{spec.robot}/{spec.node}": proc for spec, proc in zip(supervisor.specs, supervisor.processes)}


def log_clock() -> Callable[[], float]:
    """Real-time nodes: the 'simulated' clock is the wall clock since the run started."""
    import time
    start = time.monotonic()
    return lambda: time.monotonic() - start
