"""``faultmas mas run PROJECT.mas2j --processes``: one OS process per agent, talking over Zenoh.

The launcher opens a Zenoh peer on a free loopback port (the hub: multicast off, explicit
``tcp/127.0.0.1`` endpoints) and starts each agent as ``python -m agents agent run FILE --name N
--mas M --connect <hub> --project PROJECT``; gossip over those links lets the children reach each
other directly. Each child's stdout lines (``[agent] text``) are relayed in the order they are read,
stderr likewise. The MAS ends on ``.stopMAS`` (a control message seen by every process), when every
agent has reported idle with as many messages received as sent in two consecutive checks, or at
``--timeout`` (which always wins). Children are then asked to stop (control message), then sent
SIGINT, SIGTERM and SIGKILL, each after a grace period.
"""
from __future__ import annotations

import hmac
import logging
import os
import secrets
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import IO, Callable

from agents.transport.trust import is_member
from agents.zenoh_arch import LAUNCHER_TOKEN_ENV, control_delay
from robot_bridge.processes import ESCALATION, spawn, stop_processes

log = logging.getLogger("faultmas.agents")

#: Exit codes of ``faultmas mas run --processes``.
EXIT_CODES = {"stopped": 0, "idle": 0, "failed": 1, "timeout": 124, "interrupted": 130}
CHECK_INTERVAL = 0.05    # seconds between quiescence checks
START_TIMEOUT = 60.0     # seconds the children get to become reachable
GRACE = 2.0              # seconds between the stop steps (control, SIGINT, SIGTERM, SIGKILL)
MAX_STOP_DELAY = 60.0    # longest .stopMAS(D) the launcher waits for before it stops the processes itself
REPO = Path(__file__).resolve().parents[1]


def run_processes(project, timeout: float | None = None, *, out: IO[str] | None = None,
                  err: IO[str] | None = None, bridge=None, bridge_timeout: float = 30.0) -> int:
    """Run every agent of ``project`` (a ``MasProject``) in its own process; return the exit code
    (0: ``.stopMAS`` or all idle, 124: ``--timeout``, 1: an agent process failed, 130: interrupted; Code after
    ``.stopMAS(Delay, Code)``).

    ``bridge`` (an ``agents.environment.BridgeChoice``): each agent drives its robot through it. The
    simulator's world lives in this process, served on the hub (``robot_bridge.sim.server``), so that
    the agents share it through their ``zenoh`` bridges; any other bridge is opened by each agent."""
    from agents.transport import ZenohOptions, ZenohTransport, loopback_endpoint
    from agents.transport.keys import check_name
    from agentspeak.errors import AslSyntaxError, SourceError
    from agentspeak.parser import parse_program
    from agentspeak.source_text import read_source

    out, err = out or sys.stdout, err or sys.stderr
    try:
        check_name(project.name, "MAS name")
        for decl in project.agents:  # fail early, with file and line, before any process starts
            parse_program(read_source(decl.source), decl.source, source_path=tuple(project.source_dirs))
    except OSError as exc:
        print(f"{project.file}: cannot read {exc.filename}: {exc.strerror or exc}", file=err)
        return 2
    except (AslSyntaxError, SourceError, ValueError) as exc:
        print(exc, file=err)
        return 2
    from agents.transport.identity import ENVIRONMENT, IdentityError, project_identity
    try:  # the secure profile: the hub checks signatures too (an outsider's stop must not end the run)
        identity = project_identity(project)
        if identity is not None and bridge is not None and bridge.name == "sim":
            # this process serves the simulator to the agents: it signs as the environment
            identity = project_identity(project, [ENVIRONMENT])
    except IdentityError as exc:
        print(exc, file=err)
        return 2
    hub = ZenohTransport(project.name, ZenohOptions(listen=(loopback_endpoint(),)), identity=identity).open()
    served, extra = None, bridge.agent_args() if bridge is not None else []
    if bridge is not None and bridge.name == "sim":
        from agents.environment import open_bridges
        from robot_bridge.sim.server import SimServer
        try:
            served = SimServer(hub.session, project.name, open_bridges(bridge, project.agent_names(), bridge_timeout),
                               sealed=hub.sealed_channel()).start()
        except Exception as exc:
            hub.close()
            print(f"faultmas mas run: {exc}", file=err)
            return EXIT_CODES["failed"]
        extra = ["--bridge", "zenoh", "--bridge-timeout", str(bridge_timeout)]
    elif bridge is not None:
        extra += ["--bridge-timeout", str(bridge_timeout)]
    launcher = Launcher(project, hub, out, err, extra_args=extra)
    try:
        launcher.start()
        reason = launcher.wait(timeout)
    except KeyboardInterrupt:
        reason = "interrupted"
    finally:
        launcher.stop_all()
        if served is not None:
            served.stop()
            for robot in served.bridges.values():
                robot.shutdown()
        hub.close()
    if reason == "failed" or (reason != "interrupted" and launcher.failures):
        for name, code in launcher.failures:
            print(f"faultmas mas run: agent {name} exited with code {code}", file=err)
        return EXIT_CODES["failed"] if reason != "timeout" else EXIT_CODES["timeout"]
    if reason == "stopped" and launcher.exit_code:
        return launcher.exit_code
    return EXIT_CODES[reason]


class Launcher:
    """The children of one run, their output relays, and what the hub hears about them.

    ``extra_args``: more ``faultmas agent run`` options for every child (e.g. ``--bridge zenoh``).
    """

    def __init__(self, project, hub, out: IO[str], err: IO[str], extra_args: list[str] | None = None) -> None:
        self.project, self.hub, self.out, self.err = project, hub, out, err
        self.extra_args = list(extra_args or ())
        self.names = project.agent_names()
        self.token = secrets.token_hex(16)
        self._announced = 0.0
        self.children: dict[str, subprocess.Popen] = {}
        self.relays: list[threading.Thread] = []
        self.statuses: dict = {}
        self.stop_requested = threading.Event()
        self.exit_code = 0
        self.failures: list[tuple[str, int]] = []
        self._print_lock = threading.Lock()
        self._stopping = False
        self.stop_delay = 0.0   # seconds the agents were given by .stopMAS(D) to finish before they stop
        hub.on_status(self._on_status)
        hub.on_control(self._on_control)

    def _on_control(self, message: dict) -> None:
        """A ``stop`` ends the run when an agent of the MAS sent it (``.stopMAS``); a stranger's is
        refused as the agents refuse it (in the secure profile ``by`` is proved by its signature)."""
        if message.get("command") != "stop":
            return
        by = message.get("by")
        if isinstance(by, str) and self.is_member(by) or hmac.compare_digest(str(message.get("token", "")), self.token):
            code = message.get("code", 0)
            if isinstance(code, int) and not isinstance(code, bool) and code and not self.exit_code:
                self.exit_code = code   # .stopMAS(_, Code): the run exits with Code (the first one wins)
            # .stopMAS(D): every agent has D ms (+jag_shutting_down) before its process stops by itself
            self.stop_delay = max(self.stop_delay, min(control_delay(message), MAX_STOP_DELAY))
            self.stop_requested.set()
        else:
            self.hub.report_control_refused(message, "not_a_member")

    def is_member(self, name: str) -> bool:
        """An agent of the project, or made at run time by one (``.create_agent``: announced by its process)."""
        return is_member(name, self.names, self.hub.creator_of)

    def _on_status(self, status) -> None:
        """The agents' statuses, those made at run time included (what they send and receive counts too); a
        made agent's last status, published when it is killed, may come after its membership went."""
        if status.agent in self.statuses or self.is_member(status.agent):
            self.statuses[status.agent] = status

    def start(self) -> None:
        # each agent starts in the user's working directory (relative sources, aslSourcePath and
        # .create_agent resolve as in the in-process run) and finds this package where it is installed;
        # the children accept the launcher's stop by a token (agents.zenoh_arch.LAUNCHER_TOKEN_ENV):
        # a stop that merely claims to come from the launcher is refused
        path = os.pathsep.join(p for p in (str(REPO), os.environ.get("PYTHONPATH", "")) if p)
        env = dict(os.environ, PYTHONUNBUFFERED="1", PYTHONPATH=path, **{LAUNCHER_TOKEN_ENV: self.token})
        endpoint = self.hub.endpoints[0]
        for decl in self.project.agents:
            for name in decl.instance_names():
                command = [sys.executable, "-m", "agents", "agent", "run", decl.source, "--name", name,
                           "--mas", self.project.name, "--connect", endpoint, "--project", self.project.file,
                           "--wait-for-peers", str(START_TIMEOUT), *self.extra_args]
                child = spawn(command, cwd=os.getcwd(), env=env, text=True, stdin=subprocess.DEVNULL,
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
                self.children[name] = child
                for stream, sink in ((child.stdout, self.out), (child.stderr, self.err)):
                    relay = threading.Thread(target=self._relay, args=(stream, sink), daemon=True)
                    relay.start()
                    self.relays.append(relay)

    def _relay(self, stream: IO[str], sink: IO[str]) -> None:
        for line in stream:
            with self._print_lock:
                sink.write(line)
                sink.flush()

    def wait(self, timeout: float | None, stop_when_idle: bool = True,
             fatal: Callable[[str], bool] | None = None,
             others: Callable[[], list[tuple[str, int]]] | None = None) -> str:
        """Block until the MAS ends; the reason ('stopped', 'idle', 'timeout' or 'failed').
        ``fatal(name)``: 'failed' as soon as a child for which it is true ends with a non-zero status or a
        signal (``failures`` names it), not only once all have ended (a run whose agent was killed must
        not wait for its timeout). ``others()``: processes the agents depend on (robot nodes) that have
        ended, as (name, exit status): 'failed' at once, each named in ``failures``."""
        from agents.transport.status import quiescent, totals

        deadline = None if timeout is None else time.monotonic() + timeout
        previous = None
        while True:
            if self.stop_requested.is_set():
                return "stopped"
            if deadline is not None and time.monotonic() >= deadline:
                return "timeout"
            if self._check_children() or (fatal is not None and any(fatal(name) for name, _ in self.failures)):
                return "failed"
            if others is not None and self._record_others(others()):
                return "failed"
            statuses = list(self.statuses.values())
            snapshot = None
            if stop_when_idle and all(name in self.statuses for name in self.names) and quiescent(statuses):
                snapshot = (totals(statuses), tuple(statuses))
                if snapshot == previous:
                    return "idle"
            previous = snapshot
            wait = CHECK_INTERVAL if deadline is None else max(0.0, min(CHECK_INTERVAL, deadline - time.monotonic()))
            self.stop_requested.wait(wait)

    def _record_others(self, ended: list[tuple[str, int]]) -> bool:
        """Add the other processes that ended to ``failures``; True if there are any."""
        for failure in ended:
            if failure not in self.failures:
                self.failures.append(failure)
        return bool(ended)

    def _check_children(self) -> bool:
        """Record children that ended on their own; True when none is left running."""
        for name, child in self.children.items():
            code = child.poll()
            if code is not None and code != 0 and (name, code) not in self.failures:
                self.failures.append((name, code))
        self._announce_deaths()
        return all(child.poll() is not None for child in self.children.values())

    def _announce_deaths(self) -> None:
        """Tell the others, every second, which agents died: they may be waiting for them to become
        reachable (``--wait-for-peers``), which they never will; a control message has no history, so an
        agent that connects later hears it at the next announcement."""
        now = time.monotonic()
        if self.failures and now - self._announced >= 1.0:
            self._announced = now
            for name, code in self.failures:
                self.hub.publish_control("died", agent=name, exit=code, token=self.token)

    def stop_all(self) -> None:
        """Ask every child to stop, then insist: control message, SIGINT, SIGTERM, SIGKILL."""
        running = [c for c in self.children.values() if c.poll() is None]
        if running and self.stop_delay:   # .stopMAS(D): they stop by themselves once D is over
            end = time.monotonic() + self.stop_delay + GRACE
            while running and time.monotonic() < end:
                time.sleep(0.02)
                running = [c for c in running if c.poll() is None]
        if running:
            self.hub.publish_control("stop", by="launcher", delay=0.0, token=self.token)
        stop_processes(running, GRACE, (None, *ESCALATION))
        for relay in self.relays:
            relay.join(5.0)
        for child in self.children.values():  # not left to the garbage collector (a soak's descriptors grew)
            for stream in (child.stdout, child.stderr):
                if stream is not None:
                    try:
                        stream.close()
                    except OSError:
                        pass
