"""``faultmas ros launch --robots faulty,helper [--fault X] [--domain-id N]``: the ROS 2 nodes of a team.

Called by ``robot_bridge/cli.py`` (``add_ros_parser``). Imports rclpy only when the command runs, and
without ROS installed prints the one-line install hint instead of a traceback.
"""
from __future__ import annotations

import argparse
import sys


def add_ros_parser(subparsers: argparse._SubParsersAction) -> None:
    """Register ``faultmas ros launch``."""
    ros = subparsers.add_parser("ros", help="run the ROS 2 Jazzy nodes (extra 'ros2')")
    ros_sub = ros.add_subparsers(dest="ros_command", metavar="ROS_COMMAND")
    ros.set_defaults(func=lambda args: (ros.print_help(), 2)[1])
    launch = ros_sub.add_parser("launch", help="start every node of every robot; Ctrl-C stops them",
                                description=__doc__.splitlines()[0])
    launch.add_argument("--robots", default="faulty,helper", help="comma-separated robot names (namespaces)")
    launch.add_argument("--fault", default="none",
                        help="fault injected into the first robot, e.g. encoders or left_actuator:0.5")
    launch.add_argument("--domain-id", type=int, default=None, help="ROS_DOMAIN_ID (default: the environment's)")
    launch.add_argument("--no-camera", action="store_true", help="no camera_sim / visual_synthesizer nodes")
    launch.add_argument("--duration", type=float, default=None, help="stop after this many seconds")
    launch.add_argument("--ready-timeout", type=float, default=60.0, help="seconds to wait for every node")
    launch.set_defaults(func=_launch)


add_parser = add_ros_parser


def _launch(args: argparse.Namespace) -> int:
    from robot_bridge.ros2.runtime import ROS_HINT
    try:
        import rclpy  # noqa: F401
    except ImportError as exc:
        print(f"error: {ROS_HINT} ({exc})", file=sys.stderr)
        return 2
    from robot_bridge.ros2 import launch
    robots = [r.strip() for r in args.robots.split(",") if r.strip()]
    try:
        launch.plan(robots, args.fault)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    return launch.run(robots, args.fault, args.domain_id, camera=not args.no_camera,
                      duration=args.duration, ready_timeout=args.ready_timeout)
