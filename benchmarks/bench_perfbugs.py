"""The learned detector of performance bugs: training time, scoring cost per component per tick, and
the CPU share of the online observer watching the live team.

Training: ``detection.learned.evaluate.train_models`` on the paper data set when it is there, else on
the smoke data set (CPU seconds). Scoring: a recorded run replayed through the online observer
(``LearnedResourceObserver``, features + model, counters given) per component per tick, in CPU
time of the observer's thread (wall time on a shared machine measures the neighbours), target
≤ 1 ms; reading one process's counters with psutil is listed apart. Live: the team's ROS 2 nodes (no
camera) with the usual workload, the observer in a child process of its own; its CPU time over the
window divided by the wall time, target ≤ 2 % of one core (skipped with --quick), split into Fast DDS's
receive threads, the ticks and the rest (the reader taking and encoding the messages). CPU time, not
wall time: a busy machine does not add to it (beyond colder caches).
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

TARGET_TICK_MS = 1.0
TARGET_CPU_SHARE = 0.02


def _dataset(profiles: tuple[str, ...] = ("paper", "smoke")):
    """The first data set present of ``profiles`` (--quick prefers the small one: it checks the harness)."""
    from detection.learned.dataset import load
    from experiments.perfbugs import data_dir
    for profile in profiles:
        if (data_dir(profile) / "manifest.json").exists():
            return profile, load(data_dir(profile))
    raise RuntimeError("no perfbugs data set: faultmas experiment perfbugs --generate")


def _hz_config(models) -> str:
    """Observers beside the learned detector: an ``hz`` observer on every ROS 2 topic the models read
    (what ``faultmas observe CONFIG --learned`` does when both watch the same topics)."""
    from detection.learned.observer import model_columns
    topics = sorted({t for m in models.values() for t in model_columns(m) if t.startswith("/")})
    return "main_loop_rate: 10\nsetup:\n  - type: hz\n    topics:\n" + "".join(
        f"      - {{name: {t}, states: [{{state: ok, frequency: {{type: greater_than, greater_than: -1}}}}]}}\n"
        for t in topics)


def _watch_child(domain: int, models_dir: str, seconds: float, observers: str = "") -> None:
    """In the child: watch the team for ``seconds`` after a warm-up; print CPU seconds and ticks.
    ``observers``: '' the learned detector alone; 'shared' with hz observers on its topics through one
    reader (one subscription per topic); 'separate' the same with a participant each (as before)."""
    import psutil

    from detection.config import load_observers
    from detection.learned.observer import load_models
    from detection.learned.scenario import ROBOTS
    from detection.learned.watch import LiveLearnedObserver
    from detection.taps.ros2 import Ros2Tap

    from benchmarks.bench_observers import thread_cpu, thread_shares

    models = load_models(models_dir)
    tap = None
    if observers:
        config = load_observers("<bench>", _hz_config(models))
        tap = Ros2Tap(config, config.build(), lambda obs: None, domain_id=domain)
    live = LiveLearnedObserver(models, [f"/{r}" for r in ROBOTS], lambda obs: None, domain,
                               reader=tap.reader if observers == "shared" else None)
    if tap is not None:
        tap.start()
    try:
        time.sleep(3.0)
        me = psutil.Process()
        before, ticks, received = me.cpu_times(), len(live.observer.tick_seconds), live.tap.received
        before_threads, before_tick = thread_cpu(), sum(live.observer.tick_cpu_seconds)
        time.sleep(seconds)
        after, after_threads = me.cpu_times(), thread_cpu()
        cpu = (after.user + after.system) - (before.user + before.system)
        dds = sum(v - before_threads.get(k, 0.0) for k, v in after_threads.items() if k.startswith("dds."))
        tick = sum(live.observer.tick_cpu_seconds) - before_tick
        print(f"{cpu} {len(live.observer.tick_seconds) - ticks} {live.tap.received - received} {dds} {tick}",
              flush=True)
        print(thread_shares(before_threads, after_threads, seconds), flush=True)
    finally:
        live.close()
        if tap is not None:
            tap.close()


def _live_share(models, seconds: float, camera: bool, observers: tuple[str, ...] = ("",)) -> list[tuple]:
    """The team is launched as the models' data set was recorded (``camera``): models of the camera
    nodes refuse a team without them, and models without them would not watch the images."""
    import rclpy

    from detection.learned.scenario import ROBOTS, Workload
    from robot_bridge.ros2.launch import Supervisor, plan
    from robot_bridge.ros2.runtime import RosContext, loopback_env

    domain = 201 + os.getpid() % 30
    with tempfile.TemporaryDirectory() as tmp:
        for name, model in models.items():
            model.save(Path(tmp) / f"{name}.npz")
        supervisor = Supervisor(plan(list(ROBOTS), camera=camera), domain)
        supervisor.start()
        try:
            if supervisor.wait_ready(90):
                raise RuntimeError("the team did not come up")
            with RosContext(domain_id=domain) as work:
                Workload(work.add(rclpy.create_node("bench_workload", context=work.context)), ROBOTS, seed=3)
                children = [subprocess.run([sys.executable, "-c", "import sys; from benchmarks.bench_perfbugs import "
                                            f"_watch_child; _watch_child({domain}, {tmp!r}, {seconds}, {kind!r})"],
                                           capture_output=True, text=True, env=loopback_env(), timeout=seconds + 120,
                                           cwd=Path(__file__).resolve().parents[1])
                            for kind in observers]
        finally:
            supervisor.stop()
    results = []
    for child in children:
        if child.returncode != 0:
            raise RuntimeError(child.stderr[-2000:])
        figures, threads = child.stdout.strip().splitlines()[-2:]
        cpu, ticks, messages, dds, tick = figures.split()
        results.append((float(cpu) / seconds, int(ticks), int(messages), float(dds) / seconds, float(tick) / seconds,
                        threads))
    return results


def run(quick: bool = False) -> str:
    import psutil

    from detection.learned.counters import read_counters
    from detection.learned.evaluate import partitions, train_models
    from detection.learned.observer import LearnedResourceObserver, replay

    profile, dataset = _dataset(("smoke", "paper") if quick else ("paper", "smoke"))
    parts = partitions(dataset.fault_free_runs(), 1 if len(dataset.fault_free_runs()) < 10 else 2)
    started = time.process_time()
    models = train_models(dataset, parts, 0.005)
    training = time.process_time() - started
    samples = sum(len(s.select(parts[0]).run) for s in dataset.components.values())

    observer = LearnedResourceObserver(models, {c: None for c in models}, lambda obs: None)
    replay(observer, dataset.path / f"run-{parts[3][0]:03d}.npz")
    per_tick = np.array(observer.tick_cpu_seconds[1:]) / len(models) * 1000.0
    me = psutil.Process()
    started = time.perf_counter()
    for _ in range(200):
        read_counters(me)
    psutil_ms = (time.perf_counter() - started) / 200 * 1000.0

    lines = [f"{'what':<58} {'measured':>14} {'target':>10}",
             f"{f'training, {profile} data ({len(models)} components, {samples} ticks in partition 1)':<58} "
             f"{training:>12.1f} s {'-':>10}",
             f"{'scoring per component per tick, CPU, median (features+model)':<58} {np.median(per_tick):>11.3f} ms "
             f"{'<= 1 ms':>10}",
             f"{'scoring per component per tick, CPU, worst':<58} {per_tick.max():>11.3f} ms {'':>10}",
             f"{'reading one process counters (psutil)':<58} {psutil_ms:>11.3f} ms {'':>10}"]
    if quick:
        lines.append(f"{'online observer CPU share, live team':<58} {'(skipped: --quick)':>14}")
    else:
        from detection.learned.scenario import PROFILES
        kinds = ("", "separate", "shared")
        results = _live_share(models, 30.0, PROFILES[profile].camera, kinds)
        share, ticks, messages, dds, tick, threads = results[0]
        lines.append(f"{f'online observer CPU share, live team, {profile} models ({messages / 30:.0f} msg/s, {ticks} ticks)':<58} "
                     f"{share * 100:>12.2f} % {'<= 2 %':>10}")
        lines.append(f"{'  of which Fast DDS receive threads':<58} {dds * 100:>12.2f} %")
        lines.append(f"{'  of which ticks (psutil counters + features + models)':<58} {tick * 100:>12.2f} %")
        lines.append(f"{'  of which taking + encoding the messages (rest)':<58} {(share - dds - tick) * 100:>12.2f} %")
        lines.append(f"  by thread: {threads}")
        for kind, (share, _, _, dds, _, threads) in zip(kinds[1:], results[1:]):
            what = {"separate": "hz observers on its topics too, a participant each",
                    "shared": "hz observers on its topics too, one subscription per topic"}[kind]
            lines.append(f"{'  + ' + what:<58} {share * 100:>12.2f} % {'':>10}")
            lines.append(f"      Fast DDS {dds * 100:.2f} %; by thread: {threads}")
    return "\n".join(lines)
