"""A frame in which no robot can be is not rendered for the robot detector (``may_show_robots``): the
detector would have found nothing in its pixels. Checked on real rendered pixels, at the limits (image
edge, depth range) and over team placements spread over the arena."""
from __future__ import annotations

import math

import pytest

from agents.cooperative import team_scenario
from perception.detect import detect
from robot_bridge.sim.world import World


def frame_of(world: World, name: str):
    frame = world.camera_frame(name)
    return frame, detect(frame.rgb, frame.depth, frame.camera).detection


@pytest.mark.parametrize("distance, bearing_deg, shown", [
    (4.2, 0.0, True),          # within the depth range: seen
    (5.4, 0.0, False),         # beyond it (4.5 m) and its margin: no depth reading, no robot
    (2.0, 20.0, True),         # inside the 57-degree view
    (2.0, 36.0, False),        # outside it
    (2.0, 180.0, False),       # behind
])
def test_the_limits_agree_with_what_the_detector_finds(distance, bearing_deg, shown):
    world = World(seed=3)
    world.add_robot("watcher", camera=True)
    b = math.radians(bearing_deg)
    world.add_robot("other", x=distance * math.cos(b), y=distance * math.sin(b), yaw_deg=bearing_deg + 90.0)
    frame, found = frame_of(world, "watcher")
    assert frame.may_show_robots is shown
    assert (found is not None) is shown


def test_over_team_placements_a_frame_said_empty_never_shows_a_robot_and_most_are_empty():
    culled = shown = 0
    for seed in (1, 2):
        scenario = team_scenario(6, 1, seed)
        world = World(seed=seed)
        for r in scenario.robots:
            world.add_robot(r.name, x=r.x, y=r.y, yaw_deg=r.yaw_deg, camera=True)
        for r in scenario.robots:
            frame = world.camera_frame(r.name)
            if frame.may_show_robots:
                shown += 1
                continue
            culled += 1
            assert detect(frame.rgb, frame.depth, frame.camera).detection is None, (seed, r.name)
    assert culled >= shown                 # most frames of a spread-out team show nobody


def test_a_detecting_bridge_renders_only_the_frames_that_may_show_a_robot():
    from robot_bridge.sim.bridge import SimBridge
    from robot_bridge.sim.camera import frames_rendered

    world = World(seed=4)
    near = SimBridge("near", world=world, camera=True, drive=False)
    far = SimBridge("far", world=world, x=0.0, y=3.0, yaw_deg=90.0, camera=True, drive=False)  # faces away
    for bridge in (near, far):
        bridge.setup()
    world.add_robot("target", x=2.0, yaw_deg=90.0)
    before = frames_rendered()
    world.run(1.0)
    assert frames_rendered() - before == 10          # near's ten frames; far saw nobody and rendered none
    assert any(p.name == "robot_seen" for p in near.percepts())
    assert not any(p.name == "robot_seen" for p in far.percepts())
