"""``faultmas asl check FILE...`` and ``faultmas asl run FILE.asl`` (and the in-process ``mas run``)."""
from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path


def add_parser(sub: argparse._SubParsersAction) -> None:
    asl = sub.add_parser("asl", help="check or run AgentSpeak programs")
    asl_sub = asl.add_subparsers(dest="asl_command", metavar="ACTION")
    check = asl_sub.add_parser("check", help="report every syntax error, unknown internal action and wrong arity "
                                             "in the files (exit 2 if any)")
    check.add_argument("files", nargs="+", metavar="FILE", help=".asl (or .mas2j) files to check")
    check.set_defaults(func=cmd_check)
    run = asl_sub.add_parser("run", help="run one agent until .stopMAS or until it is idle",
                             description="Run one agent until .stopMAS or until it is idle. The exit status is 0 "
                                         "even when a goal failed without a failure plan: as in Jason, the failure "
                                         "is reported on stderr and the agent goes on with its other intentions; "
                                         "2 for a file that cannot be read or parsed.")
    run.add_argument("file", metavar="FILE.asl", help="the agent's program")
    run.add_argument("--name", help="agent name (default: the file's stem)")
    run.add_argument("--timeout", type=float, default=None, help="stop after S seconds")
    run.set_defaults(func=cmd_run)
    asl.set_defaults(func=lambda args: (asl.print_help(), 2)[1])


def _setup_logging() -> None:
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)


def cmd_check(args) -> int:
    from agentspeak.errors import SourceError
    from agentspeak.parser import parse_program_all_errors
    from agentspeak.source_text import read_source
    _setup_logging()
    failed = 0
    for file in args.files:
        try:
            text = read_source(file)
        except OSError as exc:
            print(f"{file}: cannot read: {exc.strerror or exc}", file=sys.stderr)
            failed += 1
            continue
        except SourceError as exc:  # not UTF-8
            print(exc, file=sys.stderr)
            failed += 1
            continue
        if file.endswith(".mas2j"):
            from agentspeak.errors import AslSyntaxError
            from agentspeak.mas2j import parse_mas2j
            try:
                parse_mas2j(text, file)
            except AslSyntaxError as exc:
                print(exc, file=sys.stderr)
                failed += 1
            continue
        program, errors = parse_program_all_errors(text, file)
        if not errors:      # names and arities of internal actions, against the registry an agent runs with
            from agentspeak.lint import internal_action_problems
            errors = internal_action_problems(program)
        for err in errors:
            print(err, file=sys.stderr)
        for warning in program.warnings:
            print(f"warning: {warning}", file=sys.stderr)
        if errors:
            failed += 1
        else:
            print(f"{file}: ok ({len(program.plans)} plans, {len(program.rules)} rules, "
                  f"{len(program.beliefs)} beliefs, {len(program.goals)} goals)")
    return 2 if failed else 0


def cmd_run(args) -> int:
    from agentspeak.errors import AslSyntaxError
    from agentspeak.runtime import LocalRuntime
    from agentspeak.source_text import read_source
    _setup_logging()
    try:
        text = read_source(args.file)
    except OSError as exc:
        print(f"{args.file}: cannot read: {exc.strerror or exc}", file=sys.stderr)
        return 2
    except AslSyntaxError.__mro__[1] as exc:  # SourceError: not UTF-8
        print(exc, file=sys.stderr)
        return 2
    name = args.name or Path(args.file).stem
    runtime = LocalRuntime()
    try:
        runtime.add_agent(name, text, args.file)
    except AslSyntaxError as exc:
        print(exc, file=sys.stderr)
        return 2
    runtime.run(timeout=args.timeout)
    return runtime.exit_code  # 0, or Code after .stopMAS(D, Code), as Jason
