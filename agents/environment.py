"""Which robot bridge a MAS's agents drive: ``--bridge`` on the command line, else the project's ``environment``.

Jason names a Java environment class in ``environment:``; faultmas reads the name as a robot bridge
(``robot_bridge.registry``: ``sim``, ``ros2``, ``zenoh``, an installed plug-in, or a Python class
``package.module.Class`` that can be imported) whose ``"KEY=VALUE"`` arguments are its options, e.g.
``environment: sim("seed=3", "camera=true")``. Each agent then drives the robot of its own name. Any other
dotted or capitalised name (``env.MyEnv``: a Java class) cannot run here: a warning says so and the agents
run without an environment, as before. Any other unknown name, and any option
the bridge does not take, is an error naming the file and line.
"""
from __future__ import annotations

import logging
# not dataclasses (its import: inspect, ast... was a tenth of `faultmas mas run`), nor typing.NamedTuple (with
# postponed annotations it compiles each field's annotation: 5 % of `faultmas mas run` for a small program)
from collections import namedtuple

log = logging.getLogger("faultmas.agents")


class BridgeChoice(namedtuple("BridgeChoice", ("name", "options", "texts"), defaults=((),))):
    """A bridge name (str) and its options, both as values (``options``, a dict, for ``create``) and as written
    (``texts``, a tuple of ``"KEY=VALUE"``, for a child's command line)."""

    __slots__ = ()

    def agent_args(self) -> list[str]:
        """The same choice as ``faultmas agent run`` options."""
        return ["--bridge", self.name, *(arg for text in self.texts for arg in ("--bridge-option", text))]


_OPTION_HELP = ("an option for the bridge (repeatable; numbers and true/false are converted; an option the bridge "
                "does not take is an error that lists the ones it does)")


def add_bridge_arguments(parser, *, default: str | None, bridge_help: str, option_help: str = _OPTION_HELP,
                         timeout: bool = True) -> None:
    """The ``--bridge``/``--bridge-option``/``--bridge-timeout`` options, declared once for every command that
    drives robots (``mas run``, ``agent run``, ``run``); only what the robots are differs, so only the help does."""
    parser.add_argument("--bridge", default=default, metavar="NAME", help=bridge_help)
    parser.add_argument("--bridge-option", action="append", default=[], metavar="KEY=VALUE", help=option_help)
    if timeout:
        parser.add_argument("--bridge-timeout", type=float, default=30.0, metavar="S",
                            help="seconds the robots get to answer at start (default %(default)s)")


def choose_bridge(project=None, name: str | None = None, option_texts: list[str] | tuple[str, ...] = ()) \
        -> BridgeChoice | None:
    """The bridge of ``project`` (a ``MasProject``, or None) unless ``name`` (``--bridge``) overrides it;
    ``option_texts`` (``--bridge-option``) add to, or replace, the project's options of the same bridge.
    None: no bridge. ``ValueError`` (with the project's file and line where it comes from there) for an
    unknown bridge or option."""
    if name is None and (project is None or not project.environment):
        return None     # before the registry's import (importlib.metadata): most projects name no bridge
    from robot_bridge.registry import UnknownBridgeError, available, check_options, load, parse_option

    where, texts = "", []
    if project is not None and project.environment and name in (None, project.environment):
        bridge = _as_bridge_name(project.environment, available())
        if bridge is None:
            log.warning("%s: environment %s is a Java class, which faultmas cannot run (robot bridges: %s); "
                        "the agents run without an environment", project.file, project.environment,
                        ", ".join(available()))
            return None
        where = f"{project.file}:{project.environment_line or 1}: environment {project.environment}: "
        # key=: the environment's public key (the secure profile, agents.transport.identity), no bridge option
        name, texts = bridge, [text for text in project.environment_args if not text.startswith("key=")]
    if name is None:
        return None
    texts += list(option_texts)
    try:
        options = dict(parse_option(text) for text in texts)
        check_options(name, load(name), options)
    except (UnknownBridgeError, ValueError, TypeError) as exc:
        raise ValueError(f"{where}{exc}") from None
    return BridgeChoice(name, options, tuple(texts))


def _as_bridge_name(name: str, installed: list[str]) -> str | None:
    """The bridge a project's ``environment`` names: an installed one, a lower-case word meant as one (a typo
    is then an error), or a dotted ``package.module.Class`` importable here (as ``package.module:Class``);
    None for anything else, a Java class such as ``env.MyEnv``."""
    from robot_bridge.registry import UnknownBridgeError, load

    if name in installed or ("." not in name and not name[:1].isupper()):
        return name
    module, _, cls = name.rpartition(".")
    if module:
        try:
            load(f"{module}:{cls}")
            return f"{module}:{cls}"
        except (UnknownBridgeError, TypeError):
            pass
    return None


def open_bridges(choice: BridgeChoice, robots: list[str], timeout: float = 30.0) -> dict:
    """Set-up bridges of ``choice`` for ``robots`` (one team: the simulator shares one world among them);
    on a failure the ones already set up are shut down and the error names the robot."""
    from robot_bridge.registry import create_team

    try:
        bridges = create_team(choice.name, robots, **choice.options)
    except (TypeError, ValueError) as exc:   # an option of the wrong kind, e.g. speed=fast
        raise ValueError(f"bridge {choice.name!r}, options {choice.options}: {exc}") from None
    ready = []
    try:
        for robot, bridge in bridges.items():
            try:
                bridge.setup(timeout=timeout)
            except Exception as exc:
                raise RuntimeError(f"robot {robot} via bridge {choice.name!r}: {exc}") from exc
            ready.append(bridge)
    except BaseException:
        for bridge in ready:
            bridge.shutdown()
        raise
    return bridges
