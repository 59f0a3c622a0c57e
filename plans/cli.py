"""``faultmas plans list|show|copy``: the fault plans and models shipped with faultmas, to read and to start from.

The shipped files are package data (this folder). ``copy`` brings a plan into your folder together with every
file it includes, so the copy runs as it is; it never overwrites a file.
"""
from __future__ import annotations

import argparse
import re
import shutil
import sys
from pathlib import Path

PLANS_DIR = Path(__file__).resolve().parent
SUFFIXES = (".asl", ".yaml", ".mas2j")
_INCLUDE = re.compile(r'include\(\s*"([^"]+)"\s*\)')


def shipped() -> dict[str, Path]:
    """Every shipped plan and model by file name."""
    return {p.name: p for p in sorted(PLANS_DIR.iterdir()) if p.suffix in SUFFIXES and p.is_file()}


def find(name: str) -> Path | None:
    """A shipped file by its name, with or without its suffix (``team_robot``, ``turtlebot_hardware.yaml``)."""
    files = shipped()
    return files.get(name) or next((files[name + s] for s in SUFFIXES if name + s in files), None)


def summary(path: Path) -> str:
    """The first comment line of a file: what it is."""
    for line in path.read_text(encoding="utf-8").splitlines():
        text = line.strip().lstrip("/#").strip()
        if text:
            return text
    return ""


def with_includes(path: Path) -> list[Path]:
    """``path`` and the shipped files it includes, recursively, each once."""
    order, todo = [], [path]
    while todo:
        current = todo.pop(0)
        if current in order:
            continue
        order.append(current)
        if current.suffix == ".asl":
            todo += [PLANS_DIR / n for n in _INCLUDE.findall(current.read_text(encoding="utf-8"))
                     if (PLANS_DIR / n).is_file()]
    return order


def add_parser(sub: argparse._SubParsersAction) -> None:
    plans = sub.add_parser("plans", help="list, show or copy the fault plans and models shipped with faultmas",
                           description=__doc__.splitlines()[0].split(": ", 1)[1])
    plans_sub = plans.add_subparsers(dest="plans_command", metavar="ACTION")
    plans.set_defaults(func=lambda args: (plans.print_help(), 2)[1])
    listing = plans_sub.add_parser("list", help="every shipped plan and model, with what it is")
    listing.set_defaults(func=cmd_list)
    show = plans_sub.add_parser("show", help="print a shipped file")
    show.add_argument("name", metavar="NAME", help="a file name from `faultmas plans list` (suffix optional)")
    show.set_defaults(func=cmd_show)
    copy = plans_sub.add_parser("copy", help="copy a shipped plan and the files it includes, to start from")
    copy.add_argument("name", metavar="NAME", help="a file name from `faultmas plans list` (suffix optional)")
    copy.add_argument("dest", nargs="?", default=".", metavar="DIR", help="where to (default: this folder)")
    copy.set_defaults(func=cmd_copy)


def _found(name: str) -> Path | None:
    path = find(name)
    if path is None:
        print(f"faultmas plans: no shipped plan or model named {name!r}; `faultmas plans list` shows them",
              file=sys.stderr)
    return path


def cmd_list(args: argparse.Namespace) -> int:
    files = shipped()
    width = max(map(len, files))
    for name, path in files.items():
        print(f"{name:<{width}}  {summary(path)}")
    print(f"\n({PLANS_DIR}; `faultmas plans copy NAME` to start from one)")
    return 0


def cmd_show(args: argparse.Namespace) -> int:
    path = _found(args.name)
    if path is None:
        return 2
    sys.stdout.write(path.read_text(encoding="utf-8"))
    return 0


def cmd_copy(args: argparse.Namespace) -> int:
    path = _found(args.name)
    if path is None:
        return 2
    dest = Path(args.dest)
    files = with_includes(path)
    existing = [dest / f.name for f in files if (dest / f.name).exists()]
    if existing:
        print(f"faultmas plans: {', '.join(map(str, existing))} already exist(s); nothing copied", file=sys.stderr)
        return 2
    dest.mkdir(parents=True, exist_ok=True)
    for f in files:
        shutil.copyfile(f, dest / f.name)
        print(f"copied {f.name} -> {dest / f.name}")
    return 0
