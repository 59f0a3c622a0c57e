"""ROS 2 node ``visual_synthesizer``: camera frames in, ``robot_seen`` percepts out (the seed paper's
``visual_perception`` node, ported).

Subscribes ``camera/rgb/image_raw`` (rgb8 or bgr8), ``camera/depth_registered/image_raw`` (16UC1 mm
or 32FC1 m) and ``camera/rgb/camera_info`` with sensor-data QoS, runs :mod:`perception`'s detector
(``detect_all``) on each RGB frame with the latest depth frame, and publishes on ``jason/percepts`` a snapshot of
source ``camera``: ``camera_ok`` plus one ``robot_seen(Name, AngleDeg, DepthM, YawDeg)`` per robot
found (see :mod:`robot_bridge.percepts`). A frame the detector fails on is dropped with a log line
(the node goes on: before, one exception ended it); after ``CAMERA_FAILED_AFTER`` such frames in a row
the snapshot says ``camera_failed(detector)`` instead of ``camera_ok``, as the simulator's camera does. The markers do not say whose they are: ``Name`` is the
parameter ``observed`` (default: the other robot of ``robots`` when there are two).
"""
from __future__ import annotations

import logging

from robot_bridge.ros2.runtime import require_ros, run_node

require_ros(__name__)

import cv2  # noqa: E402
import numpy as np  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import qos_profile_sensor_data  # noqa: E402
from sensor_msgs.msg import CameraInfo, Image  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from perception.camera import CameraModel  # noqa: E402
from robot_bridge import percepts  # noqa: E402
from robot_bridge.failure_log import FailureLog  # noqa: E402
from robot_bridge.protocol import Percept  # noqa: E402
from robot_bridge.ros2.convert import image_to_array  # noqa: E402
from robot_bridge.ros2.wire import PerceptSnapshot  # noqa: E402

FRAME_TTL_S = 1.0
"""The camera's percepts vanish this long after the last frame (``camera_ok`` means frames arrive)."""


def depth_in_metres(msg: Image) -> np.ndarray:
    """A depth image as float32 metres, 0 where there is no reading."""
    depth = image_to_array(msg)
    if msg.encoding in ("16UC1", "mono16"):
        return depth.astype(np.float32) / 1000.0
    return np.nan_to_num(depth.astype(np.float32), nan=0.0, posinf=0.0, neginf=0.0)


def camera_model(msg: CameraInfo) -> CameraModel:
    k = msg.k
    return CameraModel(int(msg.width), int(msg.height), float(k[0]), float(k[4]), float(k[2]), float(k[5]))


def seen(detection: object, name: str) -> Percept:
    """A detection (optical frame: angle and yaw positive to the right) as a ``robot_seen`` percept
    (angles positive to the left, REP 103, so ``turn(AngleDeg)`` faces the robot)."""
    return percepts.robot_seen(name, -float(detection.angle_deg), float(detection.depth_m),
                               -float(detection.yaw_deg))


def _load_detector(logger):
    """Every robot ``perception.detect`` finds in a frame; without it the node still reports
    ``camera_ok`` (frames arrive) and says so once."""
    try:
        from perception.detect import detect_all
    except ImportError as exc:
        logger.error(f"perception.detect is not available ({exc}): reporting camera_ok only")
        return lambda rgb, depth, camera: []
    return lambda rgb, depth, camera: detect_all(rgb, depth, camera).all


class VisualSynthesizer(Node):
    """Detects the other robot's markers in every frame and reports what it sees."""

    def __init__(self, namespace: str = "", options: object = None, context=None, **overrides) -> None:
        super().__init__("visual_synthesizer", namespace=namespace, context=context)
        me = namespace.strip("/").split("/")[-1]
        p = {name: self.declare_parameter(name, overrides.get(name, default)).value for name, default in
             (("robots", [me or "robot"]), ("observed", ""), ("agent_name", ""))}
        others = [r for r in p["robots"] if r != me]
        self.observed = str(p["observed"]) or (others[0] if len(others) == 1 else "robot")
        self.agent_name = str(p["agent_name"])
        self.camera: CameraModel | None = None
        self.depth: np.ndarray | None = None
        self.frames = 0
        self.last: list[Percept] = []
        self._detect = _load_detector(self.get_logger())
        self._detect_failures = FailureLog(logging.getLogger(__name__), f"visual synthesizer {namespace or '/'}: "
                                           "the detector", persistent_after=percepts.CAMERA_FAILED_AFTER)
        self.create_subscription(CameraInfo, "camera/rgb/camera_info", self._on_info, qos_profile_sensor_data)
        self.create_subscription(Image, "camera/depth_registered/image_raw", self._on_depth, qos_profile_sensor_data)
        self.create_subscription(Image, "camera/rgb/image_raw", self._on_rgb, qos_profile_sensor_data)
        self._out = self.create_publisher(String, "jason/percepts", 10)

    def _on_info(self, msg: CameraInfo) -> None:
        if self.camera is None:
            self.camera = camera_model(msg)

    def _on_depth(self, msg: Image) -> None:
        self.depth = depth_in_metres(msg)

    def _on_rgb(self, msg: Image) -> None:
        if self.camera is None or self.depth is None:
            return
        rgb = image_to_array(msg)
        if msg.encoding == "bgr8":
            rgb = cv2.cvtColor(rgb, cv2.COLOR_BGR2RGB)
        if self.depth.shape != rgb.shape[:2]:
            self.get_logger().warning(f"depth {self.depth.shape} and rgb {rgb.shape[:2]} differ; frame skipped")
            return
        try:
            found = [percepts.camera_ok()]
            found += [seen(d, self.observed) for d in self._detect(rgb, self.depth, self.camera)]
        except Exception as exc:    # this frame is lost, not the node; one that keeps failing is named
            self._detect_failures.failed(exc, f"frame {self.frames}")
            found = [percepts.camera_failed("detector") if self._detect_failures.persistent else percepts.camera_ok()]
        else:
            self._detect_failures.succeeded()
        self.frames += 1
        self.last = found
        self._out.publish(String(data=PerceptSnapshot(self.agent_name, "camera", tuple(found),
                                                      ttl=FRAME_TTL_S).to_json()))


def main(argv: list[str] | None = None) -> int:
    return run_node(VisualSynthesizer, __doc__.splitlines()[0], argv)


if __name__ == "__main__":
    raise SystemExit(main())
