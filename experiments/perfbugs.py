"""Wienke & Wrede's Table I on faultmas' own team: learned model vs One-Class SVM vs random.

Trains, per component, the learned detector of performance bugs (detection/learned) on the data set's
fault-free runs and scores the held-out fault-free runs and every run with an injected bug: F0.1, FPR,
detection rate (flagged within 80 s of the bug's start) and micro-averaged ROC AUC, then AUC per bug
kind and per component. The data sets live in experiments/data/perfbugs/PROFILE; --generate records
the missing runs of the profile first (real ROS 2 nodes; smoke: ~23 min, paper: ~2.5 h on 2 cores):

    faultmas experiment perfbugs --profile smoke
    faultmas experiment perfbugs --profile paper --generate       # makes the paper's data set once
    faultmas experiment perfbugs --json --plot roc.png --save-models models/
    faultmas experiment perfbugs --profile smoke --generate --agents --data runs-with-agents/
    faultmas experiment perfbugs --profile paper --generate --agents --jobs 2 --data paper-agents/
"""
from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

PAPER = {"model": {"f0.1": 0.521, "fpr": 0.011, "auc": 0.650}, "ocsvm": {"f0.1": 0.185, "auc": 0.626},
         "random": {"f0.1": 0.133}}
"""The paper's figures (RoboCup@Home robot, target FPR 0.005), printed beside ours."""


def data_dir(profile: str) -> Path:
    return Path(__file__).resolve().parent / "data" / "perfbugs" / profile


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.formatter_class = argparse.RawDescriptionHelpFormatter
    parser.epilog = __doc__.split("\n\n", 1)[1] + "\nMethod, data, results and what remains: docs/perfbugs.md."
    parser.add_argument("--profile", choices=("smoke", "paper"), default="smoke",
                        help="which data set (default: smoke)")
    parser.add_argument("--data", metavar="DIR", help="data set directory (default: the profile's, "
                        "experiments/data/perfbugs/PROFILE)")
    parser.add_argument("--generate", action="store_true",
                        help="record the profile's missing runs into the data directory first (real processes)")
    parser.add_argument("--agents", action="store_true",
                        help="with --generate: also run the team's AgentSpeak agents (faulty, helper) over Zenoh, "
                        "as 'faultmas run --bridge ros2' does, and record them as components (their processes, "
                        "ROS 2 topics and Zenoh keys); use another --data directory than the profile's")
    parser.add_argument("--jobs", type=int, default=1, metavar="N",
                        help="with --generate: record N runs at a time, each in its own process and ROS domain "
                        "(default 1; each run must keep real time, so N above the cores' worth skews the data)")
    parser.add_argument("--target-fpr", type=float, default=0.005, help="target false-positive rate (default 0.005)")
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of tables")
    parser.add_argument("--plot", metavar="OUT.png", help="draw the ROC curves into this file")
    parser.add_argument("--save-models", metavar="DIR", help="save every component's model into DIR")


def _fmt(value: float) -> str:
    return "  n/a" if value is None or (isinstance(value, float) and math.isnan(value)) else f"{value:.3f}"


def main(args: argparse.Namespace) -> int:
    from detection.learned.dataset import DatasetError, load
    from detection.learned.evaluate import evaluate, plot_roc

    directory = Path(args.data) if args.data else data_dir(args.profile)

    def progress(text: str) -> None:
        print(f"perfbugs: {text}", file=sys.stderr, flush=True)
    if not 0.0 < args.target_fpr < 0.5:
        print(f"error: --target-fpr must be between 0 and 0.5, got {args.target_fpr}", file=sys.stderr)
        return 2
    if (args.agents or args.jobs != 1) and not args.generate:
        print("error: --agents and --jobs go with --generate (they say how to record)", file=sys.stderr)
        return 2
    if args.jobs < 1:
        print(f"error: --jobs must be at least 1, got {args.jobs}", file=sys.stderr)
        return 2
    if args.generate:
        from detection.learned.scenario import generate
        agents = None
        if args.agents:
            from experiments.perfbugs_agents import CooperativeAgents
            agents = CooperativeAgents()
        try:
            generate(directory, args.profile, out=sys.stderr, agents=agents, jobs=args.jobs)
        except ValueError as exc:                    # e.g. runs with and without agents in one directory
            print(f"error: {exc}", file=sys.stderr)
            return 2
        except RuntimeError as exc:                  # runs that failed: the data set is not complete
            print(f"error: {exc}", file=sys.stderr)
            return 1
    try:
        dataset = load(directory, progress)
        result = evaluate(dataset, args.target_fpr, progress=progress)
    except (DatasetError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    if args.save_models:
        out = Path(args.save_models)
        out.mkdir(parents=True, exist_ok=True)
        for name, model in result.models.items():
            model.save(out / f"{name}.npz")
        progress(f"{len(result.models)} models saved in {out}")
    if args.plot:
        plot_roc(result, args.plot, f"Performance bugs ({args.profile} data set): ROC")
        progress(f"ROC curves in {args.plot}")
    summary = {"profile": args.profile, "data": str(directory), "target_fpr": args.target_fpr,
               "runs": {"train": [list(p) for p in result.partitions[:3]], "held_out_fault_free": result.partitions[3],
                        "faulty": dataset.faulty_runs()},
               "table": result.rows, "auc_by_kind": result.auc_by_kind(),
               "auc_by_component": result.auc_by_component(), "faults": result.detections(),
               "training_cpu_s": round(result.training_s, 3), "paper": PAPER}
    if args.json:
        print(json.dumps(summary, default=lambda v: None if isinstance(v, float) and math.isnan(v) else v))
        return 0
    print(f"Table I: performance-bug detection, {args.profile} data set ({len(dataset.runs)} runs: "
          f"{len(dataset.fault_free_runs())} fault-free, {len(dataset.faulty_runs())} with a bug), "
          f"target FPR {args.target_fpr:g}")
    print(f"{'detector':<10} {'F0.1':>7} {'FPR':>7} {'det.rate':>9} {'AUC':>7}   paper F0.1 / FPR / AUC")
    for name, row in result.rows.items():
        paper = PAPER.get(name, {})
        print(f"{name:<10} {_fmt(row['f0.1']):>7} {_fmt(row['fpr']):>7} {_fmt(row['detection_rate']):>9} "
              f"{_fmt(row['auc']):>7}   {_fmt(paper.get('f0.1'))} / {_fmt(paper.get('fpr'))} / {_fmt(paper.get('auc'))}")
    for title, table in (("AUC per bug kind", result.auc_by_kind()), ("AUC per component", result.auc_by_component())):
        keys = sorted({k for per in table.values() for k in per})
        print(f"\n{title}:")
        print(f"{'':<28}" + "".join(f"{d:>8}" for d in table))
        for key in keys:
            print(f"{key:<28}" + "".join(f"{_fmt(table[d].get(key, float('nan'))):>8}" for d in table))
    print("\nbug instances: flagged within 80 s of the start (share of the bug's seconds flagged):")
    for f in result.detections():
        print(f"  run {f['run']:>3} {f['kind']:<22} in {f['component']:<26} " +
              " ".join(f"{d}={'yes' if f[d] else 'no '} ({_fmt(f[d + '_share'])})" for d in ("model", "ocsvm", "random")))
    print(f"\ntraining: {result.training_s:.1f} s CPU for {len(result.models)} components")
    return 0
