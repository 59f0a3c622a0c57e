"""plans/turtlebot_hardware.yaml: the outcomes of the cooperative fault plans, alone and with a helper."""
from __future__ import annotations

import pytest

from diagnosis.engine import Diagnoser
from diagnosis.loader import load_model

OWN = {  # the robot's own observations while commanded forward: motion, straight, over-current left/right
    "none": (True, True, False, False),
    "encoders": (False, True, False, False),
    "both_actuators": (False, True, False, False),
    "stuck_wheels": (False, True, True, True),
    "left_actuator": (True, False, False, False),
    "right_actuator": (True, False, False, False),
}
HELPER = {  # what the helper's camera saw: motion, straight, veer left, veer right
    "none": (True, True, False, False),
    "encoders": (True, True, False, False),
    "both_actuators": (False, False, False, False),
    "stuck_wheels": (False, False, False, False),
    "left_actuator": (True, False, True, False),
    "right_actuator": (True, False, False, True),
}
WITH_HELPER = {
    "none": [[]],
    "encoders": [["left_encoder", "right_encoder"]],
    "both_actuators": [["left_motor", "right_motor"]],
    "stuck_wheels": [["left_wheel", "right_wheel"]],
    "left_actuator": [["left_motor"]],
    "right_actuator": [["right_motor"]],
}
NO_MOTION_SEEN_BY_ENCODERS = [["left_motor", "right_motor"], ["left_motor", "right_encoder"],
                              ["right_motor", "left_encoder"], ["left_encoder", "right_encoder"]]
ONE_SIDE_SLOW = [["left_motor"], ["right_motor"], ["left_encoder"], ["right_encoder"]]
OWN_ONLY = {
    "none": [[]],
    "encoders": NO_MOTION_SEEN_BY_ENCODERS,
    "both_actuators": NO_MOTION_SEEN_BY_ENCODERS,
    "stuck_wheels": [["left_wheel", "right_wheel"]],   # over-current on both sides settles it alone
    "left_actuator": ONE_SIDE_SLOW,
    "right_actuator": ONE_SIDE_SLOW,
}


@pytest.fixture(scope="module")
def turtlebot(repo):
    return Diagnoser(load_model(repo / "plans" / "turtlebot_hardware.yaml"))


def observations(outcome: str, helper: bool) -> dict[str, bool]:
    motion, straight, left_oc, right_oc = OWN[outcome]
    obs = {"commanded_forward": True, "encoders_report_motion": motion, "encoders_report_straight": straight,
           "left_over_current": left_oc, "right_over_current": right_oc}
    if helper:
        motion, straight, left, right = HELPER[outcome]
        obs.update(helper_found_robot=True, helper_saw_motion=motion, helper_saw_straight=straight,
                   helper_saw_veer_left=left, helper_saw_veer_right=right)
    return obs


@pytest.mark.parametrize("outcome", list(WITH_HELPER))
def test_the_helpers_observations_single_out_the_outcome(turtlebot, outcome):
    assert turtlebot.diagnose(observations(outcome, helper=True)).diagnoses == WITH_HELPER[outcome]


@pytest.mark.parametrize("outcome", list(OWN_ONLY))
def test_without_the_helper_the_robot_cannot_tell(turtlebot, outcome):
    assert turtlebot.diagnose(observations(outcome, helper=False)).diagnoses == OWN_ONLY[outcome]


def test_the_outcomes_are_told_apart_with_the_helper(turtlebot):
    answers = {o: tuple(map(tuple, turtlebot.diagnose(observations(o, True)).diagnoses)) for o in WITH_HELPER}
    assert len(set(answers.values())) == len(WITH_HELPER)


def test_a_helper_that_found_nothing_blames_its_camera_not_the_robot(turtlebot):
    obs = observations("none", helper=False) | {"helper_found_robot": False}
    assert turtlebot.diagnose(obs).diagnoses == [[]]
    obs = observations("encoders", helper=False) | {"helper_found_robot": False}
    assert turtlebot.diagnose(obs).diagnoses == NO_MOTION_SEEN_BY_ENCODERS   # no evidence gained
