"""The action and percept vocabularies: validation, defaults, literal text."""
import pytest

from robot_bridge import Action, Percept, actions, percepts


def test_optional_arguments_get_their_defaults():
    spec, args = actions.normalize(Action("move", (1,)))
    assert spec.motion and args == (1, 0.2)
    assert actions.normalize(Action("set_fault", ("left_actuator", 0.5)))[1] == ("left_actuator", 0.5)
    assert actions.normalize(Action("stop"))[1] == ()


def test_errors_name_the_action_and_what_was_expected():
    with pytest.raises(actions.ActionError, match="unknown action 'jump'; known actions: move") as exc:
        actions.normalize(Action("jump"))
    assert exc.value.reason == "unknown_action"
    with pytest.raises(actions.ActionError, match=r"turn\(400, 500\): DegreesPerSecond must be within"):
        actions.normalize(Action("turn", (400, 500)))
    with pytest.raises(actions.ActionError, match="move takes 1 to 2 arguments, got 3"):
        actions.normalize(Action("move", (1, 2, 3)))
    assert actions.check(Action("move", (float("nan"),))).reason == "bad_args"


def test_every_failure_reason_is_documented():
    assert {"unknown_action", "bad_args", "timeout", "no_progress"} <= set(actions.REASONS)


def test_percept_constructors_round_and_normalize():
    assert percepts.odom(1.23456, -0.0004, 370.04) == Percept("odom", (1.235, -0.0, 10.0))
    assert percepts.robot_seen("helper", -12.4, 1.3456, -190.0) == \
        Percept("robot_seen", ("helper", -12.0, 1.35, 170.0))
    assert percepts.encoders(70000, -1).args == (70000 - 65536, 65535)
    assert percepts.literal(percepts.odom(1, 2, 3)) == "odom(1.0,2.0,3.0)"
    assert percepts.literal(percepts.motion_state(True)) == "moving"
    with pytest.raises(ValueError, match="bumper side"):
        percepts.bumper("back")


def test_validate_rejects_percepts_outside_the_vocabulary():
    percepts.validate(percepts.camera_ok())
    with pytest.raises(ValueError, match=r"percept odom\(1\) is not in the vocabulary"):
        percepts.validate(Percept("odom", (1,)))
