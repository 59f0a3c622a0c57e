"""``load_model(path)``: the one entry point for every model format, chosen by extension and top key."""
from __future__ import annotations

from pathlib import Path

from agentspeak.errors import SourceError
from diagnosis.architecture_yaml import load_architecture
from diagnosis.bench import load_bench_model
from diagnosis.model import SystemModel
from diagnosis.system_yaml import load_system
from diagnosis.yaml_source import YamlSource


def load_model(path: str | Path) -> SystemModel:
    """A ``.bench`` netlist, or a ``.yaml``/``.yml`` file whose first key is ``system`` or ``architecture``."""
    path = Path(path)
    if not path.is_file():
        raise SourceError("no such model file", file=str(path))
    if path.suffix.lower() == ".bench":
        return load_bench_model(path)
    if path.suffix.lower() not in (".yaml", ".yml"):
        raise SourceError("a model is a .yaml system description or a .bench netlist", file=str(path))
    source = YamlSource(path)
    top = source.mapping(source.root, "a model")
    if "architecture" in top:
        return load_architecture(source)
    if "system" in top:
        return load_system(source)
    source.error(source.root, "a model starts with 'system: NAME' or 'architecture: NAME'")
