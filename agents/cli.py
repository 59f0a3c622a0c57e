"""The ``faultmas`` command: one sub-command per job, each owned by the package that does the job.

``COMMANDS`` below is the whole list (explicit, no module scanning). A module named there has
``add_parser(subparsers)`` and is imported only when one of its sub-commands runs (or shows its own
``--help``), so ``faultmas --help`` imports none of them and answers at once. The modules in turn import
heavy libraries (OpenCV, rclpy, Zenoh) only inside the function that runs.
"""
from __future__ import annotations

import argparse
import importlib
import os
import sys
from collections.abc import Sequence      # not typing: its import is a tenth of `faultmas --help`

COMMANDS: dict[str, tuple[str, str]] = {
    # ADDING A SUB-COMMAND IS ONE LINE HERE: "name": ("module with add_parser(subparsers)", "one-line help").
    # The line's help is what `faultmas --help` shows without importing the module; the module registers
    # the sub-command itself (with the same help: tests/agents/test_cli.py checks that they agree).
    "asl": ("agentspeak.cli", "check or run AgentSpeak programs"),
    "mas": ("agents.mas_cli", "run a multi-agent system from a Jason project file"),
    "agent": ("agents.mas_cli", "run one agent that joins a MAS over Zenoh"),
    "router": ("agents.mas_cli", "run a Zenoh router for multi-host MAS"),
    "keys": ("agents.mas_cli", "make Ed25519 key pairs for the secure profile"),
    "diagnose": ("diagnosis.cli", "all minimal diagnoses of a model given observations"),
    "perceive": ("perception.cli", "find a robot by its two coloured cylinders in one RGB-D frame"),
    "ros": ("robot_bridge.cli", "run the ROS 2 Jazzy nodes (extra 'ros2')"),
    "sim": ("robot_bridge.cli", "the embedded simulator: scripted runs with faults"),
    "run": ("agents.demo_cli", "the main job: two robots diagnose an injected fault together"),
    "eval": ("agents.demo_cli", "every fault scenario R times: success rates and step latencies"),
    "observe": ("detection.cli", "watch a running system: observers, diagnosis and rules"),
    "experiment": ("experiments.cli", "run an experiment that reproduces a paper's table"),
    "inspect": ("agents.inspector.cli", "a live web view of a running MAS: agents' minds, robots, timeline"),
    "plans": ("plans.cli", "list, show or copy the fault plans and models shipped with faultmas"),
}

DESCRIPTION = ("faultmas: BDI agents in AgentSpeak with which a team of robots detects, diagnoses and reacts to "
               "its own faults. Each command has its own --help.")
LOG_LEVELS = ("DEBUG", "INFO", "WARNING", "ERROR")


class _VersionAction(argparse.Action):
    """``--version``: the installed distribution's version, read only when asked (importlib.metadata is slow)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"faultmas {version()}")
        parser.exit()


def version() -> str:
    """The installed faultmas version (``unknown`` when run from a tree that was never installed)."""
    from importlib.metadata import PackageNotFoundError, version as dist_version
    try:
        return dist_version("faultmas")
    except PackageNotFoundError:
        return "unknown"


def add_logging_options(parser: argparse.ArgumentParser, top: bool = False) -> None:
    """``-v`` (INFO; ``-vv`` DEBUG) and ``--log-level``, on the top level and on every sub-command.
    Below the top level the defaults are suppressed, so ``faultmas -v run`` and ``faultmas run -v`` agree."""
    default = {} if top else {"default": argparse.SUPPRESS}
    parser.add_argument("-v", "--verbose", action="count", help="more log lines: -v info, -vv debug",
                        **({"default": 0} if top else default))
    parser.add_argument("--log-level", choices=LOG_LEVELS, type=str.upper, metavar="LEVEL",
                        help=f"log level, one of {', '.join(LOG_LEVELS)} (default WARNING)",
                        **({"default": None} if top else default))


def plain_description(text: str | None) -> str | None:
    """A description as a person reads it: without the usage line many modules' docstrings start with
    (argparse prints the usage anyway), without reStructuredText quotes, a capital first and a full stop."""
    if not text:
        return text
    text = text.strip()
    if text.startswith("``faultmas ") and "``" in text[2:]:   # str methods: a regex compiled here was 1 % of diagnose
        text = text[text.index("``", 2) + 2:].lstrip()
        text = (text[1:] if text[:1] in (":", ".") else text).lstrip()
    text = text.replace("``", "'")
    if not text:
        return None
    text = text[0].upper() + text[1:]
    return text if text.endswith((".", "!", "?", ")")) else text + "."


def _with_logging_options(parser: argparse.ArgumentParser) -> None:
    """Add the logging options to ``parser`` and to every parser below it (and make its description plain)."""
    parser.description = plain_description(parser.description)
    names = {s for action in parser._actions for s in action.option_strings}
    if "--log-level" not in names and "-v" not in names:
        add_logging_options(parser)
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in set(action.choices.values()):
                _with_logging_options(child)


def help_width() -> int:
    """The width argparse gives its help (``COLUMNS``, else the terminal's, else 80; less its margin of 2),
    found without ``shutil``: argparse imports it for that alone, and its import (with bz2 and lzma) is a
    noticeable part of ``faultmas --help`` (issue 23)."""
    try:
        columns = int(os.environ.get("COLUMNS", ""))
    except ValueError:
        columns = 0
    if columns <= 0:
        try:
            columns = os.get_terminal_size(sys.__stdout__.fileno()).columns
        except (AttributeError, ValueError, OSError):
            columns = 0
    return (columns or 80) - 2


class _Parser(argparse.ArgumentParser):
    """argparse's parser with its help width from ``help_width``: argparse's own formatter imports ``shutil`` for
    it, in every sub-command's parser too (they are made of this class: argparse uses the parent's)."""

    def _get_formatter(self) -> argparse.HelpFormatter:
        return self.formatter_class(prog=self.prog, width=help_width())


def command_of(argv: Sequence[str]) -> str | None:
    """The sub-command named in ``argv`` (its first word that is one), or None."""
    return next((word for word in argv if word in COMMANDS), None)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The parser; only ``command``'s module is imported (None: none, e.g. for ``faultmas --help``)."""
    parser = _Parser(prog="faultmas", description=DESCRIPTION)
    parser.add_argument("--version", action=_VersionAction, help="print the installed version and exit")
    add_logging_options(parser, top=True)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    if command is not None:
        module_name = COMMANDS[command][0]
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name != module_name:      # a real missing dependency: say so, do not hide it
                raise
            parser.error(f"'{command}' is not part of this installation ({module_name} is missing)")
        module.add_parser(sub)
        for chosen in {name for name, (owner, _) in COMMANDS.items() if owner == module_name} & set(sub.choices):
            _with_logging_options(sub.choices[chosen])
        # the other commands' placeholders serve only the top level's --help (the usage line says COMMAND);
        # made here they were a twentieth of a short `faultmas diagnose` (issue 23)
        return parser
    for name, (_, help_text) in COMMANDS.items():
        sub.add_parser(name, help=help_text, add_help=False)   # listed for --help; never parsed here
    return parser


def setup_logging(args: argparse.Namespace) -> None:
    """The root logger at the level asked (WARNING unless ``-v`` or ``--log-level``), lines on stderr.

    A command that writes no log lines says so (``set_defaults(logs=False)``, e.g. ``diagnose``): then logging
    is set up only when asked for, as importing it is a tenth of a short run (issue 23); a warning of a library
    it uses still reaches stderr (Python's last-resort handler), without the level and logger name."""
    if not getattr(args, "logs", True) and not (args.log_level or args.verbose):
        return
    import logging

    level = args.log_level or {0: "WARNING", 1: "INFO"}.get(args.verbose, "DEBUG")
    root = logging.getLogger()
    if not root.handlers:
        logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    elif args.log_level or args.verbose:    # logging set up by the caller (tests, an embedding program)
        root.setLevel(level)


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        parser = build_parser(command_of(argv))
        args = parser.parse_args(argv)
        if not getattr(args, "func", None):
            parser.print_help()
            return 2
        setup_logging(args)
        if getattr(args, "needs_lark", True):   # a command that may parse without Lark says so (diagnose: .bench)
            import agentspeak.lark_loader  # noqa: F401  every command refuses a replaced Lark 1.x at once, in one line
        return int(args.func(args) or 0)
    except KeyboardInterrupt:
        return 130
    except ImportError as exc:
        if type(exc).__name__ != "WrongLarkError":     # agentspeak.lark_loader's: Lark 0.12 replaced Lark 1.x
            raise
        print(exc, file=sys.stderr)     # one line ("faultmas needs Lark 1.x ..."), with the command that fixes it
        return 2


GC_THRESHOLD = 100_000
"""Allocations between two runs of the cyclic garbage collector's youngest generation (Python's default: 700).
Filling 10,000 beliefs: 4 % less CPU than with 20,000; what cycles there are (a few per intention) wait at most
this many allocations, some MB, before they are freed."""


def _stop_on_signals() -> None:
    """SIGINT and SIGTERM stop a command as Ctrl-C does (``KeyboardInterrupt``), so that its clean-up runs: a
    ``faultmas run`` stops its agent and robot processes instead of dying at once (Python's default for SIGTERM)
    and leaving them to find out on their own. Also when the process started with them ignored (a script's
    ``cmd &``, CI runners without job control: Python then never raises ``KeyboardInterrupt``): a test's
    ``kill -INT`` of ``faultmas run --inspect`` was ignored that way, the test killed it after 30 s and its
    agent went on alone (issue 22). Commands that handle these signals themselves (``agent run``, ``router``)
    install their own handlers later.

    ``_signal`` is the C module that ``signal`` wraps with the same functions and constants (as plain integers):
    ``signal``'s import turns them into enums, a fortieth of a short ``faultmas diagnose`` (issue 23)."""
    import _signal as signal

    def interrupt(signum, frame):
        raise KeyboardInterrupt(f"signal {signum}")

    for signum in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(signum) in (signal.SIG_DFL, signal.SIG_IGN):
            signal.signal(signum, interrupt)


def console_main() -> None:
    """The ``faultmas`` command (the console script, and ``python -m agents``): ``main`` in a process that ends
    as soon as it is done. Two costs only a whole process has, each about a tenth of ``faultmas asl run
    hello.asl`` and of a program that fills 10,000 beliefs (issue 23), are cut:

    * the cyclic garbage collector, by default after every 700 allocations, each time traversing the young
      objects and now and then all of them: here after every ``GC_THRESHOLD`` (the agents' terms, plans and
      beliefs seldom form cycles; what does is still collected, later);
    * the interpreter's teardown, which frees every module and object one by one: once ``main`` is done the
      process ends as the interpreter would end it (``atexit`` handlers run, the standard streams flushed),
      then with ``os._exit``. A run that leaves a non-daemon thread behind, or whose last output cannot be
      flushed (a closed pipe), ends the ordinary way (the thread is joined; Python reports the pipe).

    Code that calls ``main`` itself (tests, a program embedding faultmas) gets neither.
    """
    import gc

    if "FAULTMAS_PARENT" in os.environ:  # started by another faultmas process: never outlive it (an import only then)
        from robot_bridge.processes import die_with_parent
        die_with_parent()
    _stop_on_signals()
    gc.set_threshold(GC_THRESHOLD, *gc.get_threshold()[1:])
    try:
        code = main()
    except SystemExit as stop:          # argparse's --help, --version and usage errors
        code = stop.code
    if code is not None and not isinstance(code, int):
        sys.exit(code)                  # a message: printed by the interpreter, exit status 1
    _exit_without_teardown(code or 0)


def _exit_without_teardown(code: int) -> None:
    import atexit

    run_exit_handlers = getattr(atexit, "_run_exitfuncs", None)   # CPython's: what Py_Finalize runs
    threading = sys.modules.get("threading")                      # not imported: no other Python thread
    others = threading is not None and [t for t in threading.enumerate()
                                        if t is not threading.main_thread() and not t.daemon]
    if run_exit_handlers is None or others:
        sys.exit(code)
    run_exit_handlers()
    try:
        for stream in (sys.stdout, sys.stderr):
            if stream is not None:
                stream.flush()
    except (OSError, ValueError):
        sys.exit(code)
    os._exit(code)


if __name__ == "__main__":
    console_main()
