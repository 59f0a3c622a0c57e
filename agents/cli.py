"""The ``faultmas`` command: one sub-command per job, each owned by the package that does the job.

The table below is the whole list (explicit, no module scanning). Each module has
``add_parser(subparsers)``; it imports heavy libraries (OpenCV, rclpy, Zenoh) only inside the
function that runs, so ``faultmas --help`` stays fast and works without ROS.
"""
from __future__ import annotations

import argparse
import importlib
import sys
from typing import Sequence

SUBCOMMAND_MODULES: tuple[str, ...] = (
    "agentspeak.cli",          # faultmas asl check|run
    "agents.mas_cli",          # faultmas mas run, faultmas agent run, faultmas router
    "diagnosis.cli",           # faultmas diagnose
    "detection.cli",           # faultmas observe
    "perception.cli",          # faultmas perceive
    "robot_bridge.cli",        # faultmas ros launch, faultmas sim ...
    "agents.demo_cli",         # faultmas run, faultmas eval
    "experiments.cli",         # faultmas experiment NAME (experiments/cli.py lists them)
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="faultmas", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name != name:      # a real missing dependency: say so, do not hide it
                raise
            continue                  # that part of the framework is not built yet
        module.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())
