"""Cameras in the world: frames only on demand or at their rate, markers where the pinhole model says."""
import math

import cv2
import numpy as np
import pytest

from perception import markers
from robot_bridge import Action, percepts
from robot_bridge.sim.bridge import SimBridge
from robot_bridge.sim.world import World


@pytest.fixture(scope="module")
def pair():
    world = World(seed=5, noise=False)
    world.add_robot("watcher", camera=True)
    world.add_robot("faulty", x=2.0, yaw_deg=90.0)     # seen side-on, front marker to the left
    return world


def test_front_marker_appears_where_the_pinhole_model_says(pair):
    frame = pair.camera_frame("watcher")
    cam = frame.camera
    assert frame.rgb.shape == (cam.height, cam.width, 3) and frame.rgb.dtype == np.uint8
    # Optical frame of the camera (x right, z forward): the front cylinder's axis.
    cx, cy, _ = frame.pose
    x_right, z = -(0.0 + markers.FRONT_OFFSET_M - cy), 2.0 - cx
    u = cam.fx * x_right / z + cam.cx
    v_top = cam.cy + cam.fy * (0.30 - markers.CYLINDER_TOP_M) / z          # default rig: 0.30 m high
    v_bottom = cam.cy + cam.fy * (0.30 - markers.CYLINDER_BOTTOM_M) / z
    hsv = cv2.cvtColor(frame.rgb, cv2.COLOR_RGB2HSV)
    mask = cv2.inRange(hsv, markers.ORANGE_HSV.lo, markers.ORANGE_HSV.hi)
    rows, cols = np.nonzero(mask)
    assert len(cols) > 100
    assert cols.mean() == pytest.approx(u, abs=2.0)
    # The camera sits below the robots' top plate: the nearer body edge hides the cylinder's foot.
    v_body = cam.cy + cam.fy * (0.30 - markers.CYLINDER_BOTTOM_M) / (z - 0.177)
    assert rows.min() == pytest.approx(v_top, abs=3.0)
    assert rows.max() == pytest.approx(min(v_bottom, v_body), abs=3.0)
    depth = frame.depth[rows, cols]
    assert np.median(depth[depth > 0]) == pytest.approx(z - markers.CYLINDER_RADIUS_M, abs=0.05)
    blue = cv2.inRange(hsv, markers.BLUE_HSV.lo, markers.BLUE_HSV.hi)
    assert np.nonzero(blue)[1].mean() > cols.mean()                       # rear (blue) to the right


def test_frames_are_rendered_only_when_someone_listens_and_at_the_rate():
    world = World(noise=False)
    world.add_robot("a", camera=True)
    world.add_robot("b", x=2.0)
    world.run(0.5)
    assert "camera_ok" not in {p.name for p in world.percepts("a")}
    times = []
    unsubscribe = world.subscribe_camera("a", lambda frame: times.append(frame.time))
    world.run(1.0)
    assert len(times) == 10 and np.allclose(np.diff(times), 0.1)
    assert "camera_ok" in {p.name for p in world.percepts("a")}
    unsubscribe()
    world.run(0.5)
    assert len(times) == 10


def test_frames_on_demand_do_not_change_the_physics():
    def trajectory(peek):
        world = World(seed=11)
        world.add_robot("a", camera=True)
        world.add_robot("b", x=2.0)
        world.command("a", "turn", (45.0, 45.0))
        for _ in range(100):
            world.step()
            if peek:
                world.camera_frame("a")
        return world.trajectory("a")
    assert trajectory(False) == trajectory(True)


def test_camera_bridge_perceives_through_the_pixels():
    world = World(seed=4)
    world.add_robot("helper", x=1.6, y=0.4, yaw_deg=180.0)
    bridge = SimBridge("watcher", world=world, camera=True, drive=False)
    bridge.setup()
    try:
        world.run(0.3)
        found = bridge.percepts()
        assert "camera_ok" in {p.name for p in found}
        for p in found:
            percepts.validate(p)
        pytest.importorskip("perception.detect")
        seen = [p for p in found if p.name == "robot_seen"]
        assert len(seen) == 1
        name, angle, depth, yaw = seen[0].args
        assert name == "helper"
        assert angle == pytest.approx(math.degrees(math.atan2(0.4, 1.6 - 0.1)), abs=3)   # left: positive
        assert depth == pytest.approx(1.5, abs=0.15)
        assert abs(yaw) == pytest.approx(180, abs=15)                                    # facing us
        assert bridge.act(Action("turn", (angle,))).done() is False
    finally:
        bridge.shutdown()


def test_camera_bridge_perceives_every_robot_in_view_not_only_the_nearest():
    # issue 22's soak: a helper of a long-lived team looked for a robot standing behind another one, a little
    # to the side; the bridge reported only the detector's best pair (the nearer robot), so the search turned
    # past the robot it looked for, round after round, until the task's budget was spent
    pytest.importorskip("perception.detect")
    world = World(seed=4)
    world.add_robot("nearer", x=1.3, y=0.35, yaw_deg=90.0)
    world.add_robot("sought", x=2.4, y=-0.45, yaw_deg=90.0)
    bridge = SimBridge("watcher", world=world, camera=True, drive=False)
    bridge.setup()
    try:
        world.run(0.3)
        seen = {p.args[0]: p.args for p in bridge.percepts() if p.name == "robot_seen"}
        assert set(seen) == {"nearer", "sought"}
        assert seen["nearer"][1] > 0 > seen["sought"][1]                         # left, right of the centre
        assert seen["nearer"][2] == pytest.approx(1.3, abs=0.2) and seen["sought"][2] == pytest.approx(2.4, abs=0.25)
    finally:
        bridge.shutdown()


def test_a_frame_the_detector_fails_on_is_dropped_and_the_world_runs_on(caplog):
    # issue 22's soak: an exception in the detector (a SystemError out of OpenCV) ended the simulator's thread,
    # so the whole team stood still until the soak's wall limit
    world = World(seed=4)
    world.add_robot("seen", x=1.5, yaw_deg=90.0)
    bridge = SimBridge("watcher", world=world, camera=True, drive=False)
    bridge.setup()
    detect, failures = bridge._detect, []

    def fails_once(rgb, depth, camera):
        if not failures:
            failures.append(1)
            raise SystemError("bad argument to internal function")
        return detect(rgb, depth, camera)
    bridge._detect = fails_once
    try:
        world.run(0.5)
        assert failures and world.time == pytest.approx(0.5)
        assert "robot watcher's camera detector (SimBridge._on_frame) failed (frame at 0.00 s)" in caplog.text
        pytest.importorskip("perception.detect")
        assert any(p.name == "robot_seen" for p in bridge.percepts())     # later frames are seen again
    finally:
        bridge.shutdown()


def test_frames_are_rendered_when_read_and_the_same_whenever_read():
    from robot_bridge.sim.camera import DeferredFrame, frames_rendered

    def world_with_frames():
        world = World(seed=8)
        world.add_robot("a", camera=True)
        world.add_robot("b", x=1.5, y=0.2, yaw_deg=30.0)
        world.command("b", "rotate", (30.0,))
        frames = []
        world.subscribe_camera("a", frames.append)
        return world, frames

    world, frames = world_with_frames()
    before = frames_rendered()
    world.run(0.5)
    assert len(frames) == 5 and all(isinstance(f, DeferredFrame) and not f.rendered for f in frames)
    assert frames_rendered() == before                     # nobody looked: nothing rendered
    late = frames[2].rgb, frames[2].depth                  # read after the world moved on
    assert frames_rendered() == before + 1 and frames[2].rendered and not frames[3].rendered

    eager_world, eager = world_with_frames()
    eager_world.subscribe_camera("a", lambda frame: frame.rgb)     # a listener that reads every frame
    eager_world.run(0.5)
    assert all(f.rendered for f in eager)
    assert np.array_equal(eager[2].rgb, late[0]) and np.array_equal(eager[2].depth, late[1])
    assert not np.array_equal(eager[2].rgb, eager[3].rgb)          # the robot turned in between


def test_a_deferred_frame_pickles_as_a_plain_frame_with_its_pixels():
    import pickle

    from robot_bridge.sim.world import CameraFrame

    world = World(seed=2)
    world.add_robot("a", camera=True)
    world.add_robot("b", x=2.0)
    frame = world.camera_frame("a")
    copy = pickle.loads(pickle.dumps(frame))
    assert type(copy) is CameraFrame and copy.time == frame.time and copy.pose == frame.pose
    assert np.array_equal(copy.rgb, frame.rgb) and np.array_equal(copy.depth, frame.depth)


def test_a_frame_read_from_several_threads_is_rendered_once():
    from concurrent.futures import ThreadPoolExecutor

    from robot_bridge.sim.camera import frames_rendered

    world = World(seed=3)
    world.add_robot("a", camera=True)
    world.add_robot("b", x=2.0)
    frame = world.camera_frame("a")
    before = frames_rendered()
    with ThreadPoolExecutor(4) as pool:
        images = list(pool.map(lambda _: frame.rgb, range(8)))
    assert frames_rendered() == before + 1 and all(img is images[0] for img in images)


def test_frames_rendered_side_by_side_are_the_frames_rendered_one_by_one():
    from robot_bridge.sim.camera import frames_rendered

    def frames(reads_pixels):
        world = World(seed=6)
        got = {}
        for i, (x, yaw) in enumerate(((0.0, 0.0), (2.0, 180.0), (1.0, 90.0))):
            name = f"r{i}"
            world.add_robot(name, x=x, y=0.5 * i, yaw_deg=yaw, camera=True)
            world.command(name, "rotate", (25.0,))
            got[name] = []
            world.subscribe_camera(name, lambda frame, name=name: got[name].append((frame.rgb, frame.depth)),
                                   reads_pixels=reads_pixels)
        before = frames_rendered()
        world.run(0.3)
        assert frames_rendered() - before == 3 * 3          # every frame due, each rendered once
        return got

    side_by_side, one_by_one = frames(True), frames(False)
    for name, pixels in one_by_one.items():
        for (rgb, depth), (rgb2, depth2) in zip(pixels, side_by_side[name]):
            assert np.array_equal(rgb, rgb2) and np.array_equal(depth, depth2)


def test_frames_go_side_by_side_only_while_that_is_the_faster_way():
    from robot_bridge.sim.camera import _Pace

    pace = _Pace()
    ways = []
    for _ in range(2 * _Pace.TRIALS + 2 * _Pace.EXPLORE):
        way = pace.side_by_side()
        ways.append(way)
        pace.record(way, 0.004 if way else 0.003)        # one by one is faster here (busy cores)
    trials = 2 * _Pace.TRIALS
    assert ways[:trials] == [False, True] * _Pace.TRIALS  # both ways timed, taking turns
    later = ways[trials:]
    assert 1 <= later.count(True) <= 2 and later.count(False) >= len(later) - 2   # retried now and then
    for _ in range(4):
        pace.record(True, 0.0001)                         # a core came free: side by side wins
    assert pace.side_by_side() is True
