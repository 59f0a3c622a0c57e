"""FollowingClock: an agent's clock follows its simulator's time, and never stops an agent when the
simulator does (robot_bridge/clock.py)."""
from __future__ import annotations

from pytest import approx

from robot_bridge.clock import FollowingClock


class Manual:
    """A source or wall clock that moves only when told to."""

    def __init__(self, value: float | None = 0.0) -> None:
        self.value = value

    def __call__(self) -> float | None:
        return self.value


def test_it_follows_the_source_whatever_its_pace_against_wall_time():
    sim, wall = Manual(0.0), Manual(100.0)
    clock = FollowingClock(sim, stale=5.0, wall=wall)
    start = clock()
    sim.value, wall.value = 0.3, 104.0          # 13 times slower than wall time
    assert clock() - start == approx(0.3)
    sim.value, wall.value = 10.3, 104.5         # 20 times faster
    assert clock() - start == approx(10.3)


def test_a_silent_source_lets_it_run_on_at_wall_pace_after_the_stale_time_and_continuously():
    sim, wall = Manual(2.0), Manual(0.0)
    clock = FollowingClock(sim, stale=5.0, wall=wall)
    start = clock()
    wall.value = 4.0
    assert clock() == start                     # a slow step, not a dead simulator: time stands
    wall.value = 8.0
    assert clock() - start == approx(3.0)               # 3 s beyond the stale time: runs at wall pace
    sim.value, wall.value = 2.5, 8.1            # the simulator is back: no jump (its 0.5 s were given already)
    assert clock() - start == approx(3.1)
    sim.value, wall.value = 2.7, 8.2            # and it follows from there
    assert clock() - start == approx(3.3)


def test_before_any_reading_it_is_wall_time_and_the_first_reading_does_not_make_it_jump():
    sim, wall = Manual(None), Manual(50.0)
    clock = FollowingClock(sim, wall=wall)
    start = clock()
    wall.value = 51.5
    assert clock() - start == approx(1.5)
    sim.value = 1000.0                          # a server whose world has run for a while already
    assert clock() - start == approx(1.5)
    sim.value = 1000.25
    assert clock() - start == approx(1.75)


def test_it_never_goes_backwards_when_the_source_does():
    sim, wall = Manual(10.0), Manual(0.0)
    clock = FollowingClock(sim, wall=wall)
    before = clock()
    sim.value = 3.0                             # a new world under the same name
    assert clock() == before
    sim.value = 3.5
    assert clock() - before == approx(0.5)


def test_following_says_whether_the_source_ticks():
    sim, wall = Manual(None), Manual(0.0)
    clock = FollowingClock(sim, stale=5.0, wall=wall)
    assert not clock.following
    sim.value = 1.0
    clock()
    assert clock.following
    wall.value = 6.0
    assert not clock.following


def test_a_source_said_alive_keeps_the_clock_standing_however_long_a_step_takes():
    """A starved simulator (its runner thread alive) or a paused one: time stands; once it is gone, the
    clock runs on at wall pace, counted from when it was last seen alive (no jump)."""
    sim, wall, alive = Manual(1.0), Manual(0.0), [True]
    clock = FollowingClock(sim, stale=5.0, wall=wall, alive=lambda: alive[0])
    start = clock()
    wall.value = 60.0
    assert clock() == start and clock.following
    alive[0] = False
    wall.value = 62.0
    assert clock() == start                         # gone for 2 s only
    wall.value = 67.0
    assert clock() - start == approx(2.0) and not clock.following
