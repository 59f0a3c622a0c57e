"""``faultmas agent run FILE.asl --name N --mas M``: one agent that joins a MAS over Zenoh.

The agent runs until ``.stopMAS`` (from any process of the MAS), SIGINT/SIGTERM or ``--timeout``; it
never stops just because it is idle (others may still talk to it). ``faultmas mas run --processes``
starts one of these per agent, with ``--project`` (trust, initial beliefs/goals) and
``--wait-for-peers`` (start reasoning only once every agent of the project is reachable).
Exit code: 0 after a stop, 124 after ``--timeout``, 2 for bad input, 1 if the network cannot be joined.
"""
from __future__ import annotations

import argparse
import logging
import signal
import sys

from agents.environment import add_bridge_arguments

log = logging.getLogger("faultmas.agents")

EXIT_TIMEOUT = 124


def add_agent_parser(sub: argparse._SubParsersAction) -> None:
    """Register ``faultmas agent run`` on the CLI dispatcher's sub-parsers."""
    agent = sub.add_parser("agent", help="run one agent that joins a MAS over Zenoh")
    agent_sub = agent.add_subparsers(dest="agent_command", metavar="ACTION")
    run = agent_sub.add_parser("run", help="run FILE.asl as agent NAME of MAS M")
    run.add_argument("file", metavar="FILE.asl", help="the agent's program")
    run.add_argument("--name", required=True, help="the agent's name")
    run.add_argument("--mas", required=True, help="the MAS to join (its namespace on the network)")
    run.add_argument("--connect", action="append", default=[], metavar="ENDPOINT",
                     help="a peer or router to connect to, e.g. tcp/127.0.0.1:7447 (repeatable)")
    run.add_argument("--listen", action="append", default=None, metavar="ENDPOINT",
                     help="endpoint to listen on (repeatable; default: a free loopback port)")
    run.add_argument("--mode", choices=("peer", "client"), default="peer", help="Zenoh mode (default peer)")
    run.add_argument("--config", default=None, metavar="FILE", help="Zenoh JSON5 file (TLS, access control)")
    run.add_argument("--project", default=None, metavar="PROJECT.mas2j",
                     help="the project file: its agents may send plans; initial beliefs/goals of NAME")
    run.add_argument("--identity", default=None, metavar="KEY.pem",
                     help="the agent's private key in the secure profile (a project whose agents have key= "
                          "options; default: the .key file beside NAME's public key)")
    run.add_argument("--allow-code-from", action="append", default=[], metavar="AGENT",
                     help="also accept tellHow (plans) from AGENT (repeatable)")
    run.add_argument("--max-message-size", type=int, default=None, metavar="BYTES",
                     help="drop received messages larger than this (default 256 KiB)")
    run.add_argument("--wait-for-peers", type=float, default=0.0, metavar="S",
                     help="with --project: wait up to S seconds until every project agent is reachable")
    run.add_argument("--timeout", type=float, default=None, metavar="S", help="stop after S seconds")
    add_bridge_arguments(run, default=None, bridge_help=(
        "drive a robot through this bridge (any installed one, see `faultmas sim bridges`: e.g. zenoh for a "
        "simulator served by `faultmas sim serve`, or ros2); the robot has the agent's name; default: the "
        "--project's environment, if it names a bridge"))
    run.add_argument("--allow-pause", action="store_true",
                     help="let `faultmas inspect` pause and step this agent (read-only otherwise)")
    run.set_defaults(func=cmd_agent_run)
    agent.set_defaults(func=lambda args: (agent.print_help(), 2)[1])


def option_literals(text: str | None, file: str) -> list:
    """The literals of a ``beliefs=``/``goals=`` option of a project file."""
    if not text:
        return []
    from agentspeak.parser import parse_term
    from agentspeak.terms import list_items
    return list_items(parse_term(f"[{text}]"))


def declaration_option_literals(project, decl) -> tuple[list, list]:
    """``(beliefs, goals)`` of one agent declaration of ``project`` (``option_literals`` of its options), kept in
    the parse cache (``agentspeak.parse_cache``): a project run again never imports the parser for them (in a
    10-agent ring with a ``beliefs=`` option each, importing the parser and loading its tables for those was a
    third of the whole run). One declaration at a time: an agent process reads only its own options, so another
    agent's bad option fails that agent alone."""
    beliefs, goals = decl.options.get("beliefs"), decl.options.get("goals")
    if not (beliefs or goals):
        return [], []
    from agentspeak.parse_cache import cached
    from agentspeak.stdlib.registry import FUNCTIONS

    def parse() -> tuple[list, list]:
        return option_literals(beliefs, project.file), option_literals(goals, project.file)
    # the literals depend on the texts and on which arithmetic functions are registered, as programs do
    return cached("options", repr((beliefs, goals)), project.file, tuple(sorted(FUNCTIONS.functions)), parse)


def project_option_literals(project) -> list[tuple[list, list]]:
    """``declaration_option_literals`` of every agent declaration of ``project``, in order."""
    return [declaration_option_literals(project, decl) for decl in project.agents]


def cmd_agent_run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from agents.transport import ZenohOptions, ZenohTransport
    from agents.transport.envelope import DEFAULT_MAX_SIZE
    from agents.transport.identity import IdentityError, project_identity
    from agents.transport.keys import check_name
    from agents.zenoh_arch import TransportBridge
    from agentspeak.errors import AslSyntaxError, SourceError
    from agentspeak.mas2j import load_mas2j
    from agentspeak.parser import parse_program
    from agentspeak.runtime import LocalRuntime
    from agentspeak.source_text import read_source

    try:
        check_name(args.name)
        check_name(args.mas, "MAS name")
        source = read_source(args.file)
        project = None
        declared: list[str] = [args.name]
        beliefs: list = []
        goals: list = []
        source_dirs: list[str] = []
        if args.project:
            # sources, includes and .create_agent resolve as in the in-process run of the project
            project = load_mas2j(args.project)
            source_dirs = project.source_dirs
            declared = project.agent_names()
            for decl in project.agents:
                if args.name in decl.instance_names():
                    beliefs, goals = declaration_option_literals(project, decl)
        identity = None
        if args.project:
            identity = project_identity(project, [args.name], args.identity)
        elif args.identity:
            raise IdentityError("--identity needs --project (the project lists the members' public keys)")
        program = parse_program(source, args.file, source_path=tuple(source_dirs))
        options = ZenohOptions(mode=args.mode, listen=tuple(args.listen) if args.listen else None,
                               connect=tuple(args.connect), config_file=args.config)
    except OSError as exc:
        print(f"{exc.filename}: cannot read: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except (AslSyntaxError, SourceError, ValueError) as exc:  # IdentityError too
        print(exc, file=sys.stderr)
        return 2
    from agents.environment import choose_bridge
    try:
        choice = choose_bridge(project, args.bridge, args.bridge_option)
    except ValueError as exc:
        print(f"faultmas agent run: {exc}", file=sys.stderr)
        return 2
    runtime = LocalRuntime()
    runtime.source_dirs = list(source_dirs)
    transport = ZenohTransport(args.mas, options, max_message_size=args.max_message_size or DEFAULT_MAX_SIZE,
                               identity=identity)
    try:
        transport.open()
    except Exception as exc:  # zenoh.ZError: bad endpoint, port taken
        print(f"faultmas agent run: cannot join the network: {exc}", file=sys.stderr)
        return 1
    robot = None
    if choice is not None:
        try:
            robot = _open_robot(choice, args, transport)
        except Exception as exc:  # robot silent, bad option value: say which, exit 1
            transport.close()
            print(f"faultmas agent run: robot {args.name} via bridge {choice.name!r}: {exc}", file=sys.stderr)
            return 1
    from agents.robot_arch import RobotArch
    runtime.add_agent(args.name, source_file=args.file, program=program, extra_beliefs=beliefs,
                      extra_goals=goals, arch=RobotArch(runtime, robot) if robot is not None else None)
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, lambda *_: runtime.stop())
    from agents.memory_trace import agent_holdings, start_from_environment
    memory_trace = start_from_environment(args.name, lambda: agent_holdings(runtime))     # None unless FAULTMAS_MEMTRACE_DIR asks (a leak hunt)
    try:
        bridge = TransportBridge(runtime, transport, declared=declared, allowed_code_senders=args.allow_code_from,
                                 members=declared if args.project else None).attach()
        from agents.inspector.publisher import MindPublisher  # state on demand for `faultmas inspect`
        inspected = MindPublisher(transport, runtime, bridge, allow_control=args.allow_pause).start()
        if args.wait_for_peers > 0 and not bridge.wait_for_peers(declared, args.wait_for_peers) \
                and not runtime.stop_requested():
            missing = sorted(set(declared) - transport.alive_agents() - bridge.dead)
            log.warning("agent %s: still missing after %.0f s: %s; starting anyway", args.name,
                        args.wait_for_peers, ", ".join(missing))
        why = bridge.run(timeout=args.timeout)
        inspected.close()
        bridge.detach()
    finally:
        if robot is not None:
            robot.shutdown()
        transport.close()
        _report_drops(args.name, transport.dropped)
        if memory_trace is not None:
            memory_trace.stop()
    return EXIT_TIMEOUT if why == "timeout" else 0


def _report_drops(name: str, dropped: dict) -> None:
    """One summary line of refused messages by reason (each one was also logged when it came)."""
    if dropped:
        reasons = ", ".join(f"{reason}={count}" for reason, count in sorted(dropped.items()))
        log.warning("agent %s: dropped %d messages (%s)", name, sum(dropped.values()), reasons)


def _open_robot(choice, args: argparse.Namespace, transport):
    """Create and set up the agent's robot bridge; a ``zenoh`` bridge shares the agent's session unless it
    is told to ``connect`` elsewhere (e.g. to a ``faultmas sim serve`` of another MAS name). In the secure profile
    a ``zenoh`` bridge signs the robot's actions and checks that the environment signed the rest."""
    from robot_bridge.registry import create

    options = dict(choice.options)
    sealed = None
    if choice.name == "zenoh":
        options.setdefault("mas", args.mas)
        if not options.get("connect"):
            options.setdefault("session", transport.session)
        if transport.identity is not None:
            from agents.transport.identity import ENVIRONMENT, IdentityError
            if ENVIRONMENT not in transport.identity.public_keys:
                raise IdentityError("the project lists no key for the environment, so the robot's percepts "
                                    'cannot be checked: add one to its environment line, e.g. environment: '
                                    'sim("key=keys/environment.pub")')
            sealed = transport.sealed_channel()
    elif choice.name == "sim":
        log.warning("agent %s: bridge sim in a process of its own is a world with one robot; for a shared world "
                    "run `faultmas sim serve` and give the agents --bridge zenoh", args.name)
    elif transport.identity is not None:   # ros2, a plug-in: its own middleware, not signed by faultmas
        log.warning("agent %s: bridge %s is not covered by the secure profile: what goes between the agent and its "
                    "robot is not signed (docs/reliability.md, \"Identity\")", args.name, choice.name)
    bridge = create(choice.name, args.name, **options)
    if sealed is not None:
        bridge.sealed = sealed
    bridge.setup(timeout=args.bridge_timeout)
    return bridge
