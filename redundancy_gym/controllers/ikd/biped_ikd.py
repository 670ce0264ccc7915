"""Inverse Kineto-Dynamics for biped walking (monograph 5.5.2, (5.84)-(5.91)): joint accelerations that realize a
prescribed contact moment exactly, with the horizontal CoM as the unknown task coordinates."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple, cast

import numpy as np
from numba import types
from numpy.typing import ArrayLike, NDArray

from ...constants import GRAVITY
from ...geometry.potentials import PiecewisePotential, piecewise_potential_kernel
from ...kernel_options import JIT_EXACT, njit_on_first_call
from ...model import AccelerationTerms, RobotModel
from ..clik.redundancy_resolution import MAX_COORDINATE, WeightMatrix, check_configuration, check_finite
from ..exceptions import ControllerError
from ..kernels.linalg import cholesky_factor, cholesky_solve, rotation_error_into
from ..objectives.actuated_objective import ActuatedObjective
from ..objectives.joint_limit_objective import JointLimitObjective
from ..objectives.objective import Objective, sum_objectives

__all__ = ["BipedIkd", "BipedIkdReference", "BipedIkdResult", "GRAVITY"]


class BipedIkdReference(NamedTuple):
    """The known part of the hybrid task at one instant (world frame), and the prescribed contact moment.

    Attributes:
        feet_position: sole positions [m] (2, 3), rows right, left.
        feet_rotation: sole orientations (2, 3, 3).
        feet_velocity: sole twists [m/s, rad/s] (2, 6): linear, then angular.
        feet_acceleration: their rates [m/s^2, rad/s^2] (2, 6).
        torso_rotation: torso orientation (3, 3).
        torso_angular_velocity: [rad/s] (3).
        torso_angular_acceleration: [rad/s^2] (3).
        com_height: the CoM's z [m], its rate [m/s] and acceleration [m/s^2] (3).
        moment: the contact moment ``(T_x, T_y)`` [N m] about the world origin (5.85) with the contact force
            taken to act there (the monograph's choice ``r_F = 0``); for a ZMP ``p`` on flat ground and a
            vertical force ``F_z``, ``T = F_z (p_y, -p_x)``.
        com_plan: the planned horizontal CoM ``(x, y, xdot, ydot)`` [m, m/s] that the contact-moment stabilization
            (5.97) pulls to (None: no stabilization).
        support: the support polygon's bounding box ``((x_min, y_min), (x_max, y_max))`` [m] that the stabilized
            moment's ZMP is saturated to (None: no saturation).
    """

    feet_position: NDArray[np.float64]
    feet_rotation: NDArray[np.float64]
    feet_velocity: NDArray[np.float64]
    feet_acceleration: NDArray[np.float64]
    torso_rotation: NDArray[np.float64]
    torso_angular_velocity: NDArray[np.float64]
    torso_angular_acceleration: NDArray[np.float64]
    com_height: NDArray[np.float64]
    moment: NDArray[np.float64]
    com_plan: NDArray[np.float64] | None = None
    support: NDArray[np.float64] | None = None


class BipedIkdResult(NamedTuple):
    """One step of :class:`BipedIkd`.

    Attributes:
        qddot: generalized accelerations (nv); zeros when ``success`` is False.
        com_acceleration: the CoM's acceleration [m/s^2] (3): x and y solved for, z the prescribed one.
        residual: ``|R qddot + r|`` of (5.91) (0 up to round-off unless damped).
        sigma_min: smallest singular value of ``R W^-1/2``.
        success: False at a singular task.
        status: ``"ok"``, ``"damped"`` or ``"singular"``.
        moment: the contact moment ``(T_x, T_y)`` [N m] the motion realizes: the reference's, plus the
            stabilization's modification (5.97) where it acts.
    """

    qddot: NDArray[np.float64]
    com_acceleration: NDArray[np.float64]
    residual: float
    sigma_min: float
    success: bool
    status: str
    moment: NDArray[np.float64]


class BipedIkd:
    """``R qddot + r = 0`` (5.91) from the x/y angular momentum theorem about the CoM with the contact moment
    prescribed (5.87)-(5.89) and the task split into known rows (the CoM's height, both soles' poses, the torso's
    orientation) and unknown ones (the CoM's x and y) (5.90)::

        A qddot + B wddot_u + c = 0,   A = J_L,xy,  B = [[0, -m z_c], [m z_c, 0]],
        c = Jdot_L,xy qdot + (m y_c (g + zddot_c) - T_x, -m x_c (g + zddot_c) - T_y),
        R = J_w + T_wu B^-1 A,   r = Jdot_w qdot - T_wk wddot_k + T_wu B^-1 c.

    ``J_L`` and ``Jdot_L qdot`` are the angular rows of the centroidal momentum matrix and its drift (pinocchio,
    through :class:`~redundancy_gym.model.RobotModel`). The known rows are stabilized as in (5.19) (the
    drift compensation acts on them only: ``stiffness`` ``K_P``, ``damping`` ``K_D``; the monograph's
    ``K_P = 40 / dt``, ``K_D = 2 sqrt(K_P) 0.85`` suit a 1 ms period). The redundancy (the arms, the waist) is
    resolved by the weighted minimum of ``|qddot - qddot_pref|``, ``qddot_pref = -D qdot - K (q - posture)``
    (``self_motion_damping`` ``D``, ``posture_stiffness`` ``K``).

    This is the kinematic IKD: the contact moment that the generated motion needs is the prescribed one exactly
    (pinocchio's inverse dynamics of the motion give it back); without stabilization the CoM drifts away from
    the plan the moment came from (monograph fig. 5.21). Stabilization via the contact moment (5.97): with a
    ``com_plan`` in the reference and ``moment_gain`` ``k`` > 0, ``T += sat(B [K_p (w_plan - w) + K_d (wdot_plan -
    wdot)])`` with the monograph's ``K_p = k 40 / period`` and ``K_d = 2 * 0.85 sqrt(K_p)``, its ZMP saturated to
    the reference's ``support`` box. In the pendulum limit the error dynamics are stable for ``K_p > (g +
    zddot) / z`` (monograph footnote 19: ``k`` above about 2.7e-4 at a 1 ms period).

    Args:
        model: a floating-base model of the biped.
        feet_frames: the sole frames (right, left).
        torso_frame: the torso's frame.
        posture: the posture (nq) of the nullspace term (None: no posture term).
        moment_gain: ``k`` of (5.97) (0: the prescribed moment unmodified).
        period: the control period [s] of the gains ``K_p = k 40 / period``.
        objectives: nullspace objectives ``H(q)`` (value and gradient, as the CLIK's: joint limits (5.58),
            self-collision (5.49)); the preferred acceleration adds ``-objective_gain dH/dq``.
        objective_gain: their gain [1/s^2 per unit of ``H``'s gradient].
    """

    def __init__(
        self,
        model: RobotModel,
        *,
        feet_frames: tuple[str, str] = ("r_sole", "l_sole"),
        torso_frame: str = "imu",
        stiffness: float = 400.0,
        damping: float = 34.0,
        self_motion_damping: float = 10.0,
        posture_stiffness: float = 25.0,
        posture: ArrayLike | None = None,
        weights: ArrayLike | float = 1.0,
        singular_threshold: float = 1e-6,
        moment_gain: float = 0.0,
        period: float = 0.001,
        objectives: Sequence[Objective] = (),
        objective_gain: float = 100.0,
    ) -> None:
        if not model.floating_base:
            raise ControllerError(f"biped IKD needs a floating-base model, {model.source} has a fixed base")
        for name, value in (
            ("stiffness", stiffness),
            ("damping", damping),
            ("self_motion_damping", self_motion_damping),
            ("posture_stiffness", posture_stiffness),
            ("moment_gain", moment_gain),
            ("objective_gain", objective_gain),
        ):
            if not np.isfinite(value) or value < 0.0:
                raise ControllerError(f"{name} must be finite and >= 0, got {value!r}")
        self.model = model
        self.feet_frames = tuple(feet_frames)
        self.torso_frame = torso_frame
        for frame in (*self.feet_frames, torso_frame):
            model.frame_id(frame)  # raises naming an unknown frame
        self.kp, self.kd = float(stiffness), float(damping)
        self.self_motion_damping, self.posture_stiffness = float(self_motion_damping), float(posture_stiffness)
        self.posture = None if posture is None else model.check_configuration(posture)
        self.weights = WeightMatrix(weights, model.nv)
        self.singular_threshold = float(singular_threshold)
        self.mass = model.total_mass
        if not np.isfinite(period) or period <= 0.0:
            raise ControllerError(f"period must be finite and > 0 [s], got {period!r}")
        self.moment_gain = float(moment_gain)
        self.com_stiffness = self.moment_gain * 40.0 / float(period)
        self.com_damping = 2.0 * 0.85 * float(np.sqrt(self.com_stiffness))
        self.objectives = tuple(objectives)
        for objective in self.objectives:
            if not isinstance(objective, Objective):
                raise ControllerError(f"objectives must have evaluate(model, q), got {type(objective).__name__}")
        self.objective_gain = float(objective_gain)
        self.terms: AccelerationTerms | None = None
        """The model's terms at the last :meth:`step`'s state (CoM, centroidal map, ...), for callers that need them."""
        self._inverse_weights: tuple[WeightMatrix, NDArray[np.float64]] | None = None  # (W, W^-1) of a full W

    def step(self, q: ArrayLike, qdot: ArrayLike, reference: BipedIkdReference) -> BipedIkdResult:
        """Generalized accelerations at ``(q, qdot)`` for ``reference`` (the contact moment among it)."""
        # One pinocchio pass (RobotModel.acceleration_terms) and one compiled kernel (_solve) for the algebra and
        # the solve; inputs that are float64 arrays of the documented shapes are checked in one compiled call, any
        # others take the general checks and conversions of _checked.
        model = self.model
        stabilize = reference.com_plan is not None and self.moment_gain > 0.0
        plan = _NO_PLAN if reference.com_plan is None else reference.com_plan
        support = _NO_SUPPORT if reference.support is None else reference.support
        goal = _goal(reference, plan, support)
        arrays = (q, qdot, *goal)
        fast = False
        # numba's TypeError for other types costs some 100 us, so lists and other dtypes are not offered to it
        if all([type(a) is np.ndarray and a.dtype == _FLOAT64 for a in arrays]):
            try:
                fast = _valid(q, qdot, goal, model.nq, model.nv, MAX_COORDINATE)
            except TypeError:  # an array with another number of dimensions
                pass
        if fast:  # _valid found float64 arrays of the documented shapes
            q, qdot, ref = cast(NDArray[np.float64], q), cast(NDArray[np.float64], qdot), reference
        else:
            q, qdot, ref, plan, support = self._checked(q, qdot, reference, stabilize)
            goal = _goal(ref, plan, support)
        terms = self._terms(q, qdot)
        self.terms = terms
        posture = self.posture
        has_posture = posture is not None
        offset = self._difference(posture, q) if posture is not None else qdot
        stiffness = self.posture_stiffness
        if self.objectives:  # the kernel's preferred -K offset then carries -K (q - posture) - k_H dH/dq
            limits = _joint_limits(self.objectives, model.nq, model.nv)
            combined = None
            if limits is not None:  # the walking controller's one joint-limit objective: one compiled call
                combined = _limit_offset(q, offset, limits, self.objective_gain, stiffness, has_posture)
            if combined is None:  # other objectives, or non-finite distances (the objective's own error)
                self._prepare_objectives(q)
                gradient = sum_objectives(self.objectives, model, np.asarray(q, dtype=np.float64)).gradient
                combined = (stiffness * offset if has_posture else 0.0) + self.objective_gain * gradient
            offset = combined
            has_posture, stiffness = True, 1.0
        diagonal = self.weights.diagonal
        if diagonal is None:
            inverse = self._inverse_weights
            if inverse is None or inverse[0] is not self.weights:
                inverse = self._inverse_weights = (self.weights, self.weights.solve(np.eye(model.nv)))
            weights, inverse_weights = _NO_DIAGONAL, inverse[1]
        else:
            weights, inverse_weights = diagonal, _NO_INVERSE
        qddot, com_acceleration, moment, residual, sigma_min, ok = _solve(
            qdot,
            terms.rotation,
            terms.position,
            terms.jacobian,
            terms.drift,
            terms.com,
            terms.centroidal,
            terms.centroidal_drift,
            goal,
            offset,
            weights,
            inverse_weights,
            self.kp,
            self.kd,
            self.mass,
            self.com_stiffness,
            self.com_damping,
            self.self_motion_damping,
            stiffness,
            self.singular_threshold,
            stabilize,
            reference.support is not None,
            has_posture,
            diagonal is not None,
        )
        return BipedIkdResult(qddot, com_acceleration, residual, sigma_min, ok, "ok" if ok else "singular", moment)

    def integrate(self, q: ArrayLike, qdot: ArrayLike, dt: float) -> NDArray[np.float64]:
        """The configuration reached from ``q`` moving with ``qdot`` for ``dt`` [s] (:meth:`RobotModel.integrate`)."""
        return self.model.integrate(q, qdot, dt)

    def _difference(self, q0: NDArray[np.float64], q1: NDArray[np.float64]) -> NDArray[np.float64]:
        """``q1 (-) q0`` (nv) of checked configurations (:meth:`RobotModel.difference`)."""
        return self.model.difference(q0, q1)

    def _terms(self, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> AccelerationTerms:
        """The soles' and the torso's placements, Jacobians and drifts, the CoM and the centroidal map at the
        checked ``(q, qdot)`` (:meth:`RobotModel.acceleration_terms`, which leaves the model's cache at ``q``)."""
        return self.model.acceleration_terms(q, qdot, (*self.feet_frames, self.torso_frame))

    def _prepare_objectives(self, q: NDArray[np.float64]) -> None:
        """Make the model ready for the objectives' :meth:`~Objective.evaluate` at ``q`` (:meth:`_terms` left its
        cache there)."""

    def _checked(
        self, q: ArrayLike, qdot: ArrayLike, reference: BipedIkdReference, stabilize: bool
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], BipedIkdReference, NDArray[np.float64], NDArray[np.float64]]:
        """``(q, qdot, reference, plan, support)`` checked (:class:`ControllerError` naming the first bad input)
        and as float64 C arrays of the documented shapes: a row given with another shape is broadcast to its
        shape as NumPy would; the plan and the support box are placeholders where they are not used."""
        model = self.model
        q = check_configuration(q, "q")
        qdot = check_finite(qdot, "qdot")
        if qdot.shape != (model.nv,):
            raise ControllerError(f"qdot must be finite with shape ({model.nv},), got {qdot.shape}")
        for name in reference._fields:
            if getattr(reference, name) is not None:
                check_finite(getattr(reference, name), f"reference.{name}")
        moment = np.asarray(reference.moment, dtype=np.float64)
        height = np.asarray(reference.com_height, dtype=np.float64)
        if moment.shape != (2,) or height.shape != (3,):
            raise ControllerError("reference.moment must be (T_x, T_y) and reference.com_height (z, zdot, zddot)")
        plan, support = _NO_PLAN, _NO_SUPPORT
        if stabilize:
            plan = np.asarray(reference.com_plan, dtype=np.float64)
            if plan.shape != (4,):
                raise ControllerError(f"reference.com_plan must be (x, y, xdot, ydot), got shape {plan.shape}")
            if reference.support is not None:
                support = _rows(reference.support, 2, (2,), "support")
        checked = BipedIkdReference(
            _rows(reference.feet_position, 2, (3,), "feet_position"),
            _rows(reference.feet_rotation, 2, (3, 3), "feet_rotation", broadcast=False),
            _rows(reference.feet_velocity, 2, (6,), "feet_velocity"),
            _rows(reference.feet_acceleration, 2, (6,), "feet_acceleration"),
            _rows(reference.torso_rotation, 3, (3,), "torso_rotation", broadcast=False),
            _rows([reference.torso_angular_velocity], 1, (3,), "torso_angular_velocity")[0],
            _rows([reference.torso_angular_acceleration], 1, (3,), "torso_angular_acceleration")[0],
            np.array(height),
            np.array(moment),
            plan if stabilize else None,
            None,
        )
        return np.array(q), np.array(qdot), checked, np.array(plan), np.array(support)


def _goal(reference: BipedIkdReference, plan: NDArray[np.float64], support: NDArray[np.float64]) -> tuple[Any, ...]:
    """The reference's arrays with the CoM ``plan`` and ``support`` box, packed as the kernels take them
    (``_GOAL``)."""
    return (
        reference.feet_position,
        reference.feet_rotation,
        reference.feet_velocity,
        reference.feet_acceleration,
        reference.torso_rotation,
        reference.torso_angular_velocity,
        reference.torso_angular_acceleration,
        reference.com_height,
        reference.moment,
        plan,
        support,
    )


def _rows(
    value: Sequence[ArrayLike] | NDArray[np.float64],
    count: int,
    shape: tuple[int, ...],
    name: str,
    broadcast: bool = True,
) -> NDArray[np.float64]:
    """``value``'s first ``count`` rows (the ones the step reads), each broadcast to ``shape`` (or required to have
    it), as one float64 C array (``count``, ``*shape``)."""
    try:
        rows = [np.asarray(value[i], dtype=np.float64) for i in range(count)]
        if not broadcast and any(row.shape != shape for row in rows):
            raise ValueError
        return np.array([np.broadcast_to(row, shape) for row in rows], dtype=np.float64)
    except (IndexError, TypeError, ValueError):
        raise ControllerError(
            f"reference.{name} must have shape {(count, *shape)}, got {np.shape(cast(ArrayLike, value))}"
        ) from None


_FLOAT64 = np.dtype(np.float64)
_NO_PLAN = np.zeros(4)
_NO_SUPPORT = np.zeros((2, 2))
_NO_DIAGONAL = np.ones(0)
_NO_INVERSE = np.zeros((0, 0))
# the kernels' arrays: float64 of any layout, writable or not (the caller's of other types take BipedIkd._checked);
# their results are C arrays
_V, _M, _T = (types.Array(types.float64, n, "A", readonly=True) for n in (1, 2, 3))
_CV = types.Array(types.float64, 1, "C")
_F, _B = types.float64, types.boolean
# the reference as the kernels take it (_goal): feet position, rotation, velocity, acceleration, torso rotation,
# angular velocity, angular acceleration, CoM height, moment, CoM plan, support box
_GOAL = types.Tuple((_M, _T, _M, _M, _M, _V, _V, _V, _V, _V, _M))


_JointLimits = tuple[NDArray[np.float64], NDArray[np.float64], int, int, float, float, float, float]
"""``(lower, upper, base_nq, base_nv, activation_distance, slope, switch_ratio, weight)`` of :func:`_joint_limits`."""


def _joint_limits(objectives: tuple[Objective, ...], nq: int, nv: int) -> _JointLimits | None:
    """``(lower, upper, base_nq, base_nv, activation_distance, slope, switch_ratio, weight)`` when ``objectives``
    are exactly one :class:`ActuatedObjective` of a :class:`JointLimitObjective` (with its
    :class:`PiecewisePotential`) whose limits fit the actuated joints, read at each call (so a changed objective
    counts); None otherwise (:func:`sum_objectives` then evaluates them)."""
    if len(objectives) != 1:
        return None
    actuated = objectives[0]
    if type(actuated) is not ActuatedObjective:
        return None
    limit = actuated.objective
    if type(limit) is not JointLimitObjective:
        return None
    potential = limit.potential
    lower, upper = limit.lower, limit.upper
    base_nq, base_nv = actuated._nq, actuated._nv
    n = nq - base_nq
    if (
        type(potential) is not PiecewisePotential
        or nv - base_nv != n
        or type(lower) is not np.ndarray
        or type(upper) is not np.ndarray
        or lower.dtype != _FLOAT64
        or upper.dtype != _FLOAT64
        or lower.shape != (n,)
        or upper.shape != (n,)
    ):
        return None
    return (
        lower,
        upper,
        base_nq,
        base_nv,
        float(potential.activation_distance),
        float(potential.slope),
        float(potential.switch_ratio),
        float(limit.weight),
    )


def _limit_offset(
    q: NDArray[np.float64],
    offset: NDArray[np.float64],
    limits: _JointLimits,
    gain: float,
    stiffness: float,
    has_posture: bool,
) -> NDArray[np.float64] | None:
    """``(stiffness offset if has_posture else 0) + gain dH/dq`` of the joint-limit objective (5.58) of ``limits``
    (:func:`_joint_limits`: a :class:`JointLimitObjective` on the joints after the base's, as
    :class:`ActuatedObjective` evaluates it), the same arithmetic as :func:`sum_objectives` and the objective's;
    None where a distance to a limit is not finite (the objective raises its error there)."""
    out = np.empty(offset.shape[0])
    if not _limit_offset_into(q, offset, *limits, gain, stiffness, has_posture, out):
        return None
    return out


@njit_on_first_call(_B(_V, _V, _V, _V, types.int64, types.int64, _F, _F, _F, _F, _F, _F, _B, _CV), **JIT_EXACT)
def _limit_offset_into(
    q,
    offset,
    lower,
    upper,
    base_nq,
    base_nv,
    activation_distance,
    slope,
    switch_ratio,
    weight,
    gain,
    stiffness,
    has_posture,
    out,
):  # pragma: no cover - compiled
    """:func:`_limit_offset` into ``out`` (nv); False (``out`` unfinished) at a non-finite distance."""
    for c in range(base_nv):  # the base's gradient entries are zeros
        out[c] = (stiffness * offset[c] if has_posture else 0.0) + gain * 0.0
    for k in range(lower.shape[0]):
        x = q[base_nq + k]
        below, above = x - lower[k], upper[k] - x
        if not (np.isfinite(below) and np.isfinite(above)):
            return False
        _, d0, _ = piecewise_potential_kernel(below, activation_distance, slope, switch_ratio)
        _, d1, _ = piecewise_potential_kernel(above, activation_distance, slope, switch_ratio)
        c = base_nv + k
        out[c] = (stiffness * offset[c] if has_posture else 0.0) + gain * (weight * (d0 - d1))
    return True


@njit_on_first_call(_B(_V, _V, _GOAL, types.int64, types.int64, _F), **JIT_EXACT)
def _valid(q, qdot, goal, nq, nv, max_coordinate):  # pragma: no cover - compiled
    """Whether the inputs have the documented shapes and are finite, ``|q|`` within ``max_coordinate``
    (``goal``: as :func:`_goal` packs it)."""
    feet_position, feet_rotation, feet_velocity, feet_acceleration = goal[:4]
    torso_rotation, torso_velocity, torso_acceleration = goal[4:7]
    height, moment, plan, support = goal[7:]
    if (
        q.shape[0] != nq
        or qdot.shape[0] != nv
        or feet_position.shape != (2, 3)
        or feet_rotation.shape != (2, 3, 3)
        or feet_velocity.shape != (2, 6)
        or feet_acceleration.shape != (2, 6)
        or torso_rotation.shape != (3, 3)
        or torso_velocity.shape[0] != 3
        or torso_acceleration.shape[0] != 3
        or height.shape[0] != 3
        or moment.shape[0] != 2
        or plan.shape[0] != 4
        or support.shape != (2, 2)
    ):
        return False
    for x in q:
        if not abs(x) <= max_coordinate:
            return False
    total = 0.0  # NaN and inf survive a sum (an overflowing sum of finite entries takes the general checks)
    for x in qdot:
        total += x
    for a in (
        feet_position,
        feet_velocity,
        feet_acceleration,
        torso_rotation,
        support,
        feet_rotation[0],
        feet_rotation[1],
    ):
        for row in a:
            for x in row:
                total += x
    for a in (torso_velocity, torso_acceleration, height, moment, plan):
        for x in a:
            total += x
    return np.isfinite(total)


# _solve's argument types: the model's terms, the reference's arrays, offset and weights, then gains and flags
_SOLVE_ARGUMENTS = (_V, _T, _M, _T, _M, _V, _M, _V, _GOAL, _V, _V, _M)


@njit_on_first_call(types.Tuple((_CV, _CV, _CV, _F, _F, _B))(*_SOLVE_ARGUMENTS, *(_F,) * 8, *(_B,) * 4), **JIT_EXACT)
def _solve(
    qdot,
    rotation,
    position,
    jacobian,
    drift,
    com,
    centroidal,
    centroidal_drift,
    goal,
    offset,
    weights,
    inverse_weights,
    kp,
    kd,
    mass,
    com_stiffness,
    com_damping,
    self_motion_damping,
    posture_stiffness,
    singular_threshold,
    stabilize,
    saturate,
    has_posture,
    diagonal,
):  # pragma: no cover - compiled
    """``(qddot, com_acceleration, moment, residual, sigma_min, ok)`` of :meth:`BipedIkd.step` from the model's terms
    (rows: right sole, left sole, torso) and the checked reference.

    ``R`` (18 x nv) and ``r`` of (5.91) are the known rows (both soles, the torso's orientation, the CoM's height)
    and the CoM's x, y from the angular momentum theorem; ``qddot = W^-1 (R^T lambda - z)``, ``(R W^-1 R^T) lambda =
    -r + R W^-1 z``, ``z = -W qddot_pref`` (:func:`~redundancy_gym.controllers.clik.redundancy_resolution.resolve`):
    ``weights`` the diagonal of ``W`` if ``diagonal``, else ``inverse_weights`` is ``W^-1``. ``offset`` is the
    posture's difference from q (``has_posture``). Not ok (zeros) when ``sigma_min`` of ``R W^-1/2`` is below
    ``singular_threshold`` or the Cholesky factorization or the solution fails. ``stabilize``: apply (5.97) with
    ``plan``; ``saturate``: keep its ZMP in the ``support`` box.
    """
    feet_position, feet_rotation, feet_velocity, feet_acceleration, torso_rotation = goal[:5]
    torso_velocity, torso_acceleration, height, moment, plan, support = goal[5:]
    nv = qdot.shape[0]
    rows = 18
    r_mat = np.empty((rows, nv))
    r_vec = np.empty(rows)
    error = np.empty(3)
    # the known rows, stabilized (5.19): r = Jdot qdot - (wddot + K_D (wdot - J qdot) + K_P e)
    for i in range(3):
        first = 0 if i < 2 else 3
        if i < 2:
            rotation_error_into(feet_rotation[i], rotation[i], error)
        else:
            rotation_error_into(torso_rotation, rotation[2], error)
        for k in range(first, 6):
            row = 6 * i + k - first
            velocity = 0.0
            for c in range(nv):
                r_mat[row, c] = jacobian[i, k, c]
                velocity += jacobian[i, k, c] * qdot[c]
            if i < 2:
                e = feet_position[i, k] - position[i, k] if k < 3 else error[k - 3]
                acceleration = feet_acceleration[i, k] + kd * (feet_velocity[i, k] - velocity) + kp * e
            else:
                acceleration = torso_acceleration[k - 3] + kd * (torso_velocity[k - 3] - velocity) + kp * error[k - 3]
            r_vec[row] = drift[i, k] - acceleration
    # the CoM: J_c = A_G,lin / m, Jdot_c qdot = Adot_G,lin qdot / m
    m = mass
    com_velocity = np.zeros(3)
    drift_com = np.empty(3)
    j_com = np.empty((3, nv))
    for a in range(3):
        drift_com[a] = centroidal_drift[a] / m
        for c in range(nv):
            j_com[a, c] = centroidal[a, c] / m
            com_velocity[a] += j_com[a, c] * qdot[c]
    z_acceleration = height[2] + kd * (height[1] - com_velocity[2]) + kp * (height[0] - com[2])
    g = GRAVITY + z_acceleration  # numba folds the module's float into a constant
    mz = m * com[2]
    # (5.97): T += B [K_p (w_plan - w) + K_d (wdot_plan - wdot)], B = [[0, -m z_c], [m z_c, 0]], its ZMP kept in
    # the support box
    t_x, t_y = moment[0], moment[1]
    if stabilize:
        e_x = com_stiffness * (plan[0] - com[0]) + com_damping * (plan[2] - com_velocity[0])
        e_y = com_stiffness * (plan[1] - com[1]) + com_damping * (plan[3] - com_velocity[1])
        t_x, t_y = t_x + -mz * e_y, t_y + mz * e_x
        force = m * g
        if saturate and force > 0.0:  # np.clip(zmp, support[0], support[1])
            zmp_x = min(max(-t_y / force, support[0, 0]), support[1, 0])
            zmp_y = min(max(t_x / force, support[0, 1]), support[1, 1])
            t_x, t_y = force * zmp_y, force * -zmp_x
    moment_out = np.empty(2)
    moment_out[0], moment_out[1] = t_x, t_y
    # (5.88): c = Adot_L,xy qdot + (m y_c g - T_x, -m x_c g - T_y); (5.91) with B^-1 = [[0, 1], [-1, 0]] / (m z_c)
    c_x = centroidal_drift[3] + (m * com[1] * g - t_x)
    c_y = centroidal_drift[4] + (-m * com[0] * g - t_y)
    b_xy, b_yx = 1.0 / mz, -1.0 / mz
    for c in range(nv):
        r_mat[15, c] = j_com[2, c]
        r_mat[16, c] = j_com[0, c] + b_xy * centroidal[4, c]
        r_mat[17, c] = j_com[1, c] + b_yx * centroidal[3, c]
    r_vec[15] = drift_com[2] - z_acceleration
    r_vec[16] = drift_com[0] + b_xy * c_y
    r_vec[17] = drift_com[1] + b_yx * c_x
    # the weighted minimum of |qddot - qddot_pref|: z = -W qddot_pref, W^-1 z
    winv_z = np.empty(nv)
    for c in range(nv):
        preferred = -self_motion_damping * qdot[c]
        if has_posture:
            preferred = preferred - posture_stiffness * offset[c]
        if diagonal:
            winv_z[c] = -(weights[c] * preferred) / weights[c]
        else:
            winv_z[c] = -preferred
    winv_rt = np.empty((nv, rows))
    if diagonal:
        for c in range(nv):
            for i in range(rows):
                winv_rt[c, i] = r_mat[i, c] / weights[c]
    else:
        for c in range(nv):
            for i in range(rows):
                total = 0.0
                for d in range(nv):
                    total += inverse_weights[c, d] * r_mat[i, d]
                winv_rt[c, i] = total
    b_mat = np.empty((rows, rows))
    for i in range(rows):
        for j in range(i + 1):
            total = 0.0
            for c in range(nv):
                total += r_mat[i, c] * winv_rt[c, j]
            b_mat[i, j] = total
            b_mat[j, i] = total
    qddot = np.zeros(nv)
    com_acceleration = np.zeros(3)
    sigma = np.sqrt(max(np.linalg.eigvalsh(b_mat)[0], 0.0))
    ok = sigma >= singular_threshold
    factor = np.zeros((rows, rows))
    if ok:  # failing where LAPACK's Cholesky would (a pivot not > 0)
        ok = cholesky_factor(b_mat, rows, factor) > 0.0
    if ok:
        p = np.empty(rows)  # -r + R W^-1 z
        for i in range(rows):
            total = 0.0
            for c in range(nv):
                total += r_mat[i, c] * winv_z[c]
            p[i] = -r_vec[i] + total
        cholesky_solve(factor, rows, p)  # B lambda = p
        finite = 0.0
        for c in range(nv):
            total = 0.0
            for i in range(rows):
                total += winv_rt[c, i] * p[i]
            qddot[c] = total - winv_z[c]
            finite += qddot[c]
        ok = np.isfinite(finite) or np.all(np.isfinite(qddot))
    if not ok:
        qddot[:] = 0.0
        total = 0.0
        for i in range(rows):
            total += r_vec[i] * r_vec[i]
        return qddot, com_acceleration, moment_out, np.sqrt(total), sigma, False
    for a in range(3):
        total = 0.0
        for c in range(nv):
            total += j_com[a, c] * qddot[c]
        com_acceleration[a] = total + drift_com[a]
    residual = 0.0
    for i in range(rows):
        total = 0.0
        for c in range(nv):
            total += r_mat[i, c] * qddot[c]
        residual += (total + r_vec[i]) ** 2
    return qddot, com_acceleration, moment_out, np.sqrt(residual), sigma, True
