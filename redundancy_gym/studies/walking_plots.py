"""Biped walking figures: CoM, ZMP and support polygon over time, and L_z with and without (5.62) (fig. 5.11)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from .. import make_policy  # noqa: E402
from ..controllers.walking import SOLE_HALF_WIDTH, SOLE_X  # noqa: E402
from ..eval.evaluate import make_env  # noqa: E402
from ..eval.plots import save_figure  # noqa: E402

if TYPE_CHECKING:
    from ..envs.biped_walk import BipedWalkEnv

__all__ = ["WalkTrace", "plot_angular_momentum", "plot_com_zmp", "record_walk"]

_BIPED = "redundancy_gym/BipedWalk-v0"


@dataclass
class WalkTrace:
    """One walk of the ``walking`` policy, per control step."""

    time: NDArray[np.float64]
    com: NDArray[np.float64]
    com_ref: NDArray[np.float64]
    zmp: NDArray[np.float64]
    zmp_ref: NDArray[np.float64]
    zmp_target: NDArray[np.float64]
    """The whole body's reference ZMP [m] (``WalkingPattern.reference_zmp``: the LIPM plan's ``zmp_ref`` plus the
    multi-body correction), which ``bench walk``'s ``zmp_rms_mm`` measures the measured ZMP against."""
    zmp_plan: NDArray[np.float64]
    """The ZMP [m] the plan's whole-body motion demands (``WalkingController.plan_zmp``: a kinematic rollout of the
    CLIK on the pattern without feedback), at the trace's times; NaN before the first step and for the IKD walker,
    whose planned ZMP is the reference it realizes (``zmp_target``)."""
    feet: NDArray[np.float64]
    contact: NDArray[np.bool_]
    lz: NDArray[np.float64]
    lz_model: NDArray[np.float64]
    fell: bool
    distance: float


def record_walk(speed: float = 0.7, duration: float = 6.0, seed: int = 0, **policy_kwargs: Any) -> WalkTrace:
    """Walk BipedWalk-v0 with the ``walking`` policy and keep what the figures need."""
    env = make_env(_BIPED, {"target_speed": speed})
    policy = make_policy("walking", env, **policy_kwargs)
    obs, info = env.reset(seed=seed)
    rows: dict[str, list[Any]] = {
        k: [] for k in ("time", "com", "com_ref", "zmp", "zmp_ref", "zmp_target", "feet", "contact", "lz", "lz_model")
    }
    start = True
    try:
        for _ in range(int(round(duration / cast("BipedWalkEnv", env.unwrapped).dt))):
            action, _ = policy.predict(obs, episode_start=np.array([start]))
            start = False
            obs, _, terminated, truncated, info = env.step(action)
            command = policy.last_command
            rows["time"].append(info["time"])
            rows["com"].append(info["com"])
            rows["com_ref"].append(command.pattern.com)
            rows["zmp"].append(info["zmp"] if info["zmp_valid"] else np.full(2, np.nan))  # a gap in flight
            rows["zmp_ref"].append(command.pattern.zmp)
            rows["zmp_target"].append(policy.controller.pattern.reference_zmp(command.pattern.time))
            rows["feet"].append(command.pattern.feet)
            rows["contact"].append(command.pattern.contact)
            rows["lz"].append(info["angular_momentum"][2])
            rows["lz_model"].append(command.ik.lz)
            if terminated or truncated:
                break
    finally:
        env.close()
    arrays = {k: np.asarray(v) for k, v in rows.items()}
    arrays["zmp_plan"] = np.full_like(arrays["zmp_target"], np.nan)
    pattern = policy.controller.pattern
    if policy.controller.ikd is None and pattern is not None:
        steps = max(1, pattern.step_at(float(arrays["time"][-1])))
        plan = policy.controller.plan_zmp(speed, steps=steps)
        inside = (arrays["time"] >= plan.times[0]) & (arrays["time"] <= plan.times[-1])
        for axis in range(2):
            arrays["zmp_plan"][inside, axis] = np.interp(arrays["time"][inside], plan.times, plan.zmp[:, axis])
    return WalkTrace(**arrays, fell=bool(info["fell"]), distance=float(info["distance"]))


def plot_com_zmp(trace: WalkTrace, path: str | Path, title: str) -> Path:
    """CoM and ZMP (planned and measured) in x and y over time, with the support polygon's extent."""
    fig, axes = plt.subplots(2, 1, figsize=(10, 6.5), sharex=True)
    t = trace.time
    for axis, (ax, label) in enumerate(zip(axes, ("x [m]", "y [m]"), strict=False)):
        lo, hi = [], []
        for feet, contact in zip(trace.feet, trace.contact, strict=False):
            on = feet[np.asarray(contact)]
            ext = SOLE_X if axis == 0 else (-SOLE_HALF_WIDTH, SOLE_HALF_WIDTH)
            lo.append(on[:, axis].min() + ext[0])
            hi.append(on[:, axis].max() + ext[1])
        ax.fill_between(t, lo, hi, color="0.85", label="support polygon (extent)")
        planned = bool(np.any(np.isfinite(trace.zmp_plan)))
        if planned:
            ax.plot(t, trace.zmp_plan[:, axis], color="tab:orange", lw=1.2, label="ZMP planned (whole-body motion)")
        ax.plot(t, trace.zmp_ref[:, axis], ":", color="tab:brown", lw=0.8, label="LIPM's ZMP (planning variable)")
        reference = "ZMP reference (whole body)" if planned else "ZMP reference = planned (the IKD realizes it)"
        ax.plot(t, trace.zmp_target[:, axis], color="tab:green", lw=1.0, label=reference)
        ax.plot(t, trace.zmp[:, axis], color="tab:red", lw=0.6, alpha=0.8, label="ZMP measured (contact forces)")
        ax.plot(t, trace.com_ref[:, axis], color="tab:blue", lw=1.2, label="CoM planned (LIPM/DCM)")
        ax.plot(t, trace.com[:, axis], "--", color="navy", lw=1.0, label="CoM measured")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", fontsize=8)
    axes[1].set_xlabel("time [s]")
    fig.suptitle(title)
    return save_figure(fig, path, dpi=120)


def plot_angular_momentum(traces: dict[str, WalkTrace], path: str | Path, title: str) -> Path:
    """Vertical angular momentum about the CoM over time for each walk (fig. 5.11 analogue)."""
    fig, ax = plt.subplots(figsize=(10, 4))
    for label, trace in traces.items():
        ax.plot(trace.time, trace.lz, lw=1.0, label=label)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("L_z about the CoM [kg m^2/s]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(title)
    return save_figure(fig, path, dpi=120)
