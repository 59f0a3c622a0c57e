"""Where an ``.asl`` name is found: beside the including file, then along the source path, as Jason does.

Jason's ``aslSourcePath`` entries are folders relative to the working directory; ``include("x.asl")``
and ``.create_agent(a, "x.asl")`` look there after the including file's folder. ``$jasonJar/...`` names
a file of Jason's own library (inside its jar): here it is faultmas' own library folder
(``agentspeak/asl/``), then the source path, first with the path after ``$jasonJar/``, then by the bare
file name (Jason's test suite puts its ``inc/`` folder on the source path and includes it through the
jar; this finds the same files without copying Jason's).
"""
from __future__ import annotations

import os
from pathlib import Path

JASON_JAR = "$jasonJar/"
LIBRARY_DIR = Path(__file__).with_name("asl")
"""faultmas' own equivalents of the AgentSpeak files Jason ships in its jar (e.g. ``kqmlPlans.asl``)."""


def find_source(name: str, base_dir: str | None = None, source_path: list[str] | tuple = ()) -> str | None:
    """The path of ``name`` (an existing file), or None. ``base_dir`` is the including file's folder."""
    if name.startswith(JASON_JAR):
        rest = name[len(JASON_JAR):]
        dirs = [str(LIBRARY_DIR)] + list(source_path)
        for candidate in [rest, os.path.basename(rest)]:
            for d in dirs:
                path = os.path.join(d, candidate)
                if os.path.isfile(path):
                    return path
        return None
    if os.path.isabs(name):
        return name if os.path.isfile(name) else None
    if not base_dir and os.path.isfile(name):  # relative to the working directory, kept as written
        return name
    for d in ([base_dir] if base_dir else []) + list(source_path) + _shipped_plans():
        path = os.path.join(d, name)
        if os.path.isfile(path):
            return path
    return None


def _shipped_plans() -> list[str]:
    """The folder of the fault plans shipped with faultmas (package ``plans``), looked at last, so that
    ``{ include("team_robot.asl") }`` works from any folder (a file of that name beside yours wins).
    Found by its location only: the language never imports the plans package's code."""
    import importlib.util

    spec = importlib.util.find_spec("plans")
    return [os.path.dirname(spec.origin)] if spec is not None and spec.origin else []
