"""The simulated yaw-rate gyro, the IMU faults, wheel miscalibration and the odometry fusion."""
from __future__ import annotations

import math

import numpy as np
import pytest

from robot_bridge.sim import faults, imu, kobuki
from robot_bridge.sim.faults import Fault, GyroFaultState, inject_gyro
from robot_bridge.sim.odometry_fusion import OdometryFusion, Pose2D, advance, parse_bool
from robot_bridge.sim.world import World

DT = 0.02


def test_gyro_noise_matches_the_noise_density() -> None:
    gyro = imu.Gyro()          # no bias, no scale error
    rng = np.random.default_rng(1)
    readings = np.array([imu.measure(gyro, 0.5, DT, rng) for _ in range(20000)])
    expected_sigma = imu.KOBUKI_GYRO.noise_density / math.sqrt(DT)
    assert readings.mean() == pytest.approx(0.5, abs=3 * expected_sigma / math.sqrt(len(readings)) + 1e-4)
    assert readings.std() == pytest.approx(expected_sigma, rel=0.05)


def test_gyro_bias_scale_range_and_resolution() -> None:
    gyro = imu.Gyro(bias=0.01, scale=0.02)
    assert imu.measure(gyro, 1.0, DT, None) == pytest.approx(1.03, abs=imu.KOBUKI_GYRO.resolution)
    assert imu.measure(gyro, 10.0, DT, None) == pytest.approx(imu.KOBUKI_GYRO.range, abs=1e-6)
    reading = imu.measure(imu.Gyro(), 0.123456, DT, None)
    assert reading / imu.KOBUKI_GYRO.resolution == pytest.approx(round(reading / imu.KOBUKI_GYRO.resolution))


def test_drawn_gyros_spread_as_documented() -> None:
    rng = np.random.default_rng(2)
    gyros = [imu.Gyro.draw(rng) for _ in range(4000)]
    assert np.std([g.bias for g in gyros]) == pytest.approx(imu.KOBUKI_GYRO.bias_sigma, rel=0.1)
    assert np.std([g.scale for g in gyros]) == pytest.approx(imu.KOBUKI_GYRO.scale_sigma, rel=0.1)


@pytest.mark.parametrize("kind", ["imu_stuck", "imu_over", "imu_zero_after_rotating"])
def test_imu_faults_are_fault_kinds(kind: str) -> None:
    assert Fault.parse(kind).kind == kind


def test_imu_stuck_reports_zero() -> None:
    assert inject_gyro(Fault("imu_stuck"), 0.7, 0.7, DT)[0] == 0.0
    assert inject_gyro(Fault("none"), 0.7, 0.7, DT)[0] == 0.7


def test_imu_over_reports_twenty_percent_more() -> None:
    assert inject_gyro(Fault("imu_over"), 0.5, 0.5, DT)[0] == pytest.approx(0.6)
    assert inject_gyro(Fault("imu_over"), -0.5, -0.5, DT)[0] == pytest.approx(-0.6)


def test_imu_zero_after_rotating_only_in_long_turns() -> None:
    fault, state, reported = Fault("imu_zero_after_rotating"), GyroFaultState(), []
    for _ in range(round(2.0 / DT)):                   # a 2 s turn
        value, state = inject_gyro(fault, 0.8, 0.8, DT, state)
        reported.append(value)
    first_second = round(faults.ROTATING_FOR_S / DT)
    assert all(v == 0.8 for v in reported[:first_second - 1])
    assert all(v == 0.0 for v in reported[first_second + 1:])
    value, state = inject_gyro(fault, 0.0, 0.0, DT, state)      # the turn ends ...
    value, state = inject_gyro(fault, 0.8, 0.8, DT, state)      # ... and the next one reads right again
    assert value == 0.8


def _keep_turning(world: World, seconds: float, rate: float = 1.0) -> None:
    for _ in range(round(seconds / 0.2)):      # a command every 0.2 s: the base keeps each for 0.6 s
        world.drive("r", 0.0, rate)
        world.run(0.2)


def _turn_in_place(world: World, seconds: float, rate: float = 1.0) -> None:
    _keep_turning(world, seconds, rate)
    world.drive("r", 0.0, 0.0)
    world.run(1.0)


@pytest.mark.parametrize("kind, expected", [("none", 1.0), ("imu_over", 1.2), ("imu_stuck", 0.0)])
def test_world_gyro_under_faults(kind: str, expected: float) -> None:
    world = World(noise=False, log_interval=0.0)
    world.add_robot("r", fault=kind)
    _keep_turning(world, 2.0)                           # at full turning speed (1 rad/s) by now
    assert world.yaw_rate("r") == pytest.approx(expected, abs=0.01)


def test_world_gyro_zero_after_rotating() -> None:
    world = World(noise=False, log_interval=0.0)
    world.add_robot("r", fault="imu_zero_after_rotating")
    _keep_turning(world, 0.8)
    assert world.yaw_rate("r") > 0.5                    # turning for less than a second: read right
    _keep_turning(world, 1.0)
    assert world.yaw_rate("r") == 0.0                   # turning for longer: zero
    _turn_in_place(world, 0.0, 0.0)                     # the turn ends
    _keep_turning(world, 0.4)
    assert world.yaw_rate("r") > 0.1                    # the next turn reads right again


def test_miscalibrated_base_turns_less_than_its_encoders_say() -> None:
    params = kobuki.BaseParams(wheelbase_scale=1.05)
    world = World(noise=False, log_interval=0.0, params=params)
    world.add_robot("r")
    _turn_in_place(world, 3.0)
    true_turn = world.base_state("r").yaw
    assert world.odometry("r").rotation == pytest.approx(true_turn * 1.05, rel=0.01)


def test_miscalibration_draws_are_realistic() -> None:
    rng = np.random.default_rng(3)
    drawn = [kobuki.miscalibrated(rng) for _ in range(2000)]
    assert np.mean([p.wheelbase_scale for p in drawn]) == pytest.approx(1 + kobuki.WHEELBASE_SCRUB, abs=0.002)
    ratio = [p.right_radius_scale / p.left_radius_scale - 1 for p in drawn]
    assert np.std(ratio) == pytest.approx(kobuki.MISCALIBRATION_SIGMA["radius_ratio"], rel=0.1)
    assert kobuki.KOBUKI.wheelbase_scale == 1.0        # the default base stays exactly calibrated


def _drive_square(world: World, laps: int = 3) -> list[float]:
    """Drive squares by ground truth; returns the position errors (encoders, fused) at the end."""
    from experiments.waypoints import Route
    route = Route(((0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)))
    while route.reached < 4 * laps:
        x, y, yaw = world.pose("r")
        world.drive("r", *route.command((x, y, math.radians(yaw))))
        world.run(0.1)
    x, y, _ = world.pose("r")
    odom, fused = world.odometry("r"), world.fused_odometry("r")
    return [math.hypot(odom.x - x, odom.y - y), math.hypot(fused.x - x, fused.y - y)]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fused_odometry_beats_encoders_on_a_healthy_run(seed: int) -> None:
    world = World(seed=seed, log_interval=0.0, params=kobuki.miscalibrated(np.random.default_rng(seed)))
    world.add_robot("r")
    encoders, fused = _drive_square(world)
    assert fused < encoders / 2


def test_use_imu_parameter_switches_the_fusion_to_the_encoders() -> None:
    world = World(noise=False, log_interval=0.0, params=kobuki.BaseParams(wheelbase_scale=1.05))
    world.add_robot("r", fault="imu_stuck")
    assert world.parameter("r", "odometry", "use_imu") is True
    _turn_in_place(world, 1.0)
    assert world.fused_odometry("r").yaw == pytest.approx(0.0, abs=1e-9)    # stuck gyro: no rotation
    world.set_parameter("r", "odometry", "use_imu", False)
    assert world.parameter("r", "odometry", "use_imu") is False
    before = world.odometry("r").rotation
    _turn_in_place(world, 1.0)
    turned = world.odometry("r").rotation - before
    assert world.fused_odometry("r").yaw == pytest.approx(turned, abs=1e-6)   # the encoders' rotation now


def test_set_parameter_names_what_exists() -> None:
    world = World(noise=False)
    world.add_robot("r")
    with pytest.raises(KeyError, match="nodes: odometry"):
        world.set_parameter("r", "amcl", "use_imu", False)
    with pytest.raises(KeyError, match="parameters: use_imu"):
        world.set_parameter("r", "odometry", "use_gps", False)
    with pytest.raises(ValueError, match="true or false"):
        world.set_parameter("r", "odometry", "use_imu", "maybe")


def test_fusion_keeps_the_pose_when_switched() -> None:
    fusion = OdometryFusion()
    fusion.step(1.0, 0.5, 0.0)
    assert fusion.pose == Pose2D(1.0, 0.0, 0.0)
    fusion.set_parameter("use_imu", "false")
    fusion.step(0.0, 0.5, 0.0)
    assert fusion.pose == advance(Pose2D(1.0, 0.0, 0.0), 0.0, 0.5)
    assert parse_bool("True") is True and parse_bool(False) is False
