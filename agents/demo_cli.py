"""``faultmas run`` (the main job) and ``faultmas eval``: cooperative fault diagnosis on robots.

``faultmas run``: Faulty and Helper side by side 1.5 m apart, one agent process each over Zenoh, on the
embedded simulator, with a fault injected; shows the steps as they happen, ends with the diagnosis and
a table of step latencies (simulated and wall seconds). ``--robots N --faulty K`` runs a team instead.
``--bridge ros2`` runs the same plans against the ROS 2 nodes (``robot_bridge/ros2``).

``faultmas eval --runs R``: every fault scenario R times with random placement, lighting and noise;
a table of success rates and step latencies (mean and standard deviation), in the spirit of the
paper's Tables I-IV. Runs are independent, so they are spread over ``--jobs`` worker processes, each
running the agents in-process (the same plans and simulator as ``faultmas run``, without the network).
"""
from __future__ import annotations

import argparse
import json
import logging
import signal
import statistics
import sys

from agents.cooperative import EXPECTED, FAULTS, STEP_NAMES
from agents.environment import add_bridge_arguments

EVAL_FAULTS = ("none", "encoders", "both_actuators", "left_actuator", "right_actuator")
EVAL_TEAMS = (2, 4, 8, 12)
"""Team sizes ``faultmas eval`` runs by default (robots start anywhere in the arena, often out of sight)."""
RUN_TIMEOUT = 120.0
"""Wall seconds ``faultmas run`` gives the pair by default (a team of N: N/2 times as much)."""
EVAL_SIM_TIMEOUT = 600.0
"""Simulated seconds an evaluation run may take: more than the plans' own time-outs add up to (a run ends
with their verdict, diagnosed or undiagnosed, before), so only a run that hangs reaches it."""
STEP_LABELS = {"started": "started its task", "fault_detected": "fault detected", "ambiguous": "ambiguous alone",
               "help_requested": "asks for help", "helper_found": "helper chosen", "searching": "searching for",
               "robot_found": "robot detected:", "found_by": "found by", "lost_sight": "lost sight of",
               "diagnosed": "DIAGNOSIS:", "undiagnosed": "UNDIAGNOSED, candidates:", "arrived": "arrived"}


def add_parser(sub: argparse._SubParsersAction) -> None:
    run = sub.add_parser("run", help="the main job: two robots diagnose an injected fault together",
                         description="The main job: Faulty and Helper side by side 1.5 m apart (or a team with "
                                     "--robots), one agent process each over Zenoh, on the embedded simulator, "
                                     "with a fault injected. Shows the steps as they happen, then the diagnosis "
                                     "and a table of step latencies in simulated and wall seconds. Exit status: 0 "
                                     "correct, 1 a wrong diagnosis, 3 an agent or robot process died (named), 124 the "
                                     "run did not finish within --timeout.")
    run.add_argument("--fault", choices=FAULTS, default=None,
                     help="fault injected into the faulty robot(s) (default: encoders; with --robots: a random "
                          "fault per faulty robot)")
    run.add_argument("--seed", type=int, default=1, help="seed of placement and sensor noise (default %(default)s)")
    run.add_argument("--robots", type=int, default=None, metavar="N",
                     help="a team of N robots (2-12) at random places over the whole arena, instead of the pair")
    run.add_argument("--faulty", type=int, default=None, metavar="K",
                     help="with --robots: K of them faulty (default 1)")
    add_bridge_arguments(run, default="sim", timeout=False, bridge_help=(
        "the robots: sim (the embedded simulator, default), ros2 (ROS 2 nodes started for the run), or any other "
        "installed bridge (`faultmas sim bridges`), e.g. zenoh for a `faultmas sim serve` of MAS coop, whose "
        "robots have the fault --fault names"),
        option_help=("with a bridge other than sim and ros2: an option for it (repeatable; an option it does not "
                     "take is an error that lists the ones it does)"))
    run.add_argument("--in-process", action="store_true", help="all agents in this process (no Zenoh)")
    run.add_argument("--secure", action="store_true",
                     help="the secure profile: a key pair per robot made for the run, every message signed by its "
                          "sender and checked by its receiver (docs/reliability.md, \"Identity\"); embedded "
                          "simulator, agent processes")
    run.add_argument("--json", action="store_true", help="print one JSON object (agents' lines go to stderr)")
    run.add_argument("--plot", metavar="PNG", help="draw ground-truth and believed trajectories to this file")
    run.add_argument("--quiet", action="store_true", help="do not show the agents' own lines")
    run.add_argument("--timeout", type=float, default=None,
                     help="wall seconds before giving up (default 120; a team of N gets N/2 times as much, as "
                          "every camera slows the simulator)")
    run.add_argument("--inspect", action="store_true",
                     help="serve the live web view (faultmas inspect) of this run; wait at its end until Ctrl-C")
    run.add_argument("--inspect-hold", type=float, default=None, metavar="S",
                     help="with --inspect: wait S seconds at the end instead of until Ctrl-C (0: not at all)")
    run.add_argument("--allow-pause", action="store_true", help="with --inspect: let the page pause and step agents")
    from agents.inspector.cli import add_listen_arguments  # stdlib only: keeps --help fast
    add_listen_arguments(run)
    run.set_defaults(func=cmd_run)

    ev = sub.add_parser("eval", help="every fault scenario R times: success rates and step latencies",
                        description="Run every fault scenario R times with random placement, lighting and noise "
                                    "(pairs, and teams over the whole arena), agents in-process, spread over "
                                    "--jobs worker processes; print success rates and step latencies.")
    ev.add_argument("--runs", type=int, default=10, metavar="R", help="runs per scenario (default %(default)s)")
    ev.add_argument("--seed", type=int, default=1,
                    help="seed of the runs' placements, lighting and noise (default %(default)s)")
    ev.add_argument("--faults", default=",".join(EVAL_FAULTS),
                    help="comma-separated pair scenarios, among " + ", ".join(FAULTS) + " (default: all but "
                         "stuck_wheels); '' for teams only")
    ev.add_argument("--teams", default=",".join(map(str, EVAL_TEAMS)), metavar="SIZES",
                    help="comma-separated team sizes (2-12) run as team scenarios: random places over the whole "
                         "arena, N//4 (at least 1) faulty robots with random faults (default %(default)s); "
                         "'none' for pairs only")
    ev.add_argument("--jobs", type=int, default=2, help="worker processes (default %(default)s)")
    ev.add_argument("--json", action="store_true", help="print one JSON object: every run and the table")
    ev.add_argument("--sim-timeout", type=float, default=EVAL_SIM_TIMEOUT, metavar="S",
                    help="simulated seconds a run may take before it counts as failed: what the robots did, "
                         "whatever the machine's load (default %(default)s)")
    ev.add_argument("--timeout", type=float, default=600.0,
                    help="wall seconds per run before it counts as failed, a guard against a hung run; a team of N "
                         "gets N/2 times as much, as every camera slows the simulator (default %(default)s)")
    ev.set_defaults(func=cmd_eval)


def _setup_logging() -> None:
    logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)


def cmd_run(args: argparse.Namespace) -> int:
    from agents.cooperative import paper_scenario, run_scenario, team_scenario

    _setup_logging()
    if args.faulty is not None and args.robots is None:
        print("faultmas run: --faulty K needs --robots N (the pair has one faulty robot)", file=sys.stderr)
        return 2
    if args.secure and (args.in_process or args.bridge != "sim"):
        print("faultmas run: --secure signs the messages of agent processes on the embedded simulator; "
              "not with --in-process (no messages travel) nor with --bridge other than sim", file=sys.stderr)
        return 2
    try:
        scenario = team_scenario(args.robots, args.faulty or 1, args.seed, fault=args.fault) if args.robots \
            else paper_scenario(args.fault or "encoders", args.seed)
    except ValueError as exc:
        print(f"faultmas run: {exc}", file=sys.stderr)
        return 2
    choice = None
    if args.bridge in ("sim", "ros2"):
        if args.bridge_option:
            print(f"faultmas run: --bridge {args.bridge} takes no --bridge-option here (the run sets its robots "
                  f"up from --seed and --fault)", file=sys.stderr)
            return 2
    else:
        from agents.environment import choose_bridge
        try:
            choice = choose_bridge(None, args.bridge, args.bridge_option)
        except ValueError as exc:
            print(f"faultmas run: {exc}", file=sys.stderr)
            return 2
        if args.robots or args.in_process or args.inspect:
            print(f"faultmas run: --bridge {args.bridge} runs the pair in agent processes (not --robots, "
                  f"--in-process or --inspect)", file=sys.stderr)
            return 2
    if args.timeout is None:
        args.timeout = RUN_TIMEOUT * max(1.0, (args.robots or 2) / 2)
    show = sys.stderr if args.json else sys.stdout
    inspector = None
    if args.inspect:
        from agents.inspector.cli import parse_listen
        from agents.inspector.live import LiveInspector
        if args.in_process or args.bridge != "sim":
            print("faultmas run: --inspect needs the agents in their own processes on the simulator "
                  "(not --in-process, not --bridge ros2: use `faultmas inspect --connect` there)", file=sys.stderr)
            return 2
        try:
            host, port = parse_listen(args.listen, args.public)
        except ValueError as exc:
            print(f"faultmas run: {exc}", file=sys.stderr)
            return 2
        try:
            inspector = LiveInspector(host, port, args.inspect_hold, args.allow_pause, out=show,
                                      timeline_marks=args.timeline_marks)
        except OSError as exc:
            print(f"faultmas run: cannot serve the inspector on {args.listen}: {exc.strerror or exc}", file=sys.stderr)
            return 1
    for r in scenario.robots if args.bridge == "sim" else ():
        what = f"fault {r.fault}" + (" (a transient stall raises a false alarm)" if r.false_alarm else "")
        print(f"faultmas: {r.name:<8} at ({r.x:5.2f}, {r.y:5.2f}) heading {r.yaw_deg:6.1f} deg, {what}", file=show)
    agent_lines = None if args.quiet else show
    if args.bridge == "ros2":
        from agents.ros2_run import run_on_ros2
        result = run_on_ros2(scenario, timeout=args.timeout, out=agent_lines, echo=lambda m: _echo(m, show))
    elif choice is not None:
        from agents.bridge_run import run_on_bridge
        print(f"faultmas: faulty and helper through bridge {choice.name}; their fault is what the robots have "
              f"(scored against --fault {scenario.robots[0].fault})", file=show)
        result = run_on_bridge(scenario, choice, timeout=args.timeout, out=agent_lines, echo=lambda m: _echo(m, show))
    else:
        result = run_scenario(scenario, processes=not args.in_process, timeout=args.timeout, secure=args.secure,
                              out=agent_lines, err=sys.stderr, echo=lambda m: _echo(m, show), inspector=inspector)
    if args.plot and result.world is not None:
        from robot_bridge.cli import plot
        tested = [r for r in result.robots if r.fault != "none"] or result.robots[:1]
        plot(result.world, args.plot, title="; ".join(
            f"{r.name}: fault {r.fault}, diagnosis {r.diagnosis or 'none reached'}" for r in tested)
            + f" (seed {result.scenario.seed})")
        print(f"faultmas: trajectories drawn to {args.plot}", file=show)
    if args.json:
        print(json.dumps(_as_json(result)))
    else:
        print(_summary(result))
    return RUN_EXIT_CODES[result.outcome]


#: Exit codes of ``faultmas run`` by outcome: a scripted campaign must tell a dead agent from a timeout
#: from a wrong diagnosis (issue 22).
RUN_EXIT_CODES = {"correct": 0, "wrong": 1, "died": 3, "timeout": 124}


def died_text(agent: str, status: int) -> str:
    """``Faulty: killed by SIGKILL (exit -9)`` / ``Helper: exited with status 1``."""
    if status < 0:
        try:
            name = signal.Signals(-status).name
        except ValueError:
            name = f"signal {-status}"
        return f"{agent}: killed by {name} (exit {status})"
    return f"{agent}: exited with status {status}"


def _echo(mark, stream) -> None:
    label = STEP_LABELS.get(mark.step, mark.step)
    stream.write(f"  >> {mark.sim:7.2f} s sim {mark.wall:7.2f} s wall  {mark.agent}: {label} {mark.detail}\n")
    stream.flush()


def _seconds(steps: dict) -> dict:
    """Step latencies rounded to what they mean (10 ms: the simulator steps at 20 ms)."""
    return {step: None if value is None else round(value, 2) for step, value in steps.items()}


def _as_json(result) -> dict:
    """One schema for the pair and the team: the run's verdict and one entry per robot that had a task or a
    fault (``fault``, ``diagnosis``: strings; steps in simulated and wall seconds)."""
    return {"correct": result.correct, "finished": result.finished, "outcome": result.outcome,
            "died": [{"agent": agent, "exit": status} for agent, status in result.died],
            "frozen": [{"process": name, "seconds": seconds} for name, seconds in result.frozen],
            "seed": result.scenario.seed,
            "robots": [{"robot": r.name, "fault": r.fault, "expected": r.expected, "diagnosis": r.diagnosis,
                        "correct": r.correct, "steps": _seconds(r.steps_sim), "steps_wall": _seconds(r.steps_wall)}
                       for r in result.robots]}


def _fmt(value) -> str:
    return "-" if value is None else f"{value:.2f}"


def _summary(result) -> str:
    lines = [""]
    for r in result.robots:
        verdict = "correct" if r.correct else f"WRONG (expected {r.expected})"
        lines.append(f"{r.name}: injected {r.fault}, diagnosis {r.diagnosis or 'none reached'}: {verdict}")
    lines += ["", "| robot | step | simulated s | wall s |", "|---|---|---|---|"]
    for r in result.robots:
        for step in STEP_NAMES:
            lines.append(f"| {r.name} | {step} | {_fmt(r.steps_sim[step])} | {_fmt(r.steps_wall[step])} |")
    for agent, status in result.died:
        what = "robot process" if "/" in agent else "agent"  # ROS 2 nodes are named robot/node
        lines.append(f"\nthe run ended early: {what} {died_text(agent, status)}")
    if not result.finished and not result.died:
        lines.append("\nthe run did not finish in time")
    if result.frozen:
        lines.append("\nstopped (SIGSTOP) during the run: "
                     + ", ".join(f"{name} for {seconds:.1f} s" for name, seconds in result.frozen))
    return "\n".join(lines)


# ---- evaluation ------------------------------------------------------------------------------------
def team_label(size: int) -> str:
    return f"team of {size}"


def _team_size(scenario: str) -> int:
    return int(scenario.rsplit(" ", 1)[1]) if scenario.startswith("team of ") else 2


def eval_scenario(name: str, seed: int):
    """The scenario of one evaluation run: a pair with fault ``name``, or ``team of N``."""
    from agents.cooperative import random_pair_scenario, team_scenario

    if name.startswith("team of "):
        size = int(name.rsplit(" ", 1)[1])
        return team_scenario(size, max(1, size // 4), seed)
    return random_pair_scenario(name, seed)


def _one_run(job: tuple[str, int, float, float]) -> dict:
    """One evaluation run; a team's steps are the means over its faulty robots."""
    from agents.cooperative import run_scenario

    name, seed, timeout, sim_timeout = job
    logging.disable(logging.WARNING)
    result = run_scenario(eval_scenario(name, seed), processes=False, timeout=timeout, sim_timeout=sim_timeout)
    tested = [r for r in result.robots if r.fault != "none"] or result.robots[:1]

    def mean(clock: str) -> dict:
        values = {step: [getattr(r, clock)[step] for r in tested if getattr(r, clock)[step] is not None]
                  for step in STEP_NAMES}
        return {step: statistics.fmean(v) if v else None for step, v in values.items()}
    diagnosis = tested[0].diagnosis if len(tested) == 1 and not name.startswith("team") else \
        [r.diagnosis for r in tested]
    return {"fault": name, "seed": seed, "diagnosis": diagnosis, "correct": result.correct,
            "steps": mean("steps_sim"), "steps_wall": mean("steps_wall")}


def cmd_eval(args: argparse.Namespace) -> int:
    from concurrent.futures import ProcessPoolExecutor

    faults = [f.strip() for f in args.faults.split(",") if f.strip()]
    unknown = [f for f in faults if f not in EXPECTED]
    try:
        sizes = [int(s) for s in args.teams.split(",") if s.strip()] if args.teams != "none" else []
    except ValueError:
        sizes = [0]
    if unknown or args.runs < 1 or args.jobs < 1 or any(not 2 <= s <= 12 for s in sizes):
        why = (f"unknown scenario(s) {unknown}" if unknown else "--runs and --jobs must be >= 1"
               if args.runs < 1 or args.jobs < 1 else f"--teams {args.teams!r}: sizes must be numbers 2..12")
        print(f"faultmas eval: {why}", file=sys.stderr)
        return 2
    faults += [team_label(s) for s in sizes]
    # a team's run gets more wall time: its cameras cost the simulator in proportion to the robots
    jobs = [(f, args.seed * 100_000 + i, args.timeout * max(1.0, _team_size(f) / 2), args.sim_timeout)
            for f in faults for i in range(args.runs)]
    runs: list[dict] = []
    from tqdm import tqdm

    # runs done / total, elapsed and ETA on stderr while it works (a terminal only: no bar in a log file)
    from robot_bridge.processes import die_with_multiprocessing_parent

    # each worker ends with this process, however it ends (a SIGKILLed eval left its workers running)
    with ProcessPoolExecutor(max_workers=args.jobs, initializer=die_with_multiprocessing_parent) as pool, \
            tqdm(total=len(jobs), unit="run", desc="faultmas eval", file=sys.stderr, disable=None) as bar:
        for done in pool.map(_one_run, jobs):
            runs.append(done)
            bar.update(1)
            if not args.json:
                bar.write(f"  {done['fault']:<15} seed {done['seed']}: {done['diagnosis']} "
                          f"({'ok' if done['correct'] else 'WRONG'})", file=sys.stderr)
    table = eval_table(runs, faults)
    if args.json:
        print(json.dumps({"runs": runs, "table": table}))
    else:
        print(format_eval_table(table, args.runs))
    return 0 if all(row["success_rate"] == 1.0 for row in table) else 1


def eval_table(runs: list[dict], faults: list[str]) -> list[dict]:
    """Per scenario: success rate and mean/sd of every step (simulated and wall seconds)."""
    table = []
    for fault in faults:
        mine = [r for r in runs if r["fault"] == fault]
        row = {"scenario": fault, "runs": len(mine),
               "success_rate": sum(r["correct"] for r in mine) / len(mine) if mine else 0.0}
        for clock in ("steps", "steps_wall"):
            for step in STEP_NAMES:
                values = [r[clock][step] for r in mine if r[clock][step] is not None]
                row[f"{clock}.{step}"] = (statistics.fmean(values) if values else None,
                                          statistics.stdev(values) if len(values) > 1 else None)
        table.append(row)
    return table


def format_eval_table(table: list[dict], runs: int) -> str:
    def cell(pair) -> str:
        mean, sd = pair
        return "-" if mean is None else f"{mean:.2f} ± {sd:.2f}" if sd is not None else f"{mean:.2f}"
    head = ("| scenario | runs | correct | fault detection | robot detection | diagnosis | total "
            "| total (wall) |\n|---|---|---|---|---|---|---|---|")
    rows = [f"| {r['scenario']} | {r['runs']} | {100 * r['success_rate']:.0f}% | {cell(r['steps.fault_detection'])} "
            f"| {cell(r['steps.robot_detection'])} | {cell(r['steps.diagnosis'])} | {cell(r['steps.total'])} "
            f"| {cell(r['steps_wall.total'])} |" for r in table]
    return (f"faultmas eval: {runs} runs per scenario; latencies in simulated seconds (mean ± sd)\n"
            + head + "\n" + "\n".join(rows))
