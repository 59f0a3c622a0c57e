"""``load_model(path)``: the one entry point for every model format, chosen by extension and top key.

Each format's reader is imported when a file of that format is read: a ``.bench`` netlist needs neither
YAML nor the formula parser (Lark), whose imports would be most of a short ``faultmas diagnose`` (issue 23).
"""
from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from agentspeak.errors import SourceError

if TYPE_CHECKING:
    from diagnosis.model import SystemModel


def load_model(path: str | Path) -> SystemModel:
    """A ``.bench`` netlist, or a ``.yaml``/``.yml`` file whose first key is ``system`` or ``architecture``."""
    path = Path(path)
    if not path.is_file():
        raise SourceError("no such model file", file=str(path))
    if path.suffix.lower() == ".bench":
        from diagnosis.bench import load_bench_model

        return load_bench_model(path)
    if path.suffix.lower() not in (".yaml", ".yml"):
        raise SourceError("a model is a .yaml system description or a .bench netlist", file=str(path))
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
