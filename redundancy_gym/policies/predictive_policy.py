"""The ``predictive`` (receding horizon, algorithm 12) and ``global`` (whole-trajectory optimum) reference
policies of PlanarReach and AgriReach (monograph 5.6).

Both command the CLIK law with the optimized nullspace input, ``qdot = J# (wdot + K e) + N u`` (5.5),
(5.100): the task is tracked with feedback, the redundancy follows the optimal control problem of
:class:`PredictiveIk` (pseudoenergy (5.131), joint limits (5.58), collision (5.49)). ``predictive`` solves it
over ``horizon`` seconds at every step, warm-started; ``global`` solves it once over the whole episode at the
start and follows that plan. Like :mod:`.clik_policy` they read the env by duck typing and import no simulator.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..controllers.clik.compiled_clik import CompiledClik
from ..controllers.objectives.collision_objective import CollisionObjective
from ..controllers.objectives.joint_limit_objective import JointLimitObjective
from ..controllers.predictive.predictive_ik import (
    DESCENT_METHODS,
    PredictiveIk,
    PredictiveResult,
    PredictiveRollout,
)
from ..controllers.predictive.receding_horizon import HorizonUpdate, RecedingHorizon
from ..controllers.tasks.frame_axis_task import FrameAxisTask
from ..controllers.tasks.frame_position_task import FramePositionTask
from ..model import RobotModel
from .clik_policy import ClikPolicy
from .exceptions import PolicyError
from .grasp_clik_policy import GraspClikPolicy
from .options import config_from_options
from .per_env_policy import PerEnvPolicy

__all__ = ["MODES", "TASK_DEFAULTS", "PredictivePolicy", "PredictivePolicyConfig", "predictive_problem"]

MODES = ("predictive", "global")
"""``predictive``: receding horizon (algorithm 12); ``global``: one optimization over the whole episode."""


@dataclass(frozen=True)
class PredictivePolicyConfig:
    """Options of the predictive policies.

    The cost weights and the collision potential's shape default per task (``None`` below): they are not
    those of local CLIK, since in the optimal control problem a potential is integrated over time and weighed
    against the pseudoenergy, not added to a velocity (the monograph, fig. 5.35, uses 1 / 2 / 0.6 locally and
    1 / 5000 / 80 for MPC). :data:`TASK_DEFAULTS` lists them.

    Attributes:
        horizon: prediction horizon ``T_horizon`` [s] of ``predictive``.
        sample_time: sample time of the prediction [s]; None: the env's control period.
        iterations: conjugate gradient iterations per update (``predictive``).
        augmented: optimize the input rate with the input as a state (5.120)-(5.129) (``predictive``).
        input_weight: ``w_a`` of the input rate in the augmented cost.
        descent: ``"fletcher_reeves"``, ``"polak_ribiere"`` or ``"steepest_descent"``.
        tolerance: relative cost decrease that ends an update.
        global_iterations: iterations of the one ``global`` optimization.
        gain: task feedback ``K`` [1/s] (and the feedback to the planned joint path of ``global``); None: the
            env's ``clik`` reference gain.
        velocity_weight: ``w_v`` of the pseudoenergy (5.131).
        joint_limit_weight: weight of (5.58) on the ``clik`` reference's joint-limit potential.
        collision_weight: weight of (5.49).
        collision_activation: ``d_a`` of the collision potential [m]; None: the task default, or the
            ``clik`` reference's.
        collision_slope: ``|H'(0)|`` of the collision potential [1/m]; None as for ``collision_activation``.
        damping: ``rho`` of the prediction's pseudoinverse.
    """

    horizon: float = 1.0
    sample_time: float | None = None
    iterations: int = 2
    augmented: bool = True
    input_weight: float = 1e-3
    descent: str = "fletcher_reeves"
    tolerance: float = 1e-6
    global_iterations: int = 300
    gain: float | None = None
    velocity_weight: float = 1.0
    joint_limit_weight: float | None = None
    collision_weight: float | None = None
    collision_activation: float | None = None
    collision_slope: float | None = None
    damping: float = 1e-6

    def for_task(self, task: str) -> PredictivePolicyConfig:
        """This configuration with the ``None`` cost options of ``task`` (a key of :data:`TASK_DEFAULTS`)
        filled in."""
        if task not in TASK_DEFAULTS:
            raise PolicyError(f"unknown task {task!r}; valid: {', '.join(TASK_DEFAULTS)}")
        filled: dict[str, Any] = {k: v for k, v in TASK_DEFAULTS[task].items() if getattr(self, k) is None}
        return replace(self, **filled)


TASK_DEFAULTS: dict[str, dict[str, float | None]] = {
    "planar": {"joint_limit_weight": 0.6, "collision_weight": 1.0},
    "grasp": {
        "joint_limit_weight": 0.6,
        "collision_weight": 100.0,
        "collision_activation": 0.02,
        "collision_slope": 30.0,
    },
}
"""Cost options of :class:`PredictivePolicyConfig` left at ``None``, per task. ``planar`` (PlanarReach): the
weights of fig. 5.31 on the ``clik`` reference's potentials. ``grasp`` (AgriReach, 9 DoF): a collision
barrier 2 cm deep, steep and strongly weighted, so that a plan passes close to an obstacle when that saves
motion (the reference's 10 cm, 4/m potential made the optimum keep 5 cm away at any cost, and a weak
weight let the short horizon collide); found on the fig. 5.10 move, ``redundancy-gym bench pik``."""


def predictive_problem(
    model: RobotModel,
    task: FramePositionTask | FrameAxisTask,
    joint_limits: JointLimitObjective,
    collision: CollisionObjective | None,
    config: PredictivePolicyConfig,
    *,
    augmented: bool,
) -> PredictiveIk:
    """:class:`PredictiveIk` on a reference controller's potentials with the weights of ``config``
    (``joint_limit_weight`` on (5.58), ``collision_weight`` on (5.49), ``velocity_weight`` on (5.131)) and
    its collision potential's shape where set; ``config`` must have its weights
    (:meth:`~PredictivePolicyConfig.for_task`)."""
    if config.joint_limit_weight is None or config.collision_weight is None:
        raise PolicyError("the configuration has no cost weights; fill them with for_task()")
    p = joint_limits.potential
    limits = JointLimitObjective(
        joint_limits.lower,
        joint_limits.upper,
        activation_distance=p.activation_distance,
        slope=p.slope,
        switch_ratio=p.switch_ratio,
        weight=config.joint_limit_weight,
    )
    if collision is not None:
        p = collision.potential
        activation = p.activation_distance if config.collision_activation is None else config.collision_activation
        slope = p.slope if config.collision_slope is None else config.collision_slope
        collision = CollisionObjective(
            collision.collision_model,
            activation_distance=activation,
            slope=slope,
            switch_ratio=p.switch_ratio,
            weight=config.collision_weight,
        )
    return PredictiveIk(
        model,
        task,
        velocity_weight=config.velocity_weight,
        joint_limits=limits,
        collision=collision,
        augmented=augmented,
        input_weight=config.input_weight,
        damping=config.damping,
    )


class PredictivePolicy(PerEnvPolicy):
    """Predictive IK as a policy on PlanarReach (the TCP line of fig. 5.30, reference from the env's
    ``reference(t)``) or AgriReach (the grasp path of the ``clik`` reference, with its observed obstacles).

    An episode starts (the reference table and the problem are built, ``global`` solves it) at ``episode_start``
    or where the observation's time (PlanarReach: its ``phase``) is ~0 or went back; a batch of observations gets
    one such state per env index (:class:`~redundancy_gym.policies.PerEnvPolicy`).

    Args:
        env: the environment.
        mode: ``"predictive"`` or ``"global"``.
        **kwargs: fields of :class:`PredictivePolicyConfig`.

    Attributes:
        config: the configuration with the task's cost defaults filled in.
        control_dt: the env's control period [s]; dt: the prediction's sample time [s]; substeps: control
            steps per sample (the horizon re-plans once per sample).
        pik, horizon: the episode's problem and receding horizon (``predictive``).
        plan, global_result: the episode's plan and its optimization (``global``).
        last_update: the horizon's latest update; last_error: the task error of the latest command.
    """

    def __init__(self, env: Any, mode: str = "predictive", **kwargs: Any) -> None:
        if mode not in MODES:
            raise PolicyError(f"unknown predictive mode {mode!r}; valid: {', '.join(MODES)}")
        self.config = config_from_options(PredictivePolicyConfig, kwargs)
        c = self.config
        if c.descent not in DESCENT_METHODS:
            raise PolicyError(f"unknown descent {c.descent!r}; valid: {', '.join(DESCENT_METHODS)}")
        if not np.isfinite(c.horizon) or c.horizon <= 0.0:
            raise PolicyError(f"horizon must be finite and > 0, got {c.horizon!r}")
        if not isinstance(c.iterations, int) or c.iterations < 0:
            raise PolicyError(f"iterations must be an int >= 0, got {c.iterations!r}")
        self.mode = mode
        base = getattr(env, "unwrapped", env)
        self.control_dt = float(base.dt)
        self.dt = float(c.sample_time if c.sample_time is not None else base.dt)
        if not np.isfinite(self.dt) or self.dt <= 0.0:
            raise PolicyError(f"sample_time must be finite and > 0, got {self.dt!r}")
        self.substeps = int(round(self.dt / self.control_dt))
        if self.substeps < 1 or abs(self.substeps * self.control_dt - self.dt) > 1e-9 * self.dt:
            raise PolicyError(
                f"sample_time must be a whole multiple of the env's control period "
                f"{self.control_dt:g} s, got {self.dt!r}"
            )
        self._grasp = "grasp_position" in getattr(base, "observation_layout", {})
        self.config = c = c.for_task("grasp" if self._grasp else "planar")
        if self._grasp:
            self._reference_policy: GraspClikPolicy | ClikPolicy = GraspClikPolicy(env)
            self._gain = float(c.gain if c.gain is not None else self._reference_policy.config.gain)
            self._speeds = np.asarray(base.max_joint_speeds, dtype=np.float64)
            self._layout = dict(base.observation_layout)
        else:
            if not callable(getattr(base, "reference", None)):
                raise PolicyError(f"the {mode} policy needs an env with reference(t) (PlanarReach) or a grasp task")
            self._reference_policy = ClikPolicy(env)
            self._reference = base.reference
            self._gain = float(c.gain if c.gain is not None else self._reference_policy.config.gain)
            self._speeds = np.full(self._reference_policy.model.nv, float(base.max_joint_speed))
            self._layout = dict(base.OBSERVATION_LAYOUT)
        spec = getattr(env, "spec", None)
        self._episode_steps = int(getattr(spec, "max_episode_steps", 0) or 0)
        self.model = self._reference_policy.model
        self.pik: PredictiveIk | None = None
        self.horizon: RecedingHorizon | None = None
        self.plan: PredictiveRollout | None = None
        self._table: NDArray[np.float64] | None = None  # per control step: target (6) and its velocity (6)
        self.global_result: PredictiveResult | None = None
        self._step = 0
        self.last_update: HorizonUpdate | None = None
        self.last_error: NDArray[np.float64] | None = None
        self._init_per_env(env, {"mode": mode, **kwargs}, self._layout)

    # ------------------------------------------------------------------ episode start
    def problem(self) -> PredictiveIk:
        """The optimal control problem on the reference policy's task, joint limits and collision model, with
        the weights of this configuration."""
        ref = self._reference_policy
        task: FramePositionTask | FrameAxisTask
        if isinstance(ref, GraspClikPolicy):
            task, limits = ref.task, ref.joint_limits
        else:
            clik = ref.controller.clik if isinstance(ref.controller, CompiledClik) else ref.controller
            if not isinstance(clik.task, (FramePositionTask, FrameAxisTask)):  # ClikPolicy builds a position task
                raise PolicyError(f"the predictive problem needs a frame task, got {type(clik.task).__name__}")
            task = clik.task
            limits = JointLimitObjective.from_model(
                self.model, activation_distance=ref.config.joint_limit_activation, slope=ref.config.joint_limit_slope
            )
        return predictive_problem(
            self.model,
            task,
            limits,
            ref.collision,
            self.config,
            augmented=self.config.augmented and self.mode == "predictive",
        )

    def start(self, obs: NDArray[np.float64]) -> None:
        """A new episode: plan the reference (and the obstacles), build the problem, solve it once (global)."""
        c = self.config
        ref = self._reference_policy
        sample: Callable[[float], tuple[NDArray[np.float64], NDArray[np.float64]]]
        if isinstance(ref, GraspClikPolicy):
            ref.plan(obs)
            path = ref.path
            assert path is not None
            end = path.duration
            sample = path
        else:
            ref.update_obstacle(obs)
            end = float(self._episode_steps) * self.control_dt if self._episode_steps else 0.0

            def planar(t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
                position, velocity, _ = self._reference(t)
                return position, velocity

            sample = planar

        horizon_steps = max(1, int(round(c.horizon / self.dt)))
        total = (int(np.ceil(end / self.dt)) + horizon_steps + 1) * self.substeps
        first = sample(0.0)
        width = first[0].size
        table = np.zeros((total, 12))  # per control step
        for k in range(total):
            target, velocity = sample(k * self.control_dt)
            table[k, :width], table[k, 6 : 6 + width] = target, velocity
        self._table, self._width = table, width
        self.pik = self.problem()
        q = obs[self._layout["q"]]
        self.plan = None
        self.horizon = None
        if self.mode == "global":
            steps = max(1, int(np.ceil(end / self.dt)))
            result = self.pik.optimize(
                q,
                self.wdot(0, steps),
                self.dt,
                np.zeros((steps, self.model.nv)),
                max_iterations=c.global_iterations,
                tolerance=1e-9,
                method=c.descent,
                # the reference loop: over hundreds of iterations the compiled one may stop at another iterate
                # of about the same cost (PredictiveIk.optimize), and the global plan is the reported optimum
                backend="python",
            )
            self.plan = result.rollout
            self.global_result = result
        else:
            self.horizon = RecedingHorizon(
                self.pik, horizon_steps, self.dt, iterations=c.iterations, tolerance=c.tolerance, method=c.descent
            )
        self._step = 0

    def wdot(self, first: int, steps: int) -> NDArray[np.float64]:
        """Task velocity references of ``steps`` prediction samples from sample ``first`` (held at the end)."""
        assert self._table is not None
        index = np.minimum(np.arange(first, first + steps) * self.substeps, len(self._table) - 1)
        wdot = np.zeros((steps, 6))
        wdot[:, : self._width] = self._table[index, 6 : 6 + self._width]
        return wdot

    # ------------------------------------------------------------------ step
    def _act(self, obs: NDArray[np.float64], starting: bool) -> NDArray[np.float32]:
        """Normalized joint velocity command for one observation."""
        if self._new_episode(obs, starting) or self.pik is None:
            self.start(obs)
        assert self.pik is not None and self._table is not None
        q = obs[self._layout["q"]]
        k = self._step
        sample, within = divmod(k, self.substeps)
        if self.mode == "global":
            assert self.plan is not None
            u = self.plan.follow(sample, q, self._gain, within / self.substeps)
        else:
            assert self.horizon is not None
            if within == 0:  # a new prediction sample: re-plan (algorithm 12)
                self.last_update = self.horizon.update(q, self.wdot(sample, self.horizon.steps))
            u = self.horizon.input_at(within * self.control_dt)
        row = self._table[min(k, len(self._table) - 1)]
        qdot, self.last_error = self.pik.command(q, u, row[: self._width], row[6 : 6 + self._width], self._gain)
        self._step += 1
        return np.clip(qdot / self._speeds, -1.0, 1.0).astype(np.float32)

    def describe(self) -> dict[str, Any]:
        """The configuration, for reports."""
        return {"mode": self.mode, **asdict(self.config)}
