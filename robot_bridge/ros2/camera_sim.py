"""ROS 2 node ``camera_sim``: a simulated Kinect on a robot, rendered by the simulator's renderer.

Knows where every robot is from their ``ground_truth`` topics (parameter ``robots``: all robot
names, this one included) and renders, at ``rate`` Hz, what this robot's camera sees with
:func:`robot_bridge.sim.camera.render`. Publishes as the ROS 2 OpenNI driver does:
``camera/rgb/image_raw`` (rgb8), ``camera/depth_registered/image_raw`` (16UC1, millimetres,
0 = no reading), and ``camera/rgb/camera_info`` / ``camera/depth_registered/camera_info``.

    python -m robot_bridge.ros2.camera_sim --robot helper --ros-args -p robots:="[faulty, helper]"
"""
from __future__ import annotations

from robot_bridge.ros2.runtime import require_ros, run_node

require_ros(__name__)

import numpy as np  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.node import Node  # noqa: E402
from sensor_msgs.msg import CameraInfo, Image  # noqa: E402

from perception.camera import CameraModel  # noqa: E402
from robot_bridge.ros2.convert import array_to_image, camera_info, pose_of  # noqa: E402
from robot_bridge.sim import camera as renderer  # noqa: E402
from robot_bridge.sim.world import CameraMount  # noqa: E402

FRAME = "camera_rgb_optical_frame"


def depth_to_millimetres(depth_m: np.ndarray) -> np.ndarray:
    """float32 metres (0 or non-finite = no reading) → uint16 millimetres (0 = no reading)."""
    mm = np.nan_to_num(depth_m, nan=0.0, posinf=0.0, neginf=0.0) * 1000.0
    return np.clip(np.rint(mm), 0, 65535).astype(np.uint16)


class CameraSim(Node):
    """Renders one robot's camera from the ground-truth poses of all robots."""

    def __init__(self, namespace: str = "", options: object = None, context=None, **overrides) -> None:
        super().__init__("camera_sim", namespace=namespace, context=context)
        mount, rig = CameraMount(), renderer.CameraRig()     # the embedded simulator's defaults
        p = {name: self.declare_parameter(name, overrides.get(name, default)).value for name, default in
             (("robots", [namespace.strip("/") or "robot"]), ("rate", mount.rate_hz), ("seed", 0),
              ("width", 640), ("height", 480), ("hfov_deg", 57.0), ("vfov_deg", 43.0),
              ("camera_height", rig.height_m), ("camera_forward", rig.mount_x_m))}
        self.me = namespace.strip("/").split("/")[-1]
        model = CameraModel.from_fov(float(p["hfov_deg"]), float(p["vfov_deg"]), int(p["width"]), int(p["height"]))
        self.rig = renderer.CameraRig(camera=model, height_m=float(p["camera_height"]),
                                      mount_x_m=float(p["camera_forward"]))
        self.scene = renderer.Scene()
        self.rng = np.random.default_rng(int(p["seed"]))
        self.poses: dict[str, tuple[float, float, float]] = {}
        for robot in p["robots"]:
            topic = "ground_truth" if robot == self.me else f"/{robot}/ground_truth"
            self.create_subscription(Odometry, topic, lambda msg, r=robot: self._on_pose(r, msg), 10)
        self._rgb = self.create_publisher(Image, "camera/rgb/image_raw", 2)
        self._depth = self.create_publisher(Image, "camera/depth_registered/image_raw", 2)
        self._info = self.create_publisher(CameraInfo, "camera/rgb/camera_info", 2)
        self._depth_info = self.create_publisher(CameraInfo, "camera/depth_registered/camera_info", 2)
        self.frames = 0
        self._timer = self.create_timer(1.0 / float(p["rate"]), self._render)

    def _on_pose(self, robot: str, msg: Odometry) -> None:
        self.poses[robot] = pose_of(msg)

    def _render(self) -> None:
        if self.me not in self.poses:
            return                                   # the base has not said where it is yet
        others = [pose for name, pose in self.poses.items() if name != self.me]
        rgb, depth = renderer.render(self.rig, self.rig.pose_of(self.poses[self.me]), others, self.scene, self.rng)
        stamp = self.get_clock().now().to_msg()
        cam = self.rig.camera
        info = camera_info(cam.width, cam.height, cam.fx, cam.fy, cam.cx, cam.cy, FRAME, stamp)
        self._info.publish(info)
        self._depth_info.publish(info)
        self._depth.publish(array_to_image(depth_to_millimetres(depth), "16UC1", FRAME, stamp))
        self._rgb.publish(array_to_image(rgb, "rgb8", FRAME, stamp))
        self.frames += 1

    def stop(self) -> None:
        self._timer.cancel()


def main(argv: list[str] | None = None) -> int:
    return run_node(CameraSim, __doc__.splitlines()[0], argv)


if __name__ == "__main__":
    raise SystemExit(main())
