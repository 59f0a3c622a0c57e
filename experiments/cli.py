"""``faultmas experiment NAME ...``: the registry of experiments, one line each.

Each module has ``add_arguments(parser)`` and ``run(args) -> int`` and imports its heavy libraries
inside ``run``, so ``faultmas --help`` stays fast.
"""
from __future__ import annotations

import argparse
import importlib

EXPERIMENTS: dict[str, str] = {
    "perfbugs": "experiments.perfbugs",     # Wienke & Wrede's Table I on faultmas' own team
}


def add_parser(subparsers) -> None:
    parser = subparsers.add_parser("experiment", help="reproduce a paper's table (see docs/)",
                                   description=__doc__.splitlines()[0])
    names = parser.add_subparsers(dest="experiment", metavar="NAME")
    for name, module_name in EXPERIMENTS.items():
        module = importlib.import_module(module_name)
        sub = names.add_parser(name, help=module.__doc__.splitlines()[0], description=module.__doc__,
                               formatter_class=argparse.RawDescriptionHelpFormatter)
        module.add_arguments(sub)
        sub.set_defaults(func=module.run)
    parser.set_defaults(func=lambda args: parser.print_help() or 2)
