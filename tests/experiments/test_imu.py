"""The IMU experiment in the embedded simulator: a small profile of the real command, and its parts."""
from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest

from agents.cli import main as faultmas
from experiments import imu, imu_report, imu_sim
from experiments.imu_detection import MODEL, OBSERVERS, RULES, data_file
from experiments.imu_result import RunResult, Sample


@pytest.fixture(scope="module")
def small_profile(tmp_path_factory) -> tuple[dict, str]:
    """``faultmas experiment imu --runs 1 --duration 45 --json --plot``: every fault and a fault-free run."""
    import contextlib
    import io
    out, err = io.StringIO(), io.StringIO()
    plot = str(tmp_path_factory.mktemp("imu") / "imu.png")
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = faultmas(["experiment", "imu", "--runs", "1", "--duration", "45", "--seed", "3", "--json",
                         "--plot", plot])
    assert code == 0, err.getvalue()
    return json.loads(out.getvalue()), err.getvalue(), plot


@pytest.mark.parametrize("fault", imu.FAULTS)
def test_each_fault_is_detected_and_the_switch_beats_always_imu(small_profile, fault):
    report, _, _ = small_profile
    figures = report["faults"][fault]
    assert figures["detected"] == 1 and figures["false_switches"] == 0
    assert 0 < figures["latency_s"]["median"] < 30
    assert figures["reduction_vs_always_imu_pct"]["mean"]["median"] < 0
    assert figures["reduction_vs_always_imu_pct"]["rms"]["median"] < 0
    assert figures["paper_reduction_pct"] == dict(zip(("mean", "rms"), imu_report.PAPER_REDUCTIONS[fault]))


def test_fault_free_run_does_not_switch_and_fusion_beats_encoders(small_profile):
    report, progress, _ = small_profile
    healthy = report["faults"]["none"]
    assert healthy["false_switches"] == 0 and healthy["detected"] == 0
    errors = healthy["mean_error_m"]
    assert errors["always_imu"]["median"] < errors["encoders"]["median"]
    assert errors["switched"] == errors["always_imu"]
    assert "none run 1/1" in progress and "no switch" in progress          # progress while runs go


def test_cpu_share_is_measured_and_small(small_profile):
    report, _, _ = small_profile
    shares = [figures["cpu_share_max"] for figures in report["faults"].values()]
    assert all(0 < share < 0.05 for share in shares)


def test_plot_is_written(small_profile):
    _, _, plot = small_profile
    with open(plot, "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_without_detection_nothing_switches():
    result = imu_sim.run("imu_stuck", 5.0, seed=1, duration=30.0, detect=False)
    assert result.switch_time is None
    assert result.mean_error("switched") == result.mean_error("always_imu")


def test_the_rule_fires_on_a_faulty_run_and_the_odometry_parameter_changes(monkeypatch):
    from robot_bridge.sim.world import World
    seen = []
    original = World.set_parameter

    def spy(self, name, node, parameter, value):
        original(self, name, node, parameter, value)
        seen.append((node, parameter, self.parameter(name, node, parameter)))
    monkeypatch.setattr(World, "set_parameter", spy)
    result = imu_sim.run("imu_over", 5.0, seed=2, duration=30.0)
    assert seen and seen[0] == ("odometry", "use_imu", False)
    assert result.switch_time is not None and result.switch_time > 5.0


def test_the_experiment_files_load_and_agree():
    from detection.config import load_observers
    from diagnosis.loader import load_model
    from diagnosis.rules import load_rules
    model = load_model(data_file(MODEL))
    rules = load_rules(data_file(RULES), model)          # checks the rule's names against the model
    observers = load_observers(data_file(OBSERVERS)).build()
    assert [o.name for o in observers.observers] == ["movement(imu,wheel_odom)"]
    assert "movement(imu,wheel_odom)" in model.observables
    assert rules[0].action.node == "odometry" and rules[0].action.value is False


def _result(always: float, switched: float, switch_time: float | None, fault_time: float | None) -> RunResult:
    samples = [Sample(0.0, (0.0, 0.0), (0.0, 0.0), (always, 0.0), (switched, 0.0))]
    return RunResult("imu_over", fault_time, 0, samples, switch_time, 0.9, 90.0)


def test_report_figures():
    result = _result(2.0, 1.0, 12.0, 10.0)
    assert imu_report.reduction(result, "mean") == pytest.approx(-50.0)
    assert result.latency == pytest.approx(2.0) and not result.false_switch
    assert result.cpu_share == pytest.approx(0.01)
    assert _result(2.0, 1.0, 8.0, 10.0).false_switch
    summary = imu_report.summarize("imu_over", [_result(2.0, 1.0, 12.0, 10.0), _result(4.0, 1.0, 14.0, 10.0)])
    assert summary.mean_reduction.median == pytest.approx(-62.5)
    assert summary.latency_median == pytest.approx(3.0)
    assert summary.meets_paper() is True
    assert "switched vs always IMU: mean -62.5" in imu_report.table([summary])
    assert math.isnan(imu_report.Spread.of([]).median)


def test_command_help_and_bad_arguments_from_another_directory(tmp_path):
    run = lambda *argv: subprocess.run([sys.executable, "-m", "agents.cli", *argv], cwd=tmp_path,
                                       capture_output=True, text=True, timeout=120)
    helped = run("experiment", "imu", "--help")
    assert helped.returncode == 0 and "--bridge {sim,ros2}" in helped.stdout and "--plot" in helped.stdout
    listed = run("experiment", "--help")
    assert "imu" in listed.stdout
    short = run("experiment", "imu", "--duration", "5")
    assert short.returncode == 2 and "--duration must be more than 10 s" in short.stderr
    unknown = run("experiment", "imu", "--fault", "gremlins")
    assert unknown.returncode == 2 and "invalid choice" in unknown.stderr and "Traceback" not in unknown.stderr
