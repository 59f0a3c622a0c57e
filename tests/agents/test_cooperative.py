"""The cooperative fault diagnosis end to end: plans, agents in processes over Zenoh, the simulator.

Each run starts real agent processes (``faultmas agent run --bridge zenoh``) talking over a real Zenoh
session on loopback to the simulator served by this process; nothing is mocked. Outcomes come from the
plans and the diagnoser: a wrong model, plan or perception makes these tests fail.
"""
from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from agents.cooperative import (EXPECTED, RobotSetup, Scenario, paper_scenario, random_pair_scenario,
                                run_scenario, team_scenario)

pytestmark = pytest.mark.timeout(240)
REPO = Path(__file__).resolve().parents[2]


def marks_of(result, step):
    return [m for m in result.marks if m.step == step]


@pytest.mark.parametrize("fault", ["none", "both_actuators", "left_actuator", "right_actuator", "stuck_wheels"])
def test_each_fault_is_diagnosed_by_two_agent_processes_over_zenoh(fault):
    result = run_scenario(paper_scenario(fault, seed=3), processes=True, timeout=90)
    faulty = result.robots[0]
    assert result.finished, [(m.agent, m.step, m.detail) for m in result.marks]
    assert faulty.diagnosis == EXPECTED[fault]
    assert all(faulty.steps_sim[s] is not None and faulty.steps_sim[s] > 0
               for s in ("fault_detection", "diagnosis", "total"))
    if fault != "stuck_wheels":      # over-current on both wheels settles stuck wheels without help
        assert marks_of(result, "robot_found"), "the helper's camera found the faulty robot"


def test_faultmas_run_json_contract_with_the_default_encoder_fault(tmp_path):
    image = tmp_path / "run.png"
    done = subprocess.run([sys.executable, "-m", "agents", "run", "--json", "--seed", "2", "--plot", str(image)],
                          cwd=REPO, capture_output=True, text=True, timeout=200)
    assert done.returncode == 0, done.stderr[-2000:]
    import cv2
    picture = cv2.imread(str(image))
    assert picture is not None and picture.shape[0] > 200 and picture.std() > 0    # a real drawing
    report = json.loads(done.stdout)
    faulty = report["robots"][0]        # the schema of the team's report too (one entry per robot)
    assert faulty["fault"] == "encoders" and faulty["diagnosis"] == "encoders" and report["correct"] is True
    assert set(faulty["steps"]) == {"fault_detection", "robot_detection", "diagnosis", "total"}
    assert faulty["steps"]["total"] >= faulty["steps"]["fault_detection"] + faulty["steps"]["robot_detection"] - 0.02
    assert all(round(v, 2) == v for v in faulty["steps"].values())
    assert "robot detected" in done.stderr       # progress is shown as the steps happen


def test_a_weak_wheel_that_turns_the_robot_end_on_is_still_diagnosed():
    # an evaluation placement that used to end undiagnosed: the first leg (a weak left wheel curls it)
    # left the robot only 40 degrees off end-on to the helper, so its test motion turned it end-on,
    # where its two cylinders hide each other; now it turns to show its side first
    # (the placement of seed 100034 when the eval drew side views only, written out)
    placement = Scenario((RobotSetup("faulty", 0.0, 0.0, -171.094, "left_actuator", "faulty.asl"),
                          RobotSetup("helper", 1.9306, -2.1092, 148.902)), seed=100034, lighting=0.8748)
    result = run_scenario(placement, processes=False, timeout=90)
    assert result.finished, [(m.agent, m.step, m.detail) for m in result.marks]
    assert result.robots[0].diagnosis == "left_actuator"
    assert marks_of(result, "robot_found")


def test_an_immobile_robot_seen_end_on_is_found_by_a_side_step():
    # the one miss of the any-heading evaluation (seed 100020 of random_pair_scenario): a robot that
    # cannot turn to show its side, 3 degrees off end-on to the helper. A glimpse left the helper facing
    # it, and its old step back along its own axis kept the end-on view; a side step changes the view
    placement = Scenario((RobotSetup("faulty", 0.0, 0.0, -98.513, "both_actuators", "faulty.asl"),
                          RobotSetup("helper", 0.2097, 1.0463, -44.981)), seed=100020, lighting=0.7840)
    result = run_scenario(placement, processes=False, timeout=120)
    assert result.finished, [(m.agent, m.step, m.detail) for m in result.marks]
    assert result.robots[0].diagnosis == "both_actuators"
    assert marks_of(result, "robot_found")


def test_a_test_motion_stopped_by_a_wall_is_not_taken_for_dead_motors():
    # issue 22's soak: a robot of a long-lived team stood where its last task left it, by a wall; its first
    # leg bumped into the wall, and the side it turned to show the helper faced the wall too, so its test
    # motion stopped at once (bumper): no ticks, no motion seen, and the diagnoser concluded both motors
    # dead. A blocked test motion is not diagnosed now: the robot turns round and tries again
    # (touching the wall at x = 5, side-on to the helper 1.6 m away to the south-west: facing into the wall)
    placement = Scenario((RobotSetup("faulty", 4.8, 0.0, -45.0, "left_actuator", "faulty.asl"),
                          RobotSetup("helper", 3.67, -1.13, 45.0)), seed=5)
    result = run_scenario(placement, processes=False, timeout=120)
    assert result.finished, [(m.agent, m.step, m.detail) for m in result.marks]
    assert result.robots[0].diagnosis == "left_actuator"


def test_a_helper_killed_mid_way_is_replaced_by_another():
    base = paper_scenario("left_actuator", seed=4)
    scenario = Scenario(base.robots + (RobotSetup("helper2", 0.0, 1.5, 0.0),), seed=4)
    killed: list[str] = []

    def kill_first_helper(mark, kill):
        if mark.agent == "faulty" and mark.step == "helper_found" and not killed:
            killed.append(mark.detail)
            kill(mark.detail)
    result = run_scenario(scenario, processes=True, timeout=120, on_mark=kill_first_helper)
    assert killed
    chosen = [m.detail for m in marks_of(result, "helper_found")]
    assert len(chosen) >= 2 and chosen[-1] != killed[0], chosen
    assert result.robots[0].diagnosis == "left_actuator"


def test_a_helper_turned_away_from_the_robot_finds_it_again_and_the_diagnosis_holds(monkeypatch):
    # right after the helper found the faulty robot, something turns the helper 120 degrees away
    # (its odometry sees the turn, its plans do not know): the test motion must be watched anyway
    import agents.cooperative as cooperative

    worlds = []
    real_build_world = cooperative.build_world

    def build_and_keep(scenario, *args, **kwargs):
        world, bridges = real_build_world(scenario, *args, **kwargs)
        worlds.append(world)
        return world, bridges

    def turn_helper_away(mark):
        if mark.agent == "faulty" and mark.step == "found_by":
            worlds[0].command("helper", "turn", (120.0, 60.0))     # degrees, deg/s

    monkeypatch.setattr(cooperative, "build_world", build_and_keep)
    result = run_scenario(paper_scenario("encoders", seed=8), processes=False, timeout=120, echo=turn_helper_away)
    assert result.finished, [(m.agent, m.step, m.detail) for m in result.marks]
    assert marks_of(result, "lost_sight"), "the helper noticed it had lost sight of the robot"
    assert len(marks_of(result, "robot_found")) == 1 and result.robots[0].diagnosis == "encoders"


def test_the_helper_returns_to_its_task_when_the_faulty_robot_dies():
    def kill_faulty_while_searched(mark, kill):
        if mark.agent == "helper" and mark.step == "searching":
            kill("faulty")
        return mark.agent == "helper" and mark.step == "released"
    result = run_scenario(paper_scenario("encoders", seed=5), processes=True, timeout=60,
                          on_mark=kill_faulty_while_searched)
    assert [m.detail for m in marks_of(result, "released")] == ["faulty"]
    assert not marks_of(result, "diagnosed")


def test_without_any_helper_the_robot_reports_undiagnosed_with_its_candidates():
    scenario = Scenario((RobotSetup("faulty", 0.0, 0.0, 0.0, "encoders", "faulty.asl"),), seed=6)
    result = run_scenario(scenario, processes=False, timeout=60)
    assert result.finished and result.robots[0].diagnosis == "undiagnosed"
    candidates = marks_of(result, "undiagnosed")[0].detail
    assert "[left_encoder,right_encoder]" in candidates and "[left_motor,right_motor]" in candidates


def test_a_run_ends_at_its_limit_in_simulated_time():
    """Alone, the robot asks for help for 4 x 3 simulated seconds; a 3 s limit ends the run first, and it
    counts as not finished (the agents wait in simulated time, so the limit does not depend on the load)."""
    scenario = Scenario((RobotSetup("faulty", 0.0, 0.0, 0.0, "encoders", "faulty.asl"),), seed=6)
    result = run_scenario(scenario, processes=False, timeout=60, sim_timeout=3.0)
    assert not result.finished and result.outcome == "timeout"
    assert 3.0 <= result.world.time < 8.0
    assert marks_of(result, "help_requested") and not marks_of(result, "undiagnosed")


@pytest.mark.slow   # ~30 s; the team of two at the default seed runs the same in agent processes, `faultmas eval` teams in-process
def test_six_robots_two_of_them_faulty_diagnose_concurrently():
    scenario = team_scenario(6, 2, seed=1)
    result = run_scenario(scenario, processes=True, timeout=180)
    broken = [r for r in result.robots if r.fault != "none"]
    assert len(broken) == 2 and result.finished
    assert [r.diagnosis for r in broken] == [r.expected for r in broken]
    assert all(r.diagnosis == "none" for r in result.robots if r.fault == "none")   # the others arrived
    helpers = {m.agent for m in marks_of(result, "robot_found")}
    assert helpers and not helpers & {r.name for r in broken}        # self-suspects never help


@pytest.mark.slow   # ~70 s; agents on the ROS 2 bridge with real nodes also run in tests/detection/learned/test_agents_run.py
def test_the_same_plans_diagnose_through_the_ros2_bridge_with_real_rclpy_nodes():
    pytest.importorskip("rclpy")
    from agents.ros2_run import run_on_ros2

    result = run_on_ros2(paper_scenario("encoders"), timeout=150)
    assert result.finished, [(m.agent, m.step, m.detail) for m in result.marks]
    assert result.robots[0].diagnosis == "encoders"
    assert marks_of(result, "robot_found")


def test_faultmas_eval_prints_a_table_and_json_of_every_run():
    command = [sys.executable, "-m", "agents", "eval", "--runs", "1", "--faults", "both_actuators,none",
               "--teams", "none", "--jobs", "2", "--seed", "3"]
    done = subprocess.run(command + ["--json"], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads(done.stdout)
    assert [(r["fault"], r["diagnosis"], r["correct"]) for r in report["runs"]] == \
        [("both_actuators", "both_actuators", True), ("none", "none", True)]
    rows = {row["scenario"]: row for row in report["table"]}
    assert rows["none"]["success_rate"] == 1.0 and rows["none"]["runs"] == 1
    mean, _ = rows["both_actuators"]["steps.total"]
    assert mean == report["runs"][0]["steps"]["total"] > 0
    from agents.demo_cli import format_eval_table
    assert "| none | 1 | 100% | 1.04 |" in format_eval_table([{**rows["none"], "steps.fault_detection": (1.04, None)}], 1)
    bad = subprocess.run(command[:3] + ["--faults", "gremlins"], cwd=REPO, capture_output=True, text=True,
                         timeout=60)
    assert bad.returncode == 2 and "gremlins" in bad.stderr


def test_the_eval_draws_any_bearing_and_any_heading_including_end_on_views():
    import math
    views = []
    for seed in range(300):
        faulty, helper = random_pair_scenario("encoders", seed).robots
        distance = math.hypot(helper.x - faulty.x, helper.y - faulty.y)
        assert 1.0 <= distance <= 3.0
        line_of_sight = math.degrees(math.atan2(helper.y - faulty.y, helper.x - faulty.x))
        views.append(abs((faulty.yaw_deg - line_of_sight + 180.0) % 360.0 - 180.0))
    assert min(views) < 10.0 and max(views) > 170.0          # end-on from the front and from behind
    assert any(80.0 < v < 100.0 for v in views)               # and side views


# ---- teams: robots anywhere in the arena, a helper goes to where the robot asking for help says it is ----
def test_a_team_of_two_at_the_default_seed_diagnoses_correctly_though_out_of_camera_range():
    scenario = team_scenario(2, 1, seed=1)
    a, b = scenario.robots
    assert math.hypot(a.x - b.x, a.y - b.y) > 4.0          # beyond the camera's range: a search alone fails
    done = subprocess.run([sys.executable, "-m", "agents", "run", "--robots", "2", "--faulty", "1", "--json"],
                          cwd=REPO, capture_output=True, text=True, timeout=200)
    assert done.returncode == 0, done.stderr[-3000:]
    report = json.loads(done.stdout)
    assert report["correct"] is True and report["finished"] is True
    assert sorted(r["fault"] != "none" for r in report["robots"]) == [False, True]   # same schema as the pair
    assert "I go near it" in done.stderr and "robot detected" in done.stderr


def test_team_placements_cover_the_whole_arena_and_keep_robots_apart():
    xs, ys = [], []
    for seed in range(40):
        robots = team_scenario(12, 3, seed).robots
        xs += [r.x for r in robots]
        ys += [r.y for r in robots]
        assert all(math.hypot(p.x - q.x, p.y - q.y) >= 1.6 for p in robots for q in robots if p is not q)
    assert min(xs) < -4.0 and max(xs) > 4.0 and min(ys) < -4.0 and max(ys) > 4.0
    assert max(map(abs, xs + ys)) <= 5.0 - 0.8


def test_the_fault_option_is_injected_into_every_faulty_robot_of_a_team():
    robots = team_scenario(5, 3, seed=4, fault="left_actuator").robots
    assert sorted(r.fault for r in robots) == ["left_actuator"] * 3 + ["none"] * 2
    false_alarms = team_scenario(3, 1, seed=4, fault="none").robots
    assert [r.false_alarm for r in false_alarms].count(True) == 1
    with pytest.raises(ValueError):
        team_scenario(3, 1, seed=4, fault="gremlins")


def test_reports_after_the_run_ended_are_echoed_but_not_kept():
    """Found by the soak (issue 22): a team held up after its run (``faultmas run --inspect``, the soak's
    task after task) kept every later progress report in the run's log, ~0.85 MiB per hour of tasks for as
    long as it was held; and a diagnosis made after a run timed out became that run's result."""
    from agents.cooperative import ProgressLog
    from agents.progress import ProgressReport

    scenario = team_scenario(2, 1, seed=1)
    faulty = next(r.name for r in scenario.robots if r.under_test)
    echoed = []
    log = ProgressLog(scenario, None, lambda: None, echoed.append, clock=lambda: 0.0)
    log.record(ProgressReport(faulty, "started"))
    log.end()
    for _ in range(50):
        log.record(ProgressReport(faulty, "diagnosed", "left_actuator"))
    assert [m.step for m in log.marks] == ["started"]
    assert len(echoed) == 51, "reports after the run must still be shown"
    assert next(r for r in log.results() if r.name == faulty).diagnosis is None


def test_faulty_without_robots_is_an_error(capsys):
    from agents.cli import main
    assert main(["run", "--faulty", "2"]) == 2
    assert "--faulty K needs --robots N" in capsys.readouterr().err


def test_faultmas_eval_runs_team_placements():
    done = subprocess.run([sys.executable, "-m", "agents", "eval", "--runs", "1", "--faults", "", "--teams", "2",
                           "--seed", "2", "--jobs", "1", "--json"], cwd=REPO, capture_output=True, text=True,
                          timeout=230)
    assert done.returncode == 0, done.stderr[-2000:]
    report = json.loads(done.stdout)
    [row] = report["table"]
    assert row["scenario"] == "team of 2" and row["success_rate"] == 1.0
    [run] = report["runs"]
    assert run["correct"] is True and run["steps"]["robot_detection"] > 0
