"""numpy ↔ ROS message conversions, instead of cv_bridge and tf2 (not available as wheels).

Images: ``rgb8``/``bgr8``/``mono8``/``16UC1``/``32FC1`` with row padding and byte order honoured.
Planar poses: yaw ↔ quaternion. Odometry and camera info with the Kobuki/Kinect conventions.
"""
from __future__ import annotations

import math

import numpy as np
from geometry_msgs.msg import Quaternion, Twist
from nav_msgs.msg import Odometry
from sensor_msgs.msg import CameraInfo, Image

ENCODINGS: dict[str, tuple[str, int]] = {
    "rgb8": ("u1", 3), "bgr8": ("u1", 3), "mono8": ("u1", 1),
    "mono16": ("u2", 1), "16UC1": ("u2", 1), "32FC1": ("f4", 1),
}

# Kobuki odometry covariances (kobuki_ros odometry.cpp): x, y, yaw used; unused axes "unknown".
_POSE_COVARIANCE = [0.0] * 36
for _i, _v in ((0, 0.1), (7, 0.1), (14, 1e10), (21, 1e10), (28, 1e10), (35, 0.2)):
    _POSE_COVARIANCE[_i] = _v


def image_to_array(msg: Image) -> np.ndarray:
    """An ``(h, w, 3)`` or ``(h, w)`` array viewing the message data (no copy when unpadded)."""
    if msg.encoding not in ENCODINGS:
        raise ValueError(f"image encoding {msg.encoding!r} not supported; expected one of {sorted(ENCODINGS)}")
    kind, channels = ENCODINGS[msg.encoding]
    dtype = np.dtype(kind).newbyteorder(">" if msg.is_bigendian else "<")
    raw = np.frombuffer(msg.data, np.uint8).reshape(msg.height, msg.step)
    raw = raw[:, : msg.width * channels * dtype.itemsize]
    array = np.ascontiguousarray(raw).view(dtype)
    if channels > 1:
        return array.reshape(msg.height, msg.width, channels)
    return array.reshape(msg.height, msg.width)


def array_to_image(array: np.ndarray, encoding: str, frame_id: str, stamp=None) -> Image:
    """A little-endian, unpadded ``Image`` holding ``array``."""
    kind, channels = ENCODINGS[encoding]
    array = np.ascontiguousarray(array, dtype=np.dtype(kind).newbyteorder("<"))
    if (array.ndim == 3 and array.shape[2] != channels) or (array.ndim == 2 and channels != 1):
        raise ValueError(f"array of shape {array.shape} does not fit encoding {encoding!r}")
    msg = Image()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
    msg.height, msg.width = int(array.shape[0]), int(array.shape[1])
    msg.encoding, msg.is_bigendian = encoding, 0
    msg.step = msg.width * channels * array.dtype.itemsize
    msg.data = array.tobytes()
    return msg


def yaw_to_quaternion(yaw: float) -> Quaternion:
    return Quaternion(x=0.0, y=0.0, z=math.sin(yaw / 2.0), w=math.cos(yaw / 2.0))


def quaternion_to_yaw(q: Quaternion) -> float:
    return math.atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z))


def odometry(x: float, y: float, theta: float, v: float, w: float, stamp, frame_id: str = "odom",
             child_frame_id: str = "base_footprint") -> Odometry:
    """A Kobuki-style ``Odometry`` for pose ``(x, y, theta)`` moving at ``(v, w)``."""
    msg = Odometry()
    msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    msg.child_frame_id = child_frame_id
    msg.pose.pose.position.x = float(x)
    msg.pose.pose.position.y = float(y)
    msg.pose.pose.orientation = yaw_to_quaternion(float(theta))
    msg.pose.covariance = _POSE_COVARIANCE
    msg.twist.twist.linear.x = float(v)
    msg.twist.twist.angular.z = float(w)
    msg.twist.covariance = _POSE_COVARIANCE
    return msg


def pose_of(msg: Odometry) -> tuple[float, float, float]:
    """``(x, y, theta)`` of an ``Odometry``."""
    p = msg.pose.pose
    return p.position.x, p.position.y, quaternion_to_yaw(p.orientation)


def twist(v: float, w: float) -> Twist:
    msg = Twist()
    msg.linear.x = float(v)
    msg.angular.z = float(w)
    return msg


def camera_info(width: int, height: int, fx: float, fy: float, cx: float, cy: float,
                frame_id: str, stamp=None) -> CameraInfo:
    """A distortion-free pinhole ``CameraInfo`` (the simulated Kinect is ideal)."""
    msg = CameraInfo()
    msg.header.frame_id = frame_id
    if stamp is not None:
        msg.header.stamp = stamp
    msg.width, msg.height = int(width), int(height)
    msg.distortion_model = "plumb_bob"
    msg.d = [0.0] * 5
    msg.k = [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]
    msg.r = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    msg.p = [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0]
    return msg
