"""``load_model(path)``: the one entry point for every model format, chosen by extension and top key.

Each format's reader is imported when a file of that format is read: a ``.bench`` netlist needs neither
YAML nor the formula parser (Lark), whose imports would be most of a short ``faultmas diagnose`` (issue 23).
"""
from __future__ import annotations

import os

from agentspeak.errors import SourceError

TYPE_CHECKING = False     # typing.TYPE_CHECKING without importing typing (issue 23: start-up)
if TYPE_CHECKING:
    from diagnosis.model import SystemModel


def load_model(path: str | os.PathLike) -> SystemModel:
    """A ``.bench`` netlist, or a ``.yaml``/``.yml`` file whose first key is ``system`` or ``architecture``.
    A netlist read before, unchanged, comes from the user's cache (``diagnosis.netlist_cache``)."""
    path = os.fspath(path)
    if not os.path.isfile(path):
        raise SourceError("no such model file", file=path)
    suffix = os.path.splitext(path)[1].lower()
    if suffix == ".bench":
        from diagnosis.netlist_cache import cached_netlist_model

        return cached_netlist_model(path)
    if suffix not in (".yaml", ".yml"):
        raise SourceError("a model is a .yaml system description or a .bench netlist", file=path)
    from diagnosis.architecture_yaml import load_architecture
    from diagnosis.system_yaml import load_system
    from diagnosis.yaml_source import YamlSource

    source = YamlSource(path)
    top = source.mapping(source.root, "a model")
    if "architecture" in top:
        return load_architecture(source)
    if "system" in top:
        return load_system(source)
    source.error(source.root, "a model starts with 'system: NAME' or 'architecture: NAME'")
