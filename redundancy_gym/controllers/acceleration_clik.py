"""Acceleration-level closed-loop inverse kinematics, resolved acceleration control (monograph 5.1.3, (5.18), (5.19))."""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..model import RobotModel
from .exceptions import ControllerError
from .objective import Objective, sum_objectives
from .redundancy_resolution import METHODS, WeightMatrix, resolve
from .task import Task

__all__ = ["AccelerationClik", "AccelerationClikResult", "DriftTask"]


class DriftTask(Task, Protocol):
    """A task that also knows ``Jdot_w qdot``."""

    def drift(self, model: RobotModel, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> NDArray[np.float64]:
        """``Jdot_w qdot``."""
        ...


class AccelerationClikResult(NamedTuple):
    """Joint accelerations of one acceleration-level CLIK step and diagnostics.

    Attributes:
        qddot: joint accelerations [rad/s^2]; zeros when ``success`` is False.
        error: position error ``w_d - w(q)``.
        velocity_error: ``wdot_d - J qdot``.
        error_norm: ``|w_d - w(q)|``.
        sigma_min: smallest singular value of ``J W^-1/2``.
        damping: DLS damping used.
        objective: nullspace objective ``H(q)``.
        success: False on an unresolved singularity.
        status: ``"ok"``, ``"damped"`` or ``"singular"``.
    """

    qddot: NDArray[np.float64]
    error: NDArray[np.float64]
    velocity_error: NDArray[np.float64]
    error_norm: float
    sigma_min: float
    damping: float
    objective: float
    success: bool
    status: str


class AccelerationClik:
    """``J qddot = wddot_d + K_D (wdot_d - J qdot) + K_P (w_d - w) - Jdot qdot`` (5.18), (5.19).

    Redundancy is resolved as at velocity level with the nullspace vector
    ``z = alpha (dH/dq)^T + nullspace_damping W qdot``, so the self-motion is damped instead of drifting:
    ``qddot = J#_W (...) - N_W (alpha W^-1 (dH/dq)^T + nullspace_damping qdot)``.

    Args:
        model: the robot model.
        task: a task with ``drift`` (``Jdot qdot``).
        method: ``"pseudoinverse"``, ``"dls"`` or ``"transpose"``.
        stiffness: ``K_P`` [1/s^2] (scalar or per task coordinate), >= 0.
        damping: ``K_D`` [1/s], >= 0.
        weights: ``W``.
        nullspace_gain: ``alpha`` >= 0.
        nullspace_damping: damping of the self-motion [1/s], >= 0.
        objectives: nullspace objectives.
    """

    def __init__(self, model: RobotModel, task: DriftTask, *, method: str = "pseudoinverse",
                 stiffness: ArrayLike | float = 100.0, damping: ArrayLike | float = 20.0,
                 weights: ArrayLike | float = 1.0, nullspace_gain: float = 1.0, nullspace_damping: float = 10.0,
                 objectives: Sequence[Objective] = (), singular_threshold: float = 1e-6,
                 dls_threshold: float = 0.05, dls_max_damping: float = 0.01) -> None:
        if method not in METHODS:
            raise ControllerError(f"unknown method {method!r}; valid methods: {', '.join(METHODS)}")
        if not hasattr(task, "drift"):
            raise ControllerError("the acceleration-level CLIK needs a task with drift(model, q, qdot)")
        self.kp = np.broadcast_to(np.asarray(stiffness, dtype=np.float64), (task.dim,)).copy()
        self.kd = np.broadcast_to(np.asarray(damping, dtype=np.float64), (task.dim,)).copy()
        for name, value in (("stiffness", self.kp), ("damping", self.kd),
                            ("nullspace_gain", nullspace_gain), ("nullspace_damping", nullspace_damping)):
            if not np.all(np.isfinite(value)) or np.any(np.asarray(value) < 0.0):
                raise ControllerError(f"{name} must be finite and >= 0")
        self.model = model
        self.task = task
        self.method = method
        self.weights = WeightMatrix(weights, model.nv)
        self.nullspace_gain = float(nullspace_gain)
        self.nullspace_damping = float(nullspace_damping)
        self.objectives = tuple(objectives)
        self.singular_threshold = float(singular_threshold)
        self.dls_threshold = float(dls_threshold)
        self.dls_max_damping = float(dls_max_damping)

    def step(self, q: ArrayLike, qdot: ArrayLike, target: ArrayLike, target_velocity: ArrayLike,
             target_acceleration: ArrayLike) -> AccelerationClikResult:
        """Joint accelerations for the state ``(q, qdot)`` and the reference ``(w_d, wdot_d, wddot_d)``."""
        q = np.asarray(q, dtype=np.float64)  # checked by model.update inside task.drift
        qdot = np.asarray(qdot, dtype=np.float64)
        if qdot.shape != (self.model.nv,) or not np.all(np.isfinite(qdot)):
            raise ControllerError(f"qdot must be finite with shape ({self.model.nv},)")
        drift = self.task.drift(self.model, q, qdot)
        error = self.task.error(self.model, np.asarray(target, dtype=np.float64))
        jacobian = self.task.jacobian(self.model)
        velocity_error = np.asarray(target_velocity, dtype=np.float64) - jacobian @ qdot
        acceleration = (np.asarray(target_acceleration, dtype=np.float64) + self.kd * velocity_error
                        + self.kp * error)  # (5.19)
        value, gradient = sum_objectives(self.objectives, self.model, q)
        z = self.nullspace_gain * gradient + self.nullspace_damping * self.weights.apply(qdot)
        res = resolve(jacobian, acceleration - drift, z, self.weights, method=self.method,
                      singular_threshold=self.singular_threshold, dls_threshold=self.dls_threshold,
                      dls_max_damping=self.dls_max_damping)
        return AccelerationClikResult(res.x, error, velocity_error, float(np.linalg.norm(error)), res.sigma_min,
                                      res.damping, value, res.success, res.status)
