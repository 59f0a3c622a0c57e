"""ROS 2 node ``motion_decomposer``: agent actions in, velocity commands out, status on completion.

The robot-side half of the jason_ros convention (the seed paper's motion decomposer, fixed so that
no action is left unanswered). In: ``jason/actions`` (JSON, see :mod:`robot_bridge.ros2.wire`) and
``sensors/core`` (encoder ticks). Out: ``commands/velocity_raw`` (Twist, through the fault injector
to the base), ``commands/reset_odometry``, ``jason/actions_status`` when the motion has *finished*
(or failed, with the reason), and the base's percepts on ``jason/percepts``.

Checking (:mod:`robot_bridge.actions`), control and completion (:mod:`robot_bridge.sim.motion`) and
odometry (:mod:`robot_bridge.sim.odometry`) are the embedded simulator's own functions, so an
action ends the same way on both bridges: a control step runs on each encoder sample, in the base's time,
as the simulator steps them (a wall-clock loop on a busy computer overshot turns). ``set_fault`` sets the fault injector's ``fault``
parameter through its ``set_parameters`` service.
"""
from __future__ import annotations

import json
import math
import time

from robot_bridge.ros2.runtime import require_ros, run_node

require_ros(__name__)

from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue  # noqa: E402
from rcl_interfaces.srv import SetParameters  # noqa: E402
from geometry_msgs.msg import Twist  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from std_msgs.msg import Empty, String  # noqa: E402

from robot_bridge import actions, percepts  # noqa: E402
from robot_bridge.protocol import Action, Completion  # noqa: E402
from robot_bridge.ros2.convert import twist  # noqa: E402
from robot_bridge.ros2.wire import ActionRequest, ActionStatus, PerceptSnapshot, WireError  # noqa: E402
from robot_bridge.sim import motion  # noqa: E402
from robot_bridge.sim import odometry as dead_reckoning  # noqa: E402
from robot_bridge.sim.kobuki import wheels_to_twist  # noqa: E402

RELIABLE = QoSProfile(depth=50, reliability=ReliabilityPolicy.RELIABLE)
SENSOR_STALE_S = 0.5
"""Without encoder data for this long, a running motion fails with ``timeout``."""
COMMAND_REPEAT_S = 0.1
"""A command equal to the last one is sent again only after this long (the base stops 0.6 s after the
last): steps follow the base's 50 Hz samples, and a cruise need not cost 50 messages a second, twice over
(decomposer -> fault injector -> base), on a busy computer."""
FIRST_SENSOR_WAIT_S = 5.0
"""How long a motion waits for the base's very first report: a node just started may not yet have
discovered the base's topic (seconds on a busy machine), which is not a dead base."""


def base_percepts(odom: dead_reckoning.Odometry, over_current: int,
                  limits: motion.MotionLimits = motion.DEFAULT_LIMITS) -> list:
    """The base's percepts from the robot's own odometry and the Kobuki over-current bits."""
    result = [percepts.odom(odom.x, odom.y, math.degrees(odom.yaw))]
    if odom.ticks is not None:
        result.append(percepts.encoders(*odom.ticks))
    still = abs(odom.speed[0]) < limits.still_linear and abs(odom.speed[1]) < limits.still_angular
    result.append(percepts.motion_state(not still))
    for bit, wheel in ((1, "left"), (2, "right")):
        if over_current & bit:
            result.append(percepts.over_current(wheel))
    return result


class MotionDecomposer(Node):
    """One action at a time; a new motion preempts the running one (which fails ``preempted``)."""

    def __init__(self, namespace: str = "", options: object = None, context=None, **overrides) -> None:
        super().__init__("motion_decomposer", namespace=namespace, context=context)
        default_agent = namespace.strip("/").split("/")[-1] if namespace else ""
        p = {name: self.declare_parameter(name, overrides.get(name, default)).value for name, default in
             (("agent_name", default_agent), ("control_rate", 20.0), ("percept_rate", 10.0))}
        # control_rate: the watchdog's rate (a silent base, a motion waiting for the base); the control
        # steps themselves run on each encoder sample (``_step``)
        self.agent_name = str(p["agent_name"])
        self.dt = 1.0 / float(p["control_rate"])
        self.odom = dead_reckoning.Odometry()
        self.over_current = 0
        self._last_stamp: int | None = None
        self._last_sensor = -1.0
        self._base_time = 0.0
        """Seconds of the base's own clock (its ``time_stamp``s) since the first sample: a motion's time
        bounds and stall window count in it, as a ROS node with ``use_sim_time`` follows a simulator (a real
        base's clock is real time; a simulated one slowed by a busy computer is not)."""
        self._wall_started = self._wall_deadline = 0.0
        self._sent: object = None          # the last wheel command published, and when (wall clock)
        self._sent_at = 0.0
        self._motion_since = 0.0
        self._before_base: tuple[str, tuple, tuple[float, float]] | None = None
        """A motion asked for before the base's first report: started when that report comes."""
        self._motion: motion.MotionState | None = None
        self._motion_request: ActionRequest | None = None
        self._cmd = self.create_publisher(Twist, "commands/velocity_raw", 10)
        self._reset = self.create_publisher(Empty, "commands/reset_odometry", 10)
        self._status = self.create_publisher(String, "jason/actions_status", RELIABLE)
        self._percepts = self.create_publisher(String, "jason/percepts", 10)
        self._set_fault = self.create_client(SetParameters, "fault_injector/set_parameters")
        self.create_subscription(String, "jason/actions", self._on_action, RELIABLE)
        self.create_subscription(String, "sensors/core", self._on_sensors, 100)
        self._timers = [self.create_timer(self.dt, self._control),
                        self.create_timer(1.0 / float(p["percept_rate"]), self._publish_percepts)]

    # --- actions ---------------------------------------------------------------------------
    def _on_action(self, msg: String) -> None:
        try:
            request = ActionRequest.from_json(msg.data)
        except WireError as exc:
            self.get_logger().error(f"jason/actions: {exc}")
            return
        if request.agent_name not in ("", self.agent_name):
            return
        action = Action(request.action_name, request.values())
        try:
            spec, args = actions.normalize(action)
        except actions.ActionError as exc:
            self._answer(request, Completion.failure(exc.reason, str(exc)))
            return
        if spec.motion:
            self._start_motion(request, spec.name, args)
        elif spec.name == "reset_odometry":
            self.odom = dead_reckoning.reset(self.odom)
            self._reset.publish(Empty())
            self._answer(request, Completion.success())
        elif spec.name == "set_fault":
            self._request_fault(request, args)
        else:
            self._answer(request, Completion.failure("unsupported", f"{action} is not done by this node"))

    def _start_motion(self, request: ActionRequest, kind: str, args: tuple) -> None:
        now = time.monotonic()
        current = (self._motion.linear, self._motion.angular) if self._motion else (0.0, 0.0)
        if self._motion_request is not None:
            self._answer(self._motion_request, Completion.failure("preempted", f"by {request.action_name}"))
        self._motion_since = now
        self._motion_request = request
        if self._last_sensor < 0:
            self._motion, self._before_base = None, (kind, args, current)
        else:
            self._begin(kind, args, current, now)

    def _begin(self, kind: str, args: tuple, current: tuple[float, float], now: float) -> None:
        """Start the motion; its time bound counts on the base's clock, and also on the wall clock (the
        agent's bridge gives up then: a slow simulated base must not go on driving after that)."""
        self._motion, self._before_base = motion.start(kind, args, self.odom, self._base_time, current), None
        self._wall_started, self._wall_deadline = now, now + (self._motion.deadline - self._motion.started)
        self._sent = None                   # its first command goes out whatever the last one was

    def _request_fault(self, request: ActionRequest, args: tuple) -> None:
        kind, fraction = args
        if not self._set_fault.service_is_ready():
            self._answer(request, Completion.failure("unsupported", "no fault_injector in this namespace"))
            return
        text = f"{kind}:{fraction}" if kind in ("left_actuator", "right_actuator") else str(kind)
        call = SetParameters.Request(parameters=[Parameter(name="fault", value=ParameterValue(
            type=ParameterType.PARAMETER_STRING, string_value=text))])

        def done(future) -> None:
            result = future.result()
            ok = result is not None and all(r.successful for r in result.results)
            reason = "" if ok else "; ".join(r.reason for r in (result.results if result else []))
            self._answer(request, Completion.success() if ok else Completion.failure("bad_args", reason))
        self._set_fault.call_async(call).add_done_callback(done)

    def _answer(self, request: ActionRequest, completion: Completion) -> None:
        status = ActionStatus(request.agent_name, request.id, completion.ok, completion.reason, completion.detail)
        self._status.publish(String(data=status.to_json()))

    # --- sensing and control ---------------------------------------------------------------
    def _on_sensors(self, msg: String) -> None:
        try:
            core = json.loads(msg.data)
            ticks = (int(core["left_encoder"]), int(core["right_encoder"]))
            stamp = int(core["time_stamp"])
        except (ValueError, KeyError, TypeError) as exc:
            self.get_logger().error(f"sensors/core: {exc!r} in {msg.data!r}")
            return
        dt = 0.0 if self._last_stamp is None else ((stamp - self._last_stamp) % 65536) / 1000.0
        self._last_stamp = stamp
        self.odom = dead_reckoning.update(self.odom, ticks, dt)
        self.over_current = int(core.get("over_current", 0))
        self._last_sensor = time.monotonic()
        self._base_time += dt
        if self._before_base is not None:       # a motion that waited for the base's first report
            self._begin(*self._before_base, self._last_sensor)
        elif self._motion is not None:
            self._step(dt)

    def _step(self, dt: float) -> None:
        """One control step on the odometry just received; ``dt``: the base's time since the sample before.

        Driven by the samples, not by a wall-clock timer: a timer step on a busy computer acts on odometry
        that is one or more samples old and sends its stop a period late, while the base drives on at the
        approach speed (at 20 Hz the ROS robot turned up to 91.7 deg for 90 under load, the embedded
        simulator 89.7). Here the stop goes out with the first sample past the goal, and the velocity ramp counts the
        base's own time between samples, so it decelerates as planned however late the samples are read."""
        nxt, command, completion = motion.control(self._motion, self.odom, self._base_time, dt)
        if command is not None and (command != self._sent or self._last_sensor - self._sent_at >= COMMAND_REPEAT_S):
            self._cmd.publish(twist(*wheels_to_twist(command)))
            self._sent, self._sent_at = command, self._last_sensor
        self._complete(completion)
        self._motion = nxt

    def _control(self) -> None:
        """The wall-clock watchdog: starts a motion that waited for the base's first report, and fails the
        running one when the base has gone silent or the motion's time bound has passed on the wall clock
        too (the steps themselves follow the samples: ``_step``)."""
        now = time.monotonic()
        if self._before_base is not None and not self._await_base(now):
            return
        if self._motion is None:
            return
        if now - self._last_sensor > SENSOR_STALE_S:
            self._complete(Completion.failure("timeout", "no encoder data from the base"))
            self._motion = None
        elif now > self._wall_deadline and self._motion_request is not None:  # (a rotate, once answered, goes on)
            self._cmd.publish(twist(0.0, 0.0))
            self._sent = None
            self._complete(Completion.failure(
                "timeout", f"not done after {now - self._wall_started:.1f} s (wall clock)"))
            self._motion = None

    def _await_base(self, now: float) -> bool:
        """True once the base has reported and the waiting motion has started (its progress and time
        bounds count from then); a base silent for ``FIRST_SENSOR_WAIT_S`` fails it with ``timeout``."""
        if self._last_sensor >= 0:
            self._begin(*self._before_base, now)
            return True
        if now - self._motion_since > FIRST_SENSOR_WAIT_S:
            self._before_base = None
            self._complete(Completion.failure(
                "timeout", f"no encoder data from the base in {FIRST_SENSOR_WAIT_S:g} s"))
        return False

    def _complete(self, completion: Completion | None) -> None:
        if completion is not None and self._motion_request is not None:
            self._answer(self._motion_request, completion)
            self._motion_request = None       # answered; a rotate goes on turning until preempted

    def _publish_percepts(self) -> None:
        if self._last_sensor < 0:
            return
        snapshot = PerceptSnapshot("", "base", tuple(base_percepts(self.odom, self.over_current)),
                                   ttl=1.0)
        self._percepts.publish(String(data=snapshot.to_json()))

    def stop(self) -> None:
        for timer in self._timers:
            timer.cancel()


def main(argv: list[str] | None = None) -> int:
    return run_node(MotionDecomposer, __doc__.splitlines()[0], argv)


if __name__ == "__main__":
    raise SystemExit(main())
