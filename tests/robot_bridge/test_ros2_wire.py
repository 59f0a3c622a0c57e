"""The ros2 bridge's wire format and jason_ros manifests: pure Python, no ROS graph needed."""
from __future__ import annotations

import pytest

from agentspeak.errors import SourceError
from robot_bridge.protocol import Action, Percept
from robot_bridge.ros2 import wire
from robot_bridge.ros2.manifest import load_actions, load_perceptions

TURTLESIM_ACTIONS = """\
[cmd_vel]
method = topic
name = /turtle1/cmd_vel
msg_type = Twist
dependencies = geometry_msgs.msg
params_name = linear.x, linear.y, linear.z, angular.x, angular.y, angular.z
params_type = float, float, float, float, float, float

[set_pen]
method = service
name = /turtle1/set_pen
msg_type = SetPen
dependencies = turtlesim.srv
params_name = r, g, b
params_type = int, int, int
"""

ROSARIA_PERCEPTIONS = """\
[DEFAULT]
rate = 2

[pose]
name = /RosAria/pose
msg_type = Odometry
dependencies = nav_msgs.msg
args = pose.pose.position.x, pose.pose.position.y, pose.pose.position.z, pose.pose.orientation.x,pose.pose.orientation.y, pose.pose.orientation.z, pose.pose.orientation.w
buf = update

[motors_state]
name = /RosAria/motors_state
msg_type = std_msgs/Bool
args = data
buf = add
"""


def test_action_request_round_trip_keeps_id_and_parameters():
    request = wire.ActionRequest("faulty", "turn", ("45",), 17)
    assert wire.ActionRequest.from_json(request.to_json()) == request
    assert request.to_json() == '{"agent_name":"faulty","action_name":"turn","parameters":["45"],"id":17}'
    assert request.values() == (45,)


def test_status_carries_the_failure_reason():
    text = '{"agent_name":"faulty","id":17,"result":false,"reason":"timeout"}'
    status = wire.ActionStatus.from_json(text)
    assert (status.id, status.result, status.reason) == (17, False, "timeout")
    assert wire.ActionStatus.from_json(status.to_json()) == status


@pytest.mark.parametrize("text, problem", [
    ("{", "not JSON"), ("[1]", "JSON object"), ('{"action_name":"move"}', "'id'"),
    ('{"action_name":"move","id":true}', "wrong type"), ('{"action_name":"move","id":1,"parameters":"0.5"}', "list"),
])
def test_malformed_action_messages_are_rejected_with_the_message_quoted(text, problem):
    with pytest.raises(wire.WireError, match=problem) as info:
        wire.ActionRequest.from_json(text)
    assert repr(text) in str(info.value)


@pytest.mark.parametrize("text, value", [
    ("0.5", 0.5), ("-12", -12), ("1e3", 1000.0), ("helper", "helper"), ("[a,1,[2.5]]", ("a", 1, (2.5,))),
    ('"two words"', "two words"), ("[]", ()),
])
def test_parameters_parse_as_terms_falling_back_to_text(text, value):
    assert wire.parse_value(text) == value


@pytest.mark.parametrize("value", [0.5, -3, "left_actuator", ("a", 1, (2.5, "b")), 90.0])
def test_values_survive_the_trip_through_term_text(value):
    assert wire.parse_value(wire.format_value(value)) == value


def test_percepts_arrive_as_jason_ros_fields_or_whole_literals():
    fields = '{"agent_name":"","perception_name":"robot_seen","parameters":["helper","-12.0","1.35","90.0"],"update":true}'
    literal = '{"agent_name":"","literal":"robot_seen(helper,-12.0,1.35,90.0)"}'
    expected = Percept("robot_seen", ("helper", -12.0, 1.35, 90.0))
    assert wire.decode_percepts(fields).percept() == expected
    assert wire.decode_percepts(literal).percept() == expected


def test_a_snapshot_replaces_a_source_and_keeps_its_ttl():
    snap = wire.PerceptSnapshot("", "base", (Percept("odom", (0.5, 0.0, 90.0)), Percept("stopped")), ttl=1.0)
    back = wire.decode_percepts(snap.to_json())
    assert back == snap


def test_a_literal_with_unbalanced_brackets_is_an_error():
    with pytest.raises(wire.WireError, match="unbalanced"):
        wire.parse_literal("robot(a,[1,2)")


def test_jason_ros_actions_manifest_loads_unchanged(tmp_path):
    pytest.importorskip("geometry_msgs.msg", reason="ROS 2 message packages (extra ros2)")
    path = tmp_path / "actions_manifest"
    path.write_text(TURTLESIM_ACTIONS)
    mappings = load_actions(path)
    assert sorted(mappings) == ["cmd_vel", "set_pen"]
    msg = mappings["cmd_vel"].build((0.3, 0, 0, 0, 0, 1.5))
    assert (msg.linear.x, msg.angular.z) == (0.3, 1.5)
    with pytest.raises(ValueError, match="takes 6 arguments"):
        mappings["cmd_vel"].build((0.3,))
    with pytest.raises(SourceError) as info:        # turtlesim is not installed: named with its line
        mappings["set_pen"].build((1, 2, 3))
    assert f"{path}:13:" in str(info.value) and "turtlesim.srv" in str(info.value)


def test_jason_ros_perceptions_manifest_reads_fields_from_messages(tmp_path):
    msgs = pytest.importorskip("nav_msgs.msg", reason="ROS 2 message packages (extra ros2)")
    path = tmp_path / "perceptions_manifest"
    path.write_text(ROSARIA_PERCEPTIONS)
    mappings = load_perceptions(path)
    odom = msgs.Odometry()
    odom.pose.pose.position.x = 1.25
    pose = mappings["pose"]
    assert (pose.rate, pose.update) == (2.0, True)
    assert pose.values(odom) == (1.25, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
    assert mappings["motors_state"].update is False


def test_a_manifest_entry_without_a_topic_names_file_and_section(tmp_path):
    path = tmp_path / "actions_manifest"
    path.write_text("[cmd_vel]\nmethod = topic\nmsg_type = Twist\n")
    with pytest.raises(SourceError, match=r"actions_manifest:1:.*\[cmd_vel\].*missing 'name"):
        load_actions(path)


def test_a_manifest_with_an_unknown_method_points_at_the_line(tmp_path):
    path = tmp_path / "actions_manifest"
    path.write_text("[beep]\nname = /beep\nmsg_type = std_msgs/Empty\nmethod = carrier_pigeon\n")
    with pytest.raises(SourceError, match=r"actions_manifest:4:.*topic or service"):
        load_actions(path)


def test_the_bridge_waits_longer_than_the_motion_may_take():
    from robot_bridge.messaging import answer_timeout
    assert answer_timeout(Action("move", (2.0, 0.2))) > 2.0 / 0.2
    assert answer_timeout(Action("move", (0.5,))) < answer_timeout(Action("move", (5.0,)))


def test_the_bridge_builds_offline():
    from robot_bridge.ros2.bridge import Ros2Bridge
    bridge = Ros2Bridge("faulty")                 # no I/O before setup()
    assert bridge.namespace == "/faulty"
    assert bridge.act(Action("move", (0.5,))).result(0).reason == "shutdown"


def test_a_node_without_ros_installed_prints_a_one_line_hint(tmp_path):
    import subprocess
    import sys
    script = ("import sys, runpy; sys.modules['rclpy'] = None; "
              "runpy.run_module('robot_bridge.ros2.kobuki_sim', run_name='__main__')")
    run = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "pip install 'faultmas[ros2]'" in lines[0], run.stderr


def test_the_bridge_without_ros_raises_an_import_error_with_the_hint(monkeypatch):
    import sys
    from robot_bridge.ros2.bridge import Ros2Bridge
    from robot_bridge.ros2.runtime import RosUnavailable
    monkeypatch.setitem(sys.modules, "rclpy", None)
    with pytest.raises(RosUnavailable, match=r"faultmas\[ros2\]"):
        Ros2Bridge("faulty").setup(timeout=0.1)
