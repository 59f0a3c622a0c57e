"""``faultmas`` itself: the lazy sub-command table, --version, -v/--log-level everywhere (issue 23)."""
from __future__ import annotations

import argparse
import importlib
import logging
import subprocess
import sys

import pytest

from agents import cli


def _registered() -> dict[str, str]:
    """Every sub-command the modules register, with the help they give it."""
    sub = argparse.ArgumentParser().add_subparsers()
    for module in dict.fromkeys(m for m, _ in cli.COMMANDS.values()):
        importlib.import_module(module).add_parser(sub)
    return {action.dest: action.help for action in sub._choices_actions}


def test_the_table_lists_every_sub_command_with_the_help_its_module_gives_it() -> None:
    registered = _registered()
    assert set(registered) == set(cli.COMMANDS)
    assert {name: help_text for name, (_, help_text) in cli.COMMANDS.items()} == registered


def test_help_imports_no_sub_command_module() -> None:
    code = ("import sys\nfrom agents import cli\ntry:\n    cli.main(['--help'])\nexcept SystemExit:\n    pass\n"
            "print(sorted({m for m, _ in cli.COMMANDS.values()} & set(sys.modules)))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "asl" in done.stdout and "eval" in done.stdout          # the whole list is shown...
    assert done.stdout.strip().splitlines()[-1] == "[]"            # ...without importing any of them


def test_a_sub_command_imports_only_its_own_module() -> None:
    code = ("import sys\nfrom agents import cli\ncli.build_parser('diagnose')\n"
            "print(sorted({m for m, _ in cli.COMMANDS.values()} & set(sys.modules)))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.stdout.strip() == "['diagnosis.cli']", done.stderr


def test_version_prints_the_installed_version(capsys) -> None:
    from importlib.metadata import version
    with pytest.raises(SystemExit) as exit_:
        cli.main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"faultmas {version('faultmas')}"


@pytest.mark.parametrize("argv, level", [
    (["diagnose", "M", "--obs", "O"], logging.WARNING),
    (["-v", "diagnose", "M", "--obs", "O"], logging.INFO),
    (["diagnose", "M", "--obs", "O", "-v"], logging.INFO),
    (["diagnose", "M", "--obs", "O", "-vv"], logging.DEBUG),
    (["asl", "run", "--log-level", "error", "x.asl"], logging.ERROR),
    (["--log-level", "info", "asl", "check", "x.asl"], logging.INFO),
])
def test_log_level_options_work_on_every_command(argv: list[str], level: int) -> None:
    args = cli.build_parser(cli.command_of(argv)).parse_args(argv)
    cli.setup_logging(args)
    try:
        assert logging.getLogger().level == level
    finally:
        logging.getLogger().setLevel(logging.WARNING)


def test_every_leaf_command_has_the_log_options() -> None:
    missing = []
    for name in cli.COMMANDS:
        parser = cli.build_parser(name)
        stack = [parser._subparsers._group_actions[0].choices[name]]
        while stack:
            p = stack.pop()
            subs = [a for a in p._actions if isinstance(a, argparse._SubParsersAction)]
            for action in subs:
                stack.extend(action.choices.values())
            if not {"-v", "--log-level"} <= {s for a in p._actions for s in a.option_strings}:
                missing.append(p.prog)
    assert missing == []


def _all_parsers():
    for name in cli.COMMANDS:
        stack = [cli.build_parser(name)._subparsers._group_actions[0].choices[name]]
        while stack:
            parser = stack.pop()
            for action in parser._actions:
                if isinstance(action, argparse._SubParsersAction):
                    stack.extend(action.choices.values())
            yield parser


def test_every_option_and_argument_has_help_and_descriptions_read_as_sentences() -> None:
    missing, raw = [], []
    for parser in _all_parsers():
        missing += [f"{parser.prog} {a.option_strings or a.dest}" for a in parser._actions
                    if a.help is None and not isinstance(a, argparse._SubParsersAction)]
        if parser.description and ("``" in parser.description or not parser.description.endswith((".", ")"))):
            raw.append(f"{parser.prog}: {parser.description}")
    assert missing == [] and raw == []


def test_plain_description_drops_the_usage_line_and_rst_quotes() -> None:
    assert cli.plain_description("``faultmas router``: a Zenoh router for ``MAS`` use") == "A Zenoh router for 'MAS' use."
    assert cli.plain_description("``faultmas diagnose MODEL --obs OBS.json``.") is None


def test_router_on_a_busy_port_says_so_in_one_line() -> None:
    import socket

    from agents.router import start_failure

    with socket.socket() as busy:            # a real port taken by someone else
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        done = subprocess.run([sys.executable, "-m", "agents", "router", "--listen", f"tcp/127.0.0.1:{port}",
                               "--timeout", "1"], capture_output=True, text=True, timeout=120)
    lines = [ln for ln in done.stderr.splitlines() if not ln.startswith("WARNING")]
    assert done.returncode == 1 and len(lines) == 1, done.stderr
    assert "already in use" in lines[0] and ".rs:" not in lines[0]
    assert start_failure(["tcp/x:1"], "boom [x] at /root/src/lib.rs:12.") == "cannot start on tcp/x:1: boom x"
