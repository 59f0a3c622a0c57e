"""``faultmas run``: the main job.

Until the cooperative Faulty/Helper demonstration lands (issue 7), this runs one robot agent
(``plans/go_to_destination.asl``) on the embedded simulator with an injected fault, so that
``make run`` on a fresh machine shows the interpreter, a robot bridge and fault detection working.
"""
from __future__ import annotations

import argparse
import logging
import sys
from importlib import resources

FAULTS = ("none", "encoders", "both_actuators", "left_actuator", "right_actuator", "stuck_wheels")


def add_parser(sub: argparse._SubParsersAction) -> None:
    run = sub.add_parser("run", help="the main job: a robot with a fault on the embedded simulator")
    run.add_argument("--fault", choices=FAULTS, default="encoders")
    run.add_argument("--seed", type=int, default=1)
    run.add_argument("--timeout", type=float, default=60.0)
    run.set_defaults(func=cmd_run)


def cmd_run(args) -> int:
    from agentspeak.parser import parse_program
    from agentspeak.runtime import LocalRuntime
    from agents.robot_arch import RobotArch
    from robot_bridge.registry import create

    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    source = resources.files("plans").joinpath("go_to_destination.asl")
    program = parse_program(source.read_text(), str(source))
    bridge = create("sim", "faulty", seed=args.seed, fault=args.fault)
    bridge.setup(timeout=5.0)
    print(f"faultmas: robot 'faulty' on the embedded simulator, fault injected: {args.fault}", flush=True)
    runtime = LocalRuntime()
    try:
        runtime.add_agent("faulty", program=program, source_file=str(source), arch=RobotArch(runtime, bridge))
        reason = runtime.run(timeout=args.timeout)
    finally:
        bridge.shutdown()
    if reason == "timeout":
        print(f"faultmas: stopped after {args.timeout} s", file=sys.stderr)
    return 0
