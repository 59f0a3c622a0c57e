"""The simulated Kinect: geometry where the pinhole model says, Kinect-like depth, scenes from seeds."""
import math

import cv2
import numpy as np
import pytest

from perception import markers
from perception.camera import CameraModel
from robot_bridge.sim.camera import (BoxProp, CameraRig, CylinderProp, DepthSensor, Scene, Wall, render,
                                     render_with_pixels, true_view)
from robot_bridge.sim.render_scenes import random_scene

RIG = CameraRig(CameraModel.kinect(), height_m=0.30, mount_x_m=0.0)
CLEAN = DepthSensor(dropout=0.0, shadows=False, registration_px=0, disparity_noise_px=0.0)
CAMERA = (0.0, 0.0, 0.0)                    # at the origin, looking along +x


def _clean_scene(**kw) -> Scene:
    return Scene(rgb_noise=0.0, depth=CLEAN, **kw)


def _mask(rgb, rng):
    return cv2.inRange(cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV), rng.lo, rng.hi)


def test_marker_columns_rows_and_depth_follow_the_pinhole_model():
    robot = (2.0, 0.3, math.radians(-90))           # side-on, moving to the camera's right
    rgb, depth = render(RIG, CAMERA, [robot], _clean_scene(), np.random.default_rng(0))
    cam = RIG.camera
    truth = true_view(RIG, CAMERA, robot)
    rows, cols = np.nonzero(_mask(rgb, markers.ORANGE_HSV))
    assert cols.size > 200
    left, right = cols.min() - 0.5, cols.max() + 0.5
    fx_, fz_ = truth.front_xz
    beta = math.asin(markers.CYLINDER_RADIUS_M / math.hypot(fx_, fz_))
    phi = math.atan2(fx_, fz_)
    assert left == pytest.approx(cam.cx + cam.fx * math.tan(phi - beta), abs=1.0)
    assert right == pytest.approx(cam.cx + cam.fx * math.tan(phi + beta), abs=1.0)
    # top edge: the near rim at the cylinder's top height
    z_near = fz_ - markers.CYLINDER_RADIUS_M
    assert rows.min() == pytest.approx(cam.cy + cam.fy * (0.30 - markers.CYLINDER_TOP_M) / z_near, abs=1.0)
    # depth at the centre column is the near surface (quantised to 1/8 px of disparity)
    u = int(round(truth.front_u))
    col = depth[rows.min() + 3:rows.max() - 3, u]
    step = z_near ** 2 / (CLEAN.focal_baseline_px_m * CLEAN.subpixel)
    assert np.all(np.abs(col - z_near) <= step + 0.005)
    # rear (blue) is to the right of the front when the robot moves right
    bcols = np.nonzero(_mask(rgb, markers.BLUE_HSV))[1]
    assert bcols.mean() == pytest.approx(truth.rear_u, abs=1.0)
    assert truth.yaw_deg == pytest.approx(90.0, abs=1e-6)


def test_floor_and_wall_depth_per_row_and_column():
    wall = Wall(3.0, -5.0, 3.0, 5.0, height_m=2.0)
    rgb, depth = render(RIG, CAMERA, [], _clean_scene(walls=(wall,)), np.random.default_rng(0))
    cam = RIG.camera
    step = lambda z: z * z / (CLEAN.focal_baseline_px_m * CLEAN.subpixel) + 1e-3  # noqa: E731
    # rows above the floor-wall line see the wall at z = 3 m in every column
    v_wall = int(cam.cy + cam.fy * 0.30 / 3.0) - 2
    assert np.all(np.abs(depth[v_wall] - 3.0) <= step(3.0))
    # rows near the bottom see the floor at hc * fy / (v - cy)
    for v in (400, 450, 479):
        z = 0.30 * cam.fy / (v - cam.cy)
        expect = z if z >= CLEAN.min_m else 0.0
        assert np.all(np.abs(depth[v] - expect) <= step(z)), v


def test_kinect_range_limits_and_holes():
    rng = np.random.default_rng(1)
    sample = random_scene(3)
    _, depth = render(sample.rig, sample.camera_pose, sample.robots, sample.scene, rng)
    valid = depth[depth > 0]
    assert valid.min() >= 0.8 and valid.max() <= 4.5
    assert 0.005 < np.mean(depth == 0) < 0.9                     # dropouts plus out-of-range
    # noise grows with distance: compare the floor near the bottom with the floor far away
    _, d1 = render(RIG, CAMERA, [], Scene(), np.random.default_rng(2))
    _, d2 = render(RIG, CAMERA, [], Scene(), np.random.default_rng(3))
    near, far = slice(418, 426), slice(283, 289)     # floor at about 1 m and 4 m

    def spread(rows):
        a, b = d1[rows, 100:540], d2[rows, 100:540]
        ok = (a > 0) & (b > 0)
        return float(np.std(a[ok] - b[ok]))
    assert spread(far) > 3 * spread(near)


def test_illumination_gain_scales_brightness_and_keeps_marker_hue():
    robot = (2.0, 0.0, 1.0)                         # both cylinders in sight
    out = {}
    for gain in (0.5, 1.5):
        rgb, _ = render(RIG, CAMERA, [robot], _clean_scene(gain=gain), np.random.default_rng(0))
        hsv = cv2.cvtColor(rgb, cv2.COLOR_RGB2HSV)
        out[gain] = hsv
    assert out[1.5][..., 2].mean() > 1.8 * out[0.5][..., 2].mean()
    for hsv in out.values():
        assert cv2.countNonZero(cv2.inRange(hsv, markers.ORANGE_HSV.lo, markers.ORANGE_HSV.hi)) > 50


def test_occluder_reduces_visible_marker_pixels_and_ground_truth_counts_them():
    robot = (2.5, 0.0, math.radians(90))            # side-on: front cylinder to the left
    truth = true_view(RIG, CAMERA, robot)
    fx_, fz_ = truth.front_xz
    pole = CylinderProp(1.2, -fx_ * 1.2 / fz_, 0.04, 0.0, 1.5, (90, 90, 92))   # on the line of sight
    _, _, clear = render_with_pixels(RIG, CAMERA, [robot], _clean_scene(), np.random.default_rng(0))
    _, _, hidden = render_with_pixels(RIG, CAMERA, [robot], _clean_scene(props=(pole,)), np.random.default_rng(0))
    # the robot's own top plate hides the cylinder's foot from a camera below it
    assert clear[0].front_full > 100 and clear[0].front_visible >= 0.9 * clear[0].front_full
    assert hidden[0].front_visible == 0 and hidden[0].front_full == clear[0].front_full
    assert hidden[0].rear_visible == clear[0].rear_visible
    assert clear[0].both_visible() and not hidden[0].both_visible()


def test_boxes_render_with_their_faces_at_the_right_depth():
    box = BoxProp(2.0, 0.0, 0.0, 0.4, 0.6, 0.0, 0.5, (200, 30, 35))   # front face at x = 1.8
    _, depth = render(RIG, CAMERA, [], _clean_scene(props=(box,)), np.random.default_rng(0))
    cam = RIG.camera
    v = int(cam.cy + cam.fy * (0.30 - 0.25) / 1.8)
    u = int(cam.cx)
    assert depth[v, u] == pytest.approx(1.8, abs=0.02)


def test_scenes_and_frames_are_reproducible_from_seeds():
    a, b = random_scene(42), random_scene(42)
    assert a == b and random_scene(43) != a
    f1 = render(a.rig, a.camera_pose, a.robots, a.scene, np.random.default_rng(7))
    f2 = render(b.rig, b.camera_pose, b.robots, b.scene, np.random.default_rng(7))
    assert np.array_equal(f1[0], f2[0]) and np.array_equal(f1[1], f2[1])
    assert f1[0].shape == (480, 640, 3) and f1[0].dtype == np.uint8
    assert f1[1].shape == (480, 640) and f1[1].dtype == np.float32


def test_true_view_follows_the_detection_definitions():
    # camera at (1, 1) facing +y (yaw 90 deg); robot 2 m ahead, 0.5 m to the camera's right, facing away
    cam_pose = (1.0, 1.0, math.pi / 2)
    robot = (1.5, 3.0, math.pi / 2)
    t = true_view(RIG, cam_pose, robot)
    assert t.z_m == pytest.approx(2.0) and t.x_m == pytest.approx(0.5)
    assert t.angle_deg == pytest.approx(math.degrees(math.atan2(0.5, 2.0)))
    assert t.yaw_deg == pytest.approx(0.0, abs=1e-9)
    assert true_view(RIG, cam_pose, (1.5, 3.0, 0.0)).yaw_deg == pytest.approx(90.0)   # moving right
    assert RIG.pose_of((0.0, 0.0, math.pi / 2)) == pytest.approx((0.0, 0.0, math.pi / 2))
    assert CameraRig(mount_x_m=0.1).pose_of((1.0, 2.0, math.pi / 2)) == pytest.approx((1.0, 2.1, math.pi / 2))


def test_a_camera_standing_still_reuses_its_static_layers_with_the_same_pixels():
    from dataclasses import replace

    from robot_bridge.sim.camera import _renderer

    sample = random_scene(5)
    x, y, yaw = sample.robots[0]
    moved = ((x + 0.2, y - 0.1, yaw + 0.5),) + sample.robots[1:]
    for robots in (sample.robots, sample.robots, moved):    # the second frame keeps the layers, the third uses them
        rgb, depth = render(sample.rig, sample.camera_pose, robots, sample.scene, np.random.default_rng(9))
    kept = _renderer(sample.rig, sample.scene.depth)._static
    assert any(pose == sample.camera_pose and entry[0]() is sample.scene for (pose, _), entry in kept.items())
    # an equal scene that is another object is drawn from scratch: the pixels must not differ
    fresh = render(sample.rig, sample.camera_pose, moved, replace(sample.scene), np.random.default_rng(9))
    assert np.array_equal(rgb, fresh[0]) and np.array_equal(depth, fresh[1])
    before = render(sample.rig, sample.camera_pose, sample.robots, replace(sample.scene), np.random.default_rng(9))
    assert not np.array_equal(rgb, before[0])                    # the robot was redrawn where it moved to


def test_static_layers_of_a_scene_go_with_the_scene():
    # found by the soak (issue 22): a process running world after world kept the layers of 32 standing
    # cameras of worlds long gone (2 MiB each) and their scenes; they must go when the scene does
    import gc
    import weakref
    from dataclasses import replace

    from robot_bridge.sim.camera import _renderer

    sample = random_scene(6)
    scene = replace(sample.scene)                   # this test's own scene object
    for _ in range(2):                              # a camera standing still: its layers are kept
        render(sample.rig, sample.camera_pose, sample.robots, scene, np.random.default_rng(1))
    kept = _renderer(sample.rig, sample.scene.depth)._static
    gone, scene_id = weakref.ref(scene), id(scene)
    assert any(key[1] == scene_id for key in kept)
    del scene
    gc.collect()
    assert gone() is None, "the renderer keeps a scene alive"
    assert not any(key[1] == scene_id for key in kept), "the layers of a scene that is gone are still kept"


def test_bare_floor_rows_from_the_noise_banks_read_like_measured_ones():
    # rows below every object come from precomputed floor banks; a near pole reaching the bottom edge
    # makes every row measured: per row, the two must agree in depth, holes and colour
    pole = CylinderProp(0.45, 0.2, 0.03, 0.0, 1.0, (40, 40, 44))        # near the left edge, down to the last row
    banked, measured = [], []
    for seed in range(3):
        banked.append(render(RIG, CAMERA, [], Scene(), np.random.default_rng(seed)))
        measured.append(render(RIG, CAMERA, [], Scene(props=(pole,)), np.random.default_rng(seed)))
    u = round(RIG.camera.cx - RIG.camera.fx * 0.2 / 0.45)
    assert measured[0][0][-1, u - 3:u + 4].mean() < 70 < banked[0][0][-1, u - 3:u + 4].mean()   # the pole is there
    rows, cols = slice(300, 455), slice(200, 640)                      # floor from 3 m to 0.85 m
    for (rgb_b, d_b), (rgb_m, d_m) in zip(banked, measured):
        a, b = d_b[rows, cols], d_m[rows, cols]
        assert abs(np.mean(a == 0) - np.mean(b == 0)) < 0.01                 # holes: dropouts and out of range
        mean_a = np.array([r[r > 0].mean() for r in a])
        mean_b = np.array([r[r > 0].mean() for r in b])
        assert np.all(np.abs(mean_a - mean_b) < 0.01 * mean_b)               # same floor depth per row
        assert abs(np.mean(rgb_b[rows, cols]) - np.mean(rgb_m[rows, cols])) < 0.5
        assert abs(np.std(rgb_b[rows, cols]) - np.std(rgb_m[rows, cols])) < 0.5


def test_rows_with_nothing_in_depth_range_read_zero_as_if_measured(monkeypatch):
    # a room far beyond the 4.5 m range, robots beyond it too, and a pole just inside it: the rows above
    # the first that can read anything are not measured; measuring every row gives the same depth image
    from robot_bridge.sim.camera import _renderer

    corners = ((8.0, -8.0), (8.0, 8.0), (-8.0, 8.0), (-8.0, -8.0))
    room = tuple(Wall(*a, *b) for a, b in zip(corners, corners[1:] + corners[:1]))
    pole = CylinderProp(4.4, 1.0, 0.05, 0.0, 1.0, (90, 90, 92))
    robots = [(6.0, 0.3, 0.4), (7.0, -0.5, 1.0)]
    r = _renderer(RIG, Scene().depth)
    assert 240 < r.first_readable_floor_row < 300          # the floor is in range from about 4.7 m on
    for scene in (Scene(walls=room), Scene(walls=room, props=(pole,))):
        skipping = [render(RIG, CAMERA, robots, scene, np.random.default_rng(seed))[1] for seed in range(3)]
        with monkeypatch.context() as patch:
            patch.setattr(r, "z_readable", (0.0, math.inf))
            patch.setattr(r, "first_readable_floor_row", 0)
            measured = [render(RIG, CAMERA, robots, scene, np.random.default_rng(seed))[1] for seed in range(3)]
        for a, b in zip(skipping, measured):
            assert np.array_equal(a, b)
            assert not a[:100].any() and a[300:].any()    # nothing reads high up; the floor in range does
    u = round(RIG.camera.cx - RIG.camera.fx * 1.0 / 4.4)
    assert np.count_nonzero(skipping[0][150:250, u - 2:u + 3]) > 100      # the pole reads


def _crowd() -> tuple[list, Scene]:
    """Robots on a grid in front of the camera (near ones big, far ones a few pixels, many overlapping)
    between two poles, in a room."""
    robots = [(1.2 + 0.9 * i, -2.4 + 0.8 * j + 0.3 * (i % 2), math.radians(37.0 * (i * 7 + j)))
              for i in range(9) for j in range(7)]
    room = (Wall(-1, -6, 12, -6), Wall(12, -6, 12, 6), Wall(12, 6, -1, 6))
    poles = (CylinderProp(3.0, 0.5, 0.2, 0.0, 1.0, (200, 30, 35)), CylinderProp(6.5, -1.0, 0.3, 0.0, 0.8, (90, 90, 200)))
    # low pucks (their tops in sight) and cylinders hanging above the camera (their undersides in sight)
    caps = tuple(CylinderProp(1.5 + 1.1 * i, -2.0 + 0.9 * i, 0.06, 0.0 if i % 2 else 0.5, 0.1 if i % 2 else 0.7,
                              (60, 160, 60)) for i in range(6))
    return robots, Scene(walls=room, props=poles + caps)


@pytest.mark.parametrize("count", [False, True])
def test_small_cylinders_drawn_together_give_the_pixels_of_drawing_each_in_its_band(monkeypatch, count):
    """Far, small cylinders are z-buffered all at once (``_draw_small_cylinders``); the frame, the marker
    pixel counts and the projector shadows must be exactly what drawing them one by one gives."""
    from robot_bridge.sim import camera
    from robot_bridge.sim.camera import objects

    monkeypatch.setattr(objects, "_ZBUFFER", None)        # numpy draws (test_zbuffer compares the compiled loop)
    batched = []
    spy = objects._draw_small_cylinders
    monkeypatch.setattr(objects, "_draw_small_cylinders", lambda r, drawn, batch, *a: (batched.append(len(batch)),
                                                                                      spy(r, drawn, batch, *a)))
    robots, scene = _crowd()
    samples = [(RIG, CAMERA, robots, scene)] + [(s.rig, s.camera_pose, s.robots, s.scene)
                                                for s in map(random_scene, range(12))]
    for rig, pose, robots, scene in samples:
        frames = []
        for limit in (0, objects._BATCH_PX, 10 ** 9):          # one by one, as shipped, all together
            monkeypatch.setattr(objects, "_BATCH_PX", limit)
            frames.append(camera._render(rig, pose, robots, scene, np.random.default_rng(3), count=count))
        for rgb, depth, pixels in frames[1:]:
            assert np.array_equal(rgb, frames[0][0]) and np.array_equal(depth, frames[0][1])
            assert pixels == frames[0][2]
    assert max(batched) >= 40          # the crowd's far cylinders went through the batch
