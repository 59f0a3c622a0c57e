"""``faultmas experiment NAME``: run an experiment that reproduces a paper's table.

``EXPERIMENTS`` is the whole list (explicit, like ``agents.cli``): name -> (module, one-line help).
Each module has ``add_arguments(parser)`` and ``main(args) -> int``, and keeps its heavy imports
(numpy, rclpy, the detection pipeline) inside ``main``, so building the parser stays cheap.
"""
from __future__ import annotations

import argparse
import importlib

EXPERIMENTS: dict[str, tuple[str, str]] = {
    "imu": ("experiments.imu", "TU Graz use case: a faulty IMU found by an observer and switched off by a rule"),
    "perfbugs": ("experiments.perfbugs", "Wienke & Wrede's Table I: learned detection of performance bugs vs OCSVM"),
}


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser("experiment", help="run an experiment that reproduces a paper's table",
                                   description=__doc__.splitlines()[0])
    names = parser.add_subparsers(dest="experiment", metavar="NAME")
    for name, (module_name, help_text) in EXPERIMENTS.items():
        module = importlib.import_module(module_name)
        sub = names.add_parser(name, help=help_text, description=help_text)
        module.add_arguments(sub)
        sub.set_defaults(func=module.main)
    parser.set_defaults(func=lambda args: _usage(parser))


def _usage(parser: argparse.ArgumentParser) -> int:
    parser.print_help()
    return 2
