"""Predictive IK's figures (monograph 5.6): kinematic rollouts of local CLIK, MPC and the global optimum on
PlanarReach (figs. 5.30/5.31, the joint velocities and pseudoenergy) and on the fig. 5.10 self-collision move of the
agricultural arm (fig. 5.35), and the velocity jumps with and without the augmented state (figs. 5.33/5.34).

``redundancy-gym bench pik`` (:mod:`redundancy_gym.bench.pik`) times these controllers and writes the figures'
numbers; the plots are drawn by :func:`plot_pseudoenergy` and :func:`plot_joint_velocity`.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any, NamedTuple

import gymnasium as gym
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402

from ..controllers import PredictiveIk, PredictiveRollout  # noqa: E402
from ..controllers.predictive.receding_horizon import RecedingHorizon  # noqa: E402
from ..envs.planar_reach import PlanarReachEnv  # noqa: E402
from ..eval.plots import save_figure  # noqa: E402
from ..policies.clik_policy import ClikPolicy  # noqa: E402
from ..policies.predictive_policy import PredictivePolicy, PredictivePolicyConfig, predictive_problem  # noqa: E402
from .point_to_point import FIG_5_10, PointToPointScenario, prepare_point_to_point  # noqa: E402

__all__ = [
    "PLANAR",
    "AgriMove",
    "Command",
    "JUMP_SAMPLE_TIME",
    "JUMP_SAMPLE_TIMES",
    "KinematicTrace",
    "TaskPart",
    "agri_move",
    "agri_self_collision_traces",
    "local_command",
    "mpc_command",
    "planar_kinematic_traces",
    "plot_joint_velocity",
    "plot_pseudoenergy",
    "velocity_jumps",
]

PLANAR = "redundancy_gym/PlanarReach-v0"
"""The env id of the PlanarReach rollouts."""


class KinematicTrace(NamedTuple):
    """A kinematic rollout ``q_{k+1} = q_k + dt qdot_k`` of one controller.

    Attributes:
        time: (T,) [s]; qdot: (T, n) commanded joint velocities; q: (T + 1, n).
        task_error: (T,) norm of the task error before each step.
        clearance: (T,) smallest distance of the collision pairs after each step [m].
        update_seconds: (T,) compute time of each step [s].
        nullspace_qdot: (T, n) the part of ``qdot`` beyond the task part ``J# (wdot + K e)``.
    """

    time: NDArray[np.float64]
    qdot: NDArray[np.float64]
    q: NDArray[np.float64]
    task_error: NDArray[np.float64]
    clearance: NDArray[np.float64]
    update_seconds: NDArray[np.float64]
    nullspace_qdot: NDArray[np.float64]

    def pseudoenergy(self, joints: slice = slice(None)) -> float:
        """``integral of qdot^T qdot dt`` over ``joints``."""
        dt = float(self.time[1] - self.time[0]) if len(self.time) > 1 else 0.0
        return float(np.sum(self.qdot[:, joints] ** 2) * dt)

    def summary(self, joints: slice = slice(None)) -> dict[str, float]:
        """The bench's figures of this trace."""
        return {
            "pseudoenergy": self.pseudoenergy(joints),
            "peak_joint_speed": float(np.max(np.abs(self.qdot[:, joints]))),
            "task_error_max": float(np.max(self.task_error)),
            "min_clearance": float(np.min(self.clearance)),
            "collision": bool(np.min(self.clearance) <= 0.0),
            "update_ms_median": float(np.median(self.update_seconds) * 1e3),
            "velocity_jump_max": _largest_jump(self.qdot),
            "nullspace_jump_max": _largest_jump(self.nullspace_qdot),
            "velocity_kink_max": _largest_jump(self.qdot, order=2),
        }


def _largest_jump(qdot: NDArray[np.float64], order: int = 1) -> float:
    """Largest change of one joint's velocity between consecutive control steps (``order`` 1), or beyond
    the linear trend of the two steps before (``order`` 2: ``qdot_{k+1} - 2 qdot_k + qdot_{k-1}``, small for
    any smooth motion, the size of the jump at a jump)."""
    return float(np.max(np.abs(np.diff(qdot, n=order, axis=0)))) if len(qdot) > order else 0.0


TaskPart = Callable[[int, NDArray[np.float64]], NDArray[np.float64]]
"""``task_part(k, q) -> J# (wdot + K e)``: the joint velocity of the task alone."""


Command = Callable[[int, NDArray[np.float64]], tuple[NDArray[np.float64], float]]
"""``command(k, q) -> (qdot, task error norm)`` of one control step."""


def _rollout(
    q0: NDArray[np.float64],
    steps: int,
    dt: float,
    command: Command,
    task_part: TaskPart,
    clearance: Callable[[NDArray[np.float64]], float],
) -> KinematicTrace:
    """Run ``command`` (only it is timed); the nullspace part is ``qdot - task_part``."""
    q = np.array(q0, dtype=np.float64)
    qs, qdots, errors, nulls, seconds, clear = [q.copy()], [], [], [], [], []
    for k in range(steps):
        start = time.perf_counter()
        qdot, error = command(k, q)
        seconds.append(time.perf_counter() - start)
        nulls.append(qdot - task_part(k, q))
        q = q + dt * qdot
        qs.append(q.copy())
        qdots.append(qdot)
        errors.append(error)
        clear.append(clearance(q))
    return KinematicTrace(
        dt * np.arange(1, steps + 1, dtype=np.float64),
        np.array(qdots),
        np.array(qs),
        np.array(errors),
        np.array(clear),
        np.array(seconds),
        np.array(nulls),
    )


def _with_input(
    pik: PredictiveIk,
    q: NDArray[np.float64],
    u: NDArray[np.float64],
    target: tuple[NDArray[np.float64], NDArray[np.float64]],
    gain: float,
) -> tuple[NDArray[np.float64], float]:
    """The CLIK command with nullspace input ``u`` and its error norm."""
    qdot, error = pik.command(q, u, target[0], target[1], gain)
    return qdot, float(np.linalg.norm(error))


def _task_part(
    pik: PredictiveIk, target: Callable[[int], tuple[NDArray[np.float64], NDArray[np.float64]]], gain: float
) -> TaskPart:
    """``J# (wdot + K e)`` of ``pik``'s task (the command with ``u = 0``)."""

    def part(k: int, q: NDArray[np.float64]) -> NDArray[np.float64]:
        return _with_input(pik, q, np.zeros(pik.n), target(k), gain)[0]

    return part


def mpc_command(
    pik: PredictiveIk,
    horizon: RecedingHorizon,
    wdot: Callable[[int, int], NDArray[np.float64]],
    target: Callable[[int], tuple[NDArray[np.float64], NDArray[np.float64]]],
    gain: float,
    substeps: int = 1,
) -> Command:
    """Algorithm 12 every ``substeps`` control steps (``horizon.dt`` = ``substeps`` control periods); the
    input between updates from :meth:`RecedingHorizon.input_at`. ``wdot(first, count)`` is in samples."""
    control_dt = horizon.dt / substeps

    def command(k: int, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
        sample, within = divmod(k, substeps)
        if within == 0:
            horizon.update(q, wdot(sample, horizon.steps))
        return _with_input(pik, q, horizon.input_at(within * control_dt), target(k), gain)

    return command


def _plan_command(
    pik: PredictiveIk,
    plan: PredictiveRollout,
    target: Callable[[int], tuple[NDArray[np.float64], NDArray[np.float64]]],
    gain: float,
) -> Command:
    """Follow a global plan: its nullspace inputs, the task with feedback, the planned joint path with
    feedback in the nullspace (:meth:`~redundancy_gym.controllers.PredictiveRollout.follow`)."""

    def command(k: int, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
        return _with_input(pik, q, plan.follow(k, q, gain), target(k), gain)

    return command


def local_command(controller: Any, target: Callable[[int], tuple[NDArray[np.float64], NDArray[np.float64]]]) -> Command:
    """Local CLIK (``controller.step``)."""

    def command(k: int, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], float]:
        position, velocity = target(k)
        result = controller.step(q, position, velocity)
        return result.qdot, float(np.linalg.norm(result.error))

    return command


def planar_kinematic_traces(
    *,
    seed: int = 0,
    horizon: float = 1.0,
    global_iterations: int = 300,
    augmented: tuple[bool, ...] = (True, False),
    sample_time: float | None = None,
    local: bool = True,
    global_plan: bool = True,
) -> dict[str, KinematicTrace]:
    """PlanarReach (default obstacle) in kinematic rollouts at the env's control period from its start at
    ``seed``: local CLIK (the ``clik`` policy's controller), MPC (``horizon``, prediction ``sample_time``,
    with and without the augmented state) and global (each of the three only when asked)."""
    env = gym.make(PLANAR)
    try:
        obs, _ = env.reset(seed=seed)
        base = env.unwrapped
        assert isinstance(base, PlanarReachEnv) and env.spec is not None and env.spec.max_episode_steps is not None
        dt, steps = float(base.dt), int(env.spec.max_episode_steps)
        q0 = obs[base.OBSERVATION_LAYOUT["q"]].copy()
        clik_policy = ClikPolicy(env)  # what make_policy("clik", env) builds on PlanarReach
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

        def started(**options: Any) -> PredictivePolicy:
            policy = PredictivePolicy(env, **options)
            policy.start(obs)  # the obstacle and the problem of this episode (global: and its solve)
            assert policy.pik is not None
            return policy

        traces: dict[str, KinematicTrace] = {}
        gain = float(clik_policy.config.gain)
        mpc = {aug: started(horizon=horizon, augmented=aug, sample_time=sample_time) for aug in augmented}
        task_pik = mpc[augmented[0]].pik if augmented else started(horizon=horizon).pik  # no solve at start
        assert task_pik is not None
        task_part = _task_part(task_pik, target, gain)
        if local:
            traces["local CLIK"] = _rollout(
                q0, steps, dt, local_command(clik_policy.controller, target), task_part, clearance
            )
        for aug, policy in mpc.items():
            assert policy.pik is not None and policy.horizon is not None
            label = f"MPC {horizon:g} s" + (" (augmented)" if aug else " (velocity level)")
            command = mpc_command(policy.pik, policy.horizon, policy.wdot, target, gain, policy.substeps)
            traces[label] = _rollout(q0, steps, dt, command, task_part, clearance)
        if global_plan:
            reference = started(mode="global", global_iterations=global_iterations)
            assert reference.pik is not None and reference.plan is not None
            traces["global"] = _rollout(
                q0, steps, dt, _plan_command(reference.pik, reference.plan, target, gain), task_part, clearance
            )
    finally:
        env.close()
    return traces


JUMP_SAMPLE_TIMES = (0.01, 0.05, 0.1, 0.2)
"""Prediction sample times [s] of the velocity-jump comparison (the PlanarReach control period is 0.01 s)."""


JUMP_SAMPLE_TIME = 0.2
"""The one whose ratio the report names ``nullspace_jump_ratio`` (five samples over the 1 s horizon): the
ratio grows with the sample time, and at the control period neither variant has jumps (see the README)."""


def velocity_jumps(
    *, seed: int = 0, sample_times: tuple[float, ...] = JUMP_SAMPLE_TIMES, horizon: float = 1.0
) -> list[dict[str, float]]:
    """Figs. 5.33/5.34: PlanarReach MPC with and without the augmented state for each prediction sample time
    (control at the env's period): the largest jump of the nullspace and of the whole joint velocity between
    control steps, their ratios (velocity level / augmented) and the pseudoenergy."""
    rows = []
    for sample_time in sample_times:
        traces = planar_kinematic_traces(
            seed=seed, horizon=horizon, sample_time=sample_time, local=False, global_plan=False
        )
        aug = traces[f"MPC {horizon:g} s (augmented)"].summary()
        vel = traces[f"MPC {horizon:g} s (velocity level)"].summary()
        rows.append(
            {
                "sample_time": sample_time,
                "augmented_nullspace_jump": aug["nullspace_jump_max"],
                "velocity_level_nullspace_jump": vel["nullspace_jump_max"],
                "nullspace_jump_ratio": vel["nullspace_jump_max"] / max(aug["nullspace_jump_max"], 1e-300),
                "augmented_velocity_jump": aug["velocity_jump_max"],
                "velocity_level_velocity_jump": vel["velocity_jump_max"],
                "velocity_jump_ratio": vel["velocity_jump_max"] / max(aug["velocity_jump_max"], 1e-300),
                "augmented_velocity_kink": aug["velocity_kink_max"],
                "velocity_level_velocity_kink": vel["velocity_kink_max"],
                "velocity_kink_ratio": vel["velocity_kink_max"] / max(aug["velocity_kink_max"], 1e-300),
                "augmented_pseudoenergy": aug["pseudoenergy"],
                "velocity_level_pseudoenergy": vel["pseudoenergy"],
            }
        )
    return rows


class AgriMove(NamedTuple):
    """The fig. 5.10 move set up for kinematic rollouts (:func:`agri_move`)."""

    setup: Any
    dt: float
    target: Callable[[int], tuple[NDArray[np.float64], NDArray[np.float64]]]
    wdot: Callable[[int, int], NDArray[np.float64]]
    clearance: Callable[[NDArray[np.float64]], float]
    problem: Callable[[bool], PredictiveIk]
    gain: float


def agri_move(scenario: PointToPointScenario, longest_horizon: float) -> AgriMove:
    """The grasp policy, path table, targets, clearance and predictive problems of ``scenario``'s move."""
    setup = prepare_point_to_point(scenario)
    grasp, monitor, path, steps = setup.policy, setup.monitor, setup.path, setup.steps
    model = grasp.model
    assert grasp.collision is not None
    dt = scenario.dt
    longest = int(round(longest_horizon / dt))
    table = np.array([np.concatenate(path(k * dt)) for k in range(steps + longest + 2)])

    def target(k: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        row = table[min(k, len(table) - 1)]
        return row[:6], row[6:]

    def wdot(first: int, count: int) -> NDArray[np.float64]:
        return table[np.minimum(np.arange(first, first + count), len(table) - 1), 6:].copy()

    def clearance(q: NDArray[np.float64]) -> float:
        model.update(q)
        return float(np.min(monitor.evaluate(model).distance))

    def problem(augmented: bool) -> PredictiveIk:
        config = PredictivePolicyConfig().for_task("grasp")
        return predictive_problem(model, grasp.task, grasp.joint_limits, grasp.collision, config, augmented=augmented)

    return AgriMove(setup, dt, target, wdot, clearance, problem, float(grasp.config.gain))


def agri_self_collision_traces(
    scenario: PointToPointScenario = FIG_5_10,
    *,
    horizons: tuple[float, ...] = (0.15, 2.0),
    iterations: int = 2,
    global_iterations: int = 300,
) -> dict[str, KinematicTrace]:
    """The fig. 5.10 move of the 9-DoF arm (fig. 5.35 analogue): local grasp CLIK with self-collision
    avoidance, MPC for each horizon (augmented) and the global optimum, in kinematic rollouts."""
    move = agri_move(scenario, max(horizons, default=0.0))
    setup, dt, target, wdot, gain = move.setup, move.dt, move.target, move.wdot, move.gain
    q0, steps = setup.q_start, setup.steps
    velocity_level = move.problem(False)
    task_part = _task_part(velocity_level, target, gain)
    traces = {"local CLIK": _rollout(q0, steps, dt, local_command(setup.controller, target), task_part, move.clearance)}
    for horizon in horizons:
        pik = move.problem(True)
        mpc = RecedingHorizon(pik, max(1, int(round(horizon / dt))), dt, iterations=iterations)
        traces[f"MPC {horizon:g} s"] = _rollout(
            q0, steps, dt, mpc_command(pik, mpc, wdot, target, gain), task_part, move.clearance
        )
    plan = velocity_level.optimize(
        q0,
        wdot(0, steps),
        dt,
        np.zeros((steps, velocity_level.n)),
        max_iterations=global_iterations,
        tolerance=1e-9,
        backend="python",  # the global plan on the reference loop, as the global policy's
    ).rollout
    traces["global"] = _rollout(
        q0, steps, dt, _plan_command(velocity_level, plan, target, gain), task_part, move.clearance
    )
    return traces


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


def plot_joint_velocity(traces: dict[str, KinematicTrace], joint: int, path: Any, title: str) -> Any:
    """One joint's commanded velocity over time for each trace (figs. 5.33/5.34: the staircase of velocity-level
    MPC, the continuous augmented MPC)."""
    fig, ax = plt.subplots(figsize=(8.0, 4.0))
    for label, trace in traces.items():
        ax.step(
            trace.time - (trace.time[0] if len(trace.time) else 0.0),
            trace.qdot[:, joint],
            where="post",
            label=f"{label}: largest jump {_largest_jump(trace.qdot[:, joint : joint + 1]):.4f} rad/s",
        )
    ax.set_xlabel("time [s]")
    ax.set_ylabel(f"qdot_{joint + 1} [rad/s]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return save_figure(fig, path)
