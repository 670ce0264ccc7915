"""Velocity-level closed-loop inverse kinematics with nullspace optimization (monograph 5.1.2, 5.1.4)."""

from __future__ import annotations

from typing import NamedTuple, Unpack

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...model import RobotModel
from ..exceptions import ControllerError
from ..objectives.objective import Objective, sum_objectives
from ..tasks.task import Task
from .redundancy_resolution import METHODS, ResolutionOptions, ResolvedController, check_configuration, check_finite

__all__ = ["Clik", "ClikProblem", "ClikResult"]


class ClikProblem(NamedTuple):
    """One CLIK step, built at a configuration and ready to :meth:`Clik.solve`.

    Attributes:
        q: configuration [rad or m].
        jacobian: ``J_w`` (m x nv).
        error: ``e = w_d - w(q)`` (5.5).
        velocity: effective task velocity ``wdot_d + K e`` (5.5).
        gradient: ``(dH/dq)^T`` of the summed nullspace objectives (nv).
        objective: ``H(q)``.
    """

    q: NDArray[np.float64]
    jacobian: NDArray[np.float64]
    error: NDArray[np.float64]
    velocity: NDArray[np.float64]
    gradient: NDArray[np.float64]
    objective: float


class ClikResult(NamedTuple):
    """Joint velocities of one CLIK step and diagnostics.

    Attributes:
        qdot: joint velocities [rad/s or m/s], within the controller's speed limits and joint ranges; zeros when
            ``success`` is False.
        error: task error ``e`` before the step.
        error_norm: ``|e|``.
        sigma_min: smallest singular value of ``J W^-1/2``.
        damping: damped-least-squares damping used (0 otherwise).
        objective: nullspace objective ``H(q)``.
        success: False when the solve met a singularity it cannot pass (pseudoinverse).
        status: ``"ok"``, ``"damped"`` or ``"singular"``.
        limited: True when the solution was bounded (a joint held at its range, or the whole command scaled
            down to the speed limits), so ``qdot`` no longer gives the task velocity in full; holding a joint
            counts when it changes the command by more than round-off (a component that is zero but for its
            round-off sign, clamped on a joint at its limit, does not).
    """

    qdot: NDArray[np.float64]
    error: NDArray[np.float64]
    error_norm: float
    sigma_min: float
    damping: float
    objective: float
    success: bool
    status: str
    limited: bool = False


class Clik(ResolvedController[Task]):
    """Velocity-level CLIK ``qdot = J#_W (wdot_d + K e) - alpha N_W W^-1 (dH/dq)^T`` (5.5), (5.14), plus an
    optional nullspace input ``N_W u`` (5.100) given to :meth:`step`.

    Solved as in Algorithm 10 (Cholesky of ``J W^-1 J^T``, no explicit pseudoinverse). Variants:
    ``"pseudoinverse"`` (exact; reports singular configurations), ``"dls"`` (damped least squares (5.22) whose
    damping grows as the smallest singular value falls below ``dls_threshold``; keeps the nullspace term) and
    ``"transpose"`` (transposed Jacobian (5.24), ``qdot = W^-1 J^T (wdot_d + K e)``; ignores objectives).

    Every command is bounded (:class:`~redundancy_gym.controllers.clik.redundancy_resolution.JointBounds`), whatever
    the reference: a joint at or beyond a limit of its range gets no velocity towards it (with ``period`` given,
    ``q + qdot period`` stays inside the range), and when a joint would exceed its speed limit the whole
    ``qdot`` is scaled down by one factor (same direction, slower). :attr:`ClikResult.limited` says when.
    Non-finite ``q``, ``target`` or ``target_velocity`` raise :class:`ControllerError` naming the argument.

    Args:
        model: the robot model.
        task: the task ``w(q)``.
        method: one of ``"pseudoinverse"``, ``"dls"``, ``"transpose"``.
        gain: ``K`` [1/s], scalar or one per task coordinate, >= 0.
        weights: ``W``: scalar, diagonal (nv) or full (nv x nv) positive definite.
        nullspace_gain: ``alpha`` >= 0 of (5.14).
        objectives: nullspace objectives ``H`` (summed).
        singular_threshold: smallest singular value below which ``"pseudoinverse"`` reports a singularity.
        dls_threshold: ``eps`` of the DLS damping law.
        dls_max_damping: ``k_max`` of the DLS damping law.
        max_joint_velocity: joint speed limits [rad/s or m/s], one per velocity coordinate or one for all, > 0
            (``inf``: none); None (default) takes the model's
            (:attr:`~redundancy_gym.model.RobotModel.velocity_limits`, from the MJCF's velocity servos).
        period: control period [s] over which ``qdot`` is applied, > 0; keeps ``q + qdot period`` inside the
            joint ranges. None (default): only joints at or beyond a limit are held.
    """

    def __init__(
        self,
        model: RobotModel,
        task: Task,
        *,
        method: str = "pseudoinverse",
        gain: ArrayLike | float = 10.0,
        weights: ArrayLike | float = 1.0,
        nullspace_gain: float = 1.0,
        **options: Unpack[ResolutionOptions],
    ) -> None:
        objectives, thresholds, max_joint_velocity, period = self._read_options(options)
        if method not in METHODS:
            raise ControllerError(f"unknown method {method!r}; valid methods: {', '.join(METHODS)}")
        gain_arr = np.broadcast_to(np.asarray(gain, dtype=np.float64), (task.dim,)).copy()
        if np.any(gain_arr < 0.0) or not np.all(np.isfinite(gain_arr)):
            raise ControllerError("gain must be finite and >= 0")
        if not np.isfinite(nullspace_gain) or nullspace_gain < 0.0:
            raise ControllerError(f"nullspace_gain must be finite and >= 0, got {nullspace_gain!r}")
        for name, value in zip(("singular_threshold", "dls_threshold", "dls_max_damping"), thresholds, strict=True):
            if not np.isfinite(value) or value <= 0.0:
                raise ControllerError(f"{name} must be finite and > 0, got {value!r}")
        for objective in objectives:
            if not isinstance(objective, Objective):
                raise ControllerError(f"{objective!r} has no evaluate(model, q) method")
        self._set_resolution(model, task, method, weights, nullspace_gain)
        self._set_options(objectives, thresholds, max_joint_velocity, period)
        self.gain = gain_arr

    @property
    def max_joint_velocity(self) -> NDArray[np.float64]:
        """The joint speed limits [rad/s or m/s] (nv; ``inf`` where none)."""
        return self.bounds.max_velocity.copy()

    @property
    def period(self) -> float | None:
        """The control period [s] the command is bounded for, or None."""
        return self.bounds.period

    def build(self, q: ArrayLike, target: ArrayLike, target_velocity: ArrayLike | None = None) -> ClikProblem:
        """Evaluate kinematics and objectives at ``q`` for the reference ``w_d`` and ``wdot_d``."""
        q = self.model.update(check_configuration(q, "q"))
        error = self.task.error(self.model, check_finite(target, "target"))
        jacobian = self.task.jacobian(self.model)
        velocity = self.gain * error
        if target_velocity is not None:
            wdot = check_finite(target_velocity, "target_velocity")
            feedforward = getattr(self.task, "feedforward", None)
            if feedforward is not None:  # tasks whose velocity is given in other coordinates (FrameAxisTask)
                wdot = feedforward(self.model, wdot)
            if wdot.shape != error.shape or not np.all(np.isfinite(wdot)):
                raise ControllerError(f"target_velocity must be finite with shape {error.shape}")
            velocity = velocity + wdot
        value, gradient = sum_objectives(self.objectives, self.model, q)
        return ClikProblem(q, jacobian, error, velocity, gradient, value)

    def solve(self, problem: ClikProblem, nullspace_input: ArrayLike | None = None) -> ClikResult:
        """Joint velocities for a built problem; ``nullspace_input``: the ``u`` of (5.100) (nv) [rad/s or m/s],
        added as ``N u`` beside the objectives' ``-alpha N W^-1 dH/dq`` (ignored by ``"transpose"``, which has no
        projector)."""
        z = self.nullspace_gain * problem.gradient if self.objectives else None
        if nullspace_input is not None:
            u = check_finite(nullspace_input, "nullspace_input")
            if u.shape != (self.model.nv,):
                raise ControllerError(f"nullspace_input must be finite with shape ({self.model.nv},), got {u.shape}")
            wu = self.weights.apply(u)
            z = -wu if z is None else z - wu
        res = self._resolve(problem.jacobian, problem.velocity, z)
        qdot, limited = self.bounds.apply(res.x, problem.q)
        return ClikResult(
            qdot,
            problem.error,
            float(np.linalg.norm(problem.error)),
            res.sigma_min,
            res.damping,
            problem.objective,
            res.success,
            res.status,
            limited,
        )

    def step(
        self,
        q: ArrayLike,
        target: ArrayLike,
        target_velocity: ArrayLike | None = None,
        nullspace_input: ArrayLike | None = None,
    ) -> ClikResult:
        """``solve(build(q, target, target_velocity), nullspace_input)``."""
        return self.solve(self.build(q, target, target_velocity), nullspace_input)
