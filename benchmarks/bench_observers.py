"""Observers: replay throughput through the whole pipeline, and CPU share watching a live ROS 2 graph.

1. Replay: a synthetic run with all eight observer kinds, filters on (median, k-trimmed mean, EWMA,
   windowed means, a Student t-test), 10 topics, evaluated at 10 Hz of message time, fed to the
   pipeline with an architecture model and a rule. Two figures: messages already decoded (what a
   simulator feeding observers in-process pays) and the same run read back from an MCAP bag
   (rosbags reading + CDR decoding of the fields observers read). Target >= 100k msgs/s per core.
2. Online: 10 topics at 1,000 msgs/s in total from real rclpy publishers in 2 other processes; the CPU
   time of this process (Fast DDS, the tap's reader, observers, diagnoser, rules) over the observation
   window, as a share of one core, split into the observers' part (observers + CDR decoding +
   diagnoser + rules), Fast DDS's own threads (named ``dds.*``) and the rest (the reader taking the
   messages). Target <= 3 %. CPU time, not wall time: a busy machine slows the publishers (fewer
   messages) but does not add to our CPU time per message (beyond colder caches).
"""
from __future__ import annotations

import os
import random
import threading
import struct
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from scipy import stats  # noqa: F401  (imported before timing: the t-test's first call would pay it)

from detection.config import load_observers
from detection.message import Message
from detection.observers.activated import GRAPH_CHANNEL
from detection.observers.resource import RESOURCE_CHANNEL
from detection.pipeline import Pipeline
from diagnosis.loader import load_model
from diagnosis.rules import load_rules

TOPICS = [f"/t{i}" for i in range(10)]
CONFIG = """\
main_loop_rate: 10
start_up_time: 1
setup:
  - type: activated
    nodes: [{name: /n0}]
  - type: resource
    nodes:
      - {name: n0, filter: {type: mean, window_size: 4},
         states: [{state: ok, cpu: {type: less_than, less_than: 80}, memory: {type: less_than, less_than: 500}}]}
  - type: timeout
    topics: [{name: /t0, timeout: 0.5}]
  - type: hz
    topics:
""" + "".join(f"""\
      - {{name: {t}, filter: {{type: median, window_size: 10}},
         states: [{{state: ok, frequency: {{type: gauss, mean: 100, std_deviation: 10}}}}]}}
""" for t in TOPICS[:6]) + """\
  - type: timestamp
    topics:
      - {name: /t6, filter: {type: k_trimmed_mean, window_size: 20, k_size: 2},
         states: [{state: ok, delay: {type: less_than, less_than: 0.1}}]}
  - type: timing
    topics:
      - {name_a: /t0, name_b: /t1, filter: {type: ewma, decay_rate: 0.1},
         states: [{state: ok, delay: {type: less_than, less_than: 0.05}}]}
  - type: score
    topics:
      - {name: /t7, field: data, filter: {type: mean, window_size: 50},
         states: [{state: ok, score: {type: in_between, lower_bound: -1, upper_bound: 1}}]}
  - type: movement
    correlations:
      - source_a: {topic: /t8, field: data}
        source_b: {topic: /t9, field: data}
        filter: {type: mean, window_size: 100}
        states: [{state: agree, residual: {type: student_t, true_mean: 0, significance_level: 0.001}}]
"""
MODEL = "architecture: bench\nnodes:\n" + "".join(f"  n{i}: {{pub: [t{i}]}}\n" for i in range(10)) + \
    "observations:\n" + "".join(f"  - {o}\n" for o in [*(f"hz(t{i})" for i in range(6)), "activated(n0)",
                                                    "resource(n0)", "timeout(t0)", "timestamp(t6)", "timing(t0,t1)",
                                                    "score(t7)", "movement(t8,t9)"])
RULES = "rules:\n  - {name: note, posObs: [~hz(t0)], posPosAb: [n0], log: 'n0 slow'}\n"


def _files(folder: Path) -> tuple[Path, Path, Path]:
    paths = folder / "obs.yaml", folder / "bench.yaml", folder / "bench.rules.yaml"
    for path, text in zip(paths, (CONFIG, MODEL, RULES)):
        path.write_text(text)
    return paths


def _stamped(t: float) -> bytes:
    sec = int(t)
    return b"\x00\x01\x00\x00" + struct.pack("<iI", sec, int((t - sec) * 1e9)) + b"\x00" * 8


def synthetic(n: int, seed: int = 1) -> list[Message]:
    """n messages round-robin over the 10 topics at 1,000 msgs/s of message time (100 Hz each)."""
    rng = random.Random(seed)
    out = [Message(GRAPH_CHANNEL, 10**9, frozenset({"/n0"}))]
    for i in range(n):
        t = 1.0 + 0.001 * (i + 1)
        topic = TOPICS[i % 10]
        t_ns = int(t * 1e9)
        if topic == "/t6":
            out.append(Message(topic, t_ns, raw=_stamped(t - 0.01)))
        elif topic in ("/t7", "/t8", "/t9"):
            out.append(Message(topic, t_ns, {"data": rng.gauss(0.0, 0.1)}))
        else:
            out.append(Message(topic, t_ns, raw=b"\x00\x01\x00\x00"))
        if i % 500 == 0:
            out.append(Message(RESOURCE_CHANNEL + "n0", t_ns, {"cpu": 10.0, "memory": 50.0}))
    return out


def replay_rate(messages: list[Message], folder: Path) -> tuple[float, int]:
    obs_path, model_path, rules_path = _files(folder)
    observers = load_observers(obs_path).build()
    model = load_model(model_path)
    pipeline = Pipeline(model, load_rules(rules_path, model))
    observers.start(10**9)
    started = time.process_time()
    for msg in messages:
        changed = observers.feed(msg)
        if changed:
            pipeline.observe(changed)
    seconds = time.process_time() - started
    pipeline.close()
    return len(messages) / seconds, len(pipeline.observations)


def bag_rate(messages: list[Message], folder: Path) -> float:
    """The same run written to an MCAP bag, then replayed (reading + decoding) through the pipeline."""
    from detection.session import open_session, replay_bag
    from detection.taps import codec
    from detection.taps.bag import BagRecorder

    store = codec.typestore()
    floats, header = store.types["std_msgs/msg/Float64"], store.types["std_msgs/msg/Header"]
    rec = BagRecorder(folder / "run")
    rec.start(10**9)
    for msg in messages:
        if msg.channel.startswith("@"):
            rec.write(msg)
        elif msg.channel == "/t6":
            sec, nsec = struct.unpack_from("<iI", msg.raw, 4)
            stamp = store.types["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec)
            rec.write(Message(msg.channel, msg.t_ns, raw=bytes(store.serialize_cdr(header(stamp=stamp, frame_id=""),
                                                                                  "std_msgs/msg/Header"))),
                      "std_msgs/msg/Header")
        else:
            value = msg.data["data"] if msg.raw is None else 0.0
            rec.write(Message(msg.channel, msg.t_ns, raw=bytes(store.serialize_cdr(floats(data=value),
                                                                                  "std_msgs/msg/Float64"))),
                      "std_msgs/msg/Float64")
    rec.close()
    obs_path, model_path, rules_path = _files(folder)
    session = open_session(obs_path, model_path, rules_path)
    started = time.process_time()
    replay_bag(session, folder / "run")
    seconds = time.process_time() - started
    session.close()
    return len(messages) / seconds


# online: the same kinds but timestamp (the publishers send Float64, which has no header)
ONLINE = CONFIG.split("  - type: timestamp")[0] + CONFIG[CONFIG.index("  - type: timing"):]

PUBLISHER = """
import sys, rclpy
from rclpy.node import Node
from rclpy.executors import SingleThreadedExecutor, ExternalShutdownException
from std_msgs.msg import Float64
rclpy.init(domain_id=int(sys.argv[1]))
node = Node(sys.argv[2])
for topic in sys.argv[4:]:
    pub = node.create_publisher(Float64, topic, 10)
    node.create_timer(1.0 / float(sys.argv[3]), lambda p=pub: p.publish(Float64(data=0.0)))
print("ready", flush=True)
ex = SingleThreadedExecutor(); ex.add_node(node)
try:
    ex.spin()
except (KeyboardInterrupt, ExternalShutdownException):
    pass
"""


def _timed(function, spent: list[float]):
    """``function`` with the CPU time of its thread added to ``spent[0]`` on each call."""
    def wrapper(*args, **kwargs):
        start = time.thread_time()
        try:
            return function(*args, **kwargs)
        finally:
            spent[0] += time.thread_time() - start
    return wrapper


def thread_cpu() -> dict[str, float]:
    """CPU seconds of each of this process's threads, summed by name (``dds.shm.7411`` -> ``dds.shm``:
    Fast DDS names its threads ``dds.*``; ours are named in ``threading``)."""
    import psutil

    total: dict[str, float] = {}
    for thread in psutil.Process().threads():
        try:
            name = Path(f"/proc/self/task/{thread.id}/comm").read_text().strip()
        except OSError:
            continue
        group = ".".join(name.split(".")[:2]) if name.startswith("dds.") else name.rstrip("0123456789-_ ")
        total[group] = total.get(group, 0.0) + thread.user_time + thread.system_time
    return total


def _dds_cpu() -> float:
    """CPU seconds of this process's Fast DDS threads (Fast DDS names them ``dds.*``)."""
    return sum(seconds for name, seconds in thread_cpu().items() if name.startswith("dds."))


def thread_shares(before: dict[str, float], after: dict[str, float], wall: float) -> str:
    """``dds.shm 2.1 %, python 0.6 %, ...``: each thread group's CPU share over ``wall`` seconds, largest first."""
    shares = {name: 100.0 * (after[name] - before.get(name, 0.0)) / wall for name in after}
    return ", ".join(f"{name} {share:.2f} %" for name, share in sorted(shares.items(), key=lambda kv: -kv[1])
                     if share >= 0.01)


LAST_THREADS = ""
"""The per-thread split of the last ``online_share`` (``thread_shares``)."""


def online_share(folder: Path, seconds: float) -> tuple[float, float, float, int]:
    """CPU share of one core of this process while observing 10 topics at 1,000 msgs/s in total, the
    part spent handing the messages to the observers (observers, CDR decoding, diagnoser, rules) and
    the part of Fast DDS's threads; and the messages received per second."""
    from detection.taps.ros2 import Ros2Tap
    from robot_bridge.ros2.runtime import loopback_env, wait_for

    domain = 1 + (os.getpid() + 81) % 100
    config_path = folder / "online.yaml"
    config_path.write_text(ONLINE)
    _, model_path, rules_path = _files(folder)
    pubs = [subprocess.Popen([sys.executable, "-c", PUBLISHER, str(domain), f"n{k}", "100",
                              *TOPICS[k * 5:(k + 1) * 5]], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                             text=True, env=loopback_env())
            for k in range(2)]
    try:
        for p in pubs:
            p.stdout.readline()
        config = load_observers(config_path)
        config.topics.update({t: "std_msgs/msg/Float64" for t in config.topics})
        model = load_model(model_path)
        pipeline = Pipeline(model, load_rules(rules_path, model))
        tap = Ros2Tap(config, config.build(), pipeline.observe, domain_id=domain)
        spent = [0.0]                       # timed per batch and tick: timing each message would cost more
        tap.reader.on_batch, tap.reader.on_tick = _timed(tap.reader.on_batch, spent), _timed(tap.reader.on_tick, spent)
        tap.start()
        wait_for(lambda: tap.observers.messages > 2000, 30)
        before_msgs, before_cpu, before_wall = tap.observers.messages, time.process_time(), time.monotonic()
        before_ours, before_threads = spent[0], thread_cpu()
        threading.Event().wait(seconds)
        cpu, wall = time.process_time() - before_cpu, time.monotonic() - before_wall
        after_threads = thread_cpu()
        ours = spent[0] - before_ours
        dds = sum(v - before_threads.get(k, 0.0) for k, v in after_threads.items() if k.startswith("dds."))
        global LAST_THREADS
        LAST_THREADS = thread_shares(before_threads, after_threads, wall)
        received = tap.observers.messages - before_msgs
        tap.close()
        pipeline.close()
        return 100.0 * cpu / wall, 100.0 * ours / wall, 100.0 * dds / wall, int(received / wall)
    finally:
        for p in pubs:
            p.terminate()
            p.wait(10)


def run(quick: bool = False) -> str:
    import logging
    logging.getLogger("faultmas").setLevel(logging.ERROR)      # the rule's log line and model warnings
    n = 50_000 if quick else 300_000
    messages = synthetic(n)
    lines = ["| measure | value | target |", "|---|---|---|"]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        rate, known = replay_rate(messages, folder)
        lines.append(f"| replay, decoded messages (8 kinds, {known} observations) | {rate:,.0f} msgs/s | >= 100,000 |")
        lines.append(f"| replay from an MCAP bag (read + decode) | {bag_rate(messages, folder):,.0f} msgs/s | - |")
        try:
            import rclpy  # noqa: F401
        except ImportError:
            lines.append("| online CPU share | (ROS 2 not installed) | <= 3 % |")
        else:
            share, ours, dds, rate = online_share(folder, 5.0 if quick else 20.0)
            lines.append(f"| online: 10 topics, {rate:,} msgs/s received, whole process (CPU time) | {share:.2f} % "
                         f"of one core | <= 3 % |")
            lines.append(f"| online: of which observers + decoding + diagnoser + rules | {ours:.2f} % | - |")
            lines.append(f"| online: of which Fast DDS's receive threads | {dds:.2f} % | - |")
            lines.append(f"| online: of which the reader taking the messages (rest) | {share - ours - dds:.2f} % | - |")
            lines.append(f"| online: by thread | {LAST_THREADS} | - |")
    return "\n".join(lines)
