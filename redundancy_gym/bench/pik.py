"""``redundancy-gym bench pik``: predictive IK (monograph 5.6) against local CLIK and the global optimum.

- **PlanarReach** (fig. 5.30/5.31): the ``clik``, ``predictive`` (1 s horizon) and ``global`` policies in
  MuJoCo, the same seeds: success, collisions, pseudoenergy, peak joint speed, task error, step time (for
  ``predictive`` the time of one MPC update).
- **AgriReach, self-collision scenario** (fig. 5.35): the point-to-point move of fig. 5.10 (it self-collides
  without avoidance) in a kinematic rollout, by the local grasp CLIK with collision avoidance, MPC with 0.15 s
  and 2 s horizons and the global optimum: pseudoenergy of the revolute joints, peak joint speed, task error,
  smallest self-clearance and the median time per MPC update (``agri_horizon2s_update_ms_median``). The update
  times are measured apart, in alternating rounds (:func:`~redundancy_gym.bench.timing.alternating_rounds`:
  a warm-up round, then ``rounds`` rounds of local CLIK, MPC 0.15 s, MPC 2 s, reversed every other round, each
  sample one timed rollout of the move and its median step): the update medians are over the rounds, and
  ``agri_horizon2s_vs_local`` / ``agri_horizon015s_vs_local`` are the medians over the rounds of the MPC update over
  the local CLIK step in the same round (``*_rounds``: median, min, max and spread ``(max - min) / median``).
- **Conjugate gradient against steepest descent** (fig. 5.32): the global PlanarReach problem from the
  minimum-norm solution; iterations until the cost is within ``1e-4`` of the decrease both reach.
- **Velocity jumps** (figs. 5.33/5.34): PlanarReach MPC (1 s horizon, control at 100 Hz) in kinematic rollouts
  with and without the augmented state, for prediction sample times from the control period up: the largest
  change between control steps of the nullspace joint velocity ``N u`` (the part the MPC sets; the task part
  ``J# (wdot + K e)`` is common to all controllers), of the whole joint velocity, and of the whole joint
  velocity beyond its linear trend (second difference). Velocity-level inputs are
  piecewise constant over a sample, so ``N u`` jumps where the next update starts; the augmented input is
  continuous.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import matplotlib

matplotlib.use("Agg")


import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402
from tqdm.auto import tqdm  # noqa: E402

from .._moved import forward_attributes  # noqa: E402
from ..controllers import PredictiveIk  # noqa: E402
from ..controllers.predictive.receding_horizon import RecedingHorizon  # noqa: E402
from ..envs.planar_reach import PlanarReachEnv  # noqa: E402
from ..eval.evaluate import evaluate  # noqa: E402
from ..eval.machine import finish_machine_info, machine_info  # noqa: E402
from ..policies.predictive_policy import PredictivePolicy  # noqa: E402
from ..studies.point_to_point import FIG_5_10, PointToPointScenario  # noqa: E402
from ..studies.predictive_figures import (  # noqa: E402
    JUMP_SAMPLE_TIME,
    JUMP_SAMPLE_TIMES,
    PLANAR,
    Command,
    agri_move,
    agri_self_collision_traces,
    local_command,
    mpc_command,
    planar_kinematic_traces,
    velocity_jumps,
)
from .exceptions import BenchError  # noqa: E402
from .timing import CLOCK, alternating_rounds, check_rounds, timed_call  # noqa: E402

__all__ = ["agri_update_rounds", "format_pik_bench", "run_pik_bench"]

# the figures' rollouts and plots moved to redundancy_gym.studies.predictive_figures in 0.2 (the old names warn and
# go in 0.3)
__getattr__ = forward_attributes(
    __name__,
    dict.fromkeys(
        ("KinematicTrace", "plot_joint_velocity", "plot_pseudoenergy"), "redundancy_gym.studies.predictive_figures"
    ),
)


def _timed_rollout(q0: NDArray[np.float64], steps: int, dt: float, command: Command) -> float:
    """Median time [s] of ``command`` over a kinematic rollout (only the command is timed, by
    :func:`~redundancy_gym.bench.timing.timed_call`)."""
    q = np.array(q0, dtype=np.float64)
    seconds = []
    for k in range(steps):

        def call(k: int = k, q: NDArray[np.float64] = q) -> tuple[NDArray[np.float64], float]:
            return command(k, q)

        (qdot, _), elapsed = timed_call(call)
        seconds.append(elapsed)
        q = q + dt * qdot
    return float(np.median(seconds))


def agri_update_rounds(
    scenario: PointToPointScenario = FIG_5_10,
    *,
    horizons: tuple[float, ...] = (0.15, 2.0),
    iterations: int = 2,
    rounds: int = 5,
    progress: bool = False,
) -> Any:
    """Alternating rounds of timed rollouts of the fig. 5.10 move: ``"local CLIK"`` (the grasp CLIK step) and
    ``"MPC <h> s"`` per horizon (a fresh receding horizon per rollout, so every sample starts cold alike); each
    sample is the rollout's median step [s]. Returns the :class:`~redundancy_gym.bench.timing.Rounds`."""
    move = agri_move(scenario, max(horizons, default=0.0))
    setup, dt = move.setup, move.dt
    q0, steps = setup.q_start, setup.steps
    local = local_command(setup.controller, move.target)
    samplers = {"local CLIK": lambda: _timed_rollout(q0, steps, dt, local)}
    for horizon in horizons:
        pik = move.problem(True)
        samples = max(1, int(round(horizon / dt)))

        def sample(pik: PredictiveIk = pik, samples: int = samples) -> float:
            mpc = RecedingHorizon(pik, samples, dt, iterations=iterations)
            return _timed_rollout(q0, steps, dt, mpc_command(pik, mpc, move.wdot, move.target, move.gain))

        samplers[f"MPC {horizon:g} s"] = sample
    return alternating_rounds(samplers, rounds=rounds, progress=progress, desc="bench pik update rounds")


def _descent_comparison(seed: int, iterations: int, tolerance: float) -> dict[str, Any]:
    """Fig. 5.32: the global PlanarReach problem from u = 0 by each descent method."""
    env = gym.make(PLANAR)
    try:
        obs, _ = env.reset(seed=seed)
        policy = PredictivePolicy(env, mode="global")
        policy.start(obs)
        pik = policy.pik
        assert pik is not None
        assert env.spec is not None and env.spec.max_episode_steps is not None
        steps = int(env.spec.max_episode_steps)
        wdot = policy.wdot(0, steps)
        q0 = obs[PlanarReachEnv.OBSERVATION_LAYOUT["q"]]
        costs = {}
        for method in ("fletcher_reeves", "steepest_descent"):
            result = pik.optimize(
                q0,
                wdot,
                policy.dt,
                np.zeros((steps, pik.n)),
                max_iterations=iterations,
                tolerance=0.0,
                method=method,
                backend="python",  # fig. 5.32's descent comparison on the reference loop
            )
            costs[method] = np.array(result.costs)
    finally:
        env.close()
    best = min(float(c.min()) for c in costs.values())
    start = float(costs["fletcher_reeves"][0])

    def reach(c: NDArray[np.float64]) -> int | None:
        hit = np.flatnonzero(c - best <= tolerance * (start - best))
        return int(hit[0]) if hit.size else None

    return {
        "tolerance": tolerance,
        "max_iterations": iterations,
        "initial_cost": start,
        "best_cost": best,
        "cg_iterations": reach(costs["fletcher_reeves"]),
        "sd_iterations": reach(costs["steepest_descent"]),
        "cg_costs": costs["fletcher_reeves"].tolist(),
        "sd_costs": costs["steepest_descent"].tolist(),
    }


def run_pik_bench(
    *, seed: int = 0, episodes: int = 10, rounds: int = 5, progress: bool = True, quick: bool = False
) -> dict[str, Any]:
    """All parts of the bench; returns the report (``quick``: fewer episodes and iterations, for tests).

    Args:
        seed: reset seed.
        episodes: PlanarReach episodes per policy.
        rounds: alternating rounds of the AgriReach update timing (after a warm-up round).
        progress: show progress bars.
        quick: fewer iterations and sample times.

    Raises:
        BenchError: ``episodes < 1`` or ``rounds < 1``.
    """
    if episodes < 1:
        raise BenchError(f"episodes must be >= 1, got {episodes}")
    check_rounds(rounds)
    machine = machine_info()
    report: dict[str, Any] = {"benchmark": "pik", "seed": seed, "machine": None}  # the machine is filled in last
    planar = {}
    for name in tqdm(("clik", "predictive", "global"), desc="bench pik PlanarReach", disable=not progress):
        r = evaluate(PLANAR, name, episodes=episodes, seed=seed, progress=False).to_json()
        planar[name] = {
            k: r[k]
            for k in (
                "success_rate",
                "collision_rate",
                "pseudoenergy",
                "peak_joint_speed",
                "tracking_error_max",
                "min_clearance",
            )
        }
        planar[name]["step_time_ms_median"] = r["step_time_us"]["median"] * 1e-3
    report["planar"] = planar
    report["planar_mpc_vs_local_pseudoenergy"] = planar["predictive"]["pseudoenergy"] / planar["clik"]["pseudoenergy"]
    iterations = 40 if quick else 300
    agri = agri_self_collision_traces(global_iterations=iterations)
    report["agri_self_collision"] = {label: trace.summary(slice(1, None)) for label, trace in agri.items()}
    timed = agri_update_rounds(rounds=rounds, progress=progress)
    for label in timed.names:  # the update times of the rounds replace those of the single traced rollout
        report["agri_self_collision"][label]["update_ms_median"] = timed.median(label) * 1e3
    report["agri_horizon2s_update_ms_median"] = report["agri_self_collision"]["MPC 2 s"]["update_ms_median"]
    for label, name in (("MPC 2 s", "agri_horizon2s_vs_local"), ("MPC 0.15 s", "agri_horizon015s_vs_local")):
        stats = timed.ratio(label, "local CLIK")
        report[name] = stats.median
        report[f"{name}_rounds"] = stats.to_json()
    report["timing"] = {
        "rounds": rounds,
        "warmup": timed.warmup,
        "clock": CLOCK,
        "orders": timed.orders,
        "sample": "one kinematic rollout of the fig. 5.10 move, its median step",
    }
    report["descent"] = _descent_comparison(seed, 60 if quick else 200, 1e-4)
    kinematic = planar_kinematic_traces(seed=seed, global_iterations=iterations)
    report["planar_kinematic"] = {label: trace.summary() for label, trace in kinematic.items()}
    rows = velocity_jumps(seed=seed, sample_times=(0.01, JUMP_SAMPLE_TIME) if quick else JUMP_SAMPLE_TIMES)
    report["velocity_jumps"] = rows
    headline = next(r for r in rows if r["sample_time"] == JUMP_SAMPLE_TIME)
    report["nullspace_jump_ratio"] = headline["nullspace_jump_ratio"]
    report["machine"] = finish_machine_info(machine)
    return report


def format_pik_bench(report: dict[str, Any]) -> str:
    """A plain-text summary."""
    lines = ["PlanarReach (MuJoCo): policy | success | collision | pseudoenergy | peak speed | step median [ms]"]
    for name, r in report["planar"].items():
        lines.append(
            f"  {name} | {r['success_rate']:.2f} | {r['collision_rate']:.2f} | {r['pseudoenergy']:.4f} | "
            f"{r['peak_joint_speed']:.3f} | {r['step_time_ms_median']:.3f}"
        )
    lines.append(f"  MPC / local pseudoenergy = {report['planar_mpc_vs_local_pseudoenergy']:.3f}")
    lines.append(
        "AgriReach fig. 5.10 move (kinematic): controller | pseudoenergy (revolute) | peak speed | "
        "min clearance [mm] | update median [ms]"
    )
    for name, r in report["agri_self_collision"].items():
        lines.append(
            f"  {name} | {r['pseudoenergy']:.4f} | {r['peak_joint_speed']:.3f} | "
            f"{1e3 * r['min_clearance']:.1f} | {r['update_ms_median']:.3f}"
        )
    lines.append(f"agri_horizon2s_update_ms_median = {report['agri_horizon2s_update_ms_median']:.2f}")
    for name in ("agri_horizon2s_vs_local", "agri_horizon015s_vs_local"):
        if name in report:
            r = report[f"{name}_rounds"]
            lines.append(
                f"{name} = {report[name]:.1f}  (MPC update / local CLIK step; rounds {r['min']:.1f}-"
                f"{r['max']:.1f}, spread {100 * r['spread']:.1f} %)"
            )
    d = report["descent"]
    lines.append(
        f"descent to {d['tolerance']:g} of the decrease: CG {d['cg_iterations']} iterations, steepest "
        f"descent {d['sd_iterations']} (of {d['max_iterations']})"
    )
    lines.append(
        "PlanarReach kinematic: controller | pseudoenergy | largest jump between control steps of N u | of qdot [rad/s]"
    )
    for name, r in report["planar_kinematic"].items():
        lines.append(
            f"  {name} | {r['pseudoenergy']:.4f} | {r['nullspace_jump_max']:.4f} | {r['velocity_jump_max']:.4f}"
        )
    lines.append(
        "Velocity jumps, MPC 1 s: sample time [s] | N u jump velocity level / augmented (ratio) | "
        "qdot jump (ratio) | qdot jump beyond the trend (ratio)"
    )
    for r in report["velocity_jumps"]:
        lines.append(
            f"  {r['sample_time']:g} | {r['velocity_level_nullspace_jump']:.4f} / "
            f"{r['augmented_nullspace_jump']:.4f} ({r['nullspace_jump_ratio']:.1f}) | "
            f"{r['velocity_level_velocity_jump']:.4f} / {r['augmented_velocity_jump']:.4f} "
            f"({r['velocity_jump_ratio']:.1f}) | {r['velocity_level_velocity_kink']:.4f} / "
            f"{r['augmented_velocity_kink']:.4f} ({r['velocity_kink_ratio']:.1f})"
        )
    lines.append(f"nullspace_jump_ratio (sample time {JUMP_SAMPLE_TIME:g} s) = {report['nullspace_jump_ratio']:.3g}")
    return "\n".join(lines)
