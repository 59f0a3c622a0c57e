"""Generic event encoding (rosidl introspection, JSON envelopes) and the 1 Hz window features."""
from __future__ import annotations

import json

import numpy as np
import pytest

from detection.learned.encoding import EncodingError, JsonEncoder, flatten_json
from detection.learned.features import ChannelBuffer, WINDOWS_S, feature_names, window_features


def test_ros_messages_are_encoded_from_their_introspection():
    pytest.importorskip("rclpy")
    from nav_msgs.msg import Odometry
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import JointState

    from detection.learned.encoding import RosEncoder

    odom = RosEncoder.for_type("nav_msgs/msg/Odometry")
    assert "pose.pose.position.x" in odom.columns and "child_frame_id#len" in odom.columns
    assert not any("stamp" in c for c in odom.columns)           # absolute time is left out
    assert not any("covariance" in c for c in odom.columns)      # fixed 36-element arrays say nothing
    msg = Odometry()
    msg.child_frame_id = "base_footprint"
    msg.pose.pose.position.x = 1.5
    msg.twist.twist.angular.z = -0.25
    data = serialize_message(msg)
    vector = odom.encode_raw(data)
    columns = dict(zip(odom.columns, vector))
    assert columns["size"] == len(data)
    assert columns["pose.pose.position.x"] == 1.5 and columns["twist.twist.angular.z"] == -0.25
    assert columns["child_frame_id#len"] == len("base_footprint")
    joints = RosEncoder(JointState)
    msg = JointState(name=["a", "b", "c"], position=[1.0, 2.0, 3.0])
    assert dict(zip(joints.columns, joints.encode(msg, 99)))["position#len"] == 3.0
    with pytest.raises(EncodingError, match="unknown ROS 2 message type 'nope_msgs/msg/X'"):
        RosEncoder.for_type("nope_msgs/msg/X")


def test_json_envelopes_give_numbers_and_lengths_by_path():
    envelope = {"v": 1, "id": "ab.7", "from": "alice", "to": ["bob", "carol"], "perf": "tell",
                "content": "position(3,4)", "meta": {"hops": 2, "ok": True}}
    assert flatten_json(envelope) == {"v": 1.0, "id#len": 4.0, "from#len": 5.0, "to#len": 2.0, "perf#len": 4.0,
                                      "content#len": 13.0, "meta.hops": 2.0, "meta.ok": 1.0}
    payload = json.dumps(envelope).encode()
    encoder = JsonEncoder.from_samples([payload])
    batch = payload + b"\n" + json.dumps(dict(envelope, content="x")).encode()
    first, second = encoder.encode(batch)                       # a batch: one vector per envelope
    assert first[0] == len(payload)
    assert second[encoder.columns.index("content#len")] == 1.0
    with pytest.raises(EncodingError, match="not a JSON envelope"):
        encoder.encode(b"{broken")


def test_window_features_follow_the_definition():
    times = np.array([0.5, 1.0, 3.0, 3.5, 9.0])
    values = np.array([[1.0], [3.0], [5.0], [7.0], [11.0]])
    rows = window_features(times, values, np.array([0.0, 3.5, 4.0, 8.0]))
    names = feature_names("/t", ["v"])
    assert names == ["/t|mean2.5s|v", "/t|count2.5s", "/t|mean6s|v", "/t|count6s", "/t|last|v"]
    expected = [[0, 0, 0, 0, 0],                  # nothing yet
                [6, 2, 4, 4, 7],                  # (1.0, 3.5]: 5, 7; (-2.5, 3.5]: all four
                [6, 2, 4, 4, 7],
                [0, 0, 6, 2, 7]]                  # (5.5, 8]: none; (2, 8]: 5, 7; last still 7
    assert rows.tolist() == expected
    assert window_features(np.empty(0), np.empty((0, 0)), np.array([1.0])).shape == (1, len(WINDOWS_S))  # counts only


def test_online_buffer_gives_the_offline_features():
    rng = np.random.default_rng(3)
    times = np.sort(rng.uniform(0, 60, 900))
    times[400:500] = np.linspace(times[399], times[399] + 0.01, 100)    # a burst
    values = rng.normal(size=(900, 4))
    ticks = np.arange(1.0, 61.0)
    offline = window_features(times, values, ticks)
    buffer, online, i = ChannelBuffer(4, capacity=64), [], 0
    for tick in ticks:
        while i < len(times) and times[i] <= tick:
            buffer.add(times[i], values[i])
            i += 1
        online.append(buffer.features(tick))
    np.testing.assert_allclose(np.array(online), offline, rtol=1e-12, atol=1e-12)


def _messages_of_every_shape():
    """Messages whose layouts differ in every way CDR allows: strings (also non-ASCII), sequences of
    numbers, strings and structs, small and large fixed arrays, nested headers, booleans, float32."""
    import random

    from geometry_msgs.msg import PoseArray, Pose, Twist
    from nav_msgs.msg import Odometry
    from sensor_msgs.msg import CameraInfo, Image, Imu, JointState
    from std_msgs.msg import Empty, String

    rng = random.Random(7)
    out = []
    for _ in range(20):
        odom = Odometry()
        odom.header.frame_id = "odom" * rng.randint(0, 3)
        odom.child_frame_id = "base" * rng.randint(0, 3)
        odom.header.stamp.sec = rng.randint(0, 2**31 - 1)
        odom.pose.pose.position.x = rng.uniform(-1e6, 1e6)
        odom.twist.twist.angular.z = rng.gauss(0, 1)
        imu = Imu()
        imu.orientation.w = rng.random()
        imu.angular_velocity_covariance = [rng.random() for _ in range(9)]
        names = [rng.choice("abcdef") * rng.randint(0, 4) for _ in range(rng.randint(0, 4))]
        joints = JointState(name=names, position=[rng.random() for _ in names], effort=[1.0] * rng.randint(0, 2))
        info = CameraInfo(distortion_model="plumb_bob", d=[rng.random() for _ in range(rng.randint(0, 5))],
                          width=rng.randint(0, 640), binning_x=rng.randint(0, 4))
        info.k = [rng.random() for _ in range(9)]
        info.roi.do_rectify = rng.random() < 0.5
        image = Image(encoding="rgb8", height=2, width=3, is_bigendian=rng.randint(0, 1),
                      data=bytes(rng.randrange(256) for _ in range(rng.randint(0, 18))))
        poses = PoseArray(poses=[Pose() for _ in range(rng.randint(0, 3))])
        text = String(data=rng.choice(["", "plain", '{"x": 1}', "é und ü", "日本"]) * rng.randint(1, 3))
        twist = Twist()
        twist.linear.x = float("nan") if rng.random() < 0.2 else rng.random()
        out += [odom, imu, joints, info, image, poses, text, twist, Empty()]
    same_size = [JointState(name=["ab", "c"], position=[1.0, 2.0]), JointState(name=["a", "bc"], position=[3.0, 4.0])]
    return out + same_size


def test_numbers_read_in_place_from_cdr_equal_rclpys_deserialised_message():
    """``encode_raw`` reads the CDR bytes in place (``CdrColumns``); it must give exactly the vector of
    the deserialised message for any layout, including two messages of one size whose strings differ."""
    pytest.importorskip("rclpy")
    from rclpy.serialization import deserialize_message, serialize_message

    from detection.learned.encoding import RosEncoder

    messages = _messages_of_every_shape()
    non_ascii = sum(1 for m in messages if isinstance(getattr(m, "data", b""), str) and not m.data.isascii())
    encoders, in_place = {}, 0
    for msg in messages:
        encoder = encoders.setdefault(type(msg), RosEncoder(type(msg)))
        data = serialize_message(msg)
        expected = encoder.encode(deserialize_message(data, type(msg)), len(data))
        np.testing.assert_array_equal(encoder.encode_raw(data), expected, err_msg=type(msg).__name__)
        in_place += encoder._cdr.read(data) is not None
    assert all(encoder._cdr for encoder in encoders.values())          # every type has an in-place reader
    assert non_ascii and in_place == len(messages) - non_ascii        # all but the non-ASCII texts


def test_the_head_of_a_message_gives_its_whole_vector_or_none():
    """A ``MessageHead`` (the reader's first bytes of a big message): where the type's numbers all come
    before its bulk (``reads_heads``) and lie in the head, the vector is the whole message's; else None,
    never a wrong vector. An image's head of ``HEAD_BYTES`` always holds them (the live detector's case)."""
    pytest.importorskip("rclpy")
    from rclpy.serialization import serialize_message
    from sensor_msgs.msg import CameraInfo, Image, PointCloud2

    from detection.learned.encoding import HEAD_BYTES, CdrColumns, EncodingError, RosEncoder
    from detection.taps.ros2_take import MessageHead

    read_in_heads = 0
    for msg in _messages_of_every_shape():
        encoder = RosEncoder(type(msg))
        data = serialize_message(msg)
        whole = encoder.encode_raw(data)
        for cut in range(4, len(data), 3):
            vector = CdrColumns.for_class(type(msg), encoder.columns[1:]).read(MessageHead(data[:cut], len(data)))
            if vector is not None:
                np.testing.assert_array_equal(vector, whole, err_msg=type(msg).__name__)
                read_in_heads += 1
    assert read_in_heads > 100
    assert RosEncoder(Image).head_bytes == HEAD_BYTES
    assert RosEncoder(CameraInfo).head_bytes is None and RosEncoder(PointCloud2).head_bytes is None

    encoder = RosEncoder(Image)
    image = Image(height=480, width=640, encoding="rgb8", step=1920, data=bytes(921600))
    image.header.frame_id = "camera_rgb_optical_frame"
    data = serialize_message(image)
    np.testing.assert_array_equal(encoder.encode_raw(MessageHead(data[:HEAD_BYTES], len(data))),
                                  encoder.encode_raw(data))
    image.header.frame_id = "x" * HEAD_BYTES                        # its numbers are not in the head
    data = serialize_message(image)
    with pytest.raises(EncodingError, match="do not hold every number"):
        encoder.encode_raw(MessageHead(data[:HEAD_BYTES], len(data)))


def test_a_message_shorter_than_its_layout_is_not_read_in_place():
    pytest.importorskip("rclpy")
    from nav_msgs.msg import Odometry
    from rclpy.serialization import serialize_message

    from detection.learned.encoding import RosEncoder

    encoder = RosEncoder(Odometry)
    data = serialize_message(Odometry(child_frame_id="base"))
    encoder.encode_raw(data)
    assert encoder._cdr.read(data[:-40]) is None and encoder._cdr.read(data[:3]) is None
    big_endian = data[:1] + b"\x00" + data[2:]
    assert encoder._cdr.read(big_endian) is None
