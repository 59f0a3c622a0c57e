"""The learned detector of performance bugs: training time, scoring cost per component per tick, and
the CPU share of the online observer watching the live team.

Training: ``detection.learned.evaluate.train_models`` on the paper data set when it is there, else on
the smoke data set (CPU seconds). Scoring: a recorded run replayed through the online observer
(``LearnedResourceObserver``, features + model, counters given) per component per tick, in CPU
time of the observer's thread (wall time on a shared machine measures the neighbours), target
≤ 1 ms; reading one process's counters with psutil is listed apart. Live: the team's ROS 2 nodes with
the usual workload, launched as the data set was recorded (with cameras for the paper data) and then
without cameras, the observer in a child process of its own, alone and beside hz observers sharing its
reader; its CPU time over the window divided by the wall time, target ≤ 2 % of one core (skipped with
--quick), side by side: the whole process, Fast DDS's receive threads (what any subscriber of these
topics pays), and ours: the ticks, encoding, and taking the messages. CPU time, not wall time: a busy
machine does not add to it (beyond colder caches).
"""
from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
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
    """In the child: watch the team for ``seconds`` after a warm-up; print CPU seconds (the process, Fast
    DDS's threads, the ticks, encoding), ticks and messages, then the split by thread.
    ``observers``: '' the learned detector alone; 'shared' with hz observers on its topics through one
    reader (one subscription per topic); 'separate' the same with a participant each (as before)."""
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
    encoding = [0.0]
    listener, encode = live.tap._listener, live.tap._listener.on_batch

    def timed(batch) -> None:                   # the learned tap's part of a batch: encoding + buffers
        started = time.thread_time()
        encode(batch)
        encoding[0] += time.thread_time() - started
    listener.on_batch = timed
    if tap is not None:
        tap.start()
    try:
        time.sleep(3.0)
        before, ticks, received = time.process_time(), len(live.observer.tick_seconds), live.tap.received
        before_threads, before_tick, before_encoding = thread_cpu(), sum(live.observer.tick_cpu_seconds), encoding[0]
        time.sleep(seconds)
        cpu, after_threads = time.process_time() - before, thread_cpu()
        dds = sum(v - before_threads.get(k, 0.0) for k, v in after_threads.items() if k.startswith("dds."))
        tick = sum(live.observer.tick_cpu_seconds) - before_tick
        print(f"{cpu} {len(live.observer.tick_seconds) - ticks} {live.tap.received - received} {dds} {tick} "
              f"{encoding[0] - before_encoding}", flush=True)
        print(thread_shares(before_threads, after_threads, seconds), flush=True)
    finally:
        live.close()
        if tap is not None:
            tap.close()


@dataclass
class Share:
    """One child's CPU over the window, as shares of one core (the process, of which Fast DDS's
    threads; the rest is ours: the ticks, encoding, and the rest: taking the messages)."""

    team: str
    kind: str
    whole: float
    dds: float
    ticks: float
    encoding: float
    messages_per_s: float
    tick_count: int
    threads: str

    @property
    def ours(self) -> float:
        return self.whole - self.dds

    @property
    def rest(self) -> float:
        """Taking the messages (the reader's loop and rcl's take), and the hz observers where they run."""
        return self.ours - self.ticks - self.encoding


def _live_share(models, seconds: float, camera: bool, observers: tuple[str, ...] = ("",)) -> list[Share]:
    """The team is launched with or without its cameras; the models of nodes not launched are left out
    (they would refuse a team without their component), as are the agents' (no agents here)."""
    import rclpy

    from detection.learned.scenario import ROBOTS, Workload
    from robot_bridge.ros2.launch import Supervisor, plan
    from robot_bridge.ros2.perfbugs import component_name
    from robot_bridge.ros2.runtime import RosContext, loopback_env

    specs = plan(list(ROBOTS), camera=camera)
    launched = {component_name(spec.robot, spec.node) for spec in specs}
    domain = 201 + os.getpid() % 30
    with tempfile.TemporaryDirectory() as tmp:
        for name, model in models.items():
            if name in launched:
                model.save(Path(tmp) / f"{name}.npz")
        supervisor = Supervisor(specs, domain)
        supervisor.start()
        try:
            if supervisor.wait_ready(90):
                raise RuntimeError("the team did not come up")
            with RosContext(domain_id=domain) as work:
                Workload(work.add(rclpy.create_node("bench_workload", context=work.context)), ROBOTS, seed=3)
                children = [subprocess.run([sys.executable, "-c", "import sys; from benchmarks.bench_perfbugs import "
                                            f"_watch_child; _watch_child({domain}, {tmp!r}, {seconds}, {kind!r})"],
                                           capture_output=True, text=True, env=loopback_env(), timeout=seconds + 180,
                                           cwd=Path(__file__).resolve().parents[1])
                            for kind in observers]
        finally:
            supervisor.stop()
    results = []
    for kind, child in zip(observers, children):
        if child.returncode != 0:
            raise RuntimeError(child.stderr[-2000:])
        figures, threads = child.stdout.strip().splitlines()[-2:]
        cpu, ticks, messages, dds, tick, encoding = figures.split()
        results.append(Share("cameras" if camera else "no cameras", kind, float(cpu) / seconds, float(dds) / seconds,
                             float(tick) / seconds, float(encoding) / seconds, int(messages) / seconds, int(ticks),
                             threads))
    return results


LIVE_S = 45.0
KINDS = {"": "learned alone", "shared": "+ hz observers, shared reader",
         "separate": "+ hz observers, own participant"}


def _live_table(shares: list[Share], profile: str) -> list[str]:
    """Side by side: the whole process, Fast DDS's threads, ours and its parts; with and without cameras."""
    lines = [f"online observer, CPU share of one core over {LIVE_S:.0f} s, {profile} models, target <= 2 %:",
             f"  {'team':<11} {'watching':<31} {'msg/s':>6} {'whole':>7} {'FastDDS':>8} {'ours':>7} "
             f"{'ticks':>7} {'encoding':>8} {'rest':>7}"]
    for s in shares:
        lines.append(f"  {s.team:<11} {KINDS[s.kind]:<31} {s.messages_per_s:>6.0f} {s.whole * 100:>6.2f}% "
                     f"{s.dds * 100:>7.2f}% {s.ours * 100:>6.2f}% {s.ticks * 100:>6.2f}% {s.encoding * 100:>7.2f}% "
                     f"{s.rest * 100:>6.2f}%")
    lines.append("  (whole: CPU time of the observer's process; FastDDS: its dds.* threads; ours = whole - FastDDS:")
    lines.append("   ticks = psutil counters + features + models; encoding = the learned tap's batches; rest = taking the")
    lines.append("   messages (reader loop, rcl take), plus the hz observers' work in their rows)")
    for s in shares:
        lines.append(f"  threads, {s.team}, {KINDS[s.kind]}: {s.threads}")
    return lines


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
    started = time.process_time()
    for _ in range(200):
        read_counters(me)
    psutil_ms = (time.process_time() - started) / 200 * 1000.0

    lines = [f"{'what':<58} {'measured':>14} {'target':>10}",
             f"{f'training, {profile} data ({len(models)} components, {samples} ticks in partition 1)':<58} "
             f"{training:>12.1f} s {'-':>10}",
             f"{'scoring per component per tick, CPU, median (features+model)':<58} {np.median(per_tick):>11.3f} ms "
             f"{'<= 1 ms':>10}",
             f"{'scoring per component per tick, CPU, worst':<58} {per_tick.max():>11.3f} ms {'':>10}",
             f"{'reading one process counters (psutil), CPU':<58} {psutil_ms:>11.3f} ms {'':>10}"]
    if quick:
        lines.append(f"{'online observer CPU share, live team':<58} {'(skipped: --quick)':>14}")
    else:
        from detection.learned.scenario import PROFILES
        shares = []
        if PROFILES[profile].camera:            # the team as recorded, then without its cameras
            shares += _live_share(models, LIVE_S, True, ("", "shared"))
        shares += _live_share(models, LIVE_S, False, ("", "shared"))
        lines += _live_table(shares, profile)
    return "\n".join(lines)
