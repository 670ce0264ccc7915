"""``redundancy-gym bench pik``: predictive IK (monograph 5.6) against local CLIK and the global optimum.

- **PlanarReach** (fig. 5.30/5.31): the ``clik``, ``predictive`` (1 s horizon) and ``global`` policies in
  MuJoCo, the same seeds: success, collisions, pseudoenergy, peak joint speed, task error, step time (for
  ``predictive`` the time of one MPC update).
- **AgriReach, self-collision scenario** (fig. 5.35): the point-to-point move of fig. 5.10 (it self-collides
  without avoidance) in a kinematic rollout, by the local grasp CLIK with collision avoidance, MPC with 0.15 s
  and 2 s horizons and the global optimum: pseudoenergy of the revolute joints, peak joint speed, task error,
  smallest self-clearance and the median time per MPC update (``agri_horizon2s_update_ms_median``).
- **Conjugate gradient against steepest descent** (fig. 5.32): the global PlanarReach problem from the
  minimum-norm solution; iterations until the cost is within ``1e-4`` of the decrease both reach.
- **Velocity jumps** (figs. 5.33/5.34): PlanarReach MPC in a kinematic rollout with and without the augmented
  state; the largest jump of the nullspace velocity from what the previous update planned for this step
  (re-planning), and the largest change of the commanded velocity between control steps.
"""

from __future__ import annotations

import platform
import time
from collections.abc import Callable
from typing import Any, NamedTuple

import gymnasium as gym
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402
from tqdm.auto import tqdm  # noqa: E402

from ..assets import AGRI_ARM_TCP  # noqa: E402
from ..controllers import PredictiveIk  # noqa: E402
from ..controllers.grasp_clik_policy import GraspClikPolicy, GraspPath  # noqa: E402
from ..controllers.policies import make_policy  # noqa: E402
from ..controllers.predictive_policy import PredictivePolicy, PredictivePolicyConfig, predictive_problem  # noqa: E402
from ..controllers.receding_horizon import RecedingHorizon  # noqa: E402
from ..model import collision_model_from_mjcf  # noqa: E402
from .evaluate import evaluate  # noqa: E402
from .exceptions import EvalError  # noqa: E402
from .plots import save_figure  # noqa: E402
from .point_to_point import FIG_5_10, PointToPointScenario, _Robot  # noqa: E402

__all__ = ["KinematicTrace", "agri_self_collision_traces", "format_pik_bench", "planar_kinematic_traces",
           "plot_pseudoenergy", "run_pik_bench"]

PLANAR = "redundancy_gym/PlanarReach-v0"
AGRI = "redundancy_gym/AgriReach-v0"


class KinematicTrace(NamedTuple):
    """A kinematic rollout ``q_{k+1} = q_k + dt qdot_k`` of one controller.

    Attributes:
        time: (T,) [s]; qdot: (T, n) commanded joint velocities; q: (T + 1, n).
        task_error: (T,) norm of the task error before each step.
        clearance: (T,) smallest distance of the collision pairs after each step [m].
        update_seconds: (T,) compute time of each step [s].
        replan_jump: (T,) largest difference of the applied nullspace input from what the previous update
            planned for this step (MPC only; zeros otherwise).
    """

    time: NDArray[np.float64]
    qdot: NDArray[np.float64]
    q: NDArray[np.float64]
    task_error: NDArray[np.float64]
    clearance: NDArray[np.float64]
    update_seconds: NDArray[np.float64]
    replan_jump: NDArray[np.float64]

    def pseudoenergy(self, joints: slice = slice(None)) -> float:
        """``integral of qdot^T qdot dt`` over ``joints``."""
        dt = float(self.time[1] - self.time[0]) if len(self.time) > 1 else 0.0
        return float(np.sum(self.qdot[:, joints] ** 2) * dt)

    def summary(self, joints: slice = slice(None)) -> dict[str, float]:
        """The bench's figures of this trace."""
        return {"pseudoenergy": self.pseudoenergy(joints), "peak_joint_speed": float(np.max(np.abs(self.qdot[:, joints]))),
                "task_error_max": float(np.max(self.task_error)), "min_clearance": float(np.min(self.clearance)),
                "collision": bool(np.min(self.clearance) <= 0.0),
                "update_ms_median": float(np.median(self.update_seconds) * 1e3),
                "replan_jump_max": float(np.max(self.replan_jump)),
                "velocity_change_max": float(np.max(np.abs(np.diff(self.qdot, axis=0)))) if len(self.qdot) > 1 else 0.0}


def _rollout(q0: NDArray[np.float64], steps: int, dt: float,
             command: Callable[[int, NDArray[np.float64]], tuple[NDArray[np.float64], float, float]],
             clearance: Callable[[NDArray[np.float64]], float]) -> KinematicTrace:
    q = np.array(q0, dtype=np.float64)
    qs, qdots, errors, gaps, seconds, clear = [q.copy()], [], [], [], [], []
    for k in range(steps):
        start = time.perf_counter()
        qdot, error, gap = command(k, q)
        seconds.append(time.perf_counter() - start)
        q = q + dt * qdot
        qs.append(q.copy())
        qdots.append(qdot)
        errors.append(error)
        gaps.append(gap)
        clear.append(clearance(q))
    return KinematicTrace(dt * np.arange(1, steps + 1), np.array(qdots), np.array(qs), np.array(errors),
                          np.array(clear), np.array(seconds), np.array(gaps))


def _mpc_command(pik: PredictiveIk, horizon: RecedingHorizon, wdot: Callable[[int, int], NDArray[np.float64]],
                 target: Callable[[int], tuple[NDArray[np.float64], NDArray[np.float64]]], gain: float
                 ) -> Callable[[int, NDArray[np.float64]], tuple[NDArray[np.float64], float, float]]:
    planned: list[NDArray[np.float64]] = []

    def command(k: int, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], float, float]:
        update = horizon.update(q, wdot(k, horizon.steps))
        gap = float(np.max(np.abs(update.u - planned[0]))) if planned else 0.0
        planned[:] = [update.result.rollout.u[1].copy() if horizon.steps > 1 else update.u]
        position, velocity = target(k)
        qdot, error = pik.command(q, update.u, position, velocity, gain)
        return qdot, float(np.linalg.norm(error)), gap

    return command


def _plan_command(pik: PredictiveIk, plan: NDArray[np.float64],
                  target: Callable[[int], tuple[NDArray[np.float64], NDArray[np.float64]]], gain: float
                  ) -> Callable[[int, NDArray[np.float64]], tuple[NDArray[np.float64], float, float]]:
    """Follow a global plan's nullspace inputs with task feedback."""
    def command(k: int, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], float, float]:
        position, velocity = target(k)
        qdot, error = pik.command(q, plan[min(k, len(plan) - 1)], position, velocity, gain)
        return qdot, float(np.linalg.norm(error)), 0.0

    return command


def planar_kinematic_traces(*, seed: int = 0, horizon: float = 1.0, global_iterations: int = 300,
                            augmented: tuple[bool, ...] = (True, False)) -> dict[str, KinematicTrace]:
    """PlanarReach (default obstacle) in a kinematic rollout from the env's start at ``seed``: local CLIK
    (the ``clik`` policy's controller), MPC (``horizon``, with and without the augmented state) and global."""
    env = gym.make(PLANAR)
    try:
        obs, _ = env.reset(seed=seed)
        base = env.unwrapped
        dt, steps = float(base.dt), int(env.spec.max_episode_steps)
        q0 = obs[base.OBSERVATION_LAYOUT["q"]].copy()
        clik_policy = make_policy("clik", env)
        clik_policy.update_obstacle(obs)
        model = clik_policy.model
        monitor = clik_policy.collision.collision_model if clik_policy.collision is not None else None

        def clearance(q: NDArray[np.float64]) -> float:
            if monitor is None:
                return np.inf
            model.update(q)
            return float(np.min(monitor.evaluate(model).distance))

        def target(k: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
            position, velocity, _ = base.reference(k * dt)
            return position, velocity

        table = np.array([np.concatenate(target(k)) for k in range(steps + int(round(horizon / dt)) + 2)])

        def wdot(first: int, count: int) -> NDArray[np.float64]:
            out = np.zeros((count, 6))
            out[:, :2] = table[np.minimum(np.arange(first, first + count), len(table) - 1), 2:4]
            return out

        def local(k: int, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], float, float]:
            position, velocity = target(k)
            result = clik_policy.controller.step(q, position, velocity)
            return result.qdot, float(np.linalg.norm(result.error)), 0.0

        traces = {"local CLIK": _rollout(q0, steps, dt, local, clearance)}
        gain = float(clik_policy.config.gain)
        for aug in augmented:
            policy = PredictivePolicy(env, horizon=horizon, augmented=aug)
            policy.start(obs)  # the obstacle, the problem and the horizon of this episode
            assert policy.pik is not None and policy.horizon is not None
            label = f"MPC {horizon:g} s" + (" (augmented)" if aug else " (velocity level)")
            traces[label] = _rollout(q0, steps, dt, _mpc_command(policy.pik, policy.horizon, wdot, target, gain),
                                     clearance)
        policy = PredictivePolicy(env, mode="global", global_iterations=global_iterations)
        policy.start(obs)
        assert policy.pik is not None and policy.plan_u is not None
        traces["global"] = _rollout(q0, steps, dt, _plan_command(policy.pik, policy.plan_u, target, gain),
                                    clearance)
    finally:
        env.close()
    return traces


def agri_self_collision_traces(scenario: PointToPointScenario = FIG_5_10, *, horizons: tuple[float, ...] = (0.15, 2.0),
                               iterations: int = 2, global_iterations: int = 300) -> dict[str, KinematicTrace]:
    """The fig. 5.10 move of the 9-DoF arm (fig. 5.35 analogue): local grasp CLIK with self-collision
    avoidance, MPC for each horizon (augmented) and the global optimum, in kinematic rollouts."""
    grasp = GraspClikPolicy(_Robot(), collision_avoidance="on")
    model = grasp.model
    controller = grasp.build_controller([])
    assert grasp.collision is not None
    monitor = collision_model_from_mjcf(model, [])
    q0 = np.asarray(scenario.q_start, dtype=np.float64)
    model.update(np.asarray(scenario.q_goal, dtype=np.float64))
    goal, goal_axis = model.frame_position(AGRI_ARM_TCP).copy(), model.frame_rotation(AGRI_ARM_TCP)[:, 0].copy()
    model.update(q0)
    path = GraspPath(model.frame_position(AGRI_ARM_TCP).copy(), model.frame_rotation(AGRI_ARM_TCP)[:, 0].copy(),
                     goal, goal, goal_axis, scenario.duration, scenario.hold)
    dt = scenario.dt
    steps = int(round((scenario.duration + scenario.hold) / dt))
    longest = int(round(max(horizons, default=0.0) / dt))
    table = np.array([np.concatenate(path(k * dt)) for k in range(steps + longest + 2)])

    def target(k: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        row = table[min(k, len(table) - 1)]
        return row[:6], row[6:]

    def wdot(first: int, count: int) -> NDArray[np.float64]:
        return table[np.minimum(np.arange(first, first + count), len(table) - 1), 6:].copy()

    def clearance(q: NDArray[np.float64]) -> float:
        model.update(q)
        return float(np.min(monitor.evaluate(model).distance))

    def local(k: int, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], float, float]:
        position, velocity = target(k)
        result = controller.step(q, position, velocity)
        return result.qdot, float(np.linalg.norm(result.error)), 0.0

    def problem(augmented: bool) -> PredictiveIk:
        return predictive_problem(model, grasp.task, grasp.joint_limits, grasp.collision, PredictivePolicyConfig(),
                                  augmented=augmented)

    traces = {"local CLIK": _rollout(q0, steps, dt, local, clearance)}
    gain = float(grasp.config.gain)
    for horizon in horizons:
        pik = problem(True)
        mpc = RecedingHorizon(pik, max(1, int(round(horizon / dt))), dt, iterations=iterations)
        traces[f"MPC {horizon:g} s"] = _rollout(q0, steps, dt, _mpc_command(pik, mpc, wdot, target, gain), clearance)
    pik = problem(False)
    plan = pik.optimize(q0, wdot(0, steps), dt, np.zeros((steps, pik.n)), max_iterations=global_iterations,
                        tolerance=1e-9).rollout.u
    traces["global"] = _rollout(q0, steps, dt, _plan_command(pik, plan, target, gain), clearance)
    return traces


def _descent_comparison(seed: int, iterations: int, tolerance: float) -> dict[str, Any]:
    """Fig. 5.32: the global PlanarReach problem from u = 0 by each descent method."""
    env = gym.make(PLANAR)
    try:
        obs, _ = env.reset(seed=seed)
        policy = PredictivePolicy(env, mode="global")
        policy.start(obs)
        pik = policy.pik
        assert pik is not None
        steps = int(env.spec.max_episode_steps)
        wdot = policy.wdot(0, steps)
        q0 = obs[env.unwrapped.OBSERVATION_LAYOUT["q"]]
        costs = {}
        for method in ("fletcher_reeves", "steepest_descent"):
            result = pik.optimize(q0, wdot, policy.dt, np.zeros((steps, pik.n)), max_iterations=iterations,
                                  tolerance=0.0, method=method)
            costs[method] = np.array(result.costs)
    finally:
        env.close()
    best = min(float(c.min()) for c in costs.values())
    start = float(costs["fletcher_reeves"][0])

    def reach(c: NDArray[np.float64]) -> int | None:
        hit = np.flatnonzero(c - best <= tolerance * (start - best))
        return int(hit[0]) if hit.size else None

    return {"tolerance": tolerance, "max_iterations": iterations, "initial_cost": start, "best_cost": best,
            "cg_iterations": reach(costs["fletcher_reeves"]), "sd_iterations": reach(costs["steepest_descent"]),
            "cg_costs": costs["fletcher_reeves"].tolist(), "sd_costs": costs["steepest_descent"].tolist()}


def run_pik_bench(*, seed: int = 0, episodes: int = 10, progress: bool = True, quick: bool = False) -> dict[str, Any]:
    """All parts of the bench; returns the report (``quick``: fewer episodes and iterations, for tests)."""
    if episodes < 1:
        raise EvalError(f"episodes must be >= 1, got {episodes}")
    report: dict[str, Any] = {"benchmark": "pik", "seed": seed,
                              "machine": {"processor": platform.processor() or platform.machine(),
                                          "python": platform.python_version()}}
    planar = {}
    for name in tqdm(("clik", "predictive", "global"), desc="bench pik PlanarReach", disable=not progress):
        r = evaluate(PLANAR, name, episodes=episodes, seed=seed, progress=False).to_json()
        planar[name] = {k: r[k] for k in ("success_rate", "collision_rate", "pseudoenergy", "peak_joint_speed",
                                          "task_error_max", "min_clearance")}
        planar[name]["step_time_ms_median"] = r["step_time_us"]["median"] * 1e-3
    report["planar"] = planar
    report["planar_mpc_vs_local_pseudoenergy"] = planar["predictive"]["pseudoenergy"] / planar["clik"]["pseudoenergy"]
    iterations = 40 if quick else 300
    agri = agri_self_collision_traces(global_iterations=iterations)
    report["agri_self_collision"] = {label: trace.summary(slice(1, None)) for label, trace in agri.items()}
    report["agri_horizon2s_update_ms_median"] = report["agri_self_collision"]["MPC 2 s"]["update_ms_median"]
    report["descent"] = _descent_comparison(seed, 60 if quick else 200, 1e-4)
    kinematic = planar_kinematic_traces(seed=seed, global_iterations=iterations)
    jumps = {label: trace.summary() for label, trace in kinematic.items()}
    report["planar_kinematic"] = jumps
    aug, vel = jumps["MPC 1 s (augmented)"]["replan_jump_max"], jumps["MPC 1 s (velocity level)"]["replan_jump_max"]
    report["replan_jump_ratio"] = vel / max(aug, 1e-300)
    return report


def format_pik_bench(report: dict[str, Any]) -> str:
    """A plain-text summary."""
    lines = ["PlanarReach (MuJoCo): policy | success | collision | pseudoenergy | peak speed | step median [ms]"]
    for name, r in report["planar"].items():
        lines.append(f"  {name} | {r['success_rate']:.2f} | {r['collision_rate']:.2f} | {r['pseudoenergy']:.4f} | "
                     f"{r['peak_joint_speed']:.3f} | {r['step_time_ms_median']:.3f}")
    lines.append(f"  MPC / local pseudoenergy = {report['planar_mpc_vs_local_pseudoenergy']:.3f}")
    lines.append("AgriReach fig. 5.10 move (kinematic): controller | pseudoenergy (revolute) | peak speed | "
                 "min clearance [mm] | update median [ms]")
    for name, r in report["agri_self_collision"].items():
        lines.append(f"  {name} | {r['pseudoenergy']:.4f} | {r['peak_joint_speed']:.3f} | "
                     f"{1e3 * r['min_clearance']:.1f} | {r['update_ms_median']:.3f}")
    lines.append(f"agri_horizon2s_update_ms_median = {report['agri_horizon2s_update_ms_median']:.2f}")
    d = report["descent"]
    lines.append(f"descent to {d['tolerance']:g} of the decrease: CG {d['cg_iterations']} iterations, steepest "
                 f"descent {d['sd_iterations']} (of {d['max_iterations']})")
    for name, r in report["planar_kinematic"].items():
        lines.append(f"  {name}: largest re-planning jump {r['replan_jump_max']:.2e} rad/s, largest velocity "
                     f"change per step {r['velocity_change_max']:.4f} rad/s")
    lines.append(f"replan_jump_ratio (velocity level / augmented) = {report['replan_jump_ratio']:.3g}")
    return "\n".join(lines)


def plot_pseudoenergy(traces: dict[str, KinematicTrace], path: Any, title: str, joints: slice = slice(None)) -> Any:
    """``qdot^T qdot`` over time of each trace (figs. 5.31 and 5.35), with the integral in the legend."""
    fig, ax = plt.subplots(figsize=(8.0, 4.0))
    for label, trace in traces.items():
        power = np.sum(trace.qdot[:, joints] ** 2, axis=1)
        ax.plot(trace.time, power, label=f"{label}: {trace.pseudoenergy(joints):.3f}")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("qdot^T qdot [rad^2/s^2]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, title="pseudoenergy (integral)", title_fontsize=8)
    return save_figure(fig, path)
