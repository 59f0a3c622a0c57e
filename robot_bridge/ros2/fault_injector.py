"""ROS 2 node ``fault_injector``: between the velocity commands and the base, as in the seed paper.

Subscribes ``commands/velocity_raw`` (what the motion decomposer or a teleop sends), applies the
actuator part of the fault with the simulator's own :mod:`robot_bridge.sim.faults` and republishes on
``commands/velocity`` (the base's input). The fault is the parameter ``fault`` (``none``,
``encoders``, ``left_actuator:0.5``, ...), settable at start (``-p fault:=encoders``) or at run
time through the standard ``set_parameters`` service. Sensor and mechanical faults cannot be done
on commands, so the active fault is also published, latched, on ``faults/active`` for ``kobuki_sim``.

    python -m robot_bridge.ros2.fault_injector --robot faulty --ros-args -p fault:=encoders
"""
from __future__ import annotations

from robot_bridge.ros2.runtime import require_ros, run_node

require_ros(__name__)

from geometry_msgs.msg import Twist  # noqa: E402
from rcl_interfaces.msg import SetParametersResult  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from robot_bridge.ros2.convert import twist  # noqa: E402
from robot_bridge.sim.faults import NO_FAULT, Fault, inject_command  # noqa: E402
from robot_bridge.sim.kobuki import twist_to_wheels, wheels_to_twist  # noqa: E402

LATCHED = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
"""Late joiners (a restarted base) still get the current fault."""


def filter_twist(fault: Fault, msg: Twist) -> Twist | None:
    """The command the base receives when ``msg`` is sent under ``fault`` (``None``: dropped)."""
    wheels = inject_command(fault, twist_to_wheels(msg.linear.x, msg.angular.z))
    if wheels is None:
        return None
    return twist(*wheels_to_twist(wheels))


class FaultInjector(Node):
    """Filters Twists by the current fault; publishes the fault for the base's sensor side."""

    def __init__(self, namespace: str = "", options: object = None, context=None, fault: str = "none") -> None:
        super().__init__("fault_injector", namespace=namespace, context=context)
        self.fault = NO_FAULT
        self.declare_parameter("fault", fault)
        self.add_on_set_parameters_callback(self._on_parameters)
        self._fault_pub = self.create_publisher(String, "faults/active", LATCHED)
        self._out = self.create_publisher(Twist, "commands/velocity", 10)
        self.create_subscription(Twist, "commands/velocity_raw", self._on_command, 10)
        self._set_fault(Fault.parse(self.get_parameter("fault").value or "none"))

    def _on_parameters(self, params) -> SetParametersResult:
        for param in params:
            if param.name == "fault":
                try:
                    fault = Fault.parse(str(param.value or "none"))
                except ValueError as exc:
                    return SetParametersResult(successful=False, reason=str(exc))
                self._set_fault(fault)
        return SetParametersResult(successful=True)

    def _set_fault(self, fault: Fault) -> None:
        self.fault = fault
        text = fault.kind if fault.kind not in ("left_actuator", "right_actuator") \
            else f"{fault.kind}:{fault.fraction}"
        self._fault_pub.publish(String(data=text))
        self.get_logger().info(f"fault: {text}")

    def _on_command(self, msg: Twist) -> None:
        out = filter_twist(self.fault, msg)
        if out is not None:
            self._out.publish(out)


def main(argv: list[str] | None = None) -> int:
    return run_node(FaultInjector, __doc__.splitlines()[0], argv)


if __name__ == "__main__":
    raise SystemExit(main())
