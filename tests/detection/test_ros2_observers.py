"""Observers on a real ROS 2 graph: publishers in other processes, a unique ROS domain, the live tap.

Each publisher is a real rclpy node in its own process (``publisher_node.py``); the observers run in
this process through ``Ros2Tap`` (own rclpy context). Everything waits by polling, with generous
deadlines; nothing is a timed assertion except the issue's "activated false within 1 s".
"""
from __future__ import annotations

import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")

from detection.config import load_observers  # noqa: E402
from robot_bridge.ros2.runtime import loopback_env, wait_for  # noqa: E402
from tests.ros_domain import ros_domain  # noqa: E402

DOMAIN = ros_domain(37)      # not the other ROS test modules' domains
HERE = Path(__file__).resolve().parent


def start_publishers(*arg_lists: list[str]) -> list[subprocess.Popen]:
    """Publisher processes started together (rclpy takes seconds to import), returned once all are ready."""
    procs = [subprocess.Popen([sys.executable, str(HERE / "publisher_node.py"), "--domain-id", str(DOMAIN), *args],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=loopback_env())
             for args in arg_lists]
    for proc in procs:
        assert proc.stdout.readline().strip() == "ready", proc.stderr.read()
    return procs


def stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(10)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


CONFIG = """\
main_loop_rate: 20
start_up_time: 1.5
setup:
  - type: hz
    topics:
      - name: /ten
        msg_type: std_msgs/msg/Float64
        filter: {type: median, window_size: 10}
        states: [{state: nominal, frequency: {type: gauss, mean: 10, std_deviation: 1}}]
      - name: /three
        filter: {type: median, window_size: 10}
        states: [{state: nominal, frequency: {type: gauss, mean: 10, std_deviation: 1}}]
  - type: score
    topics:
      - name: /centered
        filter: {type: mean, window_size: 40}
        states: [{state: calibrated, score: {type: student_t, true_mean: 0.0, significance_level: 0.01}}]
      - name: /shifted
        filter: {type: mean, window_size: 40}
        states: [{state: calibrated, score: {type: student_t, true_mean: 0.0, significance_level: 0.01}}]
  - type: activated
    nodes: [{name: /victim}]
  - type: timeout
    topics: [{name: /ten, timeout: 1.0}, {name: /never, msg_type: std_msgs/msg/Float64, timeout: 1.0}]
  - type: timestamp
    topics:
      - name: /stamped
        filter: {type: median, window_size: 5}
        states: [{state: fresh, delay: {type: in_between, lower_bound: 0.0, upper_bound: 0.5}}]
  - type: timing
    topics:
      - name_a: /ten
        name_b: /three
        filter: {type: mean, window_size: 5}
        states: [{state: ok, delay: {type: in_between, lower_bound: 0.0, upper_bound: 0.35}}]
  - type: movement
    correlations:
      - source_a: {topic: /centered, field: data}
        source_b: {topic: /shifted, field: data}
        differentiate: false
        filter: {type: mean, window_size: 40}
        states: [{state: agree, residual: {type: student_t, true_mean: 0.0, significance_level: 0.01}}]
  - type: resource
    nodes:
      - name: talker
        process: "--name talker"
        states: [{state: ok, cpu: {type: less_than, less_than: 95}, memory: {type: in_between, lower_bound: 1, upper_bound: 4000}}]
"""


class Collector:
    def __init__(self):
        self.seen = []
        self.lock = threading.Lock()

    def __call__(self, observations):
        with self.lock:
            self.seen.extend(observations)

    def latest(self, name):
        with self.lock:
            found = [o for o in self.seen if o.name == name]
        return found[-1] if found else None


@pytest.fixture(scope="module")
def live(tmp_path_factory):
    from detection.taps.ros2 import Ros2Tap

    path = tmp_path_factory.mktemp("observers") / "obs.yaml"
    path.write_text(CONFIG)
    config = load_observers(path)
    pubs = start_publishers(["--name", "talker", "--pub", "/ten:10", "--pub", "/three:3",
                             "--pub", "/centered:40:0.0", "--pub", "/shifted:40:1.0"],
                            ["--name", "victim", "--pub", "/victim_out:5"],
                            ["--name", "stamper", "--stamped", "--pub", "/stamped:20"])
    collector = Collector()
    tap = Ros2Tap(config, config.build(), collector, domain_id=DOMAIN).start()
    try:
        yield tap, collector, pubs
    finally:
        tap.close()
        for p in pubs:
            stop(p)


def verdict(tap, name):
    return tap.observers.verdicts.get(name, (None, None))[0]


def settled(tap, name, rate=None):
    """The verdict once the observer has a full window of real messages (discovery takes a while)."""
    def ready():
        obs = next(o for o in tap.observers.observers if o.name == name)
        f = next(iter(obs.filters.values()))
        return verdict(tap, name) is not None and f.count > (f.spec.window_size or 1) + 2
    assert wait_for(ready, 30), f"{name}: no full window of messages"
    return verdict(tap, name)


def test_hz_10_hz_passes_and_3_hz_fails(live):
    tap, seen, _ = live
    ten, three = settled(tap, "hz(ten)"), settled(tap, "hz(three)")
    assert ten.holds and ten.measured == pytest.approx(10, rel=0.2), ten
    assert not three.holds and three.measured == pytest.approx(3, rel=0.25), three
    assert seen.latest("hz(ten)").holds and not seen.latest("hz(three)").holds


def test_topics_no_observer_decodes_are_taken_as_heads(live):
    """Without a recording, a topic whose fields no observer reads needs at most its header stamp: the
    reader copies only a big message's first bytes (``ros2_take.HEAD_BYTES``); a decoded topic whole."""
    from detection.taps.ros2_take import HEAD_BYTES

    tap, _, _ = live
    assert wait_for(lambda: {"/ten", "/centered", "/stamped"} <= set(tap.reader.topics), 30)
    assert tap.reader._heads["/ten"] == HEAD_BYTES and tap.reader._heads["/stamped"] == HEAD_BYTES
    assert tap.reader._heads["/centered"] is None                  # the t-test reads its data field


def test_t_test_accepts_an_unshifted_mean_and_rejects_a_shifted_one(live):
    tap, seen, _ = live
    assert settled(tap, "score(centered)").holds
    assert not settled(tap, "score(shifted)").holds


def test_a_stopped_node_is_not_activated_within_a_second(live):
    _, seen, pubs = live
    # discovery of the victim may take longer than the observer's start-up on a busy host: wait until seen
    assert wait_for(lambda: seen.latest("activated(victim)") is not None and seen.latest("activated(victim)").holds, 20)
    victim = pubs[1]
    victim.send_signal(2)                      # SIGINT: the node leaves the graph as a stopped node does
    victim.wait(10)
    gone = time.time()
    assert wait_for(lambda: not seen.latest("activated(victim)").holds, 10)
    assert seen.latest("activated(victim)").time - gone <= 1.0


def test_resource_reads_the_publisher_process_with_psutil(live):
    tap, seen, _ = live
    assert wait_for(lambda: seen.latest("resource(talker)") is not None, 20)
    o = seen.latest("resource(talker)")
    assert o.holds and o.state == "ok" and 0 <= o.measured < 95
    memory = next(x for x in tap.observers.observers if x.name == "resource(talker)").filters["memory"].value()
    assert 10 < memory < 4000             # MB: a Python process with rclpy loaded


def test_timeout_timestamp_timing_and_movement_on_live_topics(live):
    tap, seen, _ = live
    assert wait_for(lambda: all(seen.latest(n) for n in ("timeout(ten)", "timeout(never)")), 30)
    assert seen.latest("timeout(ten)").holds and not seen.latest("timeout(never)").holds
    stamped = settled(tap, "timestamp(stamped)")
    assert stamped.holds and 0.0 <= stamped.measured < 0.5, stamped        # header stamp read from raw CDR
    assert settled(tap, "timing(ten,three)").holds
    movement = settled(tap, "movement(centered,shifted)")                  # residual mean -1: rejected
    assert not movement.holds and movement.measured == pytest.approx(-1.0, abs=0.6)
