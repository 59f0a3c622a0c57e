"""Find bridges by name: the ``faultmas.robot_bridges`` entry-point group, or a ``module:Class`` string.

Built-in names are ``sim`` (the embedded simulator) and ``ros2``; any installed distribution can add
one by declaring, in its ``pyproject.toml``::

    [project.entry-points."faultmas.robot_bridges"]
    mybot = "mypackage.bridge:MyBotBridge"

``robot_bridge/README.md`` walks through a complete example.
"""
from __future__ import annotations

import importlib
from importlib.metadata import EntryPoint, entry_points

from robot_bridge.protocol import RobotBridge

GROUP = "faultmas.robot_bridges"


class UnknownBridgeError(LookupError):
    """No bridge of that name; the message lists the names that exist."""


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
    """A new, not yet set up, bridge ``name`` for ``robot``."""
    return load(name)(robot, **options)


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
