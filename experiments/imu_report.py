"""The IMU experiment's table (the paper's, plus latency, false switches and CPU), its JSON and its plot."""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np

from experiments.imu_result import ODOMETRIES, RunResult

PAPER_REDUCTIONS: dict[str, tuple[float, float]] = {
    "imu_stuck": (-28.1, -39.9),
    "imu_over": (-25.6, -35.6),
    "imu_zero_after_rotating": (-39.3, -50.9),
}
"""Seed paper (Zaman et al., ICRA 2013, section VI): switched vs always-IMU, mean and RMS position error (%)."""

LABELS = {"encoders": "encoders only", "always_imu": "always IMU", "switched": "diagnosis-switched"}


@dataclass(frozen=True)
class Spread:
    """Median with the 25th and 75th percentiles of a figure over runs."""

    median: float
    p25: float
    p75: float

    @classmethod
    def of(cls, values: Sequence[float]) -> "Spread":
        if not values:
            return cls(math.nan, math.nan, math.nan)
        p25, median, p75 = np.percentile(values, [25, 50, 75])
        return cls(float(median), float(p25), float(p75))

    def text(self, fmt: str = "{:.3f}") -> str:
        if math.isnan(self.median):
            return "-"
        return f"{fmt.format(self.median)} [{fmt.format(self.p25)}, {fmt.format(self.p75)}]"

    def to_json(self) -> dict[str, float]:
        return {"median": self.median, "p25": self.p25, "p75": self.p75}


def reduction(result: RunResult, measure: str) -> float:
    """Switched vs always-IMU for one run, in percent (negative: switched is better)."""
    always = getattr(result, f"{measure}_error")("always_imu")
    switched = getattr(result, f"{measure}_error")("switched")
    return 100.0 * (switched - always) / always


@dataclass(frozen=True)
class FaultSummary:
    fault: str
    runs: int
    mean_error: dict[str, Spread]
    rms_error: dict[str, Spread]
    mean_reduction: Spread
    rms_reduction: Spread
    detected: int
    latency_median: float
    latency_p95: float
    false_switches: int
    cpu_share_max: float

    def meets_paper(self) -> bool | None:
        """Median reductions at least the paper's (None: the paper has no figure for this fault)."""
        paper = PAPER_REDUCTIONS.get(self.fault)
        if paper is None:
            return None
        return self.mean_reduction.median <= paper[0] and self.rms_reduction.median <= paper[1]


def summarize(fault: str, results: Sequence[RunResult]) -> FaultSummary:
    latencies = [r.latency for r in results if r.latency is not None and not r.false_switch]
    return FaultSummary(
        fault, len(results),
        {o: Spread.of([r.mean_error(o) for r in results]) for o in ODOMETRIES},
        {o: Spread.of([r.rms_error(o) for r in results]) for o in ODOMETRIES},
        Spread.of([reduction(r, "mean") for r in results]),
        Spread.of([reduction(r, "rms") for r in results]),
        len(latencies),
        float(np.median(latencies)) if latencies else math.nan,
        float(np.percentile(latencies, 95)) if latencies else math.nan,
        sum(r.false_switch for r in results),
        max((r.cpu_share for r in results), default=0.0))


def table(summaries: Sequence[FaultSummary]) -> str:
    """The report as text: one block per fault, medians with [p25, p75] over the runs."""
    lines = []
    for s in summaries:
        lines.append(f"{s.fault} ({s.runs} runs)")
        lines.append(f"  {'odometry':<20} {'mean error (m)':<28} {'RMS error (m)':<28}")
        for o in ODOMETRIES:
            lines.append(f"  {LABELS[o]:<20} {s.mean_error[o].text():<28} {s.rms_error[o].text():<28}")
        if s.fault != "none":
            paper = PAPER_REDUCTIONS.get(s.fault)
            paper_text = f"   (paper: {paper[0]:+.1f} % / {paper[1]:+.1f} %)" if paper else ""
            lines.append(f"  switched vs always IMU: mean {s.mean_reduction.text('{:+.1f}')} %, "
                         f"RMS {s.rms_reduction.text('{:+.1f}')} %{paper_text}")
            lines.append(f"  detected in {s.detected}/{s.runs} runs; latency fault -> rule fired: "
                         f"median {s.latency_median:.2f} s, p95 {s.latency_p95:.2f} s")
        if s.fault == "none":
            lines.append(f"  false switches: {s.false_switches}/{s.runs} fault-free runs")
        else:
            lines.append(f"  false switches (rule fired before the fault began): {s.false_switches}/{s.runs}")
        lines.append(f"  CPU of observers + diagnosis + rules: {100 * s.cpu_share_max:.2f} % of one core (worst run)")
        lines.append("")
    return "\n".join(lines).rstrip() + "\n"


def to_json(summaries: Sequence[FaultSummary], settings: dict[str, Any]) -> dict[str, Any]:
    out: dict[str, Any] = {"settings": settings, "faults": {}}
    for s in summaries:
        out["faults"][s.fault] = {
            "runs": s.runs,
            "mean_error_m": {o: s.mean_error[o].to_json() for o in ODOMETRIES},
            "rms_error_m": {o: s.rms_error[o].to_json() for o in ODOMETRIES},
            "reduction_vs_always_imu_pct": {"mean": s.mean_reduction.to_json(), "rms": s.rms_reduction.to_json()},
            "paper_reduction_pct": dict(zip(("mean", "rms"), PAPER_REDUCTIONS[s.fault]))
            if s.fault in PAPER_REDUCTIONS else None,
            "meets_paper": s.meets_paper(),
            "detected": s.detected,
            "latency_s": {"median": s.latency_median, "p95": s.latency_p95},
            "false_switches": s.false_switches,
            "cpu_share_max": s.cpu_share_max,
        }
    return out


def plot(results: Sequence[RunResult], path: str) -> None:
    """Ground truth and the three odometries of one run per fault, the switch marked on each."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(5.0 * len(results), 5.0), squeeze=False)
    styles = {"truth": ("black", "-", "ground truth"), "encoders": ("tab:blue", "--", LABELS["encoders"]),
              "always_imu": ("tab:red", ":", LABELS["always_imu"]), "switched": ("tab:green", "-", LABELS["switched"])}
    for ax, result in zip(axes[0], results):
        for key, (colour, style, label) in styles.items():
            xs = [getattr(s, key)[0] for s in result.samples]
            ys = [getattr(s, key)[1] for s in result.samples]
            ax.plot(xs, ys, style, color=colour, label=label, linewidth=1.2 if key != "truth" else 1.8)
        for when, marker, label in ((result.fault_time, "x", "fault"), (result.switch_time, "o", "use_imu := false")):
            if when is None:
                continue
            sample = min(result.samples, key=lambda s: abs(s.time - when))
            ax.plot(*sample.switched, marker, color="tab:purple" if marker == "o" else "tab:orange",
                    markersize=10, label=f"{label} ({when:.1f} s)", fillstyle="none" if marker == "o" else "full")
        title = result.fault if result.fault != "none" else "no fault"
        ax.set_title(f"{title} (seed {result.seed})")
        ax.set_xlabel("x (m)")
        ax.set_ylabel("y (m)")
        # Frame the route and the odometries that stay near it; a runaway always-IMU leaves the frame.
        near = [p for s in result.samples for p in (s.truth, s.encoders, s.switched)]
        xs, ys = [p[0] for p in near], [p[1] for p in near]
        ax.set_xlim(min(xs) - 1.0, max(xs) + 1.0)
        ax.set_ylim(min(ys) - 1.0, max(ys) + 1.0)
        ax.set_aspect("equal", adjustable="box")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.12), ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
