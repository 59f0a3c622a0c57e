"""``faultmas perceive``: run the cylinder detector on one RGB-D frame stored as files.

    faultmas perceive --rgb IMG.png --depth DEPTH.npy [--hfov 57 --vfov 43] [--json] [--all]

IMG.png is a colour image as ``cv2.imwrite`` writes it (BGR order on disk); DEPTH.npy a float32 array
of metres with 0 for no reading (NaN is read as no reading; uint16 is read as millimetres, as in ROS
16UC1). Unreadable files and mismatched sizes exit with status 2 and a message naming the file.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Sequence


class InputError(Exception):
    """A file given on the command line that cannot be used; the message names it."""


def add_parser(subparsers) -> None:
    p = subparsers.add_parser(
        "perceive", help="find a robot by its two coloured cylinders in one RGB-D frame",
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="Output: robot(Name,Angle,Depth,Yaw), or JSON with --json. Angle: bearing from the optical axis "
               "in degrees, counter-clockwise (left) positive, as the robot_seen percept (turn(Angle) faces the "
               "robot; the seed paper's formula has the opposite sign); Depth in metres; Yaw: the robot's heading "
               "relative to the camera's, counter-clockwise positive.")
    p.add_argument("--rgb", required=True, metavar="IMG.png", help="colour image (BGR PNG from cv2.imwrite)")
    p.add_argument("--depth", required=True, metavar="DEPTH.npy", help="float32 metres, 0 = no reading")
    p.add_argument("--hfov", type=float, default=57.0, help="horizontal field of view, degrees (default 57)")
    p.add_argument("--vfov", type=float, default=43.0, help="vertical field of view, degrees (default 43)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--all", action="store_true", help="report every robot in view (JSON: a 'robots' list)")
    p.add_argument("--name", default="robot", help="name used in the robot(...) literal (default: robot)")
    p.set_defaults(func=run)


def load_frame(rgb_path: str, depth_path: str):
    """(rgb HxWx3 uint8 RGB, depth HxW float32 m) from files, or InputError naming the bad file."""
    import cv2
    import numpy as np

    for path in (rgb_path, depth_path):
        if not os.path.isfile(path):
            raise InputError(f"{path}: no such file")
    bgr = cv2.imread(rgb_path, cv2.IMREAD_COLOR)
    if bgr is None:
        raise InputError(f"{rgb_path}: cannot read it as an image (expected a colour PNG)")
    try:
        # mapped, not read: a header claiming a huge shape costs nothing until the shape is checked below
        depth = np.load(depth_path, allow_pickle=False, mmap_mode="r")
    except Exception as exc:  # numpy's header reader raises SyntaxError, tokenize.TokenError, ValueError, ...
        raise InputError(f"{depth_path}: cannot read it as a .npy array ({type(exc).__name__}: "
                         f"{str(exc)[:120]})") from None
    if depth.ndim == 3 and depth.shape[2] == 1:
        depth = depth[:, :, 0]
    if depth.ndim != 2:
        raise InputError(f"{depth_path}: expected a 2-D depth array (H x W), got shape {depth.shape}")
    if depth.shape != bgr.shape[:2]:
        raise InputError(f"{depth_path}: depth is {depth.shape[1]}x{depth.shape[0]} but {rgb_path} is "
                         f"{bgr.shape[1]}x{bgr.shape[0]}; they must be registered (same size)")
    depth = np.array(depth)  # into memory, now that its size is the image's
    if depth.dtype == np.uint16:
        depth = depth.astype(np.float32) / 1000.0                 # 16UC1 millimetres
    elif depth.dtype.kind == "f":
        depth = np.nan_to_num(depth.astype(np.float32), nan=0.0, posinf=0.0, neginf=0.0)
    else:
        raise InputError(f"{depth_path}: expected float32 metres (or uint16 millimetres), got {depth.dtype}")
    return cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), np.where(depth > 0, depth, 0).astype(np.float32)


def run(args: argparse.Namespace) -> int:
    from perception.camera import CameraModel
    from perception.detect import detect, detect_all

    try:
        rgb, depth = load_frame(args.rgb, args.depth)
        camera = CameraModel.from_fov(args.hfov, args.vfov, rgb.shape[1], rgb.shape[0])
    except (InputError, ValueError) as exc:
        print(f"faultmas perceive: error: {exc}", file=sys.stderr)
        return 2
    result = (detect_all if args.all else detect)(rgb, depth, camera)
    if args.json:
        out: dict = {"found": result.found}
        if result.found:
            out.update(_fields(result.detection))
        else:
            out["reason"] = result.reason
        if args.all:
            out["robots"] = [_fields(d) for d in result.all]
        print(json.dumps(out))
    elif result.found:
        for d in (result.all if args.all else (result.detection,)):
            print(f"robot({args.name},{-d.angle_deg:.0f},{d.depth_m:.2f},{-d.yaw_deg:.0f})")
    else:
        print(f"no robot: {result.reason}")
    return 0


def _fields(d) -> dict:
    # the percepts' convention (robot_seen): counter-clockwise (left) positive; the detector's optical frame
    # (perception.detect) is +right, as image x grows
    return {"angle_deg": round(-d.angle_deg, 3), "depth_m": round(d.depth_m, 4), "yaw_deg": round(-d.yaw_deg, 2),
            "x_m": round(d.x_m, 4), "confidence": d.confidence,
            "front_px": [round(v, 1) for v in d.front_px], "rear_px": [round(v, 1) for v in d.rear_px]}


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="faultmas")
    add_parser(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(["perceive", *(sys.argv[1:] if argv is None else argv)])
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
