"""The IKD as the walking controller's joint trajectory generator (monograph fig. 5.25): the walking pattern's soles,
torso and ZMP in, joint positions out, with hybrid stabilization (via planning and via the contact moment)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numba import types
from numpy.typing import ArrayLike, NDArray

from ...constants import GRAVITY
from ...kernel_options import DEFAULT_BACKEND, JIT_EXACT, njit_on_first_call
from ...model import RobotModel
from ...validation import check_backend
from ..exceptions import ControllerError
from ..ikd.biped_ikd import BipedIkd, BipedIkdReference, BipedIkdResult
from ..ikd.compiled_biped_ikd import CompiledBipedIkd
from ..ikd.plan_stabilizer import PlanStabilizer
from ..objectives.objective import Objective

if TYPE_CHECKING:  # the walking package imports this module lazily (it would otherwise import itself)
    from .walking_pattern import PatternSample

__all__ = ["WalkingIkd", "WalkingIkdConfig", "WalkingIkdStep"]


@dataclass(frozen=True)
class WalkingIkdConfig:
    """Settings of :class:`WalkingIkd`.

    Attributes:
        moment_gain: ``k`` of the contact-moment stabilization (5.97): ``K_p = k 40 / dt``, ``K_d = 2 * 0.85
            sqrt(K_p)`` at the control period ``dt`` (the pendulum needs ``K_p > g / z_c``, about 10.8 [1/s^2]).
        planning: stabilization via planning on (:class:`PlanStabilizer`: the plan restarted from the IKD's CoM at
            every step's start, the ZMP modified in the coming double support); with ``moment_gain`` > 0 the
            hybrid of fig. 5.24.
        planning_ramp: share of the double support in each ramp of the planning's trapezoid.
        planning_max_shift: largest ZMP modification of the planning [m] per axis.
        stiffness, damping: drift compensation (5.19) of the known rows (soles, torso, CoM height) [1/s^2, 1/s].
        self_motion_damping: ``D`` of the preferred ``qddot = -D qdot - K (q - posture)`` in the nullspace [1/s].
        posture_stiffness: its ``K`` [1/s^2].
        support_margin: inset [m] of the support box that the stabilized moment's ZMP is saturated to.
        toe_length, heel_length, foot_half_width: the sole's extent from the sole point [m] (the support box).
        objective_gain: gain [1/s^2] of the nullspace objectives' gradients in the preferred acceleration.
        max_velocity: largest entry of the IKD's ``qdot`` [rad/s or m/s]; a faster one is scaled down (near a
            stretched knee the acceleration-level solution grows without bound, and an integrated blow-up would
            reach the servos).
    """

    moment_gain: float = 0.01
    planning: bool = True
    planning_ramp: float = 0.25
    planning_max_shift: float = 0.05
    stiffness: float = 400.0
    damping: float = 34.0
    self_motion_damping: float = 10.0
    posture_stiffness: float = 25.0
    support_margin: float = 0.01
    toe_length: float = 0.165
    heel_length: float = 0.095
    foot_half_width: float = 0.075
    max_velocity: float = 20.0
    objective_gain: float = 100.0

    def __post_init__(self) -> None:
        if not math.isfinite(self.max_velocity) or self.max_velocity <= 0.0:
            raise ControllerError(f"max_velocity must be finite and > 0 [rad/s], got {self.max_velocity!r}")
        for name in (
            "moment_gain",
            "planning_max_shift",
            "objective_gain",
            "stiffness",
            "damping",
            "self_motion_damping",
            "posture_stiffness",
            "support_margin",
            "toe_length",
            "heel_length",
            "foot_half_width",
        ):
            value = getattr(self, name)
            if not math.isfinite(value) or value < 0.0:
                raise ControllerError(f"{name} must be finite and >= 0, got {value!r}")
        if not 0.0 < self.planning_ramp <= 0.5:
            raise ControllerError(f"planning_ramp must lie in (0, 0.5], got {self.planning_ramp!r}")
        if self.support_margin >= min(self.foot_half_width, 0.5 * (self.toe_length + self.heel_length)):
            raise ControllerError(f"support_margin={self.support_margin!r} [m] leaves no support box")


class WalkingIkdStep(NamedTuple):
    """One period of :class:`WalkingIkd`.

    Attributes:
        q: the IKD's configuration at the period's end (pinocchio convention).
        qdot: its velocity at the period's end [m/s, rad/s].
        qddot: the IKD's acceleration over the period.
        com: the IKD's CoM at the period's start [m] (3).
        com_velocity: its velocity [m/s] (3).
        zmp: the ZMP [m] (x, y) of the contact moment the motion realizes, for its vertical force ``m (g +
            zddot_c)`` (the pattern's, plus both stabilizations' modifications, saturated to the support box):
            exact, no inverse dynamics needed.
        planned_zmp: the pattern's (ideal) ZMP [m].
        planning_shift: the planning's ZMP modification [m] (zero outside double support).
        moment: the realized contact moment ``(T_x, T_y)`` [N m] about the world origin.
        support: the support box ``((x_min, y_min), (x_max, y_max))`` [m] the ZMP was saturated to.
        lz: vertical angular momentum about the CoM [kg m^2/s] at the period's start.
        residual: ``|R qddot + r|`` of (5.91).
        sigma_min: smallest singular value of the task.
        success: False at a singular task (the IKD then holds its configuration and stops moving).
        limited: True when ``qdot`` was scaled down to ``max_velocity`` (tracking and the moment are then not exact).
    """

    q: NDArray[np.float64]
    qdot: NDArray[np.float64]
    qddot: NDArray[np.float64]
    com: NDArray[np.float64]
    com_velocity: NDArray[np.float64]
    zmp: NDArray[np.float64]
    planned_zmp: NDArray[np.float64]
    planning_shift: NDArray[np.float64]
    moment: NDArray[np.float64]
    support: NDArray[np.float64]
    lz: float
    residual: float
    sigma_min: float
    success: bool
    limited: bool = False


class WalkingIkd:
    """Joint trajectories from the walking pattern by the biped IKD (5.84)-(5.91): the soles, the torso and the CoM's
    height as the known task, the pattern's ZMP as the prescribed contact moment, the horizontal CoM whatever the
    whole body's dynamics make of it; integrated over each control period (semi-implicit Euler) on the IKD's own
    kinematic model, whose joint angles are the servo targets.

    The CoM is kept on the plan by the hybrid stabilization of monograph 5.5.3: :class:`PlanStabilizer` restarts
    the plan from the IKD's CoM at each double support's start and moves the ZMP in it, and the
    contact-moment feedback (5.97) (``moment_gain``) pulls towards the restarted plan in between. The modified
    moment's ZMP is saturated to the support box (the bounding box of the soles planned on the ground, inset by
    ``support_margin``), so the realized ZMP never leaves it.

    Double support: the IKD prescribes the total contact moment only (the task needs no more); the walking
    controller's measurement splits it between the feet by the pattern's ``right_load`` (the ZMP's place between
    the feet), as its stabilizer and ZMP estimate already do.

    The walking controller's balance feedback (its CoM offset ``delta``) moves the IKD's soles by ``-delta``
    instead of its CoM (which the IKD does not prescribe): the joint angles then put the CoM ``delta`` further from
    the soles, as the CLIK walker's do, while the moment and the plan stay in the pattern's frame.

    Args:
        model: the floating-base biped.
        dt: the control period [s] (also that of the gains of (5.97)).
        config: the settings.
        omega: ``sqrt(g / z_c)`` [1/s] of the pattern's LIPM.
        posture: the nullspace's posture (nq).
        feet_frames, torso_frame: the sole frames (right, left) and the torso's.
        objectives: nullspace objectives (the CLIK walker's joint limits and self-collision) for
            :class:`BipedIkd`.
        backend: ``"compiled"`` (:class:`CompiledBipedIkd`, the terms of each step from one kernel) or ``"python"``
            (:class:`BipedIkd` on pinocchio's passes), :data:`~redundancy_gym.kernel_options.BACKENDS`.
    """

    def __init__(
        self,
        model: RobotModel,
        dt: float,
        config: WalkingIkdConfig,
        *,
        omega: float,
        posture: ArrayLike,
        feet_frames: tuple[str, str] = ("r_sole", "l_sole"),
        torso_frame: str = "imu",
        objectives: Sequence[Objective] = (),
        backend: str = DEFAULT_BACKEND,
    ) -> None:
        twin = CompiledBipedIkd if check_backend("backend", backend, error=ControllerError) == "compiled" else BipedIkd
        if not math.isfinite(dt) or dt <= 0.0:
            raise ControllerError(f"dt must be finite and > 0 [s], got {dt!r}")
        self.model = model
        self.dt = float(dt)
        self.config = config
        self.ikd = twin(
            model,
            feet_frames=feet_frames,
            torso_frame=torso_frame,
            stiffness=config.stiffness,
            damping=config.damping,
            self_motion_damping=config.self_motion_damping,
            posture_stiffness=config.posture_stiffness,
            posture=posture,
            moment_gain=config.moment_gain,
            period=self.dt,
            objectives=objectives,
            objective_gain=config.objective_gain,
        )
        self.planner = PlanStabilizer(omega, ramp=config.planning_ramp, max_shift=config.planning_max_shift)
        self._mass = model.total_mass
        self.force = self._mass * GRAVITY
        self.q = model.check_configuration(posture)
        self.qdot = np.zeros(model.nv)
        self._step = -1
        # the fast step's reference rows, filled in place by one compiled call (_assemble) and read by the IKD's
        # step only (never returned): views of one buffer in BipedIkdReference's shapes (_buffer_views)
        self._buffer = np.zeros(_BUFFER_SIZE)
        self._views: tuple[NDArray[np.float64], ...] = ()

    def start(self, q: ArrayLike) -> None:
        """Begin at ``q`` at rest."""
        self.q = self.model.check_configuration(q)
        self.qdot = np.zeros(self.model.nv)
        self.planner.reset()
        self._step = -1

    def _support(self, sample: PatternSample, shift: NDArray[np.float64] | tuple[float, float]) -> NDArray[np.float64]:
        """The bounding box of the soles planned on the ground (moved by ``shift``), inset by the margin."""
        # plain float arithmetic, the corners as _support_general computes them (a sole without yaw: cos 1, sin 0,
        # whose products change no corner); non-finite inputs and no foot down take _support_general
        c = self.config
        feet, yaws, contact = sample.feet, sample.feet_yaw, sample.contact
        heel, toe, half = c.heel_length, c.toe_length, c.foot_half_width
        x_min = y_min = math.inf
        x_max = y_max = -math.inf
        down = False
        for i in range(2):
            if not contact[i]:
                continue
            down = True
            yaw = float(yaws[i])
            x, y = float(feet[i, 0] + shift[0]), float(feet[i, 1] + shift[1])
            if not math.isfinite(x + y + yaw):
                return self._support_general(sample, shift)
            if yaw == 0.0:
                x_min, x_max = min(x_min, x + -heel), max(x_max, x + toe)
                y_min, y_max = min(y_min, y + -half), max(y_max, y + half)
                continue
            cz, sz = math.cos(yaw), math.sin(yaw)
            for along in (-heel, toe):
                for across in (-half, half):
                    px, py = x + cz * along - sz * across, y + sz * along + cz * across
                    x_min, x_max = min(x_min, px), max(x_max, px)
                    y_min, y_max = min(y_min, py), max(y_max, py)
        if not down:
            return self._support_general(sample, shift)
        m = c.support_margin
        return np.array([[x_min + m, y_min + m], [x_max - m, y_max - m]])

    def _support_general(
        self, sample: PatternSample, shift: NDArray[np.float64] | tuple[float, float]
    ) -> NDArray[np.float64]:
        """:meth:`_support` on arrays (any inputs; NaN propagates, no foot down raises NumPy's error)."""
        c = self.config
        corners = []
        for i in range(2):
            if not sample.contact[i]:
                continue
            yaw = float(sample.feet_yaw[i])
            cz, sz = math.cos(yaw), math.sin(yaw)
            x, y = float(sample.feet[i, 0] + shift[0]), float(sample.feet[i, 1] + shift[1])
            for along in (-c.heel_length, c.toe_length):
                for across in (-c.foot_half_width, c.foot_half_width):
                    corners.append((x + cz * along - sz * across, y + sz * along + cz * across))
        points = np.array(corners)
        return np.array([points.min(axis=0) + c.support_margin, points.max(axis=0) - c.support_margin])

    def step(
        self,
        start: PatternSample,
        start_reference: NDArray[np.float64],
        end_reference: NDArray[np.float64],
        double_support: tuple[float, float] | None,
        feet_shift: ArrayLike = (0.0, 0.0),
        feet_shift_rate: ArrayLike = (0.0, 0.0),
        zmp: ArrayLike | None = None,
    ) -> WalkingIkdStep:
        """One control period from ``start`` (the pattern at the period's start).

        Args:
            start: the pattern sample at the period's start (its ZMP, CoM plan, contacts, step).
            start_reference, end_reference: the packed whole-body references at the period's start and end
                (:data:`~redundancy_gym.controllers.walking.whole_body_kernels.REFERENCE_LAYOUT`; their soles and
                torso, with velocities; the CoM entries are not used).
            double_support: ``(t_0, t_1)`` [s] of the current step's double support (None during the start).
            feet_shift, feet_shift_rate: the balance feedback's CoM offset [m] and its rate [m/s] (x, y), applied
                to the soles with the opposite sign.
            zmp: the ZMP [m] to prescribe (None: ``start.zmp``): a pattern planned with a multi-body correction
                gives its reference ZMP here (:meth:`~redundancy_gym.controllers.walking.WalkingPattern.reference_zmp`),
                its CoM the plan that this ZMP needs.
        """
        # the common inputs (packed float64 references, a float pair or float64 (2,) shifts, a float64 (2,) ZMP)
        # take one compiled assembly of the IKD's reference and one of the result; others _step_general
        if not (
            _is_float_array(start_reference, _REFERENCE_SHAPE) and _is_float_array(end_reference, _REFERENCE_SHAPE)
        ):
            return self._step_general(
                start, start_reference, end_reference, double_support, feet_shift, feet_shift_rate, zmp
            )
        shift = _pair(feet_shift)
        rate = _pair(feet_shift_rate)
        ideal = np.asarray(start.zmp if zmp is None else zmp, dtype=np.float64)
        if shift is None or rate is None or ideal.shape != (2,):
            return self._step_general(
                start, start_reference, end_reference, double_support, feet_shift, feet_shift_rate, zmp
            )
        dt, c = self.dt, self.config
        shift_x, shift_y = -shift[0], -shift[1]
        t = float(start.time)
        self._replan_at_new_step(start, t, double_support)
        com, com_velocity = start.com, start.com_velocity
        plan_x, plan_y = float(com[0]), float(com[1])
        plan_xdot, plan_ydot = float(com_velocity[0]), float(com_velocity[1])
        zmp_x, zmp_y = ideal.tolist()
        if c.planning:
            planning_x, planning_y, offset_x, offset_y, offset_rate_x, offset_rate_y = self.planner._advance(t, dt)
            zmp_x, zmp_y = zmp_x + planning_x, zmp_y + planning_y
            plan_x, plan_y = plan_x + offset_x, plan_y + offset_y
            plan_xdot, plan_ydot = plan_xdot + offset_rate_x, plan_ydot + offset_rate_y
            planning_shift = np.array([planning_x, planning_y])
        else:
            planning_shift = np.zeros(2)
        support = self._support(start, (shift_x, shift_y))
        force = self.force
        _assemble(
            start_reference,
            end_reference,
            shift_x,
            shift_y,
            -rate[0],
            -rate[1],
            dt,
            float(com[2]),
            force * zmp_y,
            force * -zmp_x,
            plan_x,
            plan_y,
            plan_xdot,
            plan_ydot,
            self._buffer,
        )
        views = self._views
        if not views or views[0].base is not self._buffer:  # first use, or a copy's views (copies, not views)
            views = self._views = _buffer_views(self._buffer)
        # the views are BipedIkdReference's arrays in its order up to the CoM plan
        reference = BipedIkdReference._make((*views[:-1], views[-1] if c.moment_gain > 0.0 else None, support))
        result = self.ikd.step(self.q, self.qdot, reference)
        terms = self.ikd.terms
        assert terms is not None
        com_velocity, lz, realized, qdot, limited = _finish(
            terms.centroidal,
            self.qdot,
            result.qddot,
            result.com_acceleration,
            result.moment,
            dt,
            self._mass,
            c.max_velocity,
            force,
            result.success,
        )
        self.qdot = qdot
        if result.success:
            self.q = self.ikd.integrate(self.q, qdot, dt)
        return self._period(result, terms.com, com_velocity, realized, ideal, planning_shift, support, lz, limited)

    def _replan_at_new_step(self, start: PatternSample, t: float, double_support: tuple[float, float] | None) -> None:
        """:meth:`_replan` once per step, at the first period of its double support (planning on)."""
        if (
            self.config.planning
            and double_support is not None
            and start.step >= 0
            and start.step != self._step
            and t >= double_support[0] - 0.5 * self.dt
        ):
            self._replan(start, t, double_support)

    def _replan(self, start: PatternSample, t: float, double_support: tuple[float, float]) -> None:
        """Restart the plan from the IKD's CoM at the double support's start (once per step)."""
        model = self.model
        self._step = start.step
        model.update(self.q)
        com, centroidal = model.com_and_centroidal_matrix()
        com_velocity = centroidal[:2] @ self.qdot / model.total_mass
        self.planner.replan(t, com[:2] - start.com[:2], com_velocity - start.com_velocity[:2], double_support)

    def _step_general(
        self,
        start: PatternSample,
        start_reference: NDArray[np.float64],
        end_reference: NDArray[np.float64],
        double_support: tuple[float, float] | None,
        feet_shift: ArrayLike,
        feet_shift_rate: ArrayLike,
        zmp: ArrayLike | None,
    ) -> WalkingIkdStep:
        """:meth:`step` for any inputs, on NumPy arrays (the fast path's arithmetic, entry by entry)."""
        dt, model, c = self.dt, self.model, self.config
        shift = -np.asarray(feet_shift, dtype=np.float64)
        shift_rate = -np.asarray(feet_shift_rate, dtype=np.float64)
        ref, ahead = start_reference, end_reference
        position = ref[6:12].reshape(2, 3).copy()
        position[:, :2] += shift
        velocity = ref[30:42].reshape(2, 6).copy()
        velocity[:, :2] += shift_rate
        acceleration = (ahead[30:42] - ref[30:42]).reshape(2, 6) / dt
        torso_rotation = ref[42:51].reshape(3, 3)
        torso_rate = ref[51:54]
        torso_acceleration = (ahead[51:54] - torso_rate) / dt
        t = float(start.time)
        self._replan_at_new_step(start, t, double_support)
        planned = self.planner.advance(t, dt) if c.planning else None
        ideal = np.asarray(start.zmp if zmp is None else zmp, dtype=np.float64)
        zmp = ideal + (planned.zmp_shift if planned is not None else 0.0)
        com_plan = np.concatenate([start.com[:2], start.com_velocity[:2]])
        if planned is not None:
            com_plan += np.concatenate([planned.com_offset, planned.com_offset_rate])
        support = self._support(start, shift)
        moment = self.force * np.array([zmp[1], -zmp[0]])
        reference = BipedIkdReference(
            position,
            ref[12:30].reshape(2, 3, 3),
            velocity,
            acceleration,
            torso_rotation,
            torso_rate,
            torso_acceleration,
            np.array([float(start.com[2]), 0.0, 0.0]),
            moment,
            com_plan if c.moment_gain > 0.0 else None,
            support,
        )
        result = self.ikd.step(self.q, self.qdot, reference)
        terms = self.ikd.terms
        assert terms is not None
        com, centroidal = terms.com, terms.centroidal
        com_velocity = centroidal[:3] @ self.qdot / model.total_mass
        lz = float(centroidal[5] @ self.qdot)
        # the vertical contact force of the motion, m (g + zddot_c): the saturation's (the CoM's height is stabilized)
        force = model.total_mass * (GRAVITY + float(result.com_acceleration[2])) if result.success else self.force
        realized = np.array([-result.moment[1], result.moment[0]]) / force
        limited = False
        if result.success:
            self.qdot = self.qdot + dt * result.qddot
            fastest = float(np.max(np.abs(self.qdot)))
            if not fastest <= c.max_velocity:  # NaN included
                limited = True
                self.qdot = self.qdot * (c.max_velocity / fastest) if math.isfinite(fastest) else np.zeros(model.nv)
            self.q = self.ikd.integrate(self.q, self.qdot, dt)
        else:  # a singular task: hold still rather than integrate zeros into a moving state
            self.qdot = np.zeros(model.nv)
        planning_shift = planned.zmp_shift if planned is not None else np.zeros(2)
        return self._period(result, com, com_velocity, realized, ideal, planning_shift, support, lz, limited)

    def _period(
        self,
        result: BipedIkdResult,
        com: NDArray[np.float64],
        com_velocity: NDArray[np.float64],
        realized: NDArray[np.float64],
        ideal: NDArray[np.float64],
        planning_shift: NDArray[np.float64],
        support: NDArray[np.float64],
        lz: float,
        limited: bool,
    ) -> WalkingIkdStep:
        """The period's :class:`WalkingIkdStep`: the state the step left (``q``, ``qdot``), the IKD's ``result``
        and the period's CoM (at its start), realized and ideal ZMP [m], planning shift [m], support box and
        ``L_z`` [kg m^2/s]."""
        return WalkingIkdStep(
            self.q.copy(),
            self.qdot.copy(),
            result.qddot,
            com,
            com_velocity,
            realized,
            ideal.copy(),
            planning_shift,
            result.moment,
            support,
            lz,
            result.residual,
            result.sigma_min,
            result.success,
            limited,
        )


_FLOAT64 = np.dtype(np.float64)
_REFERENCE_SHAPE = (54,)  # whole_body_kernels.REFERENCE_SIZE
# the fast step's buffer: feet position (2, 3), rotation (2, 3, 3), velocity (2, 6), acceleration (2, 6), torso
# rotation (3, 3), rate (3), acceleration (3), CoM height (3), moment (2), CoM plan (4)
_BUFFER_SIZE = 72


def _buffer_views(b: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """The reference rows in ``b`` (:data:`_BUFFER_SIZE`), in BipedIkdReference's order, then the CoM plan."""
    return (
        b[0:6].reshape(2, 3),
        b[6:24].reshape(2, 3, 3),
        b[24:36].reshape(2, 6),
        b[36:48].reshape(2, 6),
        b[48:57].reshape(3, 3),
        b[57:60],
        b[60:63],
        b[63:66],
        b[66:68],
        b[68:72],
    )


def _is_float_array(value: object, shape: tuple[int, ...]) -> bool:
    return type(value) is np.ndarray and value.dtype == _FLOAT64 and value.shape == shape


def _pair(value: object) -> tuple[float, float] | None:
    """``value`` as two floats where it is a float64 array of shape (2,) or a tuple of two floats or ints (as
    ``np.asarray(value, dtype=np.float64)`` gives them), else None."""
    if type(value) is np.ndarray:
        if value.dtype == _FLOAT64 and value.shape == (2,):
            x, y = value.tolist()
            return x, y
        return None
    if type(value) is tuple and len(value) == 2 and all([type(v) is float or type(v) is int for v in value]):
        return float(value[0]), float(value[1])
    return None


_V = types.Array(types.float64, 1, "A", readonly=True)
_M = types.Array(types.float64, 2, "A", readonly=True)
_CV = types.Array(types.float64, 1, "C")
_F, _B = types.float64, types.boolean


@njit_on_first_call(types.void(_V, _V, _F, _F, _F, _F, _F, _F, _F, _F, _F, _F, _F, _F, _CV), **JIT_EXACT)
def _assemble(
    ref,
    ahead,
    shift_x,
    shift_y,
    rate_x,
    rate_y,
    dt,
    com_z,
    moment_x,
    moment_y,
    plan_x,
    plan_y,
    plan_xdot,
    plan_ydot,
    buffer,
):  # pragma: no cover - compiled
    """The IKD's reference of one period into ``buffer`` (:data:`_BUFFER_SIZE`), as :meth:`WalkingIkd._step_general`
    builds it from the packed references (REFERENCE_LAYOUT): the soles moved by the shift and its rate, the
    accelerations as the references' difference over ``dt``."""
    for i in range(2):
        for k in range(3):
            buffer[3 * i + k] = ref[6 + 3 * i + k]
        buffer[3 * i] += shift_x
        buffer[3 * i + 1] += shift_y
        for k in range(6):
            buffer[24 + 6 * i + k] = ref[30 + 6 * i + k]
            buffer[36 + 6 * i + k] = (ahead[30 + 6 * i + k] - ref[30 + 6 * i + k]) / dt
        buffer[24 + 6 * i] += rate_x
        buffer[24 + 6 * i + 1] += rate_y
    for k in range(18):
        buffer[6 + k] = ref[12 + k]
    for k in range(9):
        buffer[48 + k] = ref[42 + k]
    for k in range(3):
        buffer[57 + k] = ref[51 + k]
        buffer[60 + k] = (ahead[51 + k] - ref[51 + k]) / dt
    buffer[63], buffer[64], buffer[65] = com_z, 0.0, 0.0
    buffer[66], buffer[67] = moment_x, moment_y
    buffer[68], buffer[69], buffer[70], buffer[71] = plan_x, plan_y, plan_xdot, plan_ydot


@njit_on_first_call(types.Tuple((_CV, _F, _CV, _CV, _B))(_M, _V, _V, _V, _V, _F, _F, _F, _F, _B), **JIT_EXACT)
def _finish(
    centroidal, qdot, qddot, com_acceleration, moment, dt, mass, max_velocity, hold_force, success
):  # pragma: no cover - compiled
    """``(com_velocity, lz, zmp, qdot_next, limited)`` of :meth:`WalkingIkd._step_general` after the IKD: the CoM's
    velocity and ``L_z`` at the period's start, the realized ZMP (for ``m (g + zddot_c)``, or ``hold_force`` at a
    failed step), the velocity at its end bounded by ``max_velocity`` (zeros at a failed step)."""
    nv = qdot.shape[0]
    com_velocity = np.empty(3)
    for a in range(3):
        total = 0.0
        for c in range(nv):
            total += centroidal[a, c] * qdot[c]
        com_velocity[a] = total / mass
    lz = 0.0
    for c in range(nv):
        lz += centroidal[5, c] * qdot[c]
    force = mass * (GRAVITY + com_acceleration[2]) if success else hold_force
    zmp = np.empty(2)
    zmp[0], zmp[1] = -moment[1] / force, moment[0] / force
    following = np.zeros(nv)
    limited = False
    if success:
        fastest = 0.0
        for c in range(nv):
            following[c] = qdot[c] + dt * qddot[c]
            size = abs(following[c])
            if size > fastest or size != size:  # np.max's: a NaN wins (no size is > NaN)
                fastest = size
        if not fastest <= max_velocity:  # NaN included
            limited = True
            if np.isfinite(fastest):
                scale = max_velocity / fastest
                for c in range(nv):
                    following[c] = following[c] * scale
            else:
                following[:] = 0.0
    return com_velocity, lz, zmp, following, limited
