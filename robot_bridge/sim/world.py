"""A 2D world of Kobuki robots on one simulated clock, stepped at a fixed ``dt``; no I/O, no threads.

The world owns ground truth; each robot owns only what a real one has (encoders, odometry, bumper,
camera). Every public method takes the world's lock, so a runner thread (``runner.py``), bridges in
other threads, or later a network server can share one world. Motion futures are resolved after the
lock is released, so a completion callback may issue the next action at once.

Deterministic: the same seed, robots and actions issued at the same simulated times give the same
trajectories (each robot draws its noise from its own generator, seeded by the world seed and its name).
"""
from __future__ import annotations

import functools
import logging
import math
import threading
import zlib
from concurrent.futures import Future
from collections import deque
from dataclasses import dataclass, field, replace
from typing import Callable, NamedTuple

import numpy as np

from robot_bridge import percepts as vocabulary
from robot_bridge.failure_log import FailureLog
from robot_bridge.percepts import CAMERA_FAILED_AFTER
from robot_bridge.protocol import Completion, Percept
from robot_bridge.sim import allocator, faults, imu, kobuki, motion, odometry
from robot_bridge.sim.camera_frame import CameraFrame
from robot_bridge.sim.faults import NO_FAULT, Fault
from robot_bridge.sim.odometry_fusion import OdometryFusion, Pose2D

log = logging.getLogger(__name__)

DEFAULT_DT = 0.02
"""Simulated seconds per step: the Kobuki reports its sensors at 50 Hz."""


@dataclass(frozen=True)
class Obstacle:
    """A vertical cylinder standing on the floor (a post, a bin): blocks robots, shows on cameras."""

    x: float
    y: float
    radius: float = 0.15
    height: float = 0.6
    rgb: tuple[int, int, int] = (120, 110, 100)


@dataclass(frozen=True)
class CameraMount:
    """A camera on a robot, rendering at ``rate_hz`` simulated frames per second when someone listens."""

    rate_hz: float = 10.0
    rig: object | None = None
    """A ``robot_bridge.sim.camera.CameraRig`` (intrinsics, height, offset); ``None``: the default Kinect."""


LOG_KEEP_S = 600.0
"""Simulated seconds of trajectory a world keeps per robot by default (the oldest points go first): a world
that runs for hours (the soak of issue 22, a served simulator) logged 20 points a second per robot for ever,
~20 MiB per robot and simulated hour. ``World(log_keep=None)`` keeps everything (``faultmas sim --csv``)."""

OVER_CURRENT_HOLD_S = 1.0
"""An over-current flag stays up this long (simulated s) after the motor stopped pushing, like a latched
diagnostic: an agent that perceives only when its motion has failed still sees why."""


class TrajectoryPoint(NamedTuple):
    """Ground truth next to belief, logged at a fixed simulated interval."""

    time: float
    x: float
    y: float
    yaw_deg: float
    odom_x: float
    odom_y: float
    odom_yaw_deg: float


@dataclass(eq=False)
class _CameraListener:
    """One subscriber of a robot's camera, with the record of its failures."""

    call: Callable[[CameraFrame], None]
    part: str
    reads_pixels: bool
    robots_only: bool
    failures: FailureLog


@dataclass
class _Robot:
    name: str
    base: kobuki.BaseState
    rng: np.random.Generator | None
    camera_rng: np.random.Generator
    """Separate from ``rng`` so frames rendered on demand never change the physics' noise."""
    fault: Fault = NO_FAULT
    odom: odometry.Odometry = field(default_factory=odometry.Odometry)
    ticks: tuple[int, int] = (0, 0)
    motion: motion.MotionState | None = None
    pending: Future | None = None
    command: kobuki.WheelSpeeds | None = None
    bumper: str | None = None
    camera: CameraMount | None = None
    camera_listeners: list[_CameraListener] = field(default_factory=list)
    pixel_readers: int = 0
    """How many of ``camera_listeners`` read every frame's pixels (their frames are rendered in parallel)."""
    robot_readers: int = 0
    """How many of those read only frames that may show a robot (``DeferredFrame.may_show_robots``)."""
    last_frame: float = -math.inf
    over_current_at: list[float] = field(default_factory=lambda: [-math.inf, -math.inf])
    """When each motor last drew over-current (simulated seconds)."""
    trajectory: "list[TrajectoryPoint] | deque[TrajectoryPoint]" = field(default_factory=list)
    gyro: imu.Gyro = imu.Gyro()
    gyro_rng: np.random.Generator | None = None
    """Separate from ``rng`` so adding the gyro did not change the physics' noise draws."""
    gyro_fault: faults.GyroFaultState = faults.GyroFaultState()
    yaw_rate: float = 0.0
    """Last yaw rate the gyro reported to the robot's software (rad/s), faults included."""
    fusion: OdometryFusion = field(default_factory=OdometryFusion)
    """The odometry component fusing encoders and gyro; its ``use_imu`` is a settable parameter."""


NODE_PARAMETERS = {"odometry": ("use_imu",)}
"""The parameters of a simulated robot's software nodes that ``World.set_parameter`` can set."""


class World:
    """Several robots in a rectangular arena (walls) with optional obstacles, one clock for all."""

    def __init__(self, seed: int = 0, dt: float = DEFAULT_DT, arena: tuple[float, float, float, float] =
                 (-5.0, -5.0, 5.0, 5.0), obstacles: tuple[Obstacle, ...] = (), noise: bool = True,
                 log_interval: float = 0.05, lighting: float = 1.0, params: kobuki.BaseParams = kobuki.KOBUKI,
                 limits: motion.MotionLimits = motion.DEFAULT_LIMITS, log_keep: float | None = LOG_KEEP_S) -> None:
        if dt <= 0:
            raise ValueError(f"dt must be positive, got {dt!r}")
        xmin, ymin, xmax, ymax = arena
        if xmax - xmin <= 2 * kobuki.ROBOT_RADIUS or ymax - ymin <= 2 * kobuki.ROBOT_RADIUS:
            raise ValueError(f"arena (xmin, ymin, xmax, ymax) too small for a robot: {arena!r}")
        self.seed, self.dt, self.arena, self.obstacles = seed, dt, arena, tuple(obstacles)
        self.noise, self.params, self.limits = noise, params, limits
        self.log_interval, self.lighting = log_interval, lighting
        self.log_keep = log_keep
        self._scene: object | None = None
        self._robots: dict[str, _Robot] = {}
        self._steps = 0
        self._lock = threading.RLock()
        self._render_failures = FailureLog(log, "world: rendering the frames due side by side")
        self.changed = threading.Condition(self._lock)
        """Notified on every new command and every step, for runners and waiters."""

    # ------------------------------------------------------------------ set-up
    def add_robot(self, name: str, x: float = 0.0, y: float = 0.0, yaw_deg: float = 0.0,
                  fault: Fault | str = NO_FAULT, camera: CameraMount | bool | None = None) -> None:
        """Place robot ``name`` at (x, y) facing ``yaw_deg``; ``camera=True`` mounts a default camera."""
        fault = Fault.parse(fault) if isinstance(fault, str) else fault
        with self._lock:
            if name in self._robots:
                raise ValueError(f"robot {name!r} is already in the world")
            key = zlib.crc32(name.encode())
            rng = np.random.default_rng([self.seed, key]) if self.noise else None
            base = kobuki.BaseState(x=x, y=y, yaw=math.radians(yaw_deg), time=self.time)
            ticks = kobuki.encoder_ticks(base)
            mount = CameraMount() if camera is True else (camera or None)
            if mount is not None:     # frames will be rendered here, world after world: bounded heaps
                allocator.limit_arenas()
            gyro_rng = np.random.default_rng([self.seed, key, 2]) if self.noise else None
            robot = _Robot(name, base, rng, np.random.default_rng([self.seed, key, 1]), fault,
                           odometry.Odometry(ticks=ticks), ticks, camera=mount,
                           gyro=imu.Gyro.draw(gyro_rng) if gyro_rng is not None else imu.Gyro(),
                           gyro_rng=gyro_rng)   # odometry frames start at the origin
            if log_keep_points := self._log_keep_points():
                robot.trajectory = deque(maxlen=log_keep_points)
            self._robots[name] = robot
            self._log(robot)

    @property
    def robots(self) -> list[str]:
        with self._lock:
            return list(self._robots)

    @property
    def time(self) -> float:
        """Simulated seconds since the world started (exact multiple of ``dt``)."""
        return self._steps * self.dt

    def _robot(self, name: str) -> _Robot:
        try:
            return self._robots[name]
        except KeyError:
            raise KeyError(f"no robot {name!r} in the world (robots: {', '.join(self._robots) or 'none'})") \
                from None

    # ------------------------------------------------------------------ commands
    def set_fault(self, name: str, fault: Fault | str) -> None:
        """Inject ``fault`` into robot ``name`` from the next step on (``"none"`` repairs it)."""
        fault = Fault.parse(fault) if isinstance(fault, str) else fault
        with self._lock:
            self._robot(name).fault = fault

    def fault(self, name: str) -> Fault:
        with self._lock:
            return self._robot(name).fault

    def reset_odometry(self, name: str) -> None:
        with self._lock:
            robot = self._robot(name)
            robot.odom = odometry.reset(robot.odom)
            robot.fusion.pose = Pose2D()

    def set_parameter(self, name: str, node: str, parameter: str, value: object) -> None:
        """Set ``parameter`` of software node ``node`` on robot ``name`` (as ``ros2 param set`` would).

        Nodes and their parameters: ``NODE_PARAMETERS``; anything else is a ``KeyError`` naming them.
        """
        with self._lock:
            robot = self._robot(name)
            if node not in NODE_PARAMETERS:
                raise KeyError(f"robot {name!r} has no node {node!r} (nodes: {', '.join(NODE_PARAMETERS)})")
            robot.fusion.set_parameter(parameter, value)

    def drive(self, name: str, linear: float, angular: float) -> None:
        """Send a velocity command (m/s, rad/s) straight to the base, like ``commands/velocity``.

        A running motion is preempted; the base keeps the command for ``cmd_timeout`` (0.6 s), so a
        controller sends one at least that often.
        """
        with self._lock:
            robot = self._robot(name)
            previous, robot.motion, robot.pending = robot.pending, None, None
            robot.command = kobuki.twist_to_wheels(linear, angular, self.params)
            self.changed.notify_all()
        if previous is not None and not previous.done():
            previous.set_result(Completion.failure("preempted", "replaced by a velocity command"))

    def command(self, name: str, kind: str, args: tuple = ()) -> "Future[Completion]":
        """Start motion ``kind`` (move, turn, rotate, stop) with normalized args; preempts the running one."""
        future: Future[Completion] = Future()
        with self._lock:
            robot = self._robot(name)
            previous = robot.pending
            current = (robot.motion.linear, robot.motion.angular) if robot.motion else (0.0, 0.0)
            robot.motion = motion.start(kind, args, robot.odom, self.time, current, self.limits)
            robot.pending = future
            self.changed.notify_all()
        if previous is not None and not previous.done():
            previous.set_result(Completion.failure("preempted", f"replaced by {kind}"))
        return future

    def cancel_all(self, reason: str = "shutdown", name: str | None = None) -> None:
        """Fail pending actions (of robot ``name`` or all) with ``reason`` and stop their motions."""
        with self._lock:
            robots = [self._robot(name)] if name else list(self._robots.values())
            pending = [r.pending for r in robots if r.pending is not None]
            for robot in robots:
                if robot.motion is not None:
                    robot.command = kobuki.WheelSpeeds(0.0, 0.0)
                robot.motion, robot.pending = None, None
        for future in pending:
            if not future.done():
                future.set_result(Completion.failure(reason))

    # ------------------------------------------------------------------ stepping
    def busy(self) -> bool:
        """True while some robot has a motion running or a wheel turning (time matters now)."""
        with self._lock:
            return any(r.motion is not None or kobuki.is_moving(r.base) for r in self._robots.values())

    def step(self, steps: int = 1) -> None:
        """Advance the world by ``steps`` x ``dt`` simulated seconds."""
        for _ in range(steps):
            with self._lock:
                frames = self._due_frames()      # what the cameras see at the start of the step
                done = self._step_locked()
                self.changed.notify_all()
            for future, completion in done:
                if not future.done():
                    future.set_result(completion)
            if any(read for _, _, read in frames):
                from robot_bridge.sim import camera
                with self._render_failures.contained(f"at {self.time:.2f} s"):   # the listeners render their own
                    camera.render_all([frame for _, frame, read in frames if read])
            for listeners, frame, _ in frames:
                for listener in listeners:   # one that raises loses this frame, not the world (issue 22)
                    try:
                        listener.call(frame)
                    except Exception as exc:
                        listener.failures.failed(exc, f"frame at {frame.time:.2f} s")
                    else:   # a robot detector skips a frame no robot can be in: no proof that it works again
                        if not listener.robots_only or getattr(frame, "may_show_robots", True):
                            listener.failures.succeeded()

    def run(self, seconds: float) -> None:
        """Advance by ``seconds`` (rounded to whole steps)."""
        self.step(max(0, round(seconds / self.dt)))

    def run_until(self, done: Callable[[], bool], max_seconds: float) -> bool:
        """Step until ``done()`` is true or ``max_seconds`` passed; returns ``done()``."""
        end = self._steps + round(max_seconds / self.dt)
        while not done() and self._steps < end:
            self.step()
        return done()

    def run_until_idle(self, max_seconds: float = 60.0) -> bool:
        """Step until no robot moves or has a motion; returns whether that happened."""
        return self.run_until(lambda: not self.busy(), max_seconds)

    def _step_locked(self) -> list[tuple[Future, Completion]]:
        dt, done = self.dt, []
        now = self.time
        for robot in self._robots.values():
            if robot.motion is not None:
                robot.motion, wheels, completion = motion.control(
                    robot.motion, robot.odom, now, dt, robot.bumper is not None, self.limits, self.params)
                if wheels is not None:
                    robot.command = wheels
                if completion is not None and robot.pending is not None:
                    done.append((robot.pending, completion))
                    robot.pending = None
            sent, robot.command = robot.command, None
            base = faults.apply_to_base(robot.fault, robot.base)
            moved = kobuki.step(base, faults.inject_command(robot.fault, sent), dt, robot.rng, self.params)
            robot.base = self._collide(robot, base, moved)
            robot.ticks = faults.inject_encoders(robot.fault, kobuki.encoder_ticks(robot.base), robot.ticks)
            before = robot.odom
            robot.odom = odometry.update(robot.odom, robot.ticks, dt, self.params)
            self._sense_rotation(robot, base.yaw, before)
            for side, flag in enumerate(kobuki.over_current(robot.base, self.params)):
                if flag:
                    robot.over_current_at[side] = now
        self._steps += 1
        if self.log_interval > 0:
            every = max(1, round(self.log_interval / dt))
            if self._steps % every == 0:
                for robot in self._robots.values():
                    self._log(robot)
        return done

    def _sense_rotation(self, robot: _Robot, yaw_before: float, odom_before: odometry.Odometry) -> None:
        """The gyro samples the step's true rotation; the fusion integrates it with the encoders'."""
        dt = self.dt
        turned = robot.base.yaw - yaw_before
        true_rate = math.atan2(math.sin(turned), math.cos(turned)) / dt
        measured = imu.measure(robot.gyro, true_rate, dt, robot.gyro_rng)
        robot.yaw_rate, robot.gyro_fault = faults.inject_gyro(robot.fault, measured, true_rate, dt,
                                                              robot.gyro_fault)
        robot.fusion.step(robot.odom.distance - odom_before.distance,
                          robot.odom.rotation - odom_before.rotation, robot.yaw_rate * dt)

    def _collide(self, robot: _Robot, before: kobuki.BaseState, after: kobuki.BaseState) -> kobuki.BaseState:
        """Keep the robot out of walls, obstacles and other robots; wheels slip, the bumper reports."""
        robot.bumper = None
        if after.x == before.x and after.y == before.y:
            return after           # turning in place or at rest: nothing new to bump into
        contact = self._contact(robot.name, after.x, after.y)
        if contact is None:
            return after
        # Bumpers are at the front: report the side of the contact direction relative to the heading.
        bearing = math.degrees(math.atan2(contact[1], contact[0]) - after.yaw)
        bearing = vocabulary.normalize_degrees(bearing)
        if abs(bearing) < 90.0:
            robot.bumper = "left" if bearing > 25.0 else "right" if bearing < -25.0 else "centre"
        if self._contact(robot.name, before.x, before.y) is None:
            return replace(after, x=before.x, y=before.y)
        return after  # already overlapping (placed so): let it move out

    def _contact(self, name: str, x: float, y: float) -> tuple[float, float] | None:
        """Direction (dx, dy) towards the first thing a robot at (x, y) would overlap, or None."""
        r = kobuki.ROBOT_RADIUS
        xmin, ymin, xmax, ymax = self.arena
        if x - r < xmin:
            return (-1.0, 0.0)
        if x + r > xmax:
            return (1.0, 0.0)
        if y - r < ymin:
            return (0.0, -1.0)
        if y + r > ymax:
            return (0.0, 1.0)
        for o in self.obstacles:
            if math.hypot(o.x - x, o.y - y) < o.radius + r:
                return (o.x - x, o.y - y)
        reach = 2 * r
        for other in self._robots.values():   # plain loop with cheap rejection: this runs every step
            dx = other.base.x - x
            if -reach < dx < reach and other.name != name:
                dy = other.base.y - y
                if dx * dx + dy * dy < reach * reach:
                    return (dx, dy)
        return None

    def _log_keep_points(self) -> int | None:
        if self.log_keep is None or self.log_interval <= 0:
            return None
        return max(1, math.ceil(self.log_keep / self.log_interval)) + 1

    def _log(self, robot: _Robot) -> None:
        b, o = robot.base, robot.odom
        robot.trajectory.append(TrajectoryPoint(
            round(self.time, 9), b.x, b.y, math.degrees(b.yaw), o.x, o.y, math.degrees(o.yaw)))

    # ------------------------------------------------------------------ observation
    def pose(self, name: str) -> tuple[float, float, float]:
        """Ground-truth pose (x m, y m, yaw deg): for evaluation, never for the robot's own decisions."""
        with self._lock:
            b = self._robot(name).base
            return b.x, b.y, math.degrees(b.yaw)

    def odometry(self, name: str) -> odometry.Odometry:
        with self._lock:
            return self._robot(name).odom

    def yaw_rate(self, name: str) -> float:
        """The gyro's last reading (rad/s) as the robot's software gets it (IMU faults included)."""
        with self._lock:
            return self._robot(name).yaw_rate

    def fused_odometry(self, name: str) -> Pose2D:
        """The pose of robot ``name``'s odometry component (encoders fused with the gyro, see ``use_imu``)."""
        with self._lock:
            return self._robot(name).fusion.pose

    def parameter(self, name: str, node: str, parameter: str) -> object:
        """The current value of a node parameter (see ``set_parameter``)."""
        with self._lock:
            robot = self._robot(name)
            if node not in NODE_PARAMETERS or parameter not in NODE_PARAMETERS[node]:
                raise KeyError(f"robot {name!r} has no parameter {node}.{parameter}")
            return robot.fusion.use_imu

    def base_state(self, name: str) -> kobuki.BaseState:
        with self._lock:
            return self._robot(name).base

    def encoders(self, name: str) -> tuple[int, int]:
        with self._lock:
            return self._robot(name).ticks

    def trajectory(self, name: str) -> list[TrajectoryPoint]:
        """Ground truth and odometry of ``name``, every ``log_interval`` simulated seconds, the last ``log_keep``
        simulated seconds of them (all with ``log_keep=None``)."""
        with self._lock:
            return list(self._robot(name).trajectory)

    def percepts(self, name: str) -> list[Percept]:
        """What robot ``name`` perceives of its own body now (see ``robot_bridge.percepts``)."""
        with self._lock:
            robot = self._robot(name)
            o = robot.odom
            still = (abs(o.speed[0]) < self.limits.still_linear and abs(o.speed[1]) < self.limits.still_angular)
            found = [vocabulary.odom(o.x, o.y, math.degrees(o.yaw)), vocabulary.encoders(*robot.ticks),
                     vocabulary.motion_state(not still)]
            if robot.bumper:
                found.append(vocabulary.bumper(robot.bumper))
            for wheel, since in zip(("left", "right"), robot.over_current_at):
                if self.time - since <= OVER_CURRENT_HOLD_S:
                    found.append(vocabulary.over_current(wheel))
            failed = next((listener.part for listener in robot.camera_listeners if listener.failures.persistent),
                          None)
            if failed is not None:
                found.append(vocabulary.camera_failed(failed))
            elif robot.camera is not None and self.time - robot.last_frame <= 3.0 / robot.camera.rate_hz:
                found.append(vocabulary.camera_ok())
            return found

    # ------------------------------------------------------------------ cameras
    def subscribe_camera(self, name: str, listener: Callable[[CameraFrame], None],
                         reads_pixels: bool = False, robots_only: bool = False,
                         part: str = "listener") -> Callable[[], None]:
        """Call ``listener`` with each frame robot ``name``'s camera takes at its rate; returns unsubscribe.

        Frames render their pixels when first read. A listener that reads every frame (a detector)
        says so with ``reads_pixels``: then the frames due at the same step are rendered side by side
        on the cores before the listeners are called, instead of one after the other in the listeners.
        ``robots_only`` (with ``reads_pixels``): it reads only the frames that may show a robot (a robot
        detector checks ``DeferredFrame.may_show_robots`` first), so the others are not rendered for it.

        A listener that raises loses that frame (logged, rate-limited, see ``FailureLog``); the world and the
        other listeners go on. After ``CAMERA_FAILED_AFTER`` failed frames in a row the robot perceives
        ``camera_failed(Part)``, ``part`` naming the listener (the bridge's ``detector``).
        """
        what = f"robot {name}'s camera {part} ({getattr(listener, '__qualname__', type(listener).__qualname__)})"
        subscriber = _CameraListener(listener, part, bool(reads_pixels), bool(reads_pixels and robots_only),
                                     FailureLog(log, what, persistent_after=CAMERA_FAILED_AFTER))
        with self._lock:
            robot = self._robot(name)
            if robot.camera is None:
                raise ValueError(f"robot {name!r} has no camera (add it with camera=True)")
            robot.camera_listeners.append(subscriber)
            robot.pixel_readers += subscriber.reads_pixels
            robot.robot_readers += subscriber.robots_only

        def unsubscribe() -> None:
            with self._lock:
                if subscriber in robot.camera_listeners:
                    robot.camera_listeners.remove(subscriber)
                    robot.pixel_readers -= subscriber.reads_pixels
                    robot.robot_readers -= subscriber.robots_only
        return unsubscribe

    def camera_frame(self, name: str) -> CameraFrame:
        """Render robot ``name``'s camera view now (on demand, outside the frame rate)."""
        with self._lock:
            robot = self._robot(name)
            if robot.camera is None:
                raise ValueError(f"robot {name!r} has no camera (add it with camera=True)")
            return self._render(robot)

    def _due_frames(self) -> list[tuple[list, CameraFrame, bool]]:
        """Frames due now: at simulated times that are multiples of the period (rounded to whole steps),
        each with its listeners and whether one of them reads the pixels."""
        frames = []
        for robot in self._robots.values():
            if robot.camera_listeners:
                every = max(1, round(1.0 / (robot.camera.rate_hz * self.dt)))
                if self._steps % every == 0:
                    frame = self._render(robot)
                    read = robot.pixel_readers > robot.robot_readers or \
                        (robot.robot_readers > 0 and frame.may_show_robots)
                    frames.append((list(robot.camera_listeners), frame, read))
        return frames

    def _render(self, robot: _Robot) -> CameraFrame:
        from robot_bridge.sim import camera   # the renderer (OpenCV) only for worlds with cameras
        robot.last_frame = self.time
        rig = robot.camera.rig or _default_rig()
        b = robot.base
        pose = rig.pose_of((b.x, b.y, b.yaw))
        others = [(o.base.x, o.base.y, o.base.yaw) for o in self._robots.values() if o is not robot]
        # pixels are rendered when a listener first reads them (a snapshot of the scene until then)
        return camera.deferred_frame(robot.name, self.time, pose, rig, others, self.scene(), robot.camera_rng)

    def scene(self) -> object:
        """What cameras see besides robots: the arena's walls, the obstacles, the lighting."""
        if self._scene is None:
            from robot_bridge.sim import camera
            xmin, ymin, xmax, ymax = self.arena
            corners = [(xmin, ymin), (xmax, ymin), (xmax, ymax), (xmin, ymax)]
            walls = tuple(camera.Wall(*a, *b) for a, b in zip(corners, corners[1:] + corners[:1]))
            props = tuple(camera.CylinderProp(o.x, o.y, o.radius, 0.0, o.height, o.rgb) for o in self.obstacles)
            self._scene = camera.Scene(walls=walls, props=props, gain=self.lighting)
        return self._scene


@functools.lru_cache(maxsize=1)
def _default_rig() -> object:
    """One rig object for every camera without its own (a frozen value; frames refer to it)."""
    from robot_bridge.sim import camera
    return camera.CameraRig()
