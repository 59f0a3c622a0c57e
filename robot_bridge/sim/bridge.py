"""``SimBridge``: the default bridge, driving one robot of an in-process ``World``.

Several bridges may share one world (pass the same ``world=``): each drives its own robot, one runner
thread paces the shared clock (see ``runner.py`` for how simulated time relates to wall time). Without
``world=`` the bridge makes a private world with just its robot. The contract is exactly
``RobotBridge``'s, so a remote bridge (the simulator in another process) can replace it unchanged.

Options (all optional): ``world``, ``speed`` (0 = as fast as possible), ``seed``, ``x``, ``y``,
``yaw_deg`` (start pose, used when the robot is not in the world yet), ``fault`` (e.g.
``"left_actuator:0.5"``), ``camera`` (mount a camera and perceive through it), ``observed`` (the name
to give a robot the camera sees; default: the robot standing where the markers were seen, as if each
robot wore a distinct tag; ``robot`` when none stands there),
``drive`` (False: nobody runs the clock, the caller steps the world itself, for deterministic tests).

With a camera, frames rendered at the camera's rate go through ``perception.detect`` exactly as a real
camera's frames would, and each detection becomes a ``robot_seen`` percept that lasts ``FRAME_TTL_S``: every
robot in view, as the ROS 2 visual synthesizer reports them (a helper looking for one robot of a team finds it
beside a nearer one, which the detector's best pair would be).
"""
from __future__ import annotations

import logging
import math
from concurrent.futures import Future
from typing import ClassVar

from robot_bridge import actions, percepts
from robot_bridge.clock import FollowingClock
from robot_bridge.protocol import Action, Completion, Percept, RobotBridge, completed
from robot_bridge.sim.runner import WorldRunner, shared_runner
from robot_bridge.sim.world import CameraFrame, World

log = logging.getLogger(__name__)

NAME_RADIUS_M = 0.6
"""How far from a robot's centre a detection may be and still be named after that robot."""

TEAM_SPACING_M = 1.5
"""How far apart ``SimBridge.for_team`` places a team's robots (the paper's Faulty and Helper: 1.5 m)."""

FRAME_TTL_S = 1.0
"""Camera percepts vanish this long (simulated seconds) after the frame that produced them."""


class SimBridge(RobotBridge):
    """One simulated Kobuki (with optional camera) in an embedded world."""

    name: ClassVar[str] = "sim"

    def __init__(self, robot: str, world: World | None = None, speed: float = 0.0, seed: int = 0,
                 x: float = 0.0, y: float = 0.0, yaw_deg: float = 0.0, fault: str = "none",
                 camera: bool = False, observed: str = "", drive: bool = True, **options: object) -> None:
        super().__init__(robot, **options)
        if speed < 0:
            raise ValueError(f"speed must be >= 0 (0 = as fast as possible), got {speed!r}")
        self.world = world if world is not None else World(seed=seed)
        self.speed, self.drive = float(speed), drive
        self._placement = dict(x=float(x), y=float(y), yaw_deg=float(yaw_deg), fault=fault, camera=camera)
        self.observed = observed
        self._runner: WorldRunner | None = None
        self._ready = False
        self._seen: tuple[float, list[Percept]] = (-1.0, [])
        self._unsubscribe = None
        self._clock = FollowingClock(lambda: self.world.time, alive=self._stepping)

    @classmethod
    def for_team(cls, robots: list[str], **options: object) -> "dict[str, SimBridge]":
        """The team's robots in one shared world (``world=``, or a new one of ``seed``), side by side
        ``TEAM_SPACING_M`` apart along -y from (``x``, ``y``), all facing ``yaw_deg`` (the paper's pair: the
        second robot 1.5 m to the right of the first); the other options go to every robot."""
        options = dict(options)
        world = options.pop("world", None) or World(seed=int(options.get("seed", 0)))
        x, y = float(options.pop("x", 0.0)), float(options.pop("y", 0.0))
        return {robot: cls(robot, world=world, x=x, y=y - TEAM_SPACING_M * i, **options)
                for i, robot in enumerate(robots)}

    def setup(self, timeout: float = 5.0) -> None:
        """Put the robot into the world (unless already there) and start the shared clock."""
        if self.robot not in self.world.robots:
            self.world.add_robot(self.robot, **self._placement)
        if self._placement["camera"]:
            self._detect = _load_detector()
            self._unsubscribe = self.world.subscribe_camera(self.robot, self._on_frame, reads_pixels=True,
                                                            robots_only=True, part="detector")
        if self.drive:
            self._runner = shared_runner(self.world, self.speed)
            self._runner.acquire()
        self._ready = True

    def act(self, action: Action) -> "Future[Completion]":
        try:
            spec, args = actions.normalize(action)
        except actions.ActionError as exc:
            return completed(Completion.failure(exc.reason, str(exc)))
        if not self._ready:
            return completed(Completion.failure("shutdown", "the bridge is not set up (call setup())"))
        if self._runner is not None and self._runner.error is not None:
            return completed(Completion.failure("shutdown", f"simulator failed: {self._runner.error!r}"))
        log.debug("%s: %s", self.robot, action)
        if spec.motion:
            return self.world.command(self.robot, spec.name, args)
        if spec.name == "set_fault":
            self.world.set_fault(self.robot, f"{args[0]}:{args[1]}")
        elif spec.name == "reset_odometry":
            self.world.reset_odometry(self.robot)
        return completed(Completion.success())

    def percepts(self) -> list[Percept]:
        if not self._ready:
            return []
        found = self.world.percepts(self.robot)
        taken, seen = self._seen
        if seen and self.world.time - taken <= FRAME_TTL_S:
            found += seen
        return found

    def clock(self) -> float:
        """Simulated time (the world's), running on at wall pace if the world stops stepping."""
        return self._clock()

    def _stepping(self) -> bool:
        """Whether this bridge's runner steps the world (however slowly): its clock is then the world's."""
        runner = self._runner
        return runner is not None and runner.running and runner.error is None

    def _on_frame(self, frame: CameraFrame) -> None:
        """A new camera frame: detect robots in its pixels, as a real camera's frame would be. A frame in
        which no robot can be (none in the view within the depth range) is not rendered: the detector
        would find nothing in it (``tests/robot_bridge/test_world_camera.py``), and in a team spread over
        the arena that is most frames."""
        if not getattr(frame, "may_show_robots", True):
            self._seen = (frame.time, [])
            return
        try:
            found = self._detect(frame.rgb, frame.depth, frame.camera)
        except Exception:   # nothing seen in a frame the detector failed on; the world logs and counts it, and
            self._seen = (frame.time, [])   # names a detector that keeps failing: camera_failed(detector)
            raise
        self._seen = (frame.time, [self._seen_percept(frame.pose, d) for d in found])

    def _seen_percept(self, camera_pose: tuple[float, float, float], detection) -> Percept:
        """``robot_seen`` for one detection: named after the robot standing there, angles in the robot's sense."""
        name = self.observed or self._robot_at(camera_pose, detection.angle_deg, detection.depth_m)
        return percepts.robot_seen(name, -detection.angle_deg, detection.depth_m, -detection.yaw_deg)

    def _robot_at(self, camera_pose: tuple[float, float, float], angle_deg: float, depth_m: float) -> str:
        """The robot whose body is where the markers were seen (within ``NAME_RADIUS_M``), else ``robot``.

        Cylinder markers carry no identity; real teams add one (tags, colours, or poses shared in a map
        frame). The simulator plays that part from ground truth, so plans can ask for a robot by name.
        """
        x, y, yaw = camera_pose
        bearing = yaw - math.radians(angle_deg)             # optical angles are positive to the right
        reach = depth_m / max(math.cos(math.radians(angle_deg)), 0.2)
        seen_x, seen_y = x + reach * math.cos(bearing), y + reach * math.sin(bearing)
        best, best_distance = "robot", NAME_RADIUS_M
        for other in self.world.robots:
            if other != self.robot:
                ox, oy, _ = self.world.pose(other)
                distance = math.hypot(ox - seen_x, oy - seen_y)
                if distance < best_distance:
                    best, best_distance = other, distance
        return best

    def shutdown(self) -> None:
        if not self._ready:
            return
        self._ready = False
        self.world.cancel_all("shutdown", name=self.robot)
        if self._unsubscribe is not None:
            self._unsubscribe()
            self._unsubscribe = None
        if self._runner is not None:
            self._runner.release()
            self._runner = None


def _load_detector():
    """Every robot in a frame per ``perception.detect.detect_all``, best first (optical frame: angles positive
    to the right); without that module the camera reports ``camera_ok`` only."""
    try:
        from perception.detect import detect_all
    except ImportError as exc:
        log.warning("perception.detect is not available (%s): the camera reports camera_ok only", exc)
        return lambda rgb, depth, camera: ()
    return lambda rgb, depth, camera: detect_all(rgb, depth, camera).all
