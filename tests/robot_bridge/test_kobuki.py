"""Kobuki physics and odometry as pure functions: constants, wrap-around, limits, timeout."""
import math

from hypothesis import given
from hypothesis import strategies as st

from robot_bridge.sim import kobuki, odometry
from robot_bridge.sim.kobuki import BaseState, WheelSpeeds


def test_real_kobuki_constants():
    assert kobuki.WHEELBASE == 0.23 and kobuki.WHEEL_RADIUS == 0.035
    assert math.isclose(kobuki.TICKS_PER_REVOLUTION, 2578.33, abs_tol=0.01)


def test_encoder_ticks_count_wheel_rotation_and_wrap_at_16_bits():
    one_turn = BaseState(left_angle=2 * math.pi, right_angle=-2 * math.pi)
    left, right = kobuki.encoder_ticks(one_turn)
    assert left == 2578 and right == 65536 - 2579
    many = BaseState(left_angle=30 * 2 * math.pi)  # 77350 ticks: past one wrap
    assert kobuki.encoder_ticks(many)[0] == math.floor(30 * 2 * math.pi / kobuki.TICK_TO_RAD) - 65536


def test_tick_difference_is_signed_across_the_wrap():
    assert kobuki.tick_difference(2, 65534) == 4
    assert kobuki.tick_difference(65534, 2) == -4
    assert kobuki.tick_difference(1000, 900) == 100


@given(st.floats(-0.7, 0.7), st.floats(-3.0, 3.0))
def test_twist_and_wheel_speeds_are_inverse(linear, angular):
    back = kobuki.wheels_to_twist(kobuki.twist_to_wheels(linear, angular))
    assert math.isclose(back[0], linear, abs_tol=1e-9) and math.isclose(back[1], angular, abs_tol=1e-9)


def drive(state, command, seconds, dt=0.01):
    state = kobuki.step(state, command, dt)
    for _ in range(round(seconds / dt) - 1):
        state = kobuki.step(state, None, dt)
    return state


def test_acceleration_is_limited():
    state = kobuki.step(BaseState(), WheelSpeeds(10.0, 10.0), 0.01)
    assert math.isclose(state.left_speed, kobuki.KOBUKI.max_wheel_accel * 0.01)


def test_straight_line_without_noise_is_exact():
    speed = 0.2 / kobuki.WHEEL_RADIUS
    ramp = speed / kobuki.KOBUKI.max_wheel_accel  # time to reach speed
    state = BaseState()
    for _ in range(100):  # commands keep coming: 1 s of driving
        state = kobuki.step(state, WheelSpeeds(speed, speed), 0.01)
    expected = 0.2 * (1.0 - ramp) + 0.2 * ramp / 2
    assert math.isclose(state.x, expected, abs_tol=2e-3) and abs(state.y) < 1e-12 and state.yaw == 0.0


def test_in_place_rotation_keeps_position():
    w = kobuki.twist_to_wheels(0.0, 1.0)
    state = BaseState()
    for _ in range(100):
        state = kobuki.step(state, w, 0.01)
    assert math.hypot(state.x, state.y) < 1e-9 and 0.8 < state.yaw < 1.0


def test_base_stops_after_0_6_s_without_commands():
    moving = drive(BaseState(), WheelSpeeds(5.0, 5.0), 0.5)
    assert kobuki.is_moving(moving)
    stopped = drive(moving, None, 1.0)   # 0.6 s timeout, then deceleration
    assert not kobuki.is_moving(stopped)


def test_odometry_follows_encoders_through_the_wrap():
    state, odo = BaseState(), odometry.Odometry(ticks=(0, 0))
    w = kobuki.twist_to_wheels(0.5, 0.0)
    for _ in range(1500):  # 7.5 m: the counters wrap once
        state = kobuki.step(state, w, 0.01)
        odo = odometry.update(odo, kobuki.encoder_ticks(state), 0.01)
    assert state.left_angle / kobuki.TICK_TO_RAD > 65536
    assert math.isclose(odo.x, state.x, abs_tol=1e-3) and math.isclose(odo.distance, state.x, abs_tol=1e-3)
