"""The detector on rendered frames with known geometry and on hand-made edge cases."""
import math

import cv2
import numpy as np
import pytest

from perception import markers
from perception.camera import CameraModel
from perception.detect import DetectorConfig, _kernel, colour_mask, detect, detect_all
from robot_bridge.sim.camera import (CameraRig, CylinderProp, RobotLook, Scene, Wall, render, render_with_pixels,
                                     true_view)
from robot_bridge.sim.render_scenes import random_scene

CAM = CameraModel.kinect()
RIG = CameraRig(CAM, height_m=0.30, mount_x_m=0.0)
ORIGIN = (0.0, 0.0, 0.0)
ROOM = (Wall(5.5, -4, 5.5, 4), Wall(5.5, 4, -1, 4), Wall(-1, 4, -1, -4), Wall(-1, -4, 5.5, -4))


def _frame(robots, seed=0, **scene):
    scene.setdefault("walls", ROOM)
    return render(RIG, ORIGIN, robots, Scene(**scene), np.random.default_rng(seed))


def _yaw_err(a, b):
    return abs((a - b + 180) % 360 - 180)


def _assert_matches(det, truth, angle=0.5, depth=0.05, yaw=8.0):
    assert det is not None
    assert det.angle_deg == pytest.approx(truth.angle_deg, abs=angle)
    assert det.depth_m == pytest.approx(truth.depth_m, abs=depth)
    assert _yaw_err(det.yaw_deg, truth.yaw_deg) <= yaw


def _robot_at(z, bearing_deg, yaw_deg):
    """A robot whose marker midpoint is at depth z and bearing (+ right), heading per Detection.yaw_deg."""
    x_right = z * math.tan(math.radians(bearing_deg))
    return (z, -x_right, math.radians(-yaw_deg))


@pytest.mark.parametrize("z,bearing,yaw", [(1.2, 0, 90), (2.0, -15, 45), (3.0, 20, -120), (3.8, 5, 150),
                                           (1.5, 25, -60), (2.5, -25, 30)])
def test_pose_of_a_robot_in_a_plain_room(z, bearing, yaw):
    robot = _robot_at(z, bearing, yaw)
    truth = true_view(RIG, ORIGIN, robot)
    assert truth.depth_m == pytest.approx(z) and truth.yaw_deg == pytest.approx(yaw)
    rgb, depth = _frame([robot])
    res = detect(rgb, depth, CAM)
    _assert_matches(res.detection, truth, angle=0.3, depth=0.03, yaw=6.0)
    assert 0 < res.detection.confidence <= 1
    assert res.detection.front_px[0] == pytest.approx(truth.front_u, abs=1.0)


@pytest.fixture(scope="module")
def random_frames():
    out = []
    for seed in range(1000, 1040):
        s = random_scene(seed)
        rgb, depth, px = render_with_pixels(s.rig, s.camera_pose, s.robots, s.scene, np.random.default_rng(seed))
        out.append((s, rgb, depth, px))
    return out


def test_random_scenes_detected_where_visible_and_never_far_off(random_frames):
    visible = hits = 0
    for s, rgb, depth, px in random_frames:
        res = detect(rgb, depth, s.rig.camera)
        if px[0].both_visible():
            visible += 1
            hits += res.found
        if res.found:
            # whichever robot it found, it must be one of those in the scene, and close to the truth
            truths = [true_view(s.rig, s.camera_pose, r) for r in s.robots]
            t = min(truths, key=lambda t: abs(t.angle_deg - res.detection.angle_deg))
            _assert_matches(res.detection, t, angle=1.0, depth=0.08, yaw=20.0)
    assert visible >= 20
    assert hits >= 0.9 * visible


def test_one_cylinder_hidden_gives_no_detection_and_says_why():
    robot = _robot_at(2.0, 0, 90)                      # side-on: front (orange) on the left
    truth = true_view(RIG, ORIGIN, robot)
    fx_, fz_ = truth.front_xz
    wall_piece = CylinderProp(1.0, -fx_ / fz_ * 1.0, 0.05, 0.0, 1.2, (120, 120, 120))
    rgb, depth = _frame([robot], props=(wall_piece,))
    res = detect(rgb, depth, CAM)
    assert res.detection is None and res.reason == "no_orange_blob"


def test_lone_orange_distractor_is_not_a_robot():
    decoy = CylinderProp(2.0, 0.3, markers.CYLINDER_RADIUS_M, 0.42, 0.57, markers.MARKER_RGB["orange"])
    rgb, depth = _frame([], props=(decoy,))
    res = detect(rgb, depth, CAM)
    assert res.detection is None and res.reason == "no_blue_blob"
    # with a robot in view as well, the robot is found, not the decoy
    robot = _robot_at(2.5, -10, 70)
    rgb, depth = _frame([robot], props=(decoy,))
    _assert_matches(detect(rgb, depth, CAM).detection, true_view(RIG, ORIGIN, robot))


def test_two_robots_in_view_are_both_found():
    robots = [_robot_at(1.8, -12, 100), _robot_at(3.2, 14, -40)]
    rgb, depth = _frame(robots)
    res = detect_all(rgb, depth, CAM)
    assert len(res.all) == 2
    for robot in robots:
        truth = true_view(RIG, ORIGIN, robot)
        det = min(res.all, key=lambda d: abs(d.angle_deg - truth.angle_deg))
        _assert_matches(det, truth)
    assert res.detection is res.all[0]


@pytest.mark.parametrize("gain", [0.5, 1.5])
def test_dark_and_bright_scenes(gain):
    robot = _robot_at(3.0, 8, -100)
    rgb, depth = _frame([robot], gain=gain)
    _assert_matches(detect(rgb, depth, CAM).detection, true_view(RIG, ORIGIN, robot))


def test_closer_than_the_depth_sensor_range_uses_the_silhouette_size():
    robot = _robot_at(0.85, 3, 90)                     # cylinder surfaces at about 0.8 m: few or no readings
    rgb, depth = _frame([robot])
    res = detect(rgb, depth, CAM)
    _assert_matches(res.detection, true_view(RIG, ORIGIN, robot), angle=0.5, depth=0.05, yaw=15.0)


def test_colours_are_configuration_the_papers_orange_and_green():
    look = RobotLook(rear_rgb=markers.MARKER_RGB["green"])
    robot = _robot_at(2.2, -5, 60)
    rgb, depth = _frame([robot], robot_look=look)
    assert detect(rgb, depth, CAM).detection is None                      # no blue anywhere
    cfg = DetectorConfig(rear_hsv=markers.GREEN_HSV, rear_name="green")
    _assert_matches(detect(rgb, depth, CAM, cfg).detection, true_view(RIG, ORIGIN, robot))


def test_hand_drawn_frame_with_flat_depth():
    """Two painted bands on a grey image with a flat depth map: the bearing follows the pinhole model."""
    rgb = np.full((480, 640, 3), 128, np.uint8)
    depth = np.zeros((480, 640), np.float32)
    z = 2.0
    for colour, u in (("orange", 300), ("blue", 367)):
        width = int(round(2 * CAM.fx * markers.CYLINDER_RADIUS_M / z))
        cv2.rectangle(rgb, (u - width // 2, 180), (u + width // 2, 225), markers.MARKER_RGB[colour], -1)
        depth[180:226, u - width // 2:u + width // 2 + 1] = z
    res = detect(rgb, depth, CAM)
    det = res.detection
    assert det is not None, res.reason
    # a flat surface is read as the front of a cylinder: axis range = surface + radius
    u_mid = (300 + 367) / 2
    assert det.angle_deg == pytest.approx(math.degrees(math.atan((u_mid - CAM.cx) / CAM.fx)), abs=0.3)
    assert det.depth_m == pytest.approx(z + markers.CYLINDER_RADIUS_M, abs=0.02)
    assert det.yaw_deg == pytest.approx(-90, abs=8)                 # blue (rear) to the right: moving left


def test_empty_frame_and_bad_inputs():
    rgb = np.full((480, 640, 3), 90, np.uint8)
    depth = np.zeros((480, 640), np.float32)
    res = detect(rgb, depth, CAM)
    assert not res.found and res.reason == "no_orange_blob"
    with pytest.raises(ValueError, match="depth is 640x100"):
        detect(rgb, depth[:100], CAM)
    with pytest.raises(ValueError, match="uint8"):
        detect(rgb.astype(np.float32), depth, CAM)
    with pytest.raises(ValueError, match="camera model"):
        detect(rgb, depth, CameraModel.from_fov(width=320, height=240))


NAVY = (30, 40, 120)                                   # a navy prop: blue hue, but not marker-blue


@pytest.mark.parametrize("gain", [0.5, 1.0, 1.5])
def test_navy_things_are_not_the_blue_marker(gain):
    pole = CylinderProp(2.0, 0.2, 0.05, 0.0, 1.2, NAVY)
    rgb, _ = _frame([], props=(pole,), gain=gain)
    hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)
    lo = markers.BLUE_HSV.lo
    assert cv2.countNonZero(cv2.inRange(hsv, (lo[0], 100, 30), markers.BLUE_HSV.hi)) > 5000    # blue-ish
    # noisy pixels of a dim scene may pass the thresholds, never enough to survive the opening
    assert cv2.countNonZero(colour_mask(hsv, markers.BLUE_HSV, _kernel(5))) == 0
    robot = _robot_at(2.0, -5, 60)                      # while the marker itself stays blue
    rgb, depth = _frame([robot], gain=gain)
    _assert_matches(detect(rgb, depth, CAM).detection, true_view(RIG, ORIGIN, robot))


def test_a_near_cylinder_cut_by_the_top_border_is_placed_from_its_edges():
    robot = _robot_at(0.8, 12, 170)                    # facing the camera: front top above the image
    truth = true_view(RIG, ORIGIN, robot)
    assert CAM.cy + CAM.fy * (0.30 - markers.CYLINDER_TOP_M) / (truth.front_xz[1] - 0.03) < 0
    rgb, depth = _frame([robot])
    res = detect(rgb, depth, CAM)
    _assert_matches(res.detection, truth, angle=0.5, depth=0.05, yaw=15.0)
    assert res.detection.front.placed


def test_placement_is_refused_when_two_places_or_a_wide_valley_fit():
    from perception.detect import _GRID, _ambiguous

    bx, bz = 0.227 * np.sin(_GRID), 2.0 + 0.227 * np.cos(_GRID)
    one = ((_GRID - 0.5) / 0.05) ** 2                  # one narrow valley at 0.5 rad
    assert not _ambiguous(one, int(np.argmin(one)), bx, bz, one.min() + 6)
    two = np.minimum(one, ((_GRID + 1.5) / 0.05) ** 2 + 2.0)
    assert _ambiguous(two, int(np.argmin(two)), bx, bz, two.min() + 6)
    wide = ((_GRID - 0.5) / 0.6) ** 2                   # pinned to no better than ~0.2 m
    assert _ambiguous(wide, int(np.argmin(wide)), bx, bz, wide.min() + 6)


@pytest.mark.parametrize("z,yaw", [(3.0, 174), (3.8, -174)])
def test_a_cylinder_left_as_a_sliver_beside_its_partner_is_placed(z, yaw):
    robot = _robot_at(z, 0, yaw)                      # facing the camera: the rear peeks out beside the front
    rgb, depth, px = render_with_pixels(RIG, ORIGIN, [robot], Scene(walls=ROOM), np.random.default_rng(0))
    assert px[0].rear_visible < 0.4 * px[0].rear_full    # a few columns only: the opening removes it
    res = detect(rgb, depth, CAM)
    _assert_matches(res.detection, true_view(RIG, ORIGIN, robot), angle=0.3, depth=0.05, yaw=15.0)
    assert res.detection.rear.placed
