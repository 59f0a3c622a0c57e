"""Find bridges by name: the ``faultmas.robot_bridges`` entry-point group, or a ``module:Class`` string.

Built-in names are ``sim`` (the embedded simulator) and ``ros2``; any installed distribution can add
one by declaring, in its ``pyproject.toml``::

    [project.entry-points."faultmas.robot_bridges"]
    mybot = "mypackage.bridge:MyBotBridge"

``robot_bridge/README.md`` walks through a complete example.

Options are checked by name before a bridge is built: a bridge declares them in ``known_options`` (name ->
meaning), or else they are its ``__init__``'s keyword parameters. An unknown key (a typo such as
``fualt=encoders``) is an ``UnknownBridgeOptionError`` that lists the bridge's options, never a silent no-op.
"""
from __future__ import annotations

import importlib
import inspect
from importlib.metadata import EntryPoint, entry_points

from robot_bridge.protocol import RobotBridge

GROUP = "faultmas.robot_bridges"


class UnknownBridgeError(LookupError):
    """No bridge of that name; the message lists the names that exist."""


class UnknownBridgeOptionError(ValueError):
    """An option the bridge does not take; the message lists the ones it does."""


def _entry_points() -> dict[str, EntryPoint]:
    return {ep.name: ep for ep in entry_points(group=GROUP)}


def available() -> list[str]:
    """Names of every installed bridge, sorted."""
    return sorted(_entry_points())


def load(name: str) -> type[RobotBridge]:
    """The bridge class called ``name`` (an entry-point name, or ``package.module:Class``)."""
    if ":" in name:
        target, where = _import(name), f"{name!r}"
    else:
        found = _entry_points().get(name)
        if found is None:
            known = ", ".join(available()) or "none installed"
            raise UnknownBridgeError(
                f"unknown robot bridge {name!r}; known bridges: {known} "
                f"(entry-point group {GROUP!r}, or give 'package.module:Class')")
        target, where = found.load(), f"{name!r} (entry point {found.value!r})"
    if not (isinstance(target, type) and issubclass(target, RobotBridge)):
        raise TypeError(f"robot bridge {where} is {target!r}, not a subclass of robot_bridge.RobotBridge")
    return target


def create(name: str, robot: str, **options: object) -> RobotBridge:
    """A new, not yet set up, bridge ``name`` for ``robot``; unknown options raise ``UnknownBridgeOptionError``."""
    cls = load(name)
    check_options(name, cls, options)
    return cls(robot, **options)


def create_team(name: str, robots: list[str], **options: object) -> dict[str, RobotBridge]:
    """New, not yet set up, bridges ``name`` for every robot of a team (``RobotBridge.for_team``: the
    simulator puts them into one shared world), checked as ``create`` checks them."""
    cls = load(name)
    check_options(name, cls, options)
    return cls.for_team(robots, **options)


def known_options(cls: type[RobotBridge]) -> dict[str, str]:
    """The options bridge class ``cls`` takes: its ``known_options``, or else its ``__init__``'s keyword
    parameters (after ``robot``), each with its default as the meaning."""
    if cls.known_options is not None:
        return dict(cls.known_options)
    found = {}
    for parameter in list(inspect.signature(cls.__init__).parameters.values())[2:]:
        if parameter.kind in (parameter.POSITIONAL_OR_KEYWORD, parameter.KEYWORD_ONLY):
            default = parameter.default
            found[parameter.name] = "" if default is parameter.empty else f"default {default!r}"
    return found


def check_options(name: str, cls: type[RobotBridge], options: dict) -> None:
    """Raise ``UnknownBridgeOptionError`` naming every key of ``options`` that bridge ``name`` does not take."""
    known = known_options(cls)
    unknown = sorted(set(options) - set(known))
    if unknown:
        takes = ", ".join(sorted(known)) if known else "none"
        raise UnknownBridgeOptionError(
            f"robot bridge {name!r} has no option{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))}; "
            f"its options: {takes}")


def parse_option(text: str) -> tuple[str, object]:
    """``KEY=VALUE`` as written on a command line or in a project file: numbers become numbers,
    true/false booleans, the rest stays text. ``ValueError`` when there is no ``=`` or no key."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise ValueError(f"a bridge option is KEY=VALUE, got {text!r}")
    lowered = value.strip().lower()
    if lowered in ("true", "false"):
        return key.strip(), lowered == "true"
    for convert in (int, float):
        try:
            return key.strip(), convert(value)
        except ValueError:
            pass
    return key.strip(), value


def parse_options(texts: list[str]) -> dict[str, object]:
    """Several ``KEY=VALUE`` texts as one dict (the last of a repeated key wins, as on a command line)."""
    return dict(parse_option(text) for text in texts)


def _import(spec: str) -> object:
    module_name, _, attribute = spec.partition(":")
    if not module_name or not attribute:
        raise UnknownBridgeError(f"bad bridge reference {spec!r}: expected 'package.module:Class'")
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as exc:
        if exc.name and module_name.startswith(exc.name):
            raise UnknownBridgeError(f"bad bridge reference {spec!r}: no module {exc.name!r}") from None
        raise
    target: object = module
    for part in attribute.split("."):
        try:
            target = getattr(target, part)
        except AttributeError:
            raise UnknownBridgeError(f"bad bridge reference {spec!r}: {module_name} has no {attribute!r}") \
                from None
    return target
