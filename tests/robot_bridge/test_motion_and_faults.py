"""Motion decomposition on a World stepped by hand, and each fault's signature on encoders and ground truth.

Completion is judged by the robot's own odometry; the assertions compare it with ground truth.
"""
import math

import pytest

from robot_bridge.sim import motion
from robot_bridge.sim.faults import Fault
from robot_bridge.sim.world import World


def run(world, name, kind, *args, seconds=30.0):
    future = world.command(name, kind, args)
    world.run_until(future.done, seconds)
    assert future.done(), f"{kind}{args} still running after {seconds} s"
    return future.result()


def make(fault="none", noise=False, **kw):
    world = World(seed=3, noise=noise, **kw)
    world.add_robot("r", fault=fault)
    return world


def test_move_reaches_the_distance_by_odometry_and_ground_truth():
    world = make()
    assert run(world, "r", "move", 0.5, 0.2).ok
    x, y, yaw = world.pose("r")
    assert x == pytest.approx(0.5, abs=0.01) and abs(y) < 1e-6 and abs(yaw) < 1e-6
    assert world.odometry("r").x == pytest.approx(x, abs=1e-3)
    world.run_until_idle(5)
    assert world.pose("r")[0] == pytest.approx(0.5, abs=0.01)   # no coasting past the goal


def test_backwards_move_and_turns_both_ways():
    world = make()
    assert run(world, "r", "move", -0.3, 0.2).ok
    assert world.pose("r")[0] == pytest.approx(-0.3, abs=0.01)
    assert run(world, "r", "turn", 90.0, 45.0).ok
    assert world.pose("r")[2] == pytest.approx(90.0, abs=1.0)
    assert run(world, "r", "turn", -135.0, 90.0).ok
    assert world.pose("r")[2] == pytest.approx(-45.0, abs=1.0)
    assert world.pose("r")[0] == pytest.approx(-0.3, abs=0.01)   # turned in place


def test_wheel_commands_respect_the_acceleration_limit():
    world = make()
    future = world.command("r", "move", (1.0, 0.5))
    speeds = []
    while not future.done():
        world.step()
        state = world.base_state("r")
        speeds.append((state.left_speed + state.right_speed) / 2 * 0.035)
    # While it runs; the last step drops from the 2 cm/s creep speed to zero under the motor's own limit.
    running = speeds[:-1]
    accel = max(abs(b - a) for a, b in zip(running, running[1:])) / world.dt
    assert accel <= motion.DEFAULT_LIMITS.linear_accel + 1e-6
    assert max(speeds) == pytest.approx(0.5, abs=1e-6)


def test_encoders_fault_robot_drives_but_odometry_stands_still():
    world = make("encoders")
    ticks = world.encoders("r")
    result = run(world, "r", "move", 0.5, 0.2)
    assert (result.ok, result.reason) == (False, "no_progress")
    assert world.encoders("r") == ticks
    assert world.odometry("r").distance == 0.0
    assert world.pose("r")[0] > 0.1                 # ground truth: it did drive


@pytest.mark.parametrize("fault", ["both_actuators", "stuck_wheels"])
def test_dead_actuators_and_stuck_wheels_robot_does_not_move(fault):
    world = make(fault)
    ticks = world.encoders("r")
    overloaded = []
    future = world.command("r", "move", (0.5, 0.2))
    while not future.done():
        world.step()
        overloaded.append(any(p.name == "over_current" for p in world.percepts("r")))
    assert (future.result().ok, future.result().reason) == (False, "no_progress")
    assert world.encoders("r") == ticks and world.pose("r")[:2] == (0.0, 0.0)
    # Only blocked wheels draw over-current: that is what tells the two faults apart.
    assert any(overloaded) == (fault == "stuck_wheels")


@pytest.mark.parametrize("fault, sign", [("left_actuator", 1), ("right_actuator", -1)])
def test_weak_actuator_robot_curves_towards_the_weak_wheel(fault, sign):
    world = make(fault)
    assert run(world, "r", "move", 0.3, 0.2).ok     # odometry counts the path, so move completes
    x, y, yaw = world.pose("r")
    assert sign * yaw > 30.0 and sign * y > 0.05     # curved, ground truth
    assert world.odometry("r").yaw * sign > math.radians(30.0)   # and the encoders saw it


def test_weak_actuator_fraction_is_configurable():
    yaws = []
    for fraction in (0.3, 0.7):
        world = make(Fault("left_actuator", fraction))
        assert run(world, "r", "move", 0.3, 0.2).ok
        yaws.append(world.pose("r")[2])
    assert yaws[0] > yaws[1] > 5.0


def test_fault_injected_and_repaired_at_any_time():
    world = make()
    future = world.command("r", "move", (2.0, 0.2))
    world.run(2.0)
    world.set_fault("r", "both_actuators")
    world.run_until(future.done, 10)
    assert future.result().reason == "no_progress"
    stuck_at = world.pose("r")[0]
    assert 0.2 < stuck_at < 0.6
    world.set_fault("r", "none")
    assert run(world, "r", "move", 0.5, 0.2).ok
    assert world.pose("r")[0] == pytest.approx(stuck_at + 0.5, abs=0.02)


def test_a_new_motion_preempts_the_running_one():
    world = make()
    first = world.command("r", "move", (3.0, 0.2))
    world.run(1.0)
    assert run(world, "r", "turn", 90.0, 45.0).ok
    assert (first.result().ok, first.result().reason) == (False, "preempted")


def test_rotate_succeeds_once_turning_keeps_turning_until_stop():
    world = make()
    assert run(world, "r", "rotate", 30.0).ok
    yaw = world.pose("r")[2]
    world.run(1.0)
    assert world.pose("r")[2] > yaw + 20.0
    assert run(world, "r", "stop").ok
    assert {p.name for p in world.percepts("r")} >= {"stopped"}
    still = world.pose("r")
    world.run(1.0)
    assert world.pose("r") == still


def test_slow_progress_fails_with_timeout():
    world = World(noise=False, limits=motion.MotionLimits(timeout_factor=1.0, timeout_margin=0.5))
    world.add_robot("r", fault="left_actuator")      # progresses at 65 % of the nominal speed
    result = run(world, "r", "move", 1.0, 0.2)
    assert (result.ok, result.reason) == (False, "timeout")


def test_driving_into_a_wall_presses_the_bumper():
    world = World(noise=False, arena=(-1.0, -1.0, 1.0, 1.0))
    world.add_robot("r")
    result = run(world, "r", "move", 3.0, 0.3)
    assert (result.ok, result.reason) == (False, "bumper")
    assert world.pose("r")[0] == pytest.approx(1.0 - 0.176, abs=0.01)
    assert ("bumper", ("centre",)) in [(p.name, p.args) for p in world.percepts("r")]


def test_robots_do_not_drive_through_each_other():
    world = World(noise=False)
    world.add_robot("a", x=0.0)
    world.add_robot("b", x=1.0, yaw_deg=180.0)
    ra, rb = world.command("a", "move", (2.0, 0.3)), world.command("b", "move", (2.0, 0.3))
    world.run_until(lambda: ra.done() and rb.done(), 20)
    assert ra.result().reason == rb.result().reason == "bumper"
    assert world.pose("b")[0] - world.pose("a")[0] >= 2 * 0.176 - 1e-9
