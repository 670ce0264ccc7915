"""Speed-vs-error report: each policy's compute time per step against its error, as markdown and a plot.

Every function takes evaluation-contract objects (:meth:`EvalReport.to_json`) keyed by a label naming the
policy and its options. The error metrics a section can show are :data:`METRICS`; times are the policy's own
compute time per step: median, p99, the amortized mean (a plan-once policy's first-step solve included) and
the first step alone (where such a policy plans); where a report has ``sb3_predict_us`` (an SB3 policy on its
compiled fast path), a column beside the step time gives the step with stable-baselines3's own ``predict``. A policy
that failed every episode (success rate 0) is drawn
hollow and left out of the "fastest / most accurate" sentence.
"""

from __future__ import annotations

import json
import math
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.text import Text  # noqa: E402

from .plots import save_figure  # noqa: E402

__all__ = [
    "METRICS",
    "Metric",
    "axis_scale",
    "plot_speed_error",
    "plot_speed_error_panels",
    "speed_error_markdown",
    "speed_error_paragraph",
]


@dataclass(frozen=True)
class Metric:
    """One column of the report.

    Attributes:
        key: the field of the evaluation contract (in SI units).
        label: the name shown in the table, on the axis and in the paragraph.
        unit: the unit shown; ``scale`` converts the contract value into it.
        best: how the paragraph names the best policy by this metric (lowest value).
        abs_tol: values within this absolute difference [``unit``] tie, besides the relative tolerance.
    """

    key: str
    label: str
    unit: str
    scale: float = 1.0
    best: str = ""
    abs_tol: float = 0.0

    def value(self, report: Mapping[str, Any]) -> float | None:
        """The metric of ``report`` in :attr:`unit` (``None`` where the report does not define it)."""
        raw = report.get(self.key)
        if raw is None or not math.isfinite(float(raw)):
            return None
        return float(raw) * self.scale

    @property
    def heading(self) -> str:
        return f"{self.label} [{self.unit}]"

    @property
    def best_phrase(self) -> str:
        return self.best or f"most accurate by {self.label}"


METRICS: dict[str, Metric] = {
    "tracking_rms": Metric("tracking_error_rms", "tracking error rms", "mm", 1e3, abs_tol=0.005),
    "tracking_max": Metric("tracking_error_max", "tracking error max", "mm", 1e3, abs_tol=0.005),
    "goal": Metric("goal_error", "goal error at the end", "mm", 1e3, abs_tol=0.005),
    "goal_max": Metric("goal_error_max", "goal error at the end, max", "mm", 1e3, abs_tol=0.005),
    "time_to_goal": Metric("time_to_goal", "time to goal", "s", best="first at the goal", abs_tol=0.005),
    "speed": Metric("speed_error", "speed error (mean speed vs command)", "m/s", abs_tol=0.0005),
    "speed_rms": Metric("speed_error_rms", "speed error rms (instantaneous)", "m/s", abs_tol=0.0005),
    "pseudoenergy": Metric("pseudoenergy", "pseudoenergy", "rad^2/s", best="lowest pseudoenergy"),
}
"""The metrics a section can show and rank, by name."""

_LOG_SPREAD = 20.0
_SIZE = 150.0
_MARKERS = ("o", "s", "^", "D", "v", "<", ">", "p", "h")
_LEARNED_MARKERS = ("*", "P", "X")  # the learned policies' family, apart from the analytic controllers' shapes


def _metric(name: str) -> Metric:
    if name not in METRICS:
        raise ValueError(f"unknown error {name!r}; valid: {', '.join(METRICS)}")
    return METRICS[name]


def _failed(report: Mapping[str, Any]) -> bool:
    return float(report["success_rate"]) == 0.0


def _fmt(value: float | None) -> str:
    """A number with about three significant digits, without exponents in the usual range."""
    if value is None:
        return "n/a"
    size = abs(value)
    if size < 1e-12:
        return "0"
    if size >= 100.0:
        return f"{value:.0f}"
    if size >= 10.0:
        return f"{value:.1f}"
    if size >= 1.0:
        return f"{value:.2f}"
    if size >= 0.001:
        return f"{value:.3g}" if size >= 0.01 else f"{value:.4f}"
    return f"{value:.2e}"


def _median_p99(times: Mapping[str, Any] | None) -> str:
    """``median / p99`` of a time block of the contract [us], ``-`` where the report has none."""
    return "-" if times is None else f"{_fmt(times['median'])} / {_fmt(times['p99'])}"


def _runs(reports: Mapping[str, Mapping[str, Any]]) -> str:
    """Episodes and seeds of the reports, e.g. ``5 episodes per policy, seeds 0-4``."""
    runs = sorted({(int(r["episodes"]), int(r["seed"])) for r in reports.values()})

    def one(episodes: int, seed: int) -> str:
        seeds = f"seed {seed}" if episodes == 1 else f"seeds {seed}-{seed + episodes - 1}"
        return f"{episodes} episode{'s' if episodes > 1 else ''} per policy, {seeds}"

    return one(*runs[0]) if len(runs) == 1 else "; ".join(one(*run) for run in runs)


def _setting(reports: Mapping[str, Mapping[str, Any]]) -> str:
    """Env id and keyword arguments of the reports (one line per distinct setting)."""
    settings = sorted({(r["env"], json.dumps(r.get("env_kwargs") or {}, sort_keys=True)) for r in reports.values()})
    return "; ".join(f"`{env}`, env kwargs `{kwargs}`" for env, kwargs in settings)


def speed_error_markdown(
    reports: Mapping[str, Mapping[str, Any]],
    title: str,
    *,
    columns: Sequence[str] = ("tracking_rms", "tracking_max"),
    rank: Sequence[str] | None = None,
    tolerance: float = 0.05,
    time_tolerance: float = 0.20,
    note: str = "",
) -> str:
    """A markdown section: header (env, kwargs, episodes, seeds), one table row per labelled policy, and a
    paragraph naming the fastest and the most accurate policy (:func:`speed_error_paragraph`).

    Args:
        reports: label -> evaluation-contract object.
        title: the section title.
        columns: names of :data:`METRICS` shown as error columns (pseudoenergy always has its own column).
        rank: metrics the paragraph ranks by (default: the first of ``columns``).
        tolerance, time_tolerance: relative ties for the errors and for the amortized step time.
        note: a sentence added under the header.

    Raises:
        ValueError: an unknown metric name, or no reports.
    """
    if not reports:
        raise ValueError("no reports")
    metrics = [_metric(name) for name in columns if name != "pseudoenergy"]
    rank = list(rank) if rank is not None else list(columns[:1])
    for name in rank:
        _metric(name)
    pseudo = METRICS["pseudoenergy"]
    sb3 = any("sb3_predict_us" in r for r in reports.values())  # no column where no policy is a learned one
    headings = (
        ["policy", "success", "collision"]
        + [m.heading for m in metrics]
        + [pseudo.heading, "step time median / p99 [us]"]
        + (["SB3 predict median / p99 [us]"] if sb3 else [])
        + ["step time amortized (mean) [us]", "first step (plan) [ms]"]
    )
    lines = [
        f"## {title}",
        "",
        f"{_setting(reports)}; {_runs(reports)}." + (f" {note}" if note else ""),
        "",
        "| " + " | ".join(headings) + " |",
        "|" + " --- |" * len(headings),
    ]
    for label, r in reports.items():
        step = r["step_time_us"]
        cells = (
            [label + (" (failed)" if _failed(r) else ""), f"{r['success_rate']:.2f}", f"{r['collision_rate']:.2f}"]
            + [_fmt(m.value(r)) for m in metrics]
            + [_fmt(pseudo.value(r)), f"{_fmt(step['median'])} / {_fmt(step['p99'])}"]
            + ([_median_p99(r.get("sb3_predict_us"))] if sb3 else [])
            + [_fmt(step["mean"]), _fmt(1e-3 * step["first_step_mean"])]
        )
        lines.append("| " + " | ".join(cells) + " |")
    paragraph = speed_error_paragraph(reports, rank, tolerance=tolerance, time_tolerance=time_tolerance)
    return "\n".join(lines) + "\n\n" + paragraph + "\n"


def _ties(values: Mapping[str, float], tolerance: float, abs_tol: float) -> tuple[list[str], float]:
    """The labels whose value is within ``tolerance`` (relative) or ``abs_tol`` of the lowest, lowest first."""
    best = min(values.values())
    limit = max(best * (1.0 + tolerance), best + abs_tol)
    return sorted((k for k, v in values.items() if v <= limit), key=lambda k: values[k]), best


def _names(labels: Sequence[str]) -> str:
    quoted = [f"**{label}**" for label in labels]
    return quoted[0] if len(quoted) == 1 else ", ".join(quoted[:-1]) + " and " + quoted[-1]


def speed_error_paragraph(
    reports: Mapping[str, Mapping[str, Any]],
    rank: Sequence[str],
    *,
    tolerance: float = 0.05,
    time_tolerance: float = 0.20,
) -> str:
    """A paragraph computed from the reports: the fastest policy by amortized step time, the best by each
    metric of ``rank`` (ties within ``tolerance`` relative or the metric's absolute tolerance are named
    together), the cost in time of the most accurate against the fastest, and the policies left out because
    they failed every episode."""
    metrics = [_metric(name) for name in rank]
    failed = [label for label, r in reports.items() if _failed(r)]
    valid = {label: r for label, r in reports.items() if not _failed(r)}
    out = []
    if not valid:
        return (
            "Every policy failed every episode (success rate 0): no fastest or most accurate policy is named. "
            f"Failed: {_names(failed)}."
        )
    times = {label: float(r["step_time_us"]["mean"]) for label, r in valid.items()}
    fastest, t_best = _ties(times, time_tolerance, 0.0)
    head = (
        f"Fastest (amortized step time, first-step plan included): {_names(fastest[:1])}, "
        f"{_fmt(t_best)} us (median {_fmt(float(valid[fastest[0]]['step_time_us']['median']))} us)"
    )
    if len(fastest) > 1:
        head += f"; within {time_tolerance:.0%} of it: " + ", ".join(
            f"**{label}** ({_fmt(times[label])} us)" for label in fastest[1:]
        )
    out.append(head + ".")
    for k, metric in enumerate(metrics):
        values = {label: v for label, r in valid.items() if (v := metric.value(r)) is not None}
        if not values:
            out.append(f"No policy that succeeded reports {metric.label}.")
            continue
        best, v_best = _ties(values, tolerance, metric.abs_tol)
        phrase = metric.best_phrase[0].upper() + metric.best_phrase[1:]
        spread = _fmt(v_best) if _fmt(v_best) == _fmt(values[best[-1]]) else f"{_fmt(v_best)}-{_fmt(values[best[-1]])}"
        if len(best) == 1:
            sentence = f"{phrase}: {_names(best)}, {spread} {metric.unit}"
        else:
            within = f"within {tolerance:.0%}" + (f" or {metric.abs_tol:g} {metric.unit}" if metric.abs_tol else "")
            sentence = f"{phrase}: {_names(best)} tie ({spread} {metric.unit}, {within})"
        if len(best) == len(values) and len(values) > 1:
            sentence += "; this metric does not separate them"
        elif k == 0:
            both = [label for label in best if label in fastest]
            if both:
                sentence += f"; {_names(both)} {'is' if len(both) == 1 else 'are'} among the fastest as well"
            else:
                quickest = min(best, key=lambda label: times[label])
                sentence += (
                    f"; **{quickest}** takes {times[quickest] / t_best:.1f}x the amortized step time of "
                    f"**{fastest[0]}**, which has {_fmt(values.get(fastest[0]))} {metric.unit}"
                )
        out.append(sentence + ".")
    if failed:
        out.append(f"Left out as failed (success rate 0): {', '.join(failed)}.")
    return " ".join(out)


def axis_scale(values: Sequence[float]) -> str:
    """``"log"`` when every value is positive and the largest is over 20 times the smallest, else ``"linear"``
    (a linear axis then starts at 0 for non-negative data, so a small spread looks small)."""
    data = np.asarray([v for v in values if v is not None and math.isfinite(v)], dtype=np.float64)
    if data.size == 0 or np.any(data <= 0.0):
        return "linear"
    return "log" if float(data.max() / data.min()) > _LOG_SPREAD else "linear"


def _limits(ax: Any, axis: str, values: Sequence[float], scale: str) -> None:
    lo, hi = min(values), max(values)
    if scale == "log":
        pad = (hi / lo) ** 0.12 if hi > lo else 2.0
        limits = (lo / pad, hi * pad)
    else:
        span = hi - min(lo, 0.0)
        base = 0.0 if lo >= 0.0 else lo - 0.12 * span
        limits = (base, hi + 0.15 * span if span > 0 else 1.0)
    (ax.set_xlim if axis == "x" else ax.set_ylim)(*limits)


def _overlap(a: Any, b: Any) -> float:
    w = min(a.x1, b.x1) - max(a.x0, b.x0)
    h = min(a.y1, b.y1) - max(a.y0, b.y0)
    return w * h if w > 0 and h > 0 else 0.0


@dataclass
class _Label:
    """A point's label and what it must not cover: its marker (radius in points) and its median line."""

    text: Any
    radius_pt: float
    median: float


def _draw_panel(
    ax: Any, reports: Mapping[str, Mapping[str, Any]], error: str, title: str, learned: Collection[str] = ()
) -> list[_Label]:
    """Scatter (amortized time, error) with a thin line back to the median time; returns the labels to place
    once the figure is laid out. Labels in ``learned`` get the learned marker family."""
    metric = _metric(error)
    points = []
    for k, (label, r) in enumerate(reports.items()):
        value = metric.value(r)
        if value is None:
            continue
        step = r["step_time_us"]
        points.append((k, label, float(step["mean"]), float(step["median"]), value, _failed(r)))
    if not points:
        raise ValueError(f"no report defines {metric.label} ({metric.key})")
    xs = [p[2] for p in points] + [p[3] for p in points]
    ys = [p[4] for p in points]
    xscale, yscale = axis_scale(xs), axis_scale(ys)
    ax.set_xscale(xscale)
    ax.set_yscale(yscale)
    _limits(ax, "x", xs, xscale)
    _limits(ax, "y", ys, yscale)
    # points that (nearly) coincide on screen nest: the first drawn is the largest, later ones smaller on top
    screen = [ax.transData.transform((p[2], p[4])) for p in points]
    px = ax.figure.dpi / 72.0
    sizes: list[float] = []
    for i, xy in enumerate(screen):
        under = [
            sizes[j]
            for j in range(i)
            if np.hypot(*(screen[j] - xy)) < 0.6 * px * 0.5 * (math.sqrt(sizes[j]) + math.sqrt(_SIZE))
        ]
        sizes.append(max(0.4 * min(under), 16.0) if under else _SIZE)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    markers = {
        label: (_LEARNED_MARKERS[i % len(_LEARNED_MARKERS)] if label in learned else _MARKERS[i % len(_MARKERS)])
        for group in ([p[1] for p in points if p[1] not in learned], [p[1] for p in points if p[1] in learned])
        for i, label in enumerate(group)
    }
    labels = []
    for (k, label, mean, median, value, failed), size in zip(points, sizes, strict=True):
        colour = colours[k % len(colours)]
        ax.plot([median, mean], [value, value], color=colour, lw=1.0, alpha=0.8, zorder=2)
        ax.plot([median], [value], marker="|", color=colour, ms=7, zorder=2)
        ax.scatter(
            [mean],
            [value],
            s=size,
            marker=markers[label],
            zorder=4 - size / 1000,
            linewidths=1.6,
            facecolors="none" if failed else colour,
            edgecolors=colour,
            label=label + (" (failed)" if failed else ""),
        )
        text = ax.annotate(
            label + (" (failed)" if failed else ""),
            (mean, value),
            xytext=(8, 0),
            textcoords="offset points",
            fontsize=7,
            color=colour,
            va="center",
            zorder=4,
            arrowprops={
                "arrowstyle": "-",
                "color": colour,
                "lw": 0.5,
                "alpha": 0.7,
                "shrinkA": 1,
                "shrinkB": 0.5 * math.sqrt(size) + 1,
            },
        )
        text.set_in_layout(False)
        labels.append(_Label(text, 0.5 * math.sqrt(size), median))
    ax.set_xlabel(
        "policy compute time per step [us]: amortized mean, first-step plan included\n"
        f"(thin line back to the median; {xscale} axis)"
    )
    ax.set_ylabel(f"{metric.heading} ({yscale} axis)")
    ax.set_title(title, fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    handles, names = ax.get_legend_handles_labels()
    handles.append(Line2D([], [], color="grey", lw=1.0, marker="|", ms=7))
    names.append("thin line: median step time (|) to amortized mean (marker)")
    if learned:
        handles.append(Line2D([], [], color="grey", lw=0, marker="*", ms=9))
        names.append("star, plus, cross markers: learned policies; others: analytic controllers")
    legend = ax.legend(
        handles, names, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=2, frameon=False
    )
    for handle in legend.legend_handles:  # nested markers are small on the plot, not in the legend
        if hasattr(handle, "set_sizes"):
            handle.set_sizes([70.0])
    return labels


def _place_labels(fig: Any, axes: Sequence[Any], groups: Sequence[Sequence[_Label]]) -> None:
    """Put each point's label at the nearest offset where it covers no placed label, no marker, no median line
    and stays inside its axes (else where it covers least); a thin leader line joins a label to its point."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    px = fig.dpi / 72.0
    bbox = matplotlib.transforms.Bbox.from_extents
    for ax, group in zip(axes, groups, strict=True):
        frame = ax.get_window_extent(renderer)
        points = [ax.transData.transform(label.text.xy) for label in group]
        obstacles = []
        for label, (x, y) in zip(group, points, strict=True):
            r = (label.radius_pt + 1.0) * px
            obstacles.append(bbox(x - r, y - r, x + r, y + r))
            x_median = ax.transData.transform((label.median, label.text.xy[1]))[0]
            obstacles.append(bbox(min(x_median, x) - 4 * px, y - 3 * px, max(x_median, x), y + 3 * px))
        placed: list[Any] = []
        for i in sorted(range(len(group)), key=lambda i: (-points[i][1], points[i][0])):
            label = group[i]
            gap = label.radius_pt + 3.0
            candidates = sorted(
                (
                    (side * (gap + dx), dy)
                    for side in (1, -1)
                    for dx in (0.0, 12.0, 30.0, 50.0)
                    for dy in np.arange(-63.0, 64.0, 9.0)
                ),
                key=lambda c: math.hypot(c[0], 1.5 * c[1]) + (0.0 if c[0] > 0 else 4.0),
            )
            best, best_cost = candidates[0], math.inf
            for dx, dy in candidates:
                label.text.set_position((dx, dy))
                label.text.set_horizontalalignment("left" if dx > 0 else "right")
                box = Text.get_window_extent(label.text, renderer).padded(1.5 * px)
                cost = sum(_overlap(box, other) for other in placed + obstacles)
                if not (box.x0 >= frame.x0 and box.x1 <= frame.x1 and box.y0 >= frame.y0 and box.y1 <= frame.y1):
                    cost += 1e6
                if cost < best_cost:
                    best, best_cost = (dx, dy), cost
                if cost == 0.0:
                    break
            label.text.set_position(best)
            label.text.set_horizontalalignment("left" if best[0] > 0 else "right")
            placed.append(Text.get_window_extent(label.text, renderer).padded(1.5 * px))


def _run_title(title: str, reports: Mapping[str, Mapping[str, Any]]) -> str:
    return f"{title}\n{_runs(reports)}"


def plot_speed_error_panels(
    panels: Sequence[tuple[Mapping[str, Mapping[str, Any]], str, str]],
    path: str | Path,
    title: str = "",
    learned: Collection[str] = (),
) -> Path:
    """Side-by-side speed-vs-error panels, each ``(reports, panel title, error)`` as in :func:`plot_speed_error`
    (the panel title gets the episodes and seeds appended); labels in ``learned`` get the learned markers."""
    for _, _, error in panels:
        _metric(error)
    fig, grid = plt.subplots(1, len(panels), figsize=(7.2 * len(panels), 6.2), squeeze=False)
    axes = list(grid[0])
    labels = [
        _draw_panel(ax, reports, error, _run_title(panel_title, reports), learned)
        for ax, (reports, panel_title, error) in zip(axes, panels, strict=True)
    ]
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    _place_labels(fig, axes, labels)
    return save_figure(fig, path)


def plot_speed_error(
    reports: Mapping[str, Mapping[str, Any]],
    path: str | Path,
    title: str,
    error: str = "tracking_max",
    learned: Collection[str] = (),
) -> Path:
    """Scatter of the amortized compute time per step [us] (first-step plan included; a thin line reaches back
    to the median) against ``error``, a name of :data:`METRICS`, one labelled point per policy.

    Each axis is logarithmic only where its data spread over more than a factor 20 (:func:`axis_scale`); a
    policy that failed every episode is hollow and labelled "(failed)"; the title states episodes and seeds. The
    labels in ``learned`` (learned policies) are drawn as stars, plusses and crosses, the others (analytic
    controllers) as circles, squares, triangles and the like.

    Raises:
        ValueError: an unknown ``error``, or no report that defines it.
    """
    return plot_speed_error_panels([(reports, title, error)], path, learned=learned)
