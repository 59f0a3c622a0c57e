"""The agents of ``faultmas run --bridge ros2`` for the perf-bug data (``faultmas experiment perfbugs --agents``).

``detection.learned.scenario`` records runs of the ROS 2 team; with this ``AgentTeam`` the paper's two
AgentSpeak agents (``faulty.asl``, ``helper.asl``) run beside it as ``faultmas run --bridge ros2`` runs
them: one process each (``agents.distributed.Launcher``), over a Zenoh hub on loopback, driving their
robots through the ROS 2 bridge, the faulty robot with a hardware fault chosen by the run's seed so
that it raises an alarm, asks the helper and is diagnosed. The plans do this once; so that the agents
work for the whole run, Faulty is asked to ``achieve goToDestination`` again every ``episode_s``
seconds (a speech act from ``supervisor`` through the hub; the agents take it as from a member of the
MAS, ``--allow-code-from supervisor``, since ``achieve`` is refused from anyone else). The
workload keeps patrolling both robots meanwhile (the agents' and the workload's actions interleave:
more varied work, not a clean episode).
The hook lives here, not in ``detection``, because detection never imports ``agents/``.
"""
from __future__ import annotations

import os
import random
import sys
import tempfile
import threading
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable


SUPERVISOR = "supervisor"


@dataclass
class RunningTeam:
    endpoint: str
    pids: dict[str, int]
    fault: str
    _stop: Callable[[], None] = field(repr=False)

    def stop(self) -> None:
        self._stop()


class CooperativeAgents:
    """``detection.learned.scenario.AgentTeam``: Faulty and Helper over Zenoh, their robots on ROS 2."""

    def __init__(self, episode_s: float = 40.0) -> None:
        self.episode_s = episode_s

    def robot_fault(self, seed: int) -> str:
        from agents.cooperative import TEAM_FAULTS
        return random.Random(seed).choice(TEAM_FAULTS)

    def start(self, domain_id: int, seed: int, env: dict[str, str] | None = None) -> RunningTeam:
        """``env`` goes into the agents' processes' environment (e.g. ``FAULTMAS_PERFBUGS``: the run's
        perf-bug schedule, which the agent's ROS 2 bridge installs; ``robot_bridge.ros2.perfbugs``)."""
        from agents.cooperative import paper_scenario, write_project
        from agents.distributed import Launcher
        from agents.transport import ZenohOptions, ZenohTransport, loopback_endpoint
        from agentspeak.mas2j import load_mas2j
        from robot_bridge.ros2.runtime import loopback_env

        fault = self.robot_fault(seed)
        scenario = paper_scenario(fault, seed)
        os.environ.update(loopback_env())                  # the agent processes inherit it (as run_on_ros2)
        os.environ.update(env or {})                       # one run at a time per process: no one else reads it
        tmp = tempfile.TemporaryDirectory(prefix="faultmas-perfbugs-agents-")
        hub = ZenohTransport(scenario.mas, ZenohOptions(listen=(loopback_endpoint(),))).open()
        quiet = open(os.devnull, "w")                      # the agents' lines; their errors go to stderr
        launcher = Launcher(load_mas2j(str(write_project(scenario, Path(tmp.name)))), hub, quiet, sys.stderr,
                            extra_args=["--bridge", "ros2", "--bridge-option", f"domain_id={domain_id}",
                                        # the episodes' sender counts as a member (achieve is members-only)
                                        "--allow-code-from", SUPERVISOR])

        stopping = threading.Event()

        def episodes() -> None:
            from agents.transport.envelope import Envelope
            while not stopping.wait(self.episode_s):
                try:
                    hub.send(Envelope(scenario.mas, SUPERVISOR, ("faulty",), "achieve", "goToDestination"))
                except Exception as exc:        # an agent that is gone: the run notices it (lost process)
                    print(f"perfbugs agents: could not start an episode: {exc}", file=sys.stderr)
        repeater = threading.Thread(target=episodes, daemon=True, name="perfbugs-episodes")

        def stop() -> None:
            stopping.set()
            repeater.join(5.0)
            try:
                launcher.stop_all()
            finally:
                hub.close()
                quiet.close()
                tmp.cleanup()
        try:
            launcher.start()
            repeater.start()
        except BaseException:
            stop()
            raise
        return RunningTeam(hub.endpoints[0], {name: child.pid for name, child in launcher.children.items()},
                           fault, stop)
