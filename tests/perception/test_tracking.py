"""Tracker: one bad frame never loses the robot; N misses do; smoothing and outlier gates."""
import pytest

from perception.detect import Detection, DetectionResult
from perception.tracking import Tracker


def _det(angle=0.0, depth=2.0, yaw=0.0):
    return Detection(angle_deg=angle, depth_m=depth, yaw_deg=yaw, x_m=0.0, z_m=depth, front_px=(0, 0),
                     rear_px=(0, 0), spacing_m=0.227, confidence=1.0, front=None, rear=None)


MISS = DetectionResult(None, "no_orange_blob")


def test_never_seen_is_lost():
    state = Tracker(lost_after=3).update(MISS)
    assert state.lost and not state.visible and state.angle_deg is None


def test_single_missed_frame_keeps_the_track_and_n_misses_lose_it():
    tr = Tracker(lost_after=3)
    assert tr.update(DetectionResult(_det(5.0), "")).visible
    for k in (1, 2):
        s = tr.update(MISS)
        assert not s.lost and not s.visible and s.missed == k and s.angle_deg == pytest.approx(5.0)
    s = tr.update(MISS)
    assert s.lost and s.angle_deg is None
    s = tr.update(_det(-3.0))                                # re-acquired from scratch
    assert s.visible and not s.lost and s.angle_deg == pytest.approx(-3.0)


def test_smoothing_and_heading_wraps_around():
    tr = Tracker(alpha=0.5)
    tr.update(_det(0.0, 2.0, 170.0))
    s = tr.update(_det(2.0, 2.2, -170.0))
    assert s.angle_deg == pytest.approx(1.0) and s.depth_m == pytest.approx(2.1)
    assert abs(s.yaw_deg) == pytest.approx(180.0, abs=0.5)   # between 170 and -170 is 180, not 0


def test_one_outlier_is_ignored_but_a_confirmed_jump_is_followed():
    tr = Tracker(lost_after=5, alpha=1.0)
    tr.update(_det(0.0))
    s = tr.update(_det(25.0))                                # one wild frame
    assert not s.visible and s.angle_deg == pytest.approx(0.0) and not s.lost
    s = tr.update(_det(1.0))
    assert s.visible and s.angle_deg == pytest.approx(1.0)
    tr.update(_det(20.0))
    s = tr.update(_det(20.5))                                # the robot really is there now
    assert s.visible and s.angle_deg == pytest.approx(20.5)


def test_bad_parameters():
    with pytest.raises(ValueError):
        Tracker(lost_after=0)
    with pytest.raises(ValueError):
        Tracker(alpha=0.0)
