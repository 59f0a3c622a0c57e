"""The one ROS 2 reader (``detection.taps.ros2_reader``): a publisher in another process, raw bytes in
receive-time order, ticks on the same thread, and a clean end however the context goes away."""
from __future__ import annotations

import threading

import pytest

pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")

from robot_bridge.ros2.runtime import RosContext, wait_for  # noqa: E402
from tests.detection.test_ros2_observers import DOMAIN, start_publishers, stop  # noqa: E402


@pytest.fixture(scope="module")
def publisher():
    [proc] = start_publishers(["--name", "reader_pub", "--pub", "/fast:200", "--pub", "/slow:20"])
    yield proc
    stop(proc)


def test_messages_arrive_raw_in_receive_time_order_and_ticks_share_the_thread(publisher):
    from rclpy.serialization import deserialize_message
    from std_msgs.msg import Float64

    from detection.taps.ros2_reader import TopicReader

    batches, ticks, threads = [], [], set()

    def on_batch(batch):
        threads.add(threading.get_ident())
        batches.append(batch)

    def on_tick():
        threads.add(threading.get_ident())
        ticks.append(1)

    with RosContext(domain_id=DOMAIN) as ros:
        reader = TopicReader(ros.context, on_batch, on_tick=on_tick, tick_s=0.1, name="reader_test")
        reader.subscribe("/fast", Float64)
        reader.subscribe("/slow", Float64)
        reader.start()
        assert wait_for(lambda: {t for b in batches for _, t, _ in b} == {"/fast", "/slow"} and len(ticks) >= 5, 30)
        reader.close()
        reader.close()                                      # idempotent
    messages = [m for b in batches for m in b]
    assert reader.received == len(messages)
    assert all(earlier[0] <= later[0] for b in batches for earlier, later in zip(b, b[1:]))
    assert max(len(b) for b in batches) > 1                 # a wake-up takes many messages, not one
    assert isinstance(deserialize_message(messages[0][2], Float64), Float64)
    assert len(threads) == 1                                # batches and ticks: one thread, no lock needed


def test_the_reader_ends_when_its_context_is_shut_down_under_it(publisher):
    from std_msgs.msg import Float64

    from detection.taps.ros2_reader import TopicReader

    ros = RosContext(domain_id=DOMAIN).start()
    got = []
    reader = TopicReader(ros.context, got.extend, tick_s=0.2).start()
    reader.subscribe("/fast", Float64)
    assert wait_for(lambda: len(got) > 10, 30)
    ros.close()                                             # as a caller that forgets the reader does
    reader._thread.join(10)
    assert not reader._thread.is_alive()
