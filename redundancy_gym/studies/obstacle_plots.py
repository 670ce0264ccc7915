"""Biped obstacle figures: the swing foot's lateral and vertical path with SSTA and RCA against the nominal one
(figs. 5.16 / 5.19) and the footholds in a top view (fig. 5.17), on BipedObstacles-v0."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.axes import Axes  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch, Rectangle  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from .. import make_policy  # noqa: E402
from ..eval.evaluate import make_env  # noqa: E402
from ..eval.plots import save_figure  # noqa: E402

if TYPE_CHECKING:
    from ..envs.biped_obstacles import BipedObstaclesEnv

__all__ = [
    "FOOT_COLORS",
    "ObstacleTrace",
    "obstacle_windows",
    "plot_footholds_top_view",
    "plot_swing_trajectories",
    "record_obstacle_walk",
]

_OBSTACLES = "redundancy_gym/BipedObstacles-v0"
# sole extent around the sole point [m] (biped.xml: plate and toe boxes): 0.26 m long, 0.15 m wide
_SOLE_X, _SOLE_Y = (-0.095, 0.165), 0.075
_FEET = ("right", "left")
FOOT_COLORS = ("tab:red", "tab:blue")
"""Colour of the right and the left foot in both figures."""
_MEASURED_COLORS = ("darkred", "navy")
# the zoom on the obstacles [m]: from this far before the first one to this far after the last one
_BEFORE, _AFTER = 0.5, 1.0
# time shown before the first and after the last crossing of an obstacle in the swing figure [s] (a step is 0.8 s)
_TIME_MARGIN = 1.0


@dataclass(frozen=True)
class ObstacleTrace:
    """One walk of the ``walking`` policy on BipedObstacles-v0, per control step (world frame = plan frame, z up).

    The planned quantities are sampled at the start of each control period, the measured soles at the same instant
    (before the period's physics steps). Feet arrays have shape (n, 2, 3), rows right and left.

    Attributes:
        course: the env's ``course``.
        time: [s] since the reset, shape (n,).
        nominal: sole positions [m] of the plan without obstacles (SSTA and RCA off, the same start).
        planned: sole positions [m] of the walking pattern, with SSTA's footholds and swing modifications.
        reference: the final sole position references [m]: ``planned`` plus RCA's offset on the swing foot.
        measured: the soles' positions in the simulation [m] (sites ``r_sole`` / ``l_sole``).
        planned_contact: which feet the pattern has on the ground, shape (n, 2).
        obstacle_contact: a robot geom touched an obstacle during the period, shape (n,).
        footholds: the pattern's footholds ``h_0 ... h_m`` [m] (to the landing of the last step begun), (m + 1, 3).
        nominal_footholds: the same footholds without obstacles [m], (m + 1, 3).
        obstacle_boxes: the obstacles' bounding boxes [m] (world, ``(lower, upper)``), shape (b, 2, 3).
        plan_boxes: the boxes SSTA planned around [m] (mapped into the plan frame, grown by the swept-sphere radius)
            when the first modified swing lifted off (at the end when none did), shape (c, 2, 3).
        modifications: ``(step, kind, lateral [m], height [m])`` of each swing SSTA changed (``kind`` ``"over"``
            or ``"around"``); step ``k`` swings the right foot when even.
        obstacle_contacts: control steps with an obstacle contact.
        success: the env's ``is_success`` at the end.
        fell: the robot fell.
    """

    course: str
    time: NDArray[np.float64]
    nominal: NDArray[np.float64]
    planned: NDArray[np.float64]
    reference: NDArray[np.float64]
    measured: NDArray[np.float64]
    planned_contact: NDArray[np.bool_]
    obstacle_contact: NDArray[np.bool_]
    footholds: NDArray[np.float64]
    nominal_footholds: NDArray[np.float64]
    obstacle_boxes: NDArray[np.float64]
    plan_boxes: NDArray[np.float64]
    modifications: tuple[tuple[int, str, float, float], ...]
    obstacle_contacts: int
    success: bool
    fell: bool


def _boxes_array(boxes: Any) -> NDArray[np.float64]:
    """``(b, 2, 3)`` array of ``(lower, upper)`` pairs or ObstacleBoxes."""
    rows = [
        (np.asarray(b.lower), np.asarray(b.upper)) if hasattr(b, "lower") else (np.asarray(b[0]), np.asarray(b[1]))
        for b in boxes
    ]
    return np.asarray(rows, dtype=np.float64).reshape(-1, 2, 3)


def record_obstacle_walk(
    course: str, seed: int = 0, duration: float | None = None, **policy_kwargs: Any
) -> ObstacleTrace:
    """Walk BipedObstacles-v0 with the ``walking`` policy and keep what the obstacle figures need.

    The walk ends at termination (success, a fall) or truncation, when the pelvis passes the env's ``course_end``
    (where success would end it; after an obstacle contact the env walks on to its time limit), or after
    ``duration`` [s] when given. The nominal plan comes from a second ``walking`` policy with ``ssta=False,
    rca=False`` started from the same reset observation and only sampled (no physics).

    Args:
        course: ``"beam"``, ``"triangle"`` or ``"random"`` (the env's ``course``).
        seed: the reset seed.
        duration: longest walk [s] (None: until the course's end).
        **policy_kwargs: options of the ``walking`` policy (:class:`~redundancy_gym.policies.WalkingPolicyConfig`).
    """
    env = make_env(_OBSTACLES, {"course": course})
    try:
        policy = make_policy("walking", env, **policy_kwargs)
        free = make_policy("walking", env, **{**policy_kwargs, "ssta": False, "rca": False})
        obs, info = env.reset(seed=seed)
        base = cast("BipedObstaclesEnv", env.unwrapped)  # make_env returns the base Env type
        free.begin(obs)
        nominal_pattern = free.controller.pattern
        sites = (base.data.site("r_sole"), base.data.site("l_sole"))
        boxes = _boxes_array(o.bounding_box() for o in base.obstacles)
        steps = None if duration is None else int(round(duration / base.dt))
        rows: dict[str, list[Any]] = {
            k: []
            for k in ("time", "nominal", "planned", "reference", "measured", "planned_contact", "obstacle_contact")
        }
        offset = np.zeros(3)  # RCA's offset on the period-start reference: the last period's end offset
        plan_boxes = None
        last_step = -1
        start = True
        n = 0
        while steps is None or n < steps:
            measured = np.array([s.xpos for s in sites])
            action, _ = policy.predict(obs, episode_start=np.array([start]))
            start = False
            command = policy.last_command
            pattern = policy.controller.pattern
            sample = command.pattern
            reference = sample.feet.copy()
            if sample.step >= 0:
                reference[sample.step % 2] += offset
            offset = command.avoidance.offset.copy() if command.avoidance is not None else np.zeros(3)
            if sample.step != last_step:
                last_step = sample.step
                if plan_boxes is None and pattern.swing_modification(sample.step) is not None:
                    plan_boxes = _boxes_array(pattern.obstacle_boxes)
            rows["time"].append(sample.time)
            rows["nominal"].append(nominal_pattern.sample(sample.time).feet)
            rows["planned"].append(sample.feet)
            rows["reference"].append(reference)
            rows["measured"].append(measured)
            rows["planned_contact"].append(sample.contact)
            obs, _, terminated, truncated, info = env.step(action)
            rows["obstacle_contact"].append(info["obstacle_contact"])
            n += 1
            if terminated or truncated or (steps is None and float(base.data.qpos[0]) >= base.course_end):
                break
        pattern = policy.controller.pattern
        last = max(last_step + 2, 1)
        footholds = np.array([pattern.foothold(j) for j in range(last + 1)])
        nominal_footholds = np.array([nominal_pattern.foothold(j) for j in range(last + 1)])
        modifications = []
        for k in range(max(last_step + 1, 0)):
            m = pattern.swing_modification(k)
            if m is not None:
                modifications.append((k, m.kind, float(m.lateral), float(m.height)))
        if plan_boxes is None:
            plan_boxes = _boxes_array(pattern.obstacle_boxes)
    finally:
        env.close()
    arrays = {k: np.asarray(v, dtype=bool if "contact" in k else np.float64) for k, v in rows.items()}
    return ObstacleTrace(
        course=course,
        **arrays,
        footholds=footholds,
        nominal_footholds=nominal_footholds,
        obstacle_boxes=boxes,
        plan_boxes=plan_boxes,
        modifications=tuple(modifications),
        obstacle_contacts=int(info["obstacle_contacts"]),
        success=bool(info["is_success"]),
        fell=bool(info["fell"]),
    )


def obstacle_windows(trace: ObstacleTrace) -> list[tuple[int, float, float]]:
    """``(foot, start [s], end [s])`` of each time a swinging sole (planned, its full length) overlaps an obstacle
    box along x; foot 0 is the right one."""
    windows = []
    for foot in range(2):
        x = trace.planned[:, foot, 0]
        over = np.zeros(trace.time.size, dtype=bool)
        for lower, upper in trace.obstacle_boxes:
            over |= (x + _SOLE_X[1] >= lower[0]) & (x + _SOLE_X[0] <= upper[0])
        over &= ~trace.planned_contact[:, foot]
        edges = np.flatnonzero(np.diff(np.r_[0, over.astype(np.int8), 0]))
        for a, b in zip(edges[::2], edges[1::2], strict=False):
            windows.append((foot, float(trace.time[a]), float(trace.time[b - 1])))
    return sorted(windows, key=lambda w: w[1])


def _describe(trace: ObstacleTrace) -> str:
    """One line: the SSTA modifications, obstacle contacts and success."""
    parts = []
    for k, kind, lateral, height in trace.modifications:
        foot = _FEET[k % 2]
        what = f"over, toe path at {100 * height:.1f} cm" if kind == "over" else f"around, {100 * lateral:+.1f} cm in y"
        parts.append(f"step {k} ({foot}): {what}")
    swings = "; ".join(parts) if parts else "no swing modified by SSTA"
    contacts = (
        f"{trace.obstacle_contacts} control steps with an obstacle contact"
        if trace.obstacle_contacts
        else "no obstacle contact"
    )
    return f"SSTA: {swings}. {contacts}; success: {'yes' if trace.success else 'no'}"


def plot_swing_trajectories(trace: ObstacleTrace, path: str | Path, title: str) -> Path:
    """Lateral ``y_F`` (top) and vertical ``z_F`` (bottom) of both soles against time (figs. 5.16 / 5.19 analogue):
    the nominal plan without obstacles (dashed), SSTA's plan (thick, light), the final reference with RCA's offset
    and the measured sole (thin); each time a swinging sole passes an obstacle along x is shaded in the foot's
    colour, with the obstacle's lateral or vertical extent drawn over it. The time axis is zoomed on the crossings
    (one second before and after)."""
    fig, axes = plt.subplots(2, 1, figsize=(13, 7.5), sharex=True)
    t = trace.time
    windows = obstacle_windows(trace)
    for axis, ax in zip((1, 2), axes, strict=False):
        for foot, start, end in windows:
            ax.axvspan(start, end, color=FOOT_COLORS[foot], alpha=0.08, lw=0)
            for lower, upper in trace.obstacle_boxes:
                lo, hi = (lower[axis], upper[axis])
                ax.add_patch(
                    Rectangle((start, lo), end - start, hi - lo, facecolor="0.55", edgecolor="0.3", alpha=0.6, lw=0.8)
                )
                if axis == 1:  # where the sole point must not be: the box grown by the half sole width
                    ax.add_patch(
                        Rectangle(
                            (start, lo - _SOLE_Y),
                            end - start,
                            hi - lo + 2 * _SOLE_Y,
                            fill=False,
                            edgecolor="0.3",
                            ls="--",
                            lw=0.8,
                        )
                    )
        for foot in range(2):
            c = FOOT_COLORS[foot]
            ax.plot(t, trace.nominal[:, foot, axis], "--", color=c, lw=1.0, alpha=0.9)
            ax.plot(t, trace.planned[:, foot, axis], color=c, lw=3.5, alpha=0.3, solid_capstyle="butt")
            ax.plot(t, trace.reference[:, foot, axis], color=c, lw=1.3)
            ax.plot(t, trace.measured[:, foot, axis], color=_MEASURED_COLORS[foot], lw=0.6, alpha=0.9)
        contact = trace.obstacle_contact
        if contact.any():
            ax.plot(t[contact], np.full(int(contact.sum()), ax.get_ylim()[1]), "x", color="k", ms=4)
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("lateral sole position y_F [m]\n(the sole spans ±0.075 m)")
    axes[1].set_ylabel("vertical sole position z_F [m]\n(sole point; the toes-down toe tip is lower)")
    axes[1].set_xlabel("time [s]")
    if windows:
        axes[1].set_xlim(max(t[0], windows[0][1] - _TIME_MARGIN), min(t[-1], windows[-1][2] + _TIME_MARGIN))
    handles: list[Any] = [
        Line2D([], [], color="0.3", ls="--", lw=1.0, label="nominal (no obstacles)"),
        Line2D([], [], color="0.3", lw=3.5, alpha=0.3, label="SSTA-modified (ideal)"),
        Line2D([], [], color="0.3", lw=1.3, label="final reference (SSTA + RCA)"),
        Line2D([], [], color="0.1", lw=0.6, label="measured sole"),
        Patch(color=FOOT_COLORS[0], label="right foot"),
        Patch(color=FOOT_COLORS[1], label="left foot"),
        Patch(
            facecolor="0.55",
            edgecolor="0.3",
            alpha=0.6,
            label="obstacle's y / z extent, while a swinging\nsole overlaps it along x (shaded)",
        ),
        Patch(fill=False, edgecolor="0.3", ls="--", label="obstacle y-extent + half sole width (0.075 m)"),
    ]
    if trace.obstacle_contact.any():
        handles.append(Line2D([], [], color="k", marker="x", ls="", ms=4, label="obstacle contact"))
    axes[0].legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    axes[0].set_title(_describe(trace), fontsize=9)
    fig.suptitle(title)
    return save_figure(fig, path, dpi=120)


def _sole(ax: Axes, point: NDArray[np.float64], **style: Any) -> None:
    """The sole's rectangle around the sole point ``point`` [m] (heading +x)."""
    ax.add_patch(Rectangle((point[0] + _SOLE_X[0], point[1] - _SOLE_Y), _SOLE_X[1] - _SOLE_X[0], 2 * _SOLE_Y, **style))


def plot_footholds_top_view(trace: ObstacleTrace, path: str | Path, title: str) -> Path:
    """Top view (x-y, equal aspect) of the footholds around the obstacles (fig. 5.17 analogue): SSTA's footholds as
    filled soles (0.26 x 0.15 m) and the nominal ones as hollow outlines, right and left in two colours; the
    swing paths planned, with RCA, and measured; the obstacles' bounding boxes filled, and the boxes the planner
    used (plan frame, grown by the swept-sphere radius) outlined. Zoomed on x from 0.5 m before the first obstacle
    to 1 m after the last."""
    boxes = trace.obstacle_boxes
    x_lo = float(boxes[:, 0, 0].min()) - _BEFORE if boxes.size else float(trace.footholds[:, 0].min())
    x_hi = float(boxes[:, 1, 0].max()) + _AFTER if boxes.size else float(trace.footholds[:, 0].max())
    shown = (trace.footholds[:, 0] >= x_lo - 0.2) & (trace.footholds[:, 0] <= x_hi + 0.2)
    paths = np.concatenate([trace.planned, trace.reference, trace.measured], axis=1).reshape(-1, 3)
    paths = paths[(paths[:, 0] >= x_lo) & (paths[:, 0] <= x_hi)]
    soles = np.concatenate([trace.footholds[shown, 1], trace.nominal_footholds[shown, 1]])
    ys = np.concatenate([soles - _SOLE_Y, soles + _SOLE_Y, paths[:, 1], boxes[:, :, 1].ravel()])
    y_lo, y_hi = float(ys.min()) - 0.05, float(ys.max()) + 0.05
    # equal aspect: the figure's height follows the zoomed region's (about 7 in of axes width beside the legend)
    fig, ax = plt.subplots(figsize=(12.5, max(3.2, 7.0 * (y_hi - y_lo) / (x_hi - x_lo) + 2.0)))
    for lower, upper in boxes:
        ax.add_patch(
            Rectangle(lower[:2], *(upper[:2] - lower[:2]), facecolor="0.45", edgecolor="k", lw=1.0, alpha=0.8, zorder=3)
        )
    for lower, upper in trace.plan_boxes:
        ax.add_patch(
            Rectangle(lower[:2], *(upper[:2] - lower[:2]), fill=False, edgecolor="k", ls=":", lw=1.0, zorder=3)
        )
    for j, (h, n) in enumerate(zip(trace.footholds, trace.nominal_footholds, strict=False)):
        c = FOOT_COLORS[j % 2]
        _sole(ax, n, fill=False, edgecolor=c, ls="--", lw=1.0, zorder=2)
        _sole(ax, h, facecolor=c, edgecolor=c, alpha=0.3, lw=1.0, zorder=1)
        if x_lo - 0.2 <= h[0] <= x_hi:
            ax.annotate(f"h{j}", h[:2] + np.array([0.035, 0.0]), ha="center", va="center", fontsize=8, zorder=5)
    for foot in range(2):
        c = FOOT_COLORS[foot]
        swing = ~trace.planned_contact[:, foot]
        ax.plot(
            np.where(swing, trace.planned[:, foot, 0], np.nan),
            np.where(swing, trace.planned[:, foot, 1], np.nan),
            color=c,
            lw=3.0,
            alpha=0.35,
            solid_capstyle="butt",
            zorder=4,
        )
        ax.plot(
            np.where(swing, trace.reference[:, foot, 0], np.nan),
            np.where(swing, trace.reference[:, foot, 1], np.nan),
            color=c,
            lw=1.0,
            zorder=4,
        )
        ax.plot(
            trace.measured[:, foot, 0],
            trace.measured[:, foot, 1],
            color=_MEASURED_COLORS[foot],
            lw=0.8,
            ls=(0, (3, 1.5)),
            zorder=4,
        )
    contact = trace.obstacle_contact
    if contact.any():
        # the foot nearer the obstacles at each contact
        near = np.array(
            [
                np.argmin([np.min(np.abs(m[f, 0] - boxes[:, :, 0].mean(axis=1))) for f in range(2)])
                for m in trace.measured[contact]
            ]
        )
        points = trace.measured[contact][np.arange(near.size), near]
        ax.plot(points[:, 0], points[:, 1], "x", color="k", ms=5, zorder=6)
    ax.set_aspect("equal")
    ax.set_xlim(x_lo, x_hi)
    ax.set_ylim(y_lo, y_hi)
    ax.set_xlabel("x (walking direction) [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    handles: list[Any] = [
        Patch(facecolor=FOOT_COLORS[0], alpha=0.3, edgecolor=FOOT_COLORS[0], label="right foothold (SSTA plan)"),
        Patch(facecolor=FOOT_COLORS[1], alpha=0.3, edgecolor=FOOT_COLORS[1], label="left foothold (SSTA plan)"),
        Patch(fill=False, edgecolor="0.3", ls="--", label="nominal foothold (no obstacles)"),
        Line2D([], [], color="0.3", lw=3.0, alpha=0.35, label="swing path, SSTA plan"),
        Line2D([], [], color="0.3", lw=1.0, label="swing path, final reference (SSTA + RCA)"),
        Line2D([], [], color="0.1", lw=0.8, ls=(0, (3, 1.5)), label="measured sole point"),
        Patch(facecolor="0.45", edgecolor="k", alpha=0.8, label="obstacle (bounding box)"),
        Patch(fill=False, edgecolor="k", ls=":", label="box SSTA planned with (plan frame, + SSV radius)"),
    ]
    if contact.any():
        handles.append(Line2D([], [], color="k", marker="x", ls="", ms=5, label="obstacle contact (nearer sole)"))
    ax.legend(handles=handles, loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    ax.set_title(_describe(trace), fontsize=9)
    fig.suptitle(title)
    return save_figure(fig, path, dpi=120)
