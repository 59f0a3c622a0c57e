"""``faultmas mas run PROJECT.mas2j``, ``faultmas agent run FILE.asl`` and ``faultmas router``.

In one process (the default) all agents share a ``LocalRuntime`` with an in-process mailbox (no
network: the ring benchmark stays fast). ``--processes`` runs one OS process per agent over Zenoh
(``agents.distributed``); ``faultmas agent run`` (``agents.agent_cli``) joins one agent to a MAS.
"""
from __future__ import annotations

import argparse
import logging
import sys

from agents.agent_cli import add_agent_parser, project_option_literals
from agents.environment import add_bridge_arguments
from agents.keys_cli import add_keys_parser
from agents.router import add_router_parser


def add_parser(sub: argparse._SubParsersAction) -> None:
    mas = sub.add_parser("mas", help="run a multi-agent system from a Jason project file")
    mas_sub = mas.add_subparsers(dest="mas_command", metavar="ACTION")
    run = mas_sub.add_parser("run", help="run every agent of PROJECT.mas2j")
    run.add_argument("project", metavar="PROJECT.mas2j", help="the Jason project file")
    run.add_argument("--timeout", type=float, default=None, help="stop after S seconds (always wins; exit code 124)")
    run.add_argument("--processes", action="store_true", help="one OS process per agent, over Zenoh")
    run.add_argument("--listen", action="append", default=None, metavar="ENDPOINT",
                     help="in one process: also be reachable over Zenoh here (agents elsewhere may join)")
    run.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                     help="in one process: also talk over Zenoh to agents reached through ENDPOINT")
    add_bridge_arguments(run, default=None, bridge_help=(
        "give every agent a robot through this bridge (any installed one, see `faultmas sim bridges`; default: "
        "the project's `environment:` if it names one); each agent drives the robot of its own name, and sim "
        "puts them all into one world"))
    run.set_defaults(func=cmd_mas_run)
    mas.set_defaults(func=lambda args: (mas.print_help(), 2)[1])
    add_agent_parser(sub)
    add_router_parser(sub)
    add_keys_parser(sub)


def setup_logging() -> None:
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)


def build_local_mas(project, printer=None, bridges: dict | None = None):
    """A LocalRuntime holding every agent of ``project`` (parse errors raise AslSyntaxError); an agent named in
    ``bridges`` (agent -> set-up ``RobotBridge``) drives that robot (``agents.robot_arch.RobotArch``)."""
    from pathlib import Path

    from agentspeak.parse_cache import cached_program
    from agentspeak.runtime import LocalRuntime
    from agentspeak.source_text import read_source

    runtime = LocalRuntime(printer=printer)
    runtime.trusted_senders = set(project.agent_names())
    runtime.source_dirs = list(project.source_dirs)
    programs: dict[str, object] = {}
    for decl, (beliefs, goals) in zip(project.agents, project_option_literals(project)):
        if decl.source not in programs:
            try:
                text = read_source(decl.source)
            except OSError as exc:
                from agentspeak.errors import SourceError
                raise SourceError(f"agent '{decl.name}': cannot read {decl.source}: {exc.strerror or exc}",
                                  project.file) from None
            programs[decl.source] = text
        for name in decl.instance_names():
            # each instance gets its own parse: plans hold per-agent labels and state
            program = cached_program(programs[decl.source], decl.source, tuple(project.source_dirs))
            arch = None
            if bridges and name in bridges:
                from agents.robot_arch import RobotArch
                arch = RobotArch(runtime, bridges[name])
            runtime.add_agent(name, source_file=decl.source, program=program,
                              extra_beliefs=beliefs, extra_goals=goals, arch=arch)
    return runtime


def cmd_mas_run(args) -> int:
    from agentspeak.errors import AslSyntaxError, SourceError
    from agentspeak.mas2j import load_mas2j
    setup_logging()
    try:
        project = load_mas2j(args.project)
    except OSError as exc:
        print(f"{args.project}: cannot read: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except AslSyntaxError as exc:
        print(exc, file=sys.stderr)
        return 2
    from agents.environment import choose_bridge, open_bridges
    try:
        choice = choose_bridge(project, args.bridge, args.bridge_option)
    except ValueError as exc:
        print(f"faultmas mas run: {exc}", file=sys.stderr)
        return 2
    if args.processes:
        from agents.distributed import run_processes
        return run_processes(project, timeout=args.timeout, bridge=choice, bridge_timeout=args.bridge_timeout)
    bridges: dict = {}
    try:
        if choice is not None:
            bridges = open_bridges(choice, project.agent_names(), args.bridge_timeout)
        try:
            runtime = build_local_mas(project, bridges=bridges)
        except (AslSyntaxError, SourceError) as exc:
            print(exc, file=sys.stderr)
            return 2
        if args.listen or args.connect:
            return _run_networked(runtime, project, args)
        # with robots the agents wait for motions and percepts: idle is not the end, --timeout or .stopMAS is
        why = runtime.run(timeout=args.timeout, stop_when_idle=not bridges)
    except Exception as exc:  # a robot that does not answer, a bad option value
        if choice is None or not isinstance(exc, (RuntimeError, TimeoutError, ValueError, OSError)):
            raise
        print(f"faultmas mas run: {exc}", file=sys.stderr)
        return 1
    finally:
        for bridge in bridges.values():
            bridge.shutdown()
    # The same exit codes as --processes (agents.distributed.EXIT_CODES): a run cut by --timeout
    # did not finish, and scripts must be able to tell; .stopMAS(_, Code) exits with Code, as Jason does.
    return 124 if why == "timeout" else runtime.exit_code


def _run_networked(runtime, project, args) -> int:
    """All agents in this process, also reachable over Zenoh; ends on .stopMAS or --timeout (not on
    idle: agents elsewhere may still talk). Exit 0 after a stop, 124 after the timeout."""
    from agents.transport import ZenohOptions, ZenohTransport
    from agents.zenoh_arch import TransportBridge

    from agents.transport.identity import IdentityError, project_identity

    options = ZenohOptions(listen=tuple(args.listen) if args.listen else None, connect=tuple(args.connect))
    try:
        identity = project_identity(project, project.agent_names())
    except IdentityError as exc:
        print(exc, file=sys.stderr)
        return 2
    with ZenohTransport(project.name, options, identity=identity) as transport:
        bridge = TransportBridge(runtime, transport, declared=project.agent_names(),
                                 members=project.agent_names()).attach()
        from agents.inspector.publisher import MindPublisher  # state on demand for `faultmas inspect`
        inspected = MindPublisher(transport, runtime, bridge).start()
        why = bridge.run(timeout=args.timeout)
        inspected.close()
        bridge.detach()
    return 124 if why == "timeout" else runtime.exit_code
