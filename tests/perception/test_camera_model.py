"""CameraModel: FOV and intrinsics agree; projection and back-projection are inverse."""
import math

import numpy as np
import pytest

from perception.camera import CameraModel


def test_kinect_intrinsics_match_its_field_of_view():
    cam = CameraModel.kinect()
    assert (cam.width, cam.height) == (640, 480)
    assert cam.fx == pytest.approx(320 / math.tan(math.radians(28.5)))
    assert cam.hfov_deg == pytest.approx(57.0) and cam.vfov_deg == pytest.approx(43.0)
    assert (cam.cx, cam.cy) == (319.5, 239.5)


def test_project_backproject_round_trip():
    cam = CameraModel.from_fov(60, 45, 320, 240)
    pts = np.array([[0.3, -0.2, 2.0], [-1.0, 0.5, 4.0], [0.0, 0.0, 1.0]])
    uv = cam.project(pts)
    assert uv[2] == pytest.approx([cam.cx, cam.cy])
    assert cam.backproject(uv[:, 0], uv[:, 1], pts[:, 2]) == pytest.approx(pts)
    # x right, y down: a point right and below the axis lands right and below the centre
    assert uv[0, 0] > cam.cx and uv[0, 1] < cam.cy


def test_bearing_is_atan2_of_x_and_z():
    cam = CameraModel.kinect()
    u = cam.project(np.array([1.0, 0.0, 2.0]))[0]
    assert cam.bearing_deg(u) == pytest.approx(math.degrees(math.atan2(1.0, 2.0)))
    assert cam.bearing_deg(cam.width - 0.5) == pytest.approx(28.5, abs=1e-9)


def test_invalid_models_are_rejected():
    with pytest.raises(ValueError):
        CameraModel.from_fov(0, 43)
    with pytest.raises(ValueError):
        CameraModel(640, 480, -1.0, 500.0, 319.5, 239.5)
