"""Replay one task of a soak (``tests/hardening/soak.py``) from its row: the same robots where they stood at
the task's start, the same fault in the same robot, a fresh team (what a long-lived team carries over from
earlier conversations is not replayed; the places and headings it left the robots in are).

``python -m tests.hardening.soak_replay soak.jsonl 34`` runs task 34 with the agents in this process (fast:
the world steps flat out) and prints the agents' lines and the outcome; ``--processes`` runs them as the soak
does (one process each over Zenoh); ``--runs N`` repeats it (timing differs run to run), e.g. to see how
often a placement fails."""
from __future__ import annotations

import argparse
import json
import sys

from agents.cooperative import RobotSetup, Scenario, run_scenario

PROGRAM = "team_robot.asl"


def task_row(path: str, task: int) -> dict:
    """The soak's row of ``task`` (it must have the robots' poses: soaks since they were recorded)."""
    with open(path) as rows:
        for line in rows:
            row = json.loads(line)
            if row.get("task") == task:
                if "poses" not in row:
                    raise SystemExit(f"{path}: task {task} has no robot poses (a soak from before they were recorded)")
                return row
    raise SystemExit(f"{path}: no task {task}")


def scenario_of(row: dict) -> Scenario:
    """The task's placement as a team scenario: every robot at its recorded pose, the faulty one with its fault."""
    robots = tuple(RobotSetup(name, x, y, yaw, row["fault"] if name == row["faulty"] else "none", PROGRAM)
                   for name, (x, y, yaw) in sorted(row["poses"].items()))
    return Scenario(robots, seed=row.get("seed", 1000) * 1000 + row["task"], destination=0.5)


def replay(row: dict, processes: bool = False, timeout: float = 300.0, sim_timeout: float = 240.0,
           out=None) -> tuple[str | None, bool, float]:
    """(the faulty robot's diagnosis, whether every robot ended, simulated seconds) of one replay."""
    result = run_scenario(scenario_of(row), processes=processes, timeout=timeout, sim_timeout=sim_timeout, out=out)
    faulty = next(r for r in result.robots if r.name == row["faulty"])
    return faulty.diagnosis, result.finished, round(result.world.time, 1)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rows", help="the soak's JSON lines (--out)")
    parser.add_argument("task", type=int)
    parser.add_argument("--processes", action="store_true", help="agents in processes over Zenoh, as the soak")
    parser.add_argument("--runs", type=int, default=1)
    parser.add_argument("--quiet", action="store_true", help="outcomes only, not the agents' lines")
    args = parser.parse_args(argv)
    row = task_row(args.rows, args.task)
    print(f"task {args.task}: {row['faulty']} {row['fault']}; poses {row['poses']}")
    failed = 0
    for run in range(args.runs):
        diagnosis, finished, sim = replay(row, args.processes, out=None if args.quiet else sys.stdout)
        ok = finished and diagnosis == row["fault"]
        failed += not ok
        print(f"run {run + 1}: {diagnosis} ({'correct' if ok else 'WRONG' if finished else 'not ended'}), {sim} s simulated",
              flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
