"""plans/turtlebot_hardware.yaml: the five outcomes of the cooperative fault plans."""
from __future__ import annotations

import pytest

from diagnosis.engine import Diagnoser
from diagnosis.loader import load_model

OWN = {  # the robot's own observations while commanded forward
    "none": {"encoders_report_motion": True, "encoders_report_straight": True},
    "encoders": {"encoders_report_motion": False, "encoders_report_straight": True},
    "both_actuators": {"encoders_report_motion": False, "encoders_report_straight": True},
    "left_actuator": {"encoders_report_motion": True, "encoders_report_straight": False},
    "right_actuator": {"encoders_report_motion": True, "encoders_report_straight": False},
}
HELPER = {  # what the helper's camera saw: motion, straight, veer left, veer right
    "none": (True, True, False, False),
    "encoders": (True, True, False, False),
    "both_actuators": (False, False, False, False),
    "left_actuator": (True, False, True, False),
    "right_actuator": (True, False, False, True),
}
WITH_HELPER = {
    "none": [[]],
    "encoders": [["left_encoder", "right_encoder"]],
    "both_actuators": [["left_motor", "right_motor"]],
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
    "left_actuator": ONE_SIDE_SLOW,
    "right_actuator": ONE_SIDE_SLOW,
}


@pytest.fixture(scope="module")
def turtlebot(repo):
    return Diagnoser(load_model(repo / "plans" / "turtlebot_hardware.yaml"))


def observations(outcome: str, helper: bool) -> dict[str, bool]:
    obs = {"commanded_forward": True, **OWN[outcome]}
    if helper:
        motion, straight, left, right = HELPER[outcome]
        obs.update(helper_saw_motion=motion, helper_saw_straight=straight,
                   helper_saw_veer_left=left, helper_saw_veer_right=right)
    return obs


@pytest.mark.parametrize("outcome", list(WITH_HELPER))
def test_the_helpers_observations_single_out_the_outcome(turtlebot, outcome):
    assert turtlebot.diagnose(observations(outcome, helper=True)).diagnoses == WITH_HELPER[outcome]


@pytest.mark.parametrize("outcome", list(OWN_ONLY))
def test_without_the_helper_the_robot_cannot_tell(turtlebot, outcome):
    assert turtlebot.diagnose(observations(outcome, helper=False)).diagnoses == OWN_ONLY[outcome]


def test_the_five_outcomes_are_told_apart_with_the_helper(turtlebot):
    answers = {o: tuple(map(tuple, turtlebot.diagnose(observations(o, True)).diagnoses)) for o in WITH_HELPER}
    assert len(set(answers.values())) == 5
