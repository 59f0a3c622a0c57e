"""``faultmas observe [CONFIG.yaml] [--learned MODELS_DIR] [--model ARCH.yaml] [--rules RULES.yaml] [--bag PATH] [--json]``.

Runs the observers (live on the ROS 2 graph, on Zenoh with ``--zenoh``, or over a recorded bag), the
diagnoser and the rules together (with ``--learned``, the learned ``resource`` observer too); each change is also published as JSON on the ROS 2 topic
``/observers/info`` (on the Zenoh key ``faultmas/observers/info`` with ``--zenoh``). On a terminal a status table refreshes in place; otherwise one line per change (``--json``:
one JSON object per change). Ctrl-C ends it cleanly. Exit status: 0 done, 2 bad input (configuration,
model, rules, bag, models), 3 ROS 2 missing.
"""
from __future__ import annotations

import argparse


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("observe", help="watch a running system: observers, diagnosis and rules",
                              description="Watch a running system: observers (and, with --learned, the learned "
                              "resource observer of performance bugs), diagnosis and rules together, live on the "
                              "ROS 2 graph, on Zenoh, or over a recorded bag.",
                              epilog="Configuration format: docs/observers.md. Learned models: docs/perfbugs.md. "
                              "Example: faultmas observe --learned models/ --domain-id 42")
    p.add_argument("config", metavar="CONFIG.yaml", nargs="?",
                   help="observer configuration (docs/observers.md); may be left out with --learned")
    p.add_argument("--learned", metavar="MODELS_DIR",
                   help="also run the learned resource observer (docs/perfbugs.md) with the models in MODELS_DIR "
                   "('faultmas experiment perfbugs --save-models MODELS_DIR'); it emits ~resource(C) into the same "
                   "diagnoser and rules. Live it shares the observers' subscriptions (ROS 2) or session (--zenoh: "
                   "the agents' keys); with --bag it replays a bag recorded with --learned and --record. Without "
                   "--model the architecture is the one discovered (or, with --bag, the models' own)")
    p.add_argument("--model", metavar="ARCH.yaml", help="architecture model: diagnose what is observed")
    p.add_argument("--rules", metavar="RULES.yaml",
                   help="rules to fire (default: the model's NAME.rules.yaml when it exists)")
    p.add_argument("--bag", metavar="PATH", help="replay a rosbag2 (MCAP or sqlite3) instead of watching live")
    p.add_argument("--json", action="store_true", help="one JSON object per change")
    p.add_argument("--zenoh", action="store_true",
                   help="watch Zenoh key expressions and liveliness tokens instead of the ROS 2 graph")
    p.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                   help="with --zenoh, or --learned with models of agents: a Zenoh endpoint to connect to, "
                   "e.g. tcp/127.0.0.1:7447 (repeatable)")
    p.add_argument("--record", metavar="PATH", help="live ROS 2: also record what is observed (with --learned: its topics and ticks too) "
                   "to a new MCAP bag")
    p.add_argument("--domain-id", type=int, default=None, help="ROS_DOMAIN_ID (default: the environment's)")
    p.add_argument("--duration", type=float, default=None, metavar="S", help="live: stop after S seconds")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from detection.observe import observe
    return observe(args)
