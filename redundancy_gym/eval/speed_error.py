"""Speed-vs-error report: each policy's compute time per step against its task error, as markdown and a plot."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .plots import save_figure  # noqa: E402

__all__ = ["plot_speed_error", "speed_error_markdown"]


def speed_error_markdown(reports: Mapping[str, dict[str, Any]], title: str, unit: str = "m") -> str:
    """A markdown table of evaluation-contract objects, one row per labelled policy (task errors in ``unit``)."""
    lines = [f"## {title}", "",
             f"| policy | success | collision | task error rms [{unit}] | task error max [{unit}] | pseudoenergy | "
             "step median [us] | step p99 [us] |",
             "| --- | --- | --- | --- | --- | --- | --- | --- |"]
    for label, r in reports.items():
        step = r["step_time_us"]
        lines.append(f"| {label} | {r['success_rate']:.2f} | {r['collision_rate']:.2f} | {r['task_error_rms']:.2e} | "
                     f"{r['task_error_max']:.2e} | {r['pseudoenergy']:.3f} | {step['median']:.1f} | {step['p99']:.1f} |")
    return "\n".join(lines) + "\n"


def plot_speed_error(reports: Mapping[str, dict[str, Any]], path: str | Path, title: str, unit: str = "m",
                     error: str = "max") -> Path:
    """Scatter of median step time [us] against the task error [``unit``] (log-log), one point per policy;
    ``error`` picks ``"max"`` or ``"rms"``, or ``"pseudoenergy"`` for the pseudoenergy [rad^2/s] instead."""
    if error not in ("max", "rms", "pseudoenergy"):
        raise ValueError(f"error must be 'max', 'rms' or 'pseudoenergy', got {error!r}")
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    for label, r in reports.items():
        value = r["pseudoenergy"] if error == "pseudoenergy" else r[f"task_error_{error}"]
        x, y = r["step_time_us"]["median"], max(value, 1e-9)
        ax.scatter([x], [y], s=40, label=label)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("policy compute time per step, median [us]")
    ax.set_ylabel("pseudoenergy [rad^2/s]" if error == "pseudoenergy" else f"task error {error} [{unit}]")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    return save_figure(fig, path)
