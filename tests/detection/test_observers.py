"""Each observer kind on synthetic message streams, and how an ObserverSet emits observations."""
from __future__ import annotations

import math
import struct
from types import SimpleNamespace

import pytest

from detection.config import load_observers
from detection.message import Message
from detection.observers.activated import GRAPH_CHANNEL

from .conftest import merged, stream


def run(config_text: str, messages, until: float, write):
    observers = load_observers(write("obs.yaml", config_text)).build()
    observers.start(0)
    out = observers.feed_all(messages)
    out += observers.advance(int(until * 1e9))
    return observers, out


def literals(observations):
    return [(round(o.time, 3), o.literal) for o in observations]


HZ = """\
start_up_time: 1.0
setup:
  - type: hz
    topics:
      - name: /scan
        filter: {type: median, window_size: 10}
        states:
          - {state: nominal, number: 1, frequency: {type: gauss, mean: 10.0, std_deviation: 1.0}}
"""


def test_hz_passes_at_the_expected_rate_and_fails_at_a_third(write):
    observers, out = run(HZ, stream("/scan", 10, 0.05, 5), 5, write)
    assert literals(out) == [(1.0, "hz(scan)")]
    assert out[0].measured == pytest.approx(10.0) and out[0].state == "nominal"
    _, slow = run(HZ, stream("/scan", 3, 0.05, 5), 5, write)
    assert [o.literal for o in slow] == ["~hz(scan)"] and slow[0].measured == pytest.approx(3.0)


def test_hz_of_a_publisher_that_stops_falls_once_and_stays_false(write):
    _, out = run(HZ, stream("/scan", 10, 0.05, 3), 8, write)
    assert [o.literal for o in out] == ["hz(scan)", "~hz(scan)"]
    assert 3.9 <= out[1].time <= 4.2        # a window's worth of silence (10 periods) after the last message


def test_nothing_is_judged_during_start_up_and_silence_from_the_start_is_0_hz(write):
    _, out = run(HZ, [], 3, write)
    assert literals(out) == [(1.0, "~hz(scan)")] and out[0].measured == 0.0


def test_timeout(write):
    text = "setup:\n  - type: timeout\n    topics:\n      - {name: /cmd, timeout: 0.5}\n"
    _, out = run(text, merged(stream("/cmd", 5, 0.0, 2), stream("/cmd", 5, 4, 5)), 5, write)
    assert literals(out) == [(1.0, "timeout(cmd)"), (2.4, "~timeout(cmd)"), (4.1, "timeout(cmd)")]
    # (a tick at the very time of a message runs before the message is handed over)


def stamped_cdr(stamp: float) -> bytes:
    sec = int(stamp)
    return b"\x00\x01\x00\x00" + struct.pack("<iI", sec, int(round((stamp - sec) * 1e9))) + b"\x00" * 8


def test_timestamp_reads_the_header_stamp_from_raw_cdr_and_from_a_decoded_message(write):
    text = """\
setup:
  - type: timestamp
    topics:
      - name: /scan
        filter: {type: mean, window_size: 5}
        states: [{state: fresh, delay: {type: less_than, less_than: 0.1}}]
"""
    observers = load_observers(write("obs.yaml", text)).build()
    observers.start(0)
    fresh = [Message("/scan", int(t * 1e9), raw=stamped_cdr(t - 0.02)) for t in (0.1, 0.2, 0.3, 0.4, 0.5)]
    out = observers.feed_all(fresh) + observers.advance(int(1.5e9))
    assert [o.literal for o in out] == ["timestamp(scan)"] and out[0].measured == pytest.approx(0.02)

    def decoded(t: float, age: float) -> Message:
        stamp = t - age
        header = SimpleNamespace(stamp=SimpleNamespace(sec=int(stamp), nanosec=int(round((stamp % 1) * 1e9))))
        return Message("/scan", int(t * 1e9), SimpleNamespace(header=header))
    out = observers.feed_all(decoded(2 + i / 10, 0.5) for i in range(6)) + observers.advance(int(3e9))
    assert [o.literal for o in out] == ["~timestamp(scan)"] and out[0].measured > 0.1
    assert observers.observers[0].filters["delay"].value() == pytest.approx(0.5)


def test_timing_measures_from_a_message_on_a_to_the_next_on_b(write):
    text = """\
setup:
  - type: timing
    topics:
      - name_a: /scan
        name_b: /pose
        filter: {type: mean, window_size: 5}
        states: [{state: ok, delay: {type: in_between, lower_bound: 0.0, upper_bound: 0.05}}]
"""
    fast = merged(stream("/scan", 10, 0.0, 2), stream("/pose", 10, 0.03, 2))
    _, out = run(text, fast, 2, write)
    assert [o.literal for o in out] == ["timing(scan,pose)"] and out[0].measured == pytest.approx(0.03)
    slow = merged(stream("/scan", 10, 0.0, 2), stream("/pose", 10, 0.08, 2))
    _, out = run(text, slow, 2, write)
    assert [o.literal for o in out] == ["~timing(scan,pose)"]


def test_score_reads_a_field(write):
    text = """\
setup:
  - type: score
    topics:
      - name: /battery
        field: voltage
        filter: {type: ewma, decay_rate: 0.5}
        states: [{state: charged, score: {type: greater_than, greater_than: 11.0}}]
"""
    volts = merged(stream("/battery", 5, 0, 2, lambda t: {"voltage": 12.0}),
                   stream("/battery", 5, 2, 4, lambda t: {"voltage": 10.0}))
    _, out = run(text, volts, 4, write)
    assert [o.literal for o in out] == ["score(battery)", "~score(battery)"]


def test_movement_residual_with_a_student_t_test(write):
    text = """\
setup:
  - type: movement
    correlations:
      - source_a: {topic: /imu, field: angular_velocity.z}
        source_b: {topic: /wheel_odom, field: twist.twist.angular.z}
        filter: {type: mean, window_size: 20}
        states: [{state: agree, residual: {type: student_t, true_mean: 0.0, significance_level: 0.01}}]
"""
    def imu(gain):
        return lambda t: {"angular_velocity": {"z": gain * math.sin(t) + 0.001 * math.cos(37 * t)}}

    def odom(t):
        return {"twist": {"twist": {"angular": {"z": math.sin(t) + 0.001 * math.sin(53 * t)}}}}
    healthy = merged(stream("/imu", 50, 0, 4, imu(1.0)), stream("/wheel_odom", 50, 0.001, 4, odom))
    _, out = run(text, healthy, 4, write)
    assert [o.literal for o in out] == ["movement(imu,wheel_odom)"]
    over = merged(stream("/imu", 50, 0, 4, imu(1.2)), stream("/wheel_odom", 50, 0.001, 4, odom))
    _, out = run(text, over, 4, write)
    assert out and out[0].literal == "~movement(imu,wheel_odom)"


def test_activated_follows_the_graph(write):
    text = "setup:\n  - type: activated\n    nodes:\n      - name: /laser_driver\n"
    graph = [Message(GRAPH_CHANNEL, int(0.5e9), frozenset({"/laser_driver", "/amcl"})),
             Message(GRAPH_CHANNEL, int(2.55e9), frozenset({"/amcl"}))]
    _, out = run(text, graph, 3, write)
    assert literals(out) == [(1.0, "activated(laser_driver)"), (2.6, "~activated(laser_driver)")]


def test_resource_bounds_cpu_and_memory(write):
    text = """\
setup:
  - type: resource
    nodes:
      - name: amcl
        filter: {type: mean, window_size: 3}
        states: [{state: ok, cpu: {type: less_than, less_than: 50}, memory: {type: less_than, less_than: 200}}]
"""
    samples = merged(stream("@resource/amcl", 5, 0, 2, lambda t: {"cpu": 10.0, "memory": 80.0}),
                     stream("@resource/amcl", 5, 2, 4, lambda t: {"cpu": 10.0, "memory": 400.0}))
    _, out = run(text, samples, 4, write)
    assert [o.literal for o in out] == ["resource(amcl)", "~resource(amcl)"]


def test_an_unreadable_message_is_counted_never_fatal(write, caplog):
    text = """\
setup:
  - type: score
    topics:
      - {name: /battery, field: voltage, states: [{state: ok, score: {type: greater_than, greater_than: 11}}]}
"""
    msgs = [Message("/battery", int(0.1e9), {"volts": 12}), Message("/battery", int(0.2e9), {"voltage": "high"}),
            Message("/battery", int(0.3e9), raw=b"\x00"), Message("/battery", int(0.4e9), {"voltage": 12.0})]
    observers, out = run(text, msgs, 1.5, write)
    assert observers.errors["score(battery)"] == 3
    assert [o.literal for o in out] == ["score(battery)"]
    assert "unreadable message #1" in caplog.text


def test_a_state_marked_unhealthy_names_the_fault(write):
    text = """\
setup:
  - type: hz
    topics:
      - name: /scan
        states:
          - {state: nominal, frequency: {type: in_between, lower_bound: 8, upper_bound: 12}}
          - {state: throttled, healthy: false, frequency: {type: in_between, lower_bound: 4, upper_bound: 6}}
"""
    _, out = run(text, stream("/scan", 5, 0.05, 2), 2, write)
    assert [(o.literal, o.state) for o in out] == [("~hz(scan)", "throttled")]


def test_same_messages_same_observations(write):
    msgs = merged(stream("/scan", 10, 0.05, 3), stream("/scan", 3, 3, 6))
    assert run(HZ, msgs, 8, write)[1] == run(HZ, msgs, 8, write)[1]
