"""Whole-body velocity-level CLIK for a floating-base biped (monograph 5.1-5.3).

Tasks (18 rows): the CoM (3), the pose of each sole (6 + 6) and the torso orientation (3). The unknowns are
all ``nv`` velocities, the free-floating base's six included, so the base moves as the tasks demand. The
redundancy (arms, pelvis, toes: 10 DoF for the Lola-like biped) is resolved by the weighted least-norm
solution of (5.7) with the angular-momentum weight (5.62)

    W = gamma I + J_Lz^T J_Lz,     W^-1 = (I - J_Lz^T J_Lz / (gamma + |J_Lz|^2)) / gamma

(Sherman-Morrison-Woodbury: ``W`` is a rank-one update of ``gamma I``, so ``W^-1`` costs two vector products),
plus the gradient of nullspace objectives (joint limits (5.58), posture, self-collision (5.49)) projected as in
(5.14). The scale ``beta`` of (5.62) weighs ``W`` against those objectives:
``qdot = J#_W (wdot + K e) - (alpha / beta) N W^-1 dH/dq``.

Each :meth:`WholeBodyIk.step` takes the reference at the start and the end of the control period: it
integrates the CLIK velocity, then applies one Newton correction on the position error at the end of the
period, so the kinematic model follows the references to second order in the step.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...model import RobotModel
from ..exceptions import ControllerError
from ..kernels.linalg import rotation_error
from ..objectives.objective import Objective
from .ik_kernels import weighted_solve
from .whole_body_kernels import REFERENCE_LAYOUT, REFERENCE_SIZE

__all__ = [
    "REFERENCE_LAYOUT",
    "REFERENCE_SIZE",
    "TASK_ROWS",
    "Reference",
    "WholeBodyIk",
    "WholeBodyIkResult",
    "WholeBodyReference",
]

TASK_ROWS: dict[str, slice] = {
    "com": slice(0, 3),
    "right_foot": slice(3, 9),
    "left_foot": slice(9, 15),
    "torso": slice(15, 18),
}
"""Rows of the stacked task (CoM, right sole pose, left sole pose, torso orientation)."""
_M = 18


@dataclass(frozen=True)
class WholeBodyReference:
    """World-frame references of the whole-body tasks at one instant.

    Attributes:
        com: CoM position [m]; ``com_velocity`` [m/s].
        feet_position: sole positions [m], rows right and left; ``feet_rotation`` (2, 3, 3).
        feet_velocity: sole twists ``[v; omega]`` [m/s, rad/s], shape (2, 6).
        torso_rotation: (3, 3); ``torso_angular_velocity`` [rad/s].
    """

    com: NDArray[np.float64]
    com_velocity: NDArray[np.float64]
    feet_position: NDArray[np.float64]
    feet_rotation: NDArray[np.float64]
    feet_velocity: NDArray[np.float64]
    torso_rotation: NDArray[np.float64]
    torso_angular_velocity: NDArray[np.float64]

    def to_array(self) -> NDArray[np.float64]:
        """The fields flattened into one array of :data:`REFERENCE_SIZE` in the :data:`REFERENCE_LAYOUT` order."""
        out = np.empty(REFERENCE_SIZE)
        try:
            for name, rows in REFERENCE_LAYOUT.items():
                out[rows] = np.ravel(getattr(self, name))
        except ValueError as exc:
            raise ControllerError(f"a reference field has the wrong shape: {exc}") from exc
        return out

    @classmethod
    def from_array(cls, packed: ArrayLike) -> WholeBodyReference:
        """The reference of a :meth:`to_array` array."""
        a = np.asarray(packed, dtype=np.float64)
        if a.shape != (REFERENCE_SIZE,):
            raise ControllerError(f"a packed reference has shape ({REFERENCE_SIZE},), got {a.shape}")
        shapes = {
            "feet_position": (2, 3),
            "feet_rotation": (2, 3, 3),
            "feet_velocity": (2, 6),
            "torso_rotation": (3, 3),
        }
        return cls(**{name: a[rows].reshape(shapes.get(name, (3,))) for name, rows in REFERENCE_LAYOUT.items()})


Reference = WholeBodyReference | NDArray[np.float64]
"""A reference or its :meth:`WholeBodyReference.to_array` array (the fast path of the compiled IK)."""


class WholeBodyIkResult(NamedTuple):
    """Result of :meth:`WholeBodyIk.step`.

    Attributes:
        q: the configuration at the end of the period (pinocchio convention, nq).
        qdot: the CLIK velocity of the period (nv) [m/s, rad/s].
        task_error: largest task error at the end of the period before the Newton correction [m or rad]
            (the correction removes it to second order).
        lz: vertical angular momentum about the CoM of ``qdot`` [kg m^2/s].
        sigma_min: smallest pivot of the Cholesky factor of ``J W^-1 J^T`` (falls to 0 at a task singularity).
        success: False when the step met a singular task (then ``q`` is the start configuration).
        limited: True when the velocity or the correction was scaled down to ``max_velocity`` (an unreachable
            or near-singular reference; tracking is then not exact).
    """

    q: NDArray[np.float64]
    qdot: NDArray[np.float64]
    task_error: float
    lz: float
    sigma_min: float
    success: bool
    limited: bool = False


class WholeBodyIk:
    """Whole-body CLIK with angular-momentum minimization (5.62) in the nullspace.

    Args:
        model: floating-base robot model.
        feet_frames: sole frames (right, left).
        torso_frame: a frame on the upper body whose orientation is a task.
        gain: task feedback ``K`` [1/s] of (5.5) on the start-of-period error.
        gamma: ``gamma`` of (5.62), > 0 (the joint-velocity share of ``W``).
        momentum_minimization: use ``W`` of (5.62); False gives ``W = I`` (the unit weighting of fig. 5.11).
        beta: scale of (5.62) relative to the nullspace objectives, > 0.
        nullspace_gain: ``alpha`` of (5.14), >= 0.
        objectives: nullspace objectives on the full configuration (their gradient has length nv).
        damping: Tikhonov damping added to ``J W^-1 J^T`` [-] (keeps the solve finite near singularities).
        singular_threshold: Cholesky pivot below which :attr:`WholeBodyIkResult.success` is False.
        max_velocity: largest joint (or base) speed [rad/s or m/s] of a step; a larger solution is scaled down
            as a whole (direction kept), and the Newton correction to ``max_velocity * dt``. Near a singularity
            the weighted pseudoinverse grows without bound; this keeps the targets sent to the servos sane.
    """

    def __init__(
        self,
        model: RobotModel,
        *,
        feet_frames: tuple[str, str] = ("r_sole", "l_sole"),
        torso_frame: str = "imu",
        gain: float = 100.0,
        gamma: float = 0.008,
        momentum_minimization: bool = True,
        beta: float = 1.0,
        nullspace_gain: float = 1.0,
        objectives: tuple[Objective, ...] = (),
        damping: float = 1e-10,
        singular_threshold: float = 1e-6,
        max_velocity: float = 25.0,
    ) -> None:
        if not model.floating_base:
            raise ControllerError(f"the whole-body IK needs a floating-base model, {model.source} has a fixed base")
        for name, value in (("gain", gain), ("gamma", gamma), ("beta", beta), ("max_velocity", max_velocity)):
            if not np.isfinite(value) or value <= 0.0:
                raise ControllerError(f"{name} must be finite and > 0, got {value!r}")
        for name, value in (
            ("nullspace_gain", nullspace_gain),
            ("damping", damping),
            ("singular_threshold", singular_threshold),
        ):
            if not np.isfinite(value) or value < 0.0:
                raise ControllerError(f"{name} must be finite and >= 0, got {value!r}")
        self.model = model
        self.feet_frames, self.torso_frame = tuple(feet_frames), torso_frame
        self._feet = tuple(model.frame_id(f) for f in feet_frames)
        self._torso = model.frame_id(torso_frame)
        self.gain = float(gain)
        self.gamma = float(gamma)
        self.momentum_minimization = bool(momentum_minimization)
        self.beta = float(beta)
        self.nullspace_gain = float(nullspace_gain)
        self.objectives = tuple(objectives)
        self.damping = float(damping)
        self.singular_threshold = float(singular_threshold)
        self.max_velocity = float(max_velocity)
        self._mass = model.total_mass
        self._jacobian = np.zeros((_M, model.nv))

    # ------------------------------------------------------------------ build
    def build(
        self, q: ArrayLike, reference: WholeBodyReference
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """``(J, e, j_Lz)`` at ``q``: the stacked task Jacobian (18 x nv), error (reference - actual) and ``J_Lz``."""
        model = self.model
        model.update(q)
        com, centroidal = model.com_and_centroidal_matrix()
        jac, err = self._jacobian, np.empty(_M)
        jac[0:3] = centroidal[:3] / self._mass
        err[0:3] = reference.com - com
        for i, frame in enumerate(self._feet):
            rows = slice(3 + 6 * i, 9 + 6 * i)
            jac[rows] = model.frame_jacobian(frame, "full")
            rotation, position = model.frame_placement(frame)
            err[rows.start : rows.start + 3] = reference.feet_position[i] - position
            err[rows.start + 3 : rows.stop] = rotation_error(reference.feet_rotation[i], rotation)
        jac[15:18] = model.frame_jacobian(self._torso, "rotational")
        err[15:18] = rotation_error(reference.torso_rotation, model.frame_rotation(self._torso))
        return jac, err, centroidal[5]

    def reference_velocity(self, reference: WholeBodyReference) -> NDArray[np.float64]:
        """The stacked task velocity ``wdot_d`` (18)."""
        return np.concatenate(
            [
                reference.com_velocity,
                reference.feet_velocity[0],
                reference.feet_velocity[1],
                reference.torso_angular_velocity,
            ]
        )

    # ------------------------------------------------------------------ solve
    def solve(
        self,
        jac: NDArray[np.float64],
        rhs: NDArray[np.float64],
        j_lz: NDArray[np.float64],
        gradient: NDArray[np.float64] | None,
    ) -> tuple[NDArray[np.float64], float, bool]:
        """``(qdot, sigma_min, ok)``: ``qdot = W^-1 (J^T lambda - z)`` with ``J W^-1 J^T lambda = rhs + J W^-1 z``.

        ``z = (alpha / beta) dH/dq`` (``gradient`` may be None: no nullspace objective); this is (5.14) with
        ``W`` of (5.62) inverted by Sherman-Morrison-Woodbury (:func:`~.ik_kernels.weighted_solve`).
        """
        if gradient is None or self.nullspace_gain == 0.0:
            z = np.zeros(jac.shape[1])
        else:
            z = (self.nullspace_gain / self.beta) * gradient
        qdot, sigma_min, ok = weighted_solve(jac, rhs, j_lz, z, self.gamma, self.momentum_minimization, self.damping)
        return qdot, float(sigma_min), bool(ok) and sigma_min >= self.singular_threshold

    def objective_gradient(self, q: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """Sum of the nullspace objectives' gradients at ``q`` (after :meth:`build` at ``q``), or None."""
        if not self.objectives:
            return None
        gradient = np.zeros(self.model.nv)
        for objective in self.objectives:
            gradient += objective.evaluate(self.model, q).gradient
        return gradient

    # ------------------------------------------------------------------ step
    def step(self, q: ArrayLike, start: Reference, end: Reference, dt: float) -> WholeBodyIkResult:
        """Move the kinematic model over one control period ``dt`` [s] from the reference ``start`` to ``end``."""
        if not np.isfinite(dt) or dt <= 0.0:
            raise ControllerError(f"dt must be finite and > 0, got {dt!r}")
        if not isinstance(start, WholeBodyReference):
            start = WholeBodyReference.from_array(start)
        if not isinstance(end, WholeBodyReference):
            end = WholeBodyReference.from_array(end)
        if not (np.all(np.isfinite(start.to_array())) and np.all(np.isfinite(end.to_array()))):
            raise ControllerError("the references must be finite")
        q = self.model.check_configuration(q)
        jac, err, j_lz = self.build(q, start)
        rhs = self.reference_velocity(start) + self.gain * err
        qdot, sigma_min, ok = self.solve(jac, rhs, j_lz, self.objective_gradient(q))
        if not ok or not np.all(np.isfinite(qdot)):
            return WholeBodyIkResult(q, np.zeros(self.model.nv), float(np.max(np.abs(err))), 0.0, sigma_min, False)
        peak = float(np.max(np.abs(qdot)))
        limited = peak > self.max_velocity
        if limited:
            qdot = qdot * (self.max_velocity / peak)
        lz = float(j_lz @ qdot)
        q_next = self.model.integrate(q, qdot, dt)
        # Newton correction on the end-of-period error (no nullspace motion: it only removes the
        # second-order remainder of the velocity step)
        jac, err, j_lz = self.build(q_next, end)
        correction, _, ok = self.solve(jac, err, j_lz, None)
        if ok and np.all(np.isfinite(correction)):
            peak = float(np.max(np.abs(correction)))
            if peak > self.max_velocity * dt:
                correction = correction * (self.max_velocity * dt / peak)
                limited = True
            q_next = self.model.integrate(q_next, correction, 1.0)
        return WholeBodyIkResult(q_next, qdot, float(np.max(np.abs(err))), lz, sigma_min, True, limited)
