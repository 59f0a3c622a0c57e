"""faultmas perceive: the JSON contract, readable messages and exit status 2 on bad files."""
import json
import math
import subprocess
import sys

import cv2
import numpy as np
import pytest

from perception.cli import main
from robot_bridge.sim.camera import CameraRig, Scene, render, true_view

RIG = CameraRig(mount_x_m=0.0)
ROBOT = (2.4, 0.4, math.radians(-60))


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("frame")
    rgb, depth = render(RIG, (0.0, 0.0, 0.0), [ROBOT], Scene(), np.random.default_rng(4))
    cv2.imwrite(str(d / "img.png"), cv2.cvtColor(rgb, cv2.COLOR_RGB2BGR))
    np.save(d / "depth.npy", depth)
    np.save(d / "small.npy", depth[:240, :320])
    np.save(d / "empty.npy", np.zeros_like(depth))
    cv2.imwrite(str(d / "grey.png"), np.full((480, 640, 3), 100, np.uint8))
    (d / "junk.npy").write_bytes(b"not numpy")
    return d


def test_json_output_matches_ground_truth(files, capsys):
    assert main(["--rgb", str(files / "img.png"), "--depth", str(files / "depth.npy"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    truth = true_view(RIG, (0.0, 0.0, 0.0), ROBOT)
    assert out["found"] is True
    # one angle convention everywhere: counter-clockwise (left) positive, as the robot_seen percept;
    # true_view answers in the optical frame (+right)
    assert abs(truth.angle_deg) > 3 and out["angle_deg"] == pytest.approx(-truth.angle_deg, abs=0.3)
    assert out["depth_m"] == pytest.approx(truth.depth_m, abs=0.03)
    assert out["yaw_deg"] == pytest.approx(-truth.yaw_deg, abs=6)


def test_not_found_reports_a_reason(files, capsys):
    assert main(["--rgb", str(files / "grey.png"), "--depth", str(files / "empty.npy"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == {"found": False, "reason": "no_orange_blob"}


def test_literal_output(files, capsys):
    assert main(["--rgb", str(files / "img.png"), "--depth", str(files / "depth.npy"), "--name", "faulty"]) == 0
    assert capsys.readouterr().out.startswith("robot(faulty,")


@pytest.mark.parametrize("rgb,depth,message", [
    ("missing.png", "depth.npy", "missing.png: no such file"),
    ("img.png", "junk.npy", "junk.npy: cannot read"),
    ("img.png", "small.npy", "small.npy: depth is 320x240"),
    ("depth.npy", "depth.npy", "cannot read it as an image"),
])
def test_bad_files_exit_2_naming_the_file(files, capsys, rgb, depth, message):
    assert main(["--rgb", str(files / rgb), "--depth", str(files / depth), "--json"]) == 2
    assert message in capsys.readouterr().err


def test_through_the_faultmas_command(files):
    cmd = [sys.executable, "-m", "agents.cli", "perceive", "--rgb", str(files / "img.png"),
           "--depth", str(files / "depth.npy"), "--hfov", "57", "--vfov", "43", "--json"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["found"] is True
