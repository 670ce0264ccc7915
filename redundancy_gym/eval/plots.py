"""Plots of evaluation traces (matplotlib, headless)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from .evaluate import EpisodeTrace  # noqa: E402

__all__ = ["plot_clearance", "plot_traces", "save_figure"]


def plot_traces(
    traces: Mapping[str, EpisodeTrace], path: str | Path, *, title: str = "", error_tolerance: float | None = 1e-3
) -> Path:
    """TCP tracking error (against the env's reference path), peak joint speed and obstacle clearance over time,
    one line per labelled episode.

    Args:
        traces: label -> episode trace.
        path: PNG path (parents created).
        title: figure title.
        error_tolerance: drawn as a dashed line on the error axis [m] (``None`` for none).
    """
    fig, axes = plt.subplots(3, 1, figsize=(8, 8.5), sharex=True)
    for label, trace in traces.items():
        axes[0].semilogy(trace.time, np.maximum(trace.tracking_error, 1e-9), label=label)
        axes[1].plot(trace.time, trace.joint_speed, label=label)
        clearance = np.where(np.isfinite(trace.min_clearance), trace.min_clearance, np.nan)
        axes[2].plot(trace.time, clearance, label=label)
    if error_tolerance is not None:
        axes[0].axhline(error_tolerance, color="k", ls="--", lw=0.8, label=f"tolerance {error_tolerance:g} m")
    axes[2].axhline(0.0, color="r", ls="--", lw=0.8, label="contact")
    axes[0].set_ylabel("TCP tracking error [m]")
    axes[1].set_ylabel("max |joint speed| [rad/s]")
    axes[2].set_ylabel("obstacle clearance [m]")
    axes[2].set_xlabel("time [s]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    if title:
        fig.suptitle(title)
    return save_figure(fig, path)


def save_figure(fig: plt.Figure, path: str | Path, dpi: int = 110) -> Path:
    """Lay out, write as PNG (parents created) and close a figure."""
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def plot_clearance(traces: dict[str, EpisodeTrace], path: str | Path, title: str) -> Path:
    """Minimum swept-sphere clearance over time, one line per labelled episode, with the contact line."""
    fig, ax = plt.subplots(figsize=(7.5, 3.6))
    for label, trace in traces.items():
        ax.plot(trace.time, 1e3 * trace.min_clearance, label=label)
    ax.axhline(0.0, color="k", lw=0.8, ls="--", label="contact")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("min clearance [mm]")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    return save_figure(fig, path)
