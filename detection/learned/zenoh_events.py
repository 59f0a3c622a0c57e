"""The Zenoh side of the learned detector: the agents as components, their key expressions as channels.

Every sample under ``faultmas/**`` (the one prefix of every faultmas key, ``docs/agents.md``) is
decoded generically: its payload as JSON Lines (a batch of envelopes has one per line, a single
message one line), each value flattened into numbers and lengths (``encoding.flatten_json``) with its
size in bytes. Nothing here knows the envelope's fields or the key layout beyond two conventions
of every faultmas JSON message, read generically: a value's sender is its ``from`` (a speech act's
envelope) or ``agent`` field (a status, a progress report), its receivers its ``to`` list. So a key
on which agent A's values go out is an *output* of A, one on which values addressed to A come in an
*input* of A; the channel is the key itself (``faultmas/coop/agent/helper/inbox``; ROS 2 topics
start with ``/``, keys never do). Detection never imports ``agents/``: this reads the wire only.

An agent's process is found by its command line (``... agent run FILE --name A ...``, as the launcher
of ``faultmas mas run --processes`` and ``faultmas run`` starts it, or a user by hand); its component is
``A_agent``, beside the ROS nodes' ``robot_node``.
"""
from __future__ import annotations

import logging
import threading
import time
from typing import Any, Callable, Iterable, Sequence

from detection.learned.encoding import EncodingError, decode_json_lines, flatten_json, vector_of
from detection.learned.ros_tap import Component
from robot_bridge.ros2.perfbugs import AGENT_NODE, agent_component

log = logging.getLogger("faultmas.detection")

KEY_PREFIX = "faultmas/**"
CHANNEL_TYPE = "zenoh/json"
"""What the manifest says a Zenoh channel carries (ROS 2 channels give their message type)."""


def is_zenoh_channel(channel: str) -> bool:
    return not channel.startswith("/")


def mas_of(keys: Iterable[str]) -> str | None:
    """The MAS of faultmas keys (``faultmas/<mas>/...``); None when they name none or several."""
    names = {k.split("/")[1] for k in keys if k.startswith("faultmas/") and k.count("/") >= 2}
    return names.pop() if len(names) == 1 else None


def parties(value: Any) -> tuple[str | None, list[str]]:
    """The sender (``from`` or ``agent``) and the receivers (``to``) a JSON value names, if any."""
    if not isinstance(value, dict):
        return None, []
    sender = value.get("from", value.get("agent"))
    to = value.get("to")
    receivers = [r for r in to if isinstance(r, str)] if isinstance(to, list) else []
    return (sender if isinstance(sender, str) else None), receivers


class ZenohChannels:
    """Which agent sends and receives on which key, learnt from the traffic itself."""

    def __init__(self) -> None:
        self.outputs: dict[str, set[str]] = {}
        self.inputs: dict[str, set[str]] = {}

    def note(self, key: str, value: Any) -> None:
        sender, receivers = parties(value)
        if sender is not None:
            self.outputs.setdefault(sender, set()).add(key)
        for receiver in receivers:
            self.inputs.setdefault(receiver, set()).add(key)

    def components(self, agents: Iterable[str]) -> dict[str, Component]:
        """The ``Component`` of each agent in ``agents`` (those with at least one channel)."""
        out = {}
        for agent in agents:
            inputs, outputs = sorted(self.inputs.get(agent, ())), sorted(self.outputs.get(agent, ()))
            if inputs or outputs:
                name = agent_component(agent)
                out[name] = Component(name, "", agent, inputs, outputs)
        return out


class ZenohEventTap:
    """Every sample on ``key_expr`` as ``on_event(t, key, size, flat)`` per JSON value (``flat``: the
    flattened numbers), its parties noted in ``channels``. An undecodable payload is counted in
    ``dropped`` (per key) and logged, never raised on Zenoh's thread."""

    def __init__(self, on_event: Callable[[float, str, int, dict[str, float]], None], *, keys=None,
                 connect: Sequence[str] = (), key_expr: str = KEY_PREFIX, clock: Callable[[], float] = time.time) -> None:
        from detection.taps.zenoh import ZenohKeys

        self.channels = ZenohChannels()
        self.dropped: dict[str, int] = {}
        self.received = 0
        self._on_event, self._clock = on_event, clock
        self._lock = threading.Lock()              # Zenoh may call from several threads
        self._owns = keys is None
        self.keys = keys if keys is not None else ZenohKeys(connect=connect)
        self.keys.subscribe(key_expr, self._on_sample)

    def _on_sample(self, key: str, payload: bytes) -> None:
        now = self._clock()
        try:
            values = decode_json_lines(payload)
        except EncodingError as exc:
            with self._lock:
                self.dropped[key] = self.dropped.get(key, 0) + 1
                n = self.dropped[key]
            if n == 1 or n % 1000 == 0:
                log.warning("learned Zenoh tap: %d payload(s) on %s could not be decoded (%s)", n, key, exc)
            return
        with self._lock:
            for size, value in values:
                self.channels.note(key, value)
                self.received += 1
                self._on_event(now, key, size, flatten_json(value))

    def close(self) -> None:
        if self._owns:
            self.keys.close()


class ZenohFeed:
    """The Zenoh keys a live observer watches: samples are queued on Zenoh's threads and handed to
    ``on_event(t, key, vector)`` by ``drain()``, in the caller's thread (the observer's buffers are
    then touched by one thread only), encoded with the columns each key had in training."""

    def __init__(self, columns: dict[str, list[str]], on_event: Callable[[float, str, Any], None], *,
                 connect: Sequence[str] = (), keys=None) -> None:
        from queue import SimpleQueue

        self._index = {key: {c: i for i, c in enumerate(cols)} for key, cols in columns.items()}
        self._queue: SimpleQueue = SimpleQueue()
        self._on_event = on_event
        self.tap = ZenohEventTap(self._keep, connect=connect, keys=keys)

    def _keep(self, t: float, key: str, size: int, flat: dict[str, float]) -> None:
        if key in self._index:
            self._queue.put((t, key, size, flat))

    def drain(self) -> int:
        """Hand every queued sample over; returns how many."""
        n = 0
        while not self._queue.empty():
            t, key, size, flat = self._queue.get()
            self._on_event(t, key, vector_of(size, flat, self._index[key]))
            n += 1
        return n

    def close(self) -> None:
        self.tap.close()


def adopt_bridge_nodes(components: dict[str, Component], agents: Iterable[str]) -> dict[str, Component]:
    """``components`` (from the ROS graph) with each agent's ROS 2 bridge node (``faultmas_agent_A``,
    robot_bridge.ros2.bridge) renamed to the agent's component: one process, one component, with its
    ROS topics and (``merge_zenoh``) its Zenoh keys."""
    from robot_bridge.ros2.bridge import agent_node_name

    by_node = {agent_node_name(a): agent_component(a) for a in agents}
    out = {}
    for name, c in components.items():
        if c.node in by_node:
            name = by_node[c.node]
            c = Component(name, c.namespace, c.node, list(c.inputs), list(c.outputs))
        out[name] = c
    return out


def wait_for_bridge_nodes(probe, agents: Iterable[str], timeout: float) -> set[str]:
    """Until every agent's ROS 2 bridge node is in the graph with its topics (a node appears before its
    publishers and subscriptions do); returns the nodes still missing at ``timeout``."""
    from robot_bridge.ros2.bridge import agent_node_name

    def ready(node: str, namespace: str) -> bool:
        try:
            return bool(probe.get_publisher_names_and_types_by_node(node, namespace)) and \
                bool(probe.get_subscriber_names_and_types_by_node(node, namespace))
        except Exception:                   # the node went between the two queries
            return False

    deadline = time.monotonic() + timeout
    wanted = {agent_node_name(a) for a in agents}
    while (missing := wanted - {name for name, ns in probe.get_node_names_and_namespaces() if ready(name, ns)}):
        if time.monotonic() > deadline:
            return missing
        time.sleep(0.2)
    time.sleep(1.0)                         # the last of their topics
    return set()


def merge_zenoh(components: dict[str, Component], zenoh: dict[str, Component]) -> None:
    """Add the Zenoh channels of ``zenoh`` (``ZenohChannels.components``) to ``components``, in place."""
    for name, z in zenoh.items():
        c = components.setdefault(name, Component(name, z.namespace, z.node))
        c.inputs += [k for k in z.inputs if k not in c.inputs]
        c.outputs += [k for k in z.outputs if k not in c.outputs]


def agent_processes(agents: Iterable[str], mas: str | None = None, connect: Sequence[str] = ()) -> dict[str, object]:
    """The process of each agent (component name → ``psutil.Process``), found by its command line
    ``... agent run ... --name A`` (and ``--mas M`` when ``mas`` is given). When several match, those
    connected (``--connect``) to one of ``connect`` (the endpoints we watch the agents through) are
    taken. Raises ``ValueError`` when an agent still matches several processes."""
    import psutil

    def option(cmdline: list[str], name: str) -> str | None:
        return cmdline[cmdline.index(name) + 1] if name in cmdline[:-1] else None

    wanted = set(agents)
    found: dict[str, list] = {}
    for process in psutil.process_iter(["cmdline"]):
        cmdline = process.info.get("cmdline") or []
        if not any(cmdline[i:i + 2] == ["agent", "run"] for i in range(len(cmdline))):
            continue                    # 'python -m agents agent run ...' or 'faultmas agent run ...'
        name = option(cmdline, "--name")
        if name in wanted and (mas is None or option(cmdline, "--mas") == mas):
            found.setdefault(agent_component(name), []).append(process)
    for name, ps in found.items():
        if len(ps) > 1 and connect:
            found[name] = [p for p in ps if option(p.info.get("cmdline") or [], "--connect") in connect] or ps
    ambiguous = {name: [p.pid for p in ps] for name, ps in found.items() if len(ps) > 1}
    if ambiguous:
        raise ValueError(f"several processes look like the same agent (pids {ambiguous}); name the MAS")
    return {name: ps[0] for name, ps in found.items()}
