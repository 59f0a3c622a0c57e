"""The shared world: determinism for a seed, trajectory logs (truth next to belief), percepts, bad input."""
import pytest

from robot_bridge import percepts
from robot_bridge.sim.world import World


def scripted_run(seed):
    world = World(seed=seed)
    world.add_robot("a", x=-1.0)
    world.add_robot("b", x=1.0, yaw_deg=90.0, fault="left_actuator")
    for kind, args in (("move", (0.6, 0.3)), ("turn", (120.0, 60.0)), ("move", (0.4, 0.2))):
        futures = [world.command(name, kind, args) for name in ("a", "b")]
        world.run_until(lambda: all(f.done() for f in futures), 30)
    return world.trajectory("a") + world.trajectory("b")


def test_same_seed_same_trajectory_other_seed_other_trajectory():
    first, again, other = scripted_run(7), scripted_run(7), scripted_run(8)
    assert len(first) > 100
    assert first == again
    assert first != other


def test_trajectory_logs_ground_truth_and_belief_at_a_fixed_interval():
    world = World(noise=False, log_interval=0.1)
    world.add_robot("r", fault="encoders")
    world.command("r", "move", (1.0, 0.2))
    world.run(2.0)
    log = world.trajectory("r")
    assert [round(p.time, 6) for p in log[:3]] == [0.0, 0.1, 0.2] and len(log) == 21
    assert log[-1].x > 0.1 and log[-1].odom_x == 0.0          # it drove; it believes it did not


def test_percepts_are_in_the_vocabulary_and_reflect_belief():
    world = World(noise=False)
    world.add_robot("r", fault="encoders")
    world.command("r", "move", (1.0, 0.2))
    world.run(0.5)
    found = world.percepts("r")
    for p in found:
        percepts.validate(p)
    names = {p.name for p in found}
    assert "stopped" in names and "moving" not in names        # dead encoders: believes it stands still
    world.set_fault("r", "none")
    world.run(0.2)
    assert "moving" in {p.name for p in world.percepts("r")}


def test_clock_is_shared_and_counts_steps():
    world = World(dt=0.02)
    world.add_robot("a")
    world.add_robot("b")
    world.run(1.0)
    assert world.time == pytest.approx(1.0)
    assert world.base_state("a").time == pytest.approx(world.base_state("b").time)


def test_bad_input_is_named():
    world = World()
    world.add_robot("a")
    with pytest.raises(ValueError, match="already"):
        world.add_robot("a")
    with pytest.raises(KeyError, match="no robot 'zz'.*robots: a"):
        world.pose("zz")
    with pytest.raises(ValueError, match="unknown fault 'wheels'.*stuck_wheels"):
        world.set_fault("a", "wheels")
    with pytest.raises(ValueError, match="fraction"):
        world.set_fault("a", "left_actuator:1.5")
    with pytest.raises(ValueError, match="no camera"):
        world.camera_frame("a")
    with pytest.raises(ValueError, match="dt"):
        World(dt=0)


def test_a_world_that_runs_for_hours_keeps_only_the_last_minutes_of_trajectory():
    # found by the soak (issue 22): 20 points a second per robot, kept for ever, ~20 MiB per robot and hour
    from robot_bridge.sim.world import LOG_KEEP_S

    kept = World(seed=1, noise=False, log_keep=1.0)
    everything = World(seed=1, noise=False, log_keep=None)
    for world in (kept, everything):
        world.add_robot("r")
        world.run(5.0)
    recent = kept.trajectory("r")
    assert len(recent) <= 1.0 / kept.log_interval + 1 and recent[-1].time == pytest.approx(5.0)
    assert recent[0].time >= 4.0 - 0.06                        # the oldest points went first
    assert everything.trajectory("r")[0].time == 0.0 and len(everything.trajectory("r")) > len(recent)
    assert World().log_keep == LOG_KEEP_S
