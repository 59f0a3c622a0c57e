"""The one ROS 2 reader (``detection.taps.ros2_reader``): a publisher in another process, raw bytes in
receive-time order, ticks on the same thread, and a clean end however the context goes away."""
from __future__ import annotations

import threading

import numpy as np
import pytest

pytest.importorskip("rclpy", reason="ROS 2 is an optional extra (pip install 'faultmas[ros2]')")

from robot_bridge.ros2.runtime import RosContext, wait_for  # noqa: E402
from tests.detection.test_ros2_observers import DOMAIN, start_publishers, stop  # noqa: E402


@pytest.fixture(scope="module")
def publisher():
    [proc] = start_publishers(["--name", "reader_pub", "--pub", "/fast:200", "--pub", "/slow:20", "--image", "/image:10"])
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


def test_a_consumer_of_heads_gets_the_first_bytes_of_big_messages_and_their_size(publisher):
    """``subscribe(head=N)``: an image comes as its first N bytes and its size (its pixels are not
    copied), small messages whole; the numbers read from the head are the whole image's."""
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import Image
    from std_msgs.msg import Float64

    from detection.learned.encoding import RosEncoder
    from detection.taps.ros2_reader import TopicReader
    from detection.taps.ros2_take import MessageHead, Taker
    from tests.detection.publisher_node import image_message

    assert Taker.create() is not None                       # rcl's C API is usable here (else rclpy takes)
    whole = serialize_message(image_message())
    got = []
    with RosContext(domain_id=DOMAIN) as ros:
        reader = TopicReader(ros.context, got.extend, tick_s=0.2)
        reader.subscribe("/image", Image, head=4096)
        reader.subscribe("/fast", Float64, head=4096)
        reader.start()
        assert wait_for(lambda: {t for _, t, _ in got} == {"/image", "/fast"}, 30)
        reader.close()
    images = [data for _, topic, data in got if topic == "/image"]
    assert all(isinstance(d, MessageHead) and len(d) == 4096 and d.size == len(whole) for d in images)
    assert all(not isinstance(d, MessageHead) and len(d) == 12 for _, topic, d in got if topic == "/fast")
    assert images[0][-1000:] == whole[4096 - 1000:4096]     # pixels (CDR's padding bytes may differ)
    encoder = RosEncoder(Image)
    np.testing.assert_array_equal(encoder.encode_raw(images[0]), encoder.encode_raw(whole))


def test_a_topic_is_taken_whole_when_one_of_its_consumers_needs_whole_messages(publisher):
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import Image

    from detection.taps.ros2_reader import TopicReader
    from tests.detection.publisher_node import image_message

    size = len(serialize_message(image_message()))
    heads, wholes = [], []
    with RosContext(domain_id=DOMAIN) as ros:
        reader = TopicReader(ros.context, heads.extend, tick_s=0.2)
        reader.subscribe("/image", Image, head=4096)
        reader.add_listener(wholes.extend, topics={"/image"})
        reader.subscribe("/image", Image)                   # the second consumer wants whole messages
        reader.start()
        assert wait_for(lambda: len(wholes) >= 2, 30)
        reader.close()
    assert all(type(d) is bytes and len(d) == size for _, _, d in heads + wholes)


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


def test_a_consumer_that_raises_loses_its_batch_not_the_reader_the_others_share(publisher, caplog):
    """Before: one consumer's exception ended the reader's thread ("ROS 2 reader stopped"), and every observer
    sharing it went deaf."""
    import logging

    from std_msgs.msg import Float64

    from detection.taps.ros2_reader import TopicReader

    raised, others, ticks = [], [], []

    def broken(batch):
        raised.append(len(batch))
        raise ValueError("an observer's bug")

    def broken_tick():
        ticks.append(1)
        raise ValueError("a tick's bug")

    with caplog.at_level(logging.WARNING, logger="faultmas.detection"):
        with RosContext(domain_id=DOMAIN) as ros:
            reader = TopicReader(ros.context, broken, on_tick=broken_tick, tick_s=0.05, name="reader_raising")
            reader.add_listener(others.append)
            reader.subscribe("/fast", Float64)
            reader.start()
            assert wait_for(lambda: len(raised) >= 5 and len(others) >= 5 and len(ticks) >= 5, 30)
            assert reader._thread.is_alive()
            reader.close()
    lines = [r.getMessage() for r in caplog.records if "ROS 2 reader" in r.getMessage()]
    assert 1 <= len(lines) <= 3 and "ValueError" in lines[0], lines    # said once (then at 10), not per batch
