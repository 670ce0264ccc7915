"""General Inverse Kineto-Dynamics (monograph 5.5.2, (5.92)-(5.96)): joint accelerations for a hybrid task of known
and unknown generalized forces and task coordinates.

The multi-body equations ``M qddot + h = W_lambda lambda`` (5.92), with the impressed forces split into known and
unknown ones ``lambda = T_lk lambda_k + T_lu lambda_u`` (5.93), and the task ``J_w qddot + Jdot_w qdot =
T_wk wddot_k + T_wu wddot_u`` (5.95) combine into one linear equation in the unknowns (5.96)::

    G (lambda_u, wddot_u) + f = 0,
    G = (J_w M^-1 W_lambda T_lu,  -T_wu),
    f = J_w M^-1 W_lambda T_lk lambda_k - J_w M^-1 h + Jdot_w qdot - T_wk wddot_k.

Solved for the unknowns (weighted minimum norm where they outnumber the task rows), ``qddot = M^-1 (W_lambda lambda
- h)`` follows. This is the forward dynamics of the system under ``lambda_k`` with the known task coordinates as
rheonomic constraints: the unknown forces are the constraint forces that make the motion follow the task.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...model import RobotModel
from ..clik.acceleration_clik import DriftTask
from ..clik.redundancy_resolution import METHODS, WeightMatrix, check_configuration, check_finite, resolve
from ..exceptions import ControllerError

__all__ = ["WEIGHTINGS", "GeneralIkd", "GeneralIkdResult"]

WEIGHTINGS: tuple[str, ...] = ("forces", "acceleration")
"""How :class:`GeneralIkd` weighs the unknown forces where they outnumber the task rows."""


class GeneralIkdResult(NamedTuple):
    """One step of :class:`GeneralIkd`.

    Attributes:
        qddot: generalized accelerations [rad/s^2 or m/s^2] (nv); zeros when ``success`` is False.
        forces: all impressed forces ``lambda`` [N m or N] (known and solved); the known ones alone when
            ``success`` is False.
        unknown_forces: the solved ``lambda_u``.
        unknown_task_acceleration: the solved ``wddot_u`` (the accelerations of the task rows left free).
        task_acceleration: ``wddot_k`` with the drift compensation, the known rows' acceleration demanded.
        residual: ``|G x + f|``, how far the solution is from satisfying (5.96) (0 up to round-off unless damped).
        sigma_min: smallest singular value of ``G W^-1/2`` (distance to a singular hybrid task).
        damping: damped-least-squares damping used (0 for the exact solution).
        success: False when the hybrid task is singular (e.g. more known task rows than unknowns can serve).
        status: ``"ok"``, ``"damped"`` or ``"singular"``.
    """

    qddot: NDArray[np.float64]
    forces: NDArray[np.float64]
    unknown_forces: NDArray[np.float64]
    unknown_task_acceleration: NDArray[np.float64]
    task_acceleration: NDArray[np.float64]
    residual: float
    sigma_min: float
    damping: float
    success: bool
    status: str


def _indices(name: str, values: Sequence[int], size: int) -> NDArray[np.intp]:
    """``values`` as distinct indices into a vector of ``size``; ControllerError naming ``name`` otherwise."""
    try:
        index = np.array([int(v) for v in values], dtype=np.intp)
    except (TypeError, ValueError):
        raise ControllerError(f"{name} must be indices in [0, {size}), got {values!r}") from None
    if index.size and (index.min() < 0 or index.max() >= size):
        raise ControllerError(f"{name} must be indices in [0, {size}), got {index.tolist()}")
    if np.unique(index).size != index.size:
        raise ControllerError(f"{name} must not repeat, got {index.tolist()}")
    return index


class GeneralIkd:
    """Inverse Kineto-Dynamics for a hybrid position/force task on any :class:`~redundancy_gym.model.RobotModel`.

    The partition matrices of (5.90) and (5.93) are selections here: ``known_forces`` picks the rows of ``lambda``
    whose values are prescribed (``T_lk``; the others are unknown, ``T_lu``), ``known_task`` the rows of the task
    whose accelerations are prescribed (``T_wk``; the others are free, ``T_wu``). The known rows' acceleration is
    stabilized as in (5.19), on those rows only: ``wddot_k = wddot_kd + K_D (wdot_kd - J_k qdot) + K_P (w_kd -
    w_k)``. Where the unknowns outnumber the task rows, the solution has the least weighted norm
    ``lambda_u^T W_l lambda_u + wddot_u^T W_w wddot_u`` (the monograph: weights that account for the unknowns'
    different units). With ``weighting="acceleration"`` the weight of the unknown forces is ``(W_lambda^T M^-1
    W_lambda)_uu``, the acceleration they cause measured in the kinetic metric (Gauss's principle of least
    constraint): the torque norm alone let the light wrist joints do the motion, and along a path they ran off
    within a second. With ``self_motion_damping`` ``D`` the solution is the one closest to the forces
    ``(W_lambda^T (h - D qdot))_u`` (for joint torques: holding the robot against gravity and damping its joints),
    which damps the self-motion without touching the task; ``posture_stiffness`` ``K`` adds ``-K (q - posture)``
    to them, which holds the self-motion near a posture (without it the arm, following a 14 cm path, drifted into a
    singular posture and ran off).

    Args:
        model: the robot model (fixed or floating base).
        task: the task ``w(q)`` with ``drift`` (``Jdot_w qdot``), e.g. :class:`~..FramePositionTask`.
        known_forces: indices of the prescribed entries of ``lambda``.
        force_map: ``W_lambda`` (nv x n_lambda); None: the identity (``lambda`` are the joint forces of a fully
            actuated fixed-base robot).
        known_task: indices of the task rows with prescribed accelerations; None: all of them.
        stiffness: ``K_P`` [1/s^2] on the known rows (scalar or per known row), >= 0.
        damping: ``K_D`` [1/s] on the known rows, >= 0.
        force_weights: ``W_l`` of the unknown forces (scalar or per unknown force), > 0, with ``weighting="forces"``.
        weighting: ``"acceleration"`` (the kinetic metric, state-dependent) or ``"forces"`` (``W_l``).
        task_weights: ``W_w`` of the free task accelerations (scalar or per free row), > 0.
        method: ``"pseudoinverse"`` (reports a singular hybrid task) or ``"dls"`` (damped least squares near one).
        self_motion_damping: ``D`` [N m s/rad] (scalar or nv) of the preferred forces, >= 0; None: the plain
            weighted minimum norm.
        posture_stiffness: ``K`` [N m/rad] (scalar or nv) of the preferred forces, >= 0 (with
            ``self_motion_damping``).
        posture: the posture (nq; fixed base: the joint positions) the preferred forces pull to; needed when
            ``posture_stiffness`` is not 0.

    Raises:
        ControllerError: bad indices, shapes or gains (naming the argument).
    """

    def __init__(
        self,
        model: RobotModel,
        task: DriftTask,
        *,
        known_forces: Sequence[int],
        force_map: ArrayLike | None = None,
        known_task: Sequence[int] | None = None,
        stiffness: ArrayLike | float = 0.0,
        damping: ArrayLike | float = 0.0,
        force_weights: ArrayLike | float = 1.0,
        task_weights: ArrayLike | float = 1.0,
        weighting: str = "acceleration",
        method: str = "pseudoinverse",
        singular_threshold: float = 1e-9,
        dls_threshold: float = 1e-3,
        dls_max_damping: float = 1e-6,
        self_motion_damping: ArrayLike | float | None = None,
        posture_stiffness: ArrayLike | float = 0.0,
        posture: ArrayLike | None = None,
    ) -> None:
        if method not in METHODS or method == "transpose":
            raise ControllerError(f"unknown method {method!r}; valid methods: pseudoinverse, dls")
        if not hasattr(task, "drift"):
            raise ControllerError("inverse kineto-dynamics needs a task with drift(model, q, qdot)")
        nv = model.nv
        if force_map is None:
            w_lambda = np.eye(nv)
        else:
            w_lambda = check_finite(force_map, "force_map")
            if w_lambda.ndim != 2 or w_lambda.shape[0] != nv:
                raise ControllerError(
                    f"force_map must be an nv x n_lambda matrix with nv = {nv}, got shape {w_lambda.shape}"
                )
        n_lambda = w_lambda.shape[1]
        self.known_forces = _indices("known_forces", known_forces, n_lambda)
        self.unknown_forces = np.setdiff1d(np.arange(n_lambda), self.known_forces)
        rows = range(task.dim) if known_task is None else known_task
        self.known_task = _indices("known_task", rows, task.dim)
        self.free_task = np.setdiff1d(np.arange(task.dim), self.known_task)
        n_known = self.known_task.size
        self._t_wu = np.zeros((task.dim, self.free_task.size))  # T_wu of (5.90), a selection of the free rows
        self._t_wu[self.free_task, np.arange(self.free_task.size)] = 1.0
        self.kp = np.broadcast_to(np.asarray(stiffness, dtype=np.float64), (n_known,)).copy()
        self.kd = np.broadcast_to(np.asarray(damping, dtype=np.float64), (n_known,)).copy()
        for name, value in (("stiffness", self.kp), ("damping", self.kd)):
            if not np.all(np.isfinite(value)) or np.any(value < 0.0):
                raise ControllerError(f"{name} must be finite and >= 0, got {value.tolist()}")
        n_unknown = self.unknown_forces.size + self.free_task.size
        if n_unknown == 0:
            raise ControllerError("nothing to solve for: every force is known and every task row prescribed")
        force_w = np.broadcast_to(np.asarray(force_weights, dtype=np.float64), (self.unknown_forces.size,))
        task_w = np.broadcast_to(np.asarray(task_weights, dtype=np.float64), (self.free_task.size,))
        if weighting not in WEIGHTINGS:
            raise ControllerError(f"unknown weighting {weighting!r}; valid: {', '.join(WEIGHTINGS)}")
        self.weighting = weighting
        self.weights = WeightMatrix(np.concatenate([force_w, task_w]), n_unknown)
        self._task_weights = np.array(task_w, dtype=np.float64)
        if self_motion_damping is None:
            self.self_motion_damping: NDArray[np.float64] | None = None
        else:
            self.self_motion_damping = np.broadcast_to(np.asarray(self_motion_damping, dtype=np.float64), (nv,)).copy()
            if not np.all(np.isfinite(self.self_motion_damping)) or np.any(self.self_motion_damping < 0.0):
                raise ControllerError(f"self_motion_damping must be finite and >= 0, got {self_motion_damping!r}")
        self.posture_stiffness = np.broadcast_to(np.asarray(posture_stiffness, dtype=np.float64), (nv,)).copy()
        if not np.all(np.isfinite(self.posture_stiffness)) or np.any(self.posture_stiffness < 0.0):
            raise ControllerError(f"posture_stiffness must be finite and >= 0, got {posture_stiffness!r}")
        self.posture = None if posture is None else model.check_configuration(posture)
        if np.any(self.posture_stiffness > 0.0) and (self.posture is None or self_motion_damping is None):
            raise ControllerError("posture_stiffness needs a posture and self_motion_damping")
        self.model = model
        self.task = task
        self.force_map = w_lambda
        self.method = method
        self.singular_threshold = float(singular_threshold)
        self.dls_threshold = float(dls_threshold)
        self.dls_max_damping = float(dls_max_damping)

    def step(
        self,
        q: ArrayLike,
        qdot: ArrayLike,
        known_forces: ArrayLike,
        target: ArrayLike,
        target_velocity: ArrayLike,
        target_acceleration: ArrayLike,
    ) -> GeneralIkdResult:
        """Generalized accelerations and the unknown forces at ``(q, qdot)`` for the prescribed ``lambda_k``
        (``known_forces``) and the known task rows' reference ``(w_kd, wdot_kd, wddot_kd)``."""
        model = self.model
        q = check_configuration(q, "q")
        qdot = check_finite(qdot, "qdot")
        if qdot.shape != (model.nv,):
            raise ControllerError(f"qdot must be finite with shape ({model.nv},), got {qdot.shape}")
        lam_k = check_finite(known_forces, "known_forces")
        n_known = self.known_task.size
        if lam_k.shape != (self.known_forces.size,):
            raise ControllerError(f"known_forces must have shape ({self.known_forces.size},), got {lam_k.shape}")
        references = []
        for name, value in (
            ("target", target),
            ("target_velocity", target_velocity),
            ("target_acceleration", target_acceleration),
        ):
            value = check_finite(value, name)
            if value.shape != (n_known,):
                raise ControllerError(f"{name} must have shape ({n_known},) (the known task rows), got {value.shape}")
            references.append(value)
        w_kd, wdot_kd, wddot_kd = references
        drift = self.task.drift(model, q, qdot)  # updates the model at q
        jacobian = self.task.jacobian(model)
        value = self.task.value(model)
        mass = model.mass_matrix()
        h = model.nonlinear_effects(q, qdot)
        known = self.known_task
        wddot_k = wddot_kd + self.kd * (wdot_kd - jacobian[known] @ qdot) + self.kp * (w_kd - value[known])
        # M^-1 (W_lambda, h) in one Cholesky solve (M is symmetric positive definite)
        factor = np.linalg.cholesky(mass)
        rhs = np.column_stack([self.force_map, h])
        minv = np.linalg.solve(factor.T, np.linalg.solve(factor, rhs))
        minv_w, minv_h = minv[:, :-1], minv[:, -1]
        j_minv_w = jacobian @ minv_w
        g = np.hstack([j_minv_w[:, self.unknown_forces], -self._t_wu])  # (5.96)
        f = j_minv_w[:, self.known_forces] @ lam_k - jacobian @ minv_h + drift
        f[known] -= wddot_k  # - T_wk wddot_k: T_wk selects the known rows
        n_u = self.unknown_forces.size
        weights = self.weights
        if self.weighting == "acceleration":
            n_w = self.free_task.size
            full = np.zeros((n_u + n_w, n_u + n_w))
            full[:n_u, :n_u] = (self.force_map.T @ minv_w)[np.ix_(self.unknown_forces, self.unknown_forces)]
            full[n_u:, n_u:] = np.diag(self._task_weights)
            weights = WeightMatrix(0.5 * (full + full.T), n_u + n_w)
        z = None
        if self.self_motion_damping is not None:  # min |x - x_pref|_W: the nullspace vector z = -W x_pref
            preferred = np.zeros(g.shape[1])
            hold = h - self.self_motion_damping * qdot
            if self.posture is not None:
                hold = hold - self.posture_stiffness * model.difference(self.posture, q)
            preferred[:n_u] = (self.force_map.T @ hold)[self.unknown_forces]
            z = -weights.apply(preferred)
        res = resolve(
            g,
            -f,
            z,
            weights,
            method=self.method,
            singular_threshold=self.singular_threshold,
            dls_threshold=self.dls_threshold,
            dls_max_damping=self.dls_max_damping,
        )
        forces = np.zeros(self.force_map.shape[1])
        forces[self.known_forces] = lam_k
        if not res.success:
            return GeneralIkdResult(
                np.zeros(model.nv),
                forces,
                np.zeros(n_u),
                np.zeros(self.free_task.size),
                wddot_k,
                float(np.linalg.norm(f)),
                res.sigma_min,
                res.damping,
                False,
                res.status,
            )
        lam_u, wddot_u = res.x[:n_u], res.x[n_u:]
        forces[self.unknown_forces] = lam_u
        qddot = minv_w @ forces - minv_h  # (5.92) solved for qddot
        residual = float(np.linalg.norm(g @ res.x + f))
        return GeneralIkdResult(
            qddot, forces, lam_u, wddot_u, wddot_k, residual, res.sigma_min, res.damping, True, res.status
        )
