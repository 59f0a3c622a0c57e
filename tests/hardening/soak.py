"""The soak of issue 22 (``make soak``): a team of six robots diagnoses faults over and over, one
``faultmas run --robots 6`` run after another (agent processes over Zenoh, the embedded simulator served by
this process), until the runs add up to ``--sim-seconds`` of simulated time (default one hour).

What it watches: this long-lived process (the launcher's hub, the simulator server, the world: what
``faultmas eval`` keeps for hundreds of runs) for RSS, threads and open file descriptors after each run,
with the least-squares slope of RSS per run and per simulated hour; and at the end of every run that
finished, before the agents are stopped, each agent's intentions, events and beliefs (the inspector's
summary query) and its process's RSS and threads. A run that leaves intentions behind, threads or
descriptors that grow, or RSS that climbs run after run is a defect; the figures go to
docs/reliability.md. The agents live one run each: a leak inside an agent shows as a per-run figure that
grows with the run's length, not across runs.

``python -m tests.hardening.soak --sim-seconds 3600 --out soak.jsonl`` (one JSON line per run, then the
summary line). A team run lasts seconds of simulated time (the robots stop once the fault is diagnosed or
declared undiagnosed) and tens of wall seconds (six agent processes start), so an hour of simulated time
takes many hours of wall time: ``--wall-seconds`` caps it, and the summary says which limit ended it."""
from __future__ import annotations

import argparse
import json
import sys
import threading
import time

import psutil


def _team_state(hub, mas: str) -> dict:
    """Every agent's summary (intentions, events, beliefs) through the inspector's queryable."""
    from agents.inspector.keys import state_key

    selector = state_key(mas, "x").rsplit("/x/", 1)[0] + "/*/state?summary"
    states = {}
    for reply in hub.session.get(selector, timeout=5.0):
        if reply.ok is not None:
            state = json.loads(reply.ok.payload.to_bytes())
            states[state["agent"]] = {k: state.get(k) for k in ("intentions", "events", "beliefs", "top")}
    return states


def _agent_processes() -> dict:
    """RSS (MiB) and threads of this process's agent children, by agent name."""
    found = {}
    for child in psutil.Process().children():
        try:
            argv = child.cmdline()
            if "--name" in argv:
                found[argv[argv.index("--name") + 1]] = {"rss_mib": round(child.memory_info().rss / 2 ** 20, 1),
                                                         "threads": child.num_threads()}
        except psutil.Error:
            pass
    return found


def one_run(seed: int, timeout: float) -> dict:
    """One team run as ``faultmas run --robots 6`` does it, with the agents' state read before they stop."""
    from agents.cooperative import build_world, run_agent_processes, team_scenario
    from robot_bridge.sim.server import SimServer

    scenario = team_scenario(6, 1, seed)
    world, bridges = build_world(scenario)
    hub_of: dict = {}
    seen: dict = {}

    def serve(hub):
        hub_of["hub"] = hub
        return SimServer(hub.session, scenario.mas, bridges).start().stop

    def hold():
        seen["agents"] = _team_state(hub_of["hub"], scenario.mas)
        seen["processes"] = _agent_processes()
    started = time.monotonic()
    try:
        log = run_agent_processes(scenario, ["--bridge", "zenoh"], timeout, world=world, serve=serve, hold=hold)
    finally:
        for bridge in bridges.values():
            bridge.shutdown()
    results = log.results()
    return {"seed": seed, "sim_s": round(world.time, 1), "wall_s": round(time.monotonic() - started, 1),
            "finished": log.done.is_set(), "died": log.died, "frozen": log.frozen,
            "faults": [r.fault for r in results], "diagnoses": [r.diagnosis for r in results],
            "correct": log.done.is_set() and all(r.correct for r in results),
            "agents": seen.get("agents", {}), "agent_processes": seen.get("processes", {})}


def _slope(xs: list[float], ys: list[float]) -> float:
    if len(xs) < 2:
        return 0.0
    import numpy as np
    return float(np.polyfit(xs, ys, 1)[0])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sim-seconds", type=float, default=3600.0, help="simulated time to reach (default 1 h)")
    parser.add_argument("--wall-seconds", type=float, default=None,
                        help="also stop after this much wall time (the summary says which limit ended it)")
    parser.add_argument("--run-timeout", type=float, default=240.0, help="wall seconds per run (default 240)")
    parser.add_argument("--first-seed", type=int, default=1000)
    parser.add_argument("--out", default=None, help="also write the JSON lines here")
    args = parser.parse_args(argv)
    me = psutil.Process()
    out = open(args.out, "w") if args.out else None
    rows, sim_total, seed = [], 0.0, args.first_seed
    started = time.monotonic()
    while sim_total < args.sim_seconds and (args.wall_seconds is None
                                            or time.monotonic() - started < args.wall_seconds):
        row = one_run(seed, args.run_timeout)
        sim_total += row["sim_s"]
        row.update(sim_total_s=round(sim_total, 1), soak_rss_mib=round(me.memory_info().rss / 2 ** 20, 1),
                   soak_threads=threading.active_count(), soak_os_threads=me.num_threads(), soak_fds=me.num_fds())
        rows.append(row)
        line = json.dumps(row)
        print(line, flush=True)
        if out:
            out.write(line + "\n")
            out.flush()
        seed += 1
    settled = rows[1:] or rows  # the first run loads the interpreter, models and Zenoh: not a leak
    rss = [r["soak_rss_mib"] for r in settled]
    left = [a["intentions"] for r in rows if r["finished"] for a in r["agents"].values()]
    summary = {
        "ended_by": "sim_seconds" if sim_total >= args.sim_seconds else "wall_seconds",
        "runs": len(rows), "sim_hours": round(sim_total / 3600, 2), "wall_hours": round((time.monotonic() - started) / 3600, 2),
        "correct": sum(r["correct"] for r in rows), "finished": sum(r["finished"] for r in rows),
        "died": sum(bool(r["died"]) for r in rows), "frozen": sum(bool(r["frozen"]) for r in rows),
        "rss_mib_first_last": [rss[0], rss[-1]],
        "rss_slope_kib_per_run": round(_slope(list(range(len(rss))), rss) * 1024, 1),
        "rss_slope_mib_per_sim_hour": round(_slope([r["sim_total_s"] / 3600 for r in settled], rss), 2),
        "threads_first_last": [settled[0]["soak_os_threads"], settled[-1]["soak_os_threads"]],
        "fds_first_last": [settled[0]["soak_fds"], settled[-1]["soak_fds"]],
        "max_intentions_left_after_a_finished_run": max(left, default=None),
        "agent_rss_mib_max": max((p["rss_mib"] for r in rows for p in r["agent_processes"].values()), default=None),
        "agent_threads_max": max((p["threads"] for r in rows for p in r["agent_processes"].values()), default=None),
    }
    line = json.dumps({"summary": summary})
    print(line, flush=True)
    if out:
        out.write(line + "\n")
        out.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
