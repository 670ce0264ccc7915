"""BipedTerrain figures: one walk of the ``walking`` reference recorded (:func:`record_terrain_walk`) and drawn from
the side (:func:`plot_terrain_walk`): the terrain under each foot's lane, the planned and measured feet and CoM, and
the planned and measured ZMP over time (relative to the planned CoM)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from numpy.typing import NDArray

from .. import make_policy
from ..eval.evaluate import make_env

__all__ = ["TerrainTrace", "plot_terrain_walk", "record_terrain_walk"]

_TERRAIN = "redundancy_gym/BipedTerrain-v0"


@dataclass(frozen=True)
class TerrainTrace:
    """One recorded walk on BipedTerrain (world frame, per control period unless said otherwise).

    Attributes:
        time: [s].
        planned_feet, measured_feet: (n, 2, 3) the soles' points [m], rows right and left (planned: the pattern's,
            in its frame, shifted back to the world by the stance foot's drift along x).
        planned_com, measured_com: (n, 3) [m].
        planned_zmp, measured_zmp: (n,) the ZMP's x [m] (measured: NaN in flight).
        profile_x, profile: the terrain's height [m] under each foot's lane (2, m) at ``profile_x`` (m,) [m].
        description: the terrain's segments, one line each.
        success, fell: how the walk ended.
    """

    time: NDArray[np.float64]
    planned_feet: NDArray[np.float64]
    measured_feet: NDArray[np.float64]
    planned_com: NDArray[np.float64]
    measured_com: NDArray[np.float64]
    planned_zmp: NDArray[np.float64]
    measured_zmp: NDArray[np.float64]
    profile_x: NDArray[np.float64]
    profile: NDArray[np.float64]
    description: tuple[str, ...]
    success: bool
    fell: bool


def record_terrain_walk(env_kwargs: dict[str, Any], seed: int = 0, **policy_kwargs: Any) -> TerrainTrace:
    """Walk BipedTerrain-v0 (``env_kwargs``) with the ``walking`` policy from ``reset(seed=seed)`` to the episode's
    end and keep what :func:`plot_terrain_walk` draws."""
    env = make_env(_TERRAIN, env_kwargs)
    try:
        policy = make_policy("walking", env, **policy_kwargs)
        obs, info = env.reset(seed=seed)
        base = cast(Any, env.unwrapped)
        sites = (base.data.site("r_sole"), base.data.site("l_sole"))
        rows: dict[str, list[Any]] = {k: [] for k in ("time", "pf", "mf", "pc", "mc", "pz", "mz")}
        done = False
        start = True
        while not done:
            measured = np.array([s.xpos for s in sites])
            action, _ = policy.predict(obs, episode_start=np.array([start]))
            start = False
            command = policy.last_command
            assert command is not None
            sample = command.pattern
            # the plan's frame is the world's shifted by the stance foot's drift along x
            shift = float(policy.controller.world_to_plan[1][0])
            obs, _, terminated, truncated, info = env.step(action)
            done = bool(terminated or truncated)
            rows["time"].append(sample.time)
            rows["pf"].append(sample.feet - (shift, 0.0, 0.0))
            rows["mf"].append(measured)
            rows["pc"].append(sample.com - (shift, 0.0, 0.0))
            rows["mc"].append(np.asarray(info["com"], dtype=np.float64))
            rows["pz"].append(float(sample.zmp[0]) - shift)
            rows["mz"].append(float(info["zmp"][0]) if info["zmp_valid"] else np.nan)
        terrain = base.terrain
        end = max(float(terrain.end), float(np.max(np.array(rows["mc"])[:, 0]))) + 0.5
        profile_x = np.arange(-0.3, end, 0.005)
        lanes = np.array(
            [terrain.heights(np.column_stack((profile_x, np.full_like(profile_x, y)))) for y in (-0.09, 0.09)]
        )
        return TerrainTrace(
            time=np.array(rows["time"]),
            planned_feet=np.array(rows["pf"]),
            measured_feet=np.array(rows["mf"]),
            planned_com=np.array(rows["pc"]),
            measured_com=np.array(rows["mc"]),
            planned_zmp=np.array(rows["pz"]),
            measured_zmp=np.array(rows["mz"]),
            profile_x=profile_x,
            profile=lanes,
            description=tuple(s.describe() for s in terrain.segments),
            success=bool(info["is_success"]),
            fell=bool(info["fell"]),
        )
    finally:
        env.close()


def plot_terrain_walk(trace: TerrainTrace, path: str | Path, title: str) -> Path:
    """The walk from the side: above, the terrain under each lane (filled), the soles' planned (dashed) and
    measured (solid) paths, the planned and measured CoM; below, the planned and measured ZMP's x and the measured
    CoM's over time, relative to the planned CoM."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig, (side, zmp) = plt.subplots(2, 1, figsize=(12, 7.5), gridspec_kw={"height_ratios": [2.2, 1.0]})
    colors = ("tab:red", "tab:blue")
    for lane, (name, color) in enumerate(zip(("right", "left"), colors, strict=True)):
        side.fill_between(trace.profile_x, 0.0, trace.profile[lane], color=color, alpha=0.12, step="mid")
        side.plot(trace.profile_x, trace.profile[lane], color=color, lw=0.8, alpha=0.6, label=f"terrain, {name} lane")
        side.plot(
            trace.planned_feet[:, lane, 0],
            trace.planned_feet[:, lane, 2],
            "--",
            color=color,
            lw=1.0,
            label=f"{name} sole, planned",
        )
        side.plot(
            trace.measured_feet[:, lane, 0],
            trace.measured_feet[:, lane, 2],
            color=color,
            lw=1.6,
            label=f"{name} sole, measured",
        )
    side.plot(
        trace.planned_com[:, 0],
        trace.planned_com[:, 2] - 0.6,
        "--",
        color="black",
        lw=1.0,
        label="CoM planned (-0.6 m)",
    )
    side.plot(
        trace.measured_com[:, 0], trace.measured_com[:, 2] - 0.6, color="black", lw=1.6, label="CoM measured (-0.6 m)"
    )
    side.set_xlabel("x [m]")
    side.set_ylabel("z [m]")
    side.set_aspect("equal", adjustable="datalim")
    side.grid(alpha=0.3)
    side.legend(loc="upper left", fontsize=7, ncol=4)
    outcome = "success" if trace.success else ("fall" if trace.fell else "no success")
    side.set_title(f"{title}\n{'; '.join(trace.description)} -> {outcome}", fontsize=9)
    # relative to the planned CoM: the ZMP's swing under the feet, which the walk's progress would hide
    reference = trace.planned_com[:, 0]
    zmp.plot(trace.time, trace.planned_zmp - reference, "--", color="tab:green", lw=1.0, label="ZMP planned")
    zmp.plot(
        trace.time,
        trace.measured_zmp - reference,
        color="tab:green",
        lw=1.2,
        alpha=0.8,
        label="ZMP measured (contact forces)",
    )
    zmp.plot(trace.time, trace.measured_com[:, 0] - reference, color="black", lw=0.8, alpha=0.6, label="CoM measured")
    zmp.set_xlabel("time [s]")
    zmp.set_ylabel("x - planned CoM x [m]")
    zmp.grid(alpha=0.3)
    zmp.legend(loc="upper left", fontsize=7, ncol=3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
