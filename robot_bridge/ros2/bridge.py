"""``Ros2Bridge``: the agent side of the jason_ros convention over real rclpy.

Per robot, in namespace ``/<robot>`` (relative names): publishes ``jason/actions``, listens to
``jason/actions_status`` and ``jason/percepts`` (JSON in ``std_msgs/String``, see
:mod:`robot_bridge.ros2.wire`). Each action carries an explicit id; its future resolves when the
status with that id arrives (completion-based: the motion has finished), or fails with ``timeout``
when the robot does not answer in time. Malformed or unknown actions fail at once, checked by the
same :mod:`robot_bridge.actions` as every bridge.

jason_ros manifests (``actions_manifest=``, ``perceptions_manifest=``) map further actions and
percepts to plain ROS topics or services; such an action completes when its message is published
(or its service answers), since a plain topic has no completion to wait for.

    bridge = Ros2Bridge("faulty", domain_id=17)
    bridge.setup(timeout=10)              # TimeoutError names the topic nothing answers on
    bridge.act(Action("move", (0.5,))).result()   # Completion(ok=True)
"""
from __future__ import annotations

from concurrent.futures import Future
from typing import Any, ClassVar

from robot_bridge import actions
from robot_bridge.messaging import ANSWER_MARGIN_S, PendingActions, PerceptStore, answer_timeout
from robot_bridge.protocol import Action, Completion, Percept, RobotBridge, completed
from robot_bridge.ros2 import wire
from robot_bridge.ros2.manifest import ActionMapping, PerceptionMapping, load_actions, load_perceptions


def agent_node_name(agent: str) -> str:
    """The ROS 2 node through which ``agent`` drives its robot (``faultmas_agent_<agent>``, in the
    robot's namespace); observers find an agent's ROS side by it."""
    return f"faultmas_agent_{agent}".replace("-", "_")

class Ros2Bridge(RobotBridge):
    """Drives one robot through its ROS 2 nodes (``motion_decomposer`` and the percept synthesizers).

    Options: ``namespace`` (default ``/<robot>``), ``agent_name`` (default the robot name),
    ``domain_id`` (default ``ROS_DOMAIN_ID``), ``action_timeout`` (seconds; default from the
    action's time bound), ``actions_manifest`` and ``perceptions_manifest`` (jason_ros INI files),
    ``wait_for_robot`` (default true: ``setup`` waits until a decomposer listens).
    """

    name: ClassVar[str] = "ros2"
    known_options: ClassVar[dict[str, str]] = {
        "namespace": "the robot's ROS namespace (default /<robot>)",
        "agent_name": "the agent name in the wire messages (default the robot name)",
        "domain_id": "the ROS domain id (default ROS_DOMAIN_ID)",
        "action_timeout": "seconds an action may take (default: from the action's own time bound)",
        "actions_manifest": "a jason_ros actions manifest (INI file)",
        "perceptions_manifest": "a jason_ros perceptions manifest (INI file)",
        "wait_for_robot": "setup waits until a decomposer listens (default true)",
    }

    def __init__(self, robot: str, **options: Any) -> None:
        super().__init__(robot, **options)
        self.namespace = str(options.get("namespace") or f"/{robot}")
        self.agent_name = str(options.get("agent_name") or robot)
        self.domain_id = options.get("domain_id")
        self.action_timeout = options.get("action_timeout")
        manifest = options.get("actions_manifest")
        self.action_map: dict[str, ActionMapping] = load_actions(manifest) if manifest else {}
        manifest = options.get("perceptions_manifest")
        self.perception_map: dict[str, PerceptionMapping] = load_perceptions(manifest) if manifest else {}
        self._pending = PendingActions()
        self._store = PerceptStore(self.agent_name)
        self._ros = None
        self._node = None
        self._publishers: dict[str, Any] = {}
        self._clients: dict[str, Any] = {}
        self._perfbugs = None

    # --- life cycle --------------------------------------------------------------------------
    def setup(self, timeout: float = 5.0) -> None:
        from robot_bridge.ros2.runtime import require_ros
        require_ros()                         # RosUnavailable (an ImportError) with the install hint
        from std_msgs.msg import String

        from robot_bridge.ros2.motion_decomposer import RELIABLE
        from robot_bridge.ros2.runtime import RosContext, wait_for

        domain = None if self.domain_id is None else int(self.domain_id)
        self._ros = RosContext(domain_id=domain)
        node_name = agent_node_name(self.agent_name)
        import rclpy
        self._node = node = rclpy.create_node(node_name, namespace=self.namespace, context=self._ros.context)
        self._actions = node.create_publisher(String, "jason/actions", RELIABLE)
        node.create_subscription(String, "jason/actions_status", self._on_status, RELIABLE)
        node.create_subscription(String, "jason/percepts", self._on_percepts, 50)
        for mapping in self.action_map.values():
            cls = mapping.message_class()
            if mapping.method == "service":
                self._clients[mapping.action] = node.create_client(cls, mapping.name)
            else:
                self._publishers[mapping.action] = node.create_publisher(cls, mapping.name, self._qos(mapping))
        for mapping in self.perception_map.values():
            node.create_subscription(mapping.message_class(), mapping.name,
                                     lambda msg, m=mapping: self._on_mapped(m, msg), 10)
        node.create_timer(0.05, self._expire)
        from robot_bridge.ros2.perfbugs import agent_component, install_from_env
        # the perf-bug experiments (FAULTMAS_PERFBUGS) reach an agent's process through its bridge node:
        # its callbacks and publishers are the agent's ROS side, the resource bugs act on the whole process
        self._perfbugs = install_from_env(node, self.robot, component=agent_component(self.agent_name))
        self._ros.add(node)
        self._ros.start()
        if self.options.get("wait_for_robot", True):
            topic = f"{self.namespace.rstrip('/')}/jason/actions"
            if not wait_for(lambda: self._actions.get_subscription_count() > 0, timeout):
                self.shutdown()
                raise TimeoutError(f"no robot listens on {topic} after {timeout:g} s "
                                   f"(is motion_decomposer running in domain {domain}?)")

    @staticmethod
    def _qos(mapping: ActionMapping):
        from rclpy.qos import DurabilityPolicy, QoSProfile
        if mapping.latch:
            return QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        return QoSProfile(depth=10)

    def shutdown(self) -> None:
        self._pending.fail_all("shutdown")
        if self._perfbugs is not None:
            self._perfbugs.stop()
            self._perfbugs = None
        if self._ros is not None:
            self._ros.close()
            self._ros = None

    # --- actions -----------------------------------------------------------------------------
    def act(self, action: Action) -> "Future[Completion]":
        if self._ros is None or not self._ros.ok():
            return completed(Completion.failure("shutdown", "the bridge is not set up"))
        if action.name in self.action_map:
            return self._act_mapped(self.action_map[action.name], action)
        failure = actions.check(action)
        if failure is not None:
            return completed(failure)
        if self._actions.get_subscription_count() == 0:
            return completed(Completion.failure(
                "timeout", f"nothing listens on {self.namespace.rstrip('/')}/jason/actions"))
        limit = float(self.action_timeout) if self.action_timeout else answer_timeout(action)
        future = self._pending.add(action, limit)
        request = wire.ActionRequest(self.agent_name, action.name,
                                     tuple(wire.format_value(a) for a in action.args), action.id)
        from std_msgs.msg import String
        self._actions.publish(String(data=request.to_json()))
        return future

    def _act_mapped(self, mapping: ActionMapping, action: Action) -> "Future[Completion]":
        try:
            msg = mapping.build(action.args)
        except ValueError as exc:
            return completed(Completion.failure("bad_args", str(exc)))
        if mapping.method == "topic":
            self._publishers[mapping.action].publish(msg)
            return completed(Completion.success())
        client = self._clients[mapping.action]
        if not client.service_is_ready():
            return completed(Completion.failure("timeout", f"service {mapping.name} is not available"))
        limit = float(self.action_timeout) if self.action_timeout else ANSWER_MARGIN_S
        future = self._pending.add(action, limit)

        def done(call) -> None:
            error = call.exception()
            self._pending.finish(action.id, Completion.success() if error is None
                                 else Completion.failure("unsupported", f"{mapping.name}: {error}"))
        client.call_async(msg).add_done_callback(done)
        return future

    def _on_status(self, msg) -> None:
        try:
            status = wire.ActionStatus.from_json(msg.data)
        except wire.WireError as exc:
            self._node.get_logger().error(f"jason/actions_status: {exc}")
            return
        if status.agent_name not in ("", self.agent_name):
            return
        self._pending.finish(status.id, Completion.success() if status.result
                             else Completion.failure(status.reason or "failed", status.detail))

    def _expire(self) -> None:
        self._pending.expire(self.namespace)

    # --- percepts ----------------------------------------------------------------------------
    def _on_percepts(self, msg) -> None:
        try:
            self._store.receive(msg.data)
        except wire.WireError as exc:
            self._node.get_logger().error(f"jason/percepts: {exc}")

    def _on_mapped(self, mapping: PerceptionMapping, msg) -> None:
        self._store.store(Percept(mapping.perception, mapping.values(msg)), mapping.update)

    def percepts(self) -> list[Percept]:
        return self._store.percepts()
