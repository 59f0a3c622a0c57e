"""``faultmas diagnose MODEL --obs OBS.json [--max-card K] [--min-card-only] [--timeout S] [--json]``.

MODEL is a ``.yaml`` system description (or architecture model) or a ``.bench`` netlist. OBS.json maps
observation names to 0/1 (or false/true); for a netlist, signal names (primary inputs and outputs, or any
other signal that was probed). Exit status: 0 answered, 2 bad model or observations, 3 stopped by --timeout (before the search) or
--max-memory.
"""
from __future__ import annotations

import argparse
import json
import sys

from diagnosis.limits import DEFAULT_MAX_MEMORY_MB, RunLimits


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser("diagnose", help="all minimal diagnoses of a model given observations",
                              description=__doc__.splitlines()[0])
    p.add_argument("model", help="a .yaml system description or a .bench netlist, or the name of a model shipped "
                                 "with faultmas (e.g. turtlebot_hardware; `faultmas plans list`)")
    p.add_argument("--obs", required=True, metavar="OBS.json", help="JSON object: observation name -> 0/1")
    p.add_argument("--max-card", type=int, default=None, metavar="K",
                   help="largest diagnosis size to enumerate (default: no bound)")
    p.add_argument("--min-card-only", action="store_true", help="only the minimum-cardinality diagnoses")
    p.add_argument("--max-count", type=int, default=None, metavar="N", help="stop after N diagnoses")
    p.add_argument("--timeout", type=float, default=None, metavar="S",
                   help="wall-clock limit in seconds for the whole run (reading, building, search); a search "
                        "cut short reports what it found as INCOMPLETE, an earlier phase is an error (exit 3)")
    p.add_argument("--max-memory", type=float, default=DEFAULT_MAX_MEMORY_MB, metavar="MIB",
                   help=f"resident memory limit in MiB; beyond it the run stops with an error (exit 3) "
                        f"(default {DEFAULT_MAX_MEMORY_MB})")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    # logs=False: nothing here logs (logging is set up only for -v); needs_lark=False: only a .yaml model's
    # formulas are parsed with Lark, and diagnosis.formula makes the refusal of a replaced Lark 1.x itself
    p.set_defaults(func=run, logs=False, needs_lark=False)


def read_observations(path: str) -> dict[str, bool]:
    """OBS.json as name -> bool; a bad file raises SourceError naming it."""
    from agentspeak.errors import SourceError
    from agentspeak.source_text import read_source

    try:
        data = json.loads(read_source(path, "observations file"))
    except RecursionError:  # json's C decoder guards its recursion: a file nested 100,000 deep
        raise SourceError(f"nested too deeply (JSON arrays or objects inside each other beyond "
                          f"{sys.getrecursionlimit()} levels)", file=path) from None
    except OSError as exc:
        raise SourceError(f"cannot read observations: {exc.strerror}", file=path) from None
    except json.JSONDecodeError as exc:
        raise SourceError(f"not JSON: {exc.msg}", file=path, line=exc.lineno, column=exc.colno) from None
    except SourceError:
        raise  # located already (read_source: not UTF-8)
    except ValueError as exc:  # an integer over Python's 4,300-digit limit (found by the fuzz campaign)
        raise SourceError(f"not usable JSON: {str(exc)[:80]}", file=path) from None
    if not isinstance(data, dict):
        raise SourceError("observations must be a JSON object mapping names to 0/1", file=path)
    out = {}
    for name, value in data.items():
        if value in (0, 1) and not isinstance(value, float) or isinstance(value, bool):
            out[name] = bool(value)
        else:
            raise SourceError(f"observation {name!r} must be 0, 1, true or false, not {value!r}", file=path)
    return out


def model_file(name: str) -> str:
    """``name`` as given when it is a file; else a model shipped with faultmas by that name
    (``turtlebot_hardware`` is ``plans/turtlebot_hardware.yaml``, as ``.diagnose`` finds it)."""
    import os

    if os.path.exists(name) or os.sep in name:
        return name
    from importlib import resources

    shipped = resources.files("plans")
    for suffix in ("", ".yaml", ".bench"):
        candidate = shipped.joinpath(name + suffix)
        if candidate.is_file():
            return str(candidate)
    return name          # load_model says it is not there


def run(args: argparse.Namespace) -> int:
    from agentspeak.errors import SourceError
    from diagnosis.engine import Diagnoser
    from diagnosis.loader import load_model

    if args.timeout is not None and not args.timeout > 0 or not args.max_memory > 0:
        print("faultmas diagnose: --timeout and --max-memory must be positive", file=sys.stderr)
        return 2
    try:
        with RunLimits(args.timeout, args.max_memory) as limits:
            limits.phase("reading the model")
            model = load_model(model_file(args.model))
            limits.phase("reading the observations")
            observations = read_observations(args.obs)
            limits.phase("building the solver")
            diagnoser = Diagnoser(model)
            limits.phase("searching for diagnoses")
            result = diagnoser.diagnose(observations, max_card=args.max_card, max_count=args.max_count,
                                        timeout=limits.left(), min_card_only=args.min_card_only)
            limits.phase("printing the diagnoses")
    except SourceError as exc:
        print(f"faultmas diagnose: {exc}", file=sys.stderr)
        return 2
    if args.json:
        print(json.dumps(result.to_json()))
        return 0
    if not result.consistent_with_model:
        print("no diagnosis: the observations contradict the model whatever is faulty")
    elif result.diagnoses == [[]]:
        print("no fault: the observations are consistent with every component healthy")
    else:
        for d in result.diagnoses:
            print("{" + ", ".join(d) + "}")
    state = "complete" if result.complete else "INCOMPLETE (limit reached)"
    print(f"{len(result.diagnoses)} minimal diagnoses, min cardinality {result.min_cardinality}, "
          f"{state}, {result.seconds:.3f} s", file=sys.stderr)
    return 0
