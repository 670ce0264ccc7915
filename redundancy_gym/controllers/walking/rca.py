"""RCA: reactive 3D collision avoidance of the swing leg in task space (monograph 5.4.2, (5.75)-(5.83)).

The second, reactive layer of obstacle avoidance. The swing foot's position reference ``w_d0`` (from the walking
pattern, after SSTA) is modified to ``w_d1 = w_d0 + w_col``; ``w_col`` moves at

``wdot_col = -[(S_F J_w)^#]^T (dH_col/dq + dH_limit/dq)^T - s_att w_col``      (5.80), (5.82), (5.83)

where ``H_col`` is the swept-sphere potential (5.58) between the swing leg's volumes and the obstacles,
``H_limit`` the joint-limit potential of the swing leg, and the attractor ``s_att / 2 |w_col|^2`` (5.82) pulls
towards the nominal trajectory. The pseudoinverse is not formed: ``(S_F J)^#^T g = (J_F J_F^T)^-1 J_F g`` is one
3 x 3 Cholesky solve (algorithm 10). The distance Jacobians of swept-sphere volumes jump where the witness
points jump; as the monograph does, the modification's rate is temporally filtered (first order) instead.

Before touchdown the potentials are switched off and ``w_col`` returns to zero along a quintic from its
position, velocity and acceleration (C2), short enough not to overshoot zero; the foothold and the touchdown
time are kept exactly.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...geometry import SSV, CollisionModel, Segment
from ...model import RobotModel, box_volumes, collision_geometry_from_mjcf
from ...validation import check_real
from ..exceptions import ControllerError
from ..objectives.actuated_objective import ActuatedObjective
from ..objectives.collision_objective import CollisionObjective
from ..objectives.joint_limit_objective import JointLimitObjective

__all__ = ["LEG_SEGMENTS", "SOLE_GEOMS", "Rca", "RcaConfig", "RcaState", "return_quintic_no_overshoot_time"]

LEG_SEGMENTS = (("r_thigh", "r_shank", "r_foot", "r_toe"), ("l_thigh", "l_shank", "l_foot", "l_toe"))
"""The collision segments of the right and left leg (body names of the biped's MJCF) that RCA keeps off
obstacles while the leg swings."""
SOLE_GEOMS = ("r_sole_geom", "r_toe_sole_geom", "l_sole_geom", "l_toe_sole_geom")
"""The biped's sole boxes (contact geoms, 0.26 x 0.15 m), which RCA adds to their leg segments as swept-sphere covers
(:func:`~redundancy_gym.model.box_volumes`): the foot's capsule (r 45 mm) and the toe's sphere (r 35 mm) leave the
sole's sides 30-40 mm uncovered, and a sole touched boxes that those volumes kept 40-75 mm off."""

# the basis of a quintic from (w0, v0, a0) at tau = 0 to rest at zero at tau = 1 (tau = s / T):
# w = w0 sigma + v0 T psi + a0 T^2 chi, each basis function >= 0 on [0, 1]; psi / sigma <= 0.4 and
# chi / sigma <= 0.05 there (both largest at tau = 1), which bounds the return time that cannot overshoot
_PSI_OVER_SIGMA = 0.4
_CHI_OVER_SIGMA = 0.05


def return_quintic_no_overshoot_time(w0: float, v0: float, a0: float) -> float:
    """The longest return time [s] of the quintic from ``(w0, v0, a0)`` to rest at 0 that cannot cross zero
    (infinite when the velocity and acceleration do not point towards zero).

    With ``w0 > 0`` the quintic is ``w0 sigma + v0 T psi + a0 T^2 chi``; it stays >= 0 when
    ``w0 + 0.4 T min(v0, 0) + 0.05 T^2 min(a0, 0) >= 0`` (the basis ratios' bounds), solved here for ``T``.
    """
    if w0 == 0.0:
        return float("inf") if v0 == 0.0 and a0 == 0.0 else 0.0
    sign = 1.0 if w0 > 0.0 else -1.0
    w, v, a = abs(w0), min(sign * v0, 0.0), min(sign * a0, 0.0)
    b, c = _PSI_OVER_SIGMA * -v, _CHI_OVER_SIGMA * -a
    if b == 0.0 and c == 0.0:
        return float("inf")
    if c == 0.0:
        return w / b
    return (-b + np.sqrt(b * b + 4.0 * c * w)) / (2.0 * c)


@dataclass(frozen=True)
class RcaConfig:
    """Gains and timing of :class:`Rca`.

    Attributes:
        activation_distance: ``d_a`` [m] of the collision potential (5.58): obstacles farther from the swing leg
            do not act.
        slope: ``|H'(0)|`` [1/m] of the collision potential at contact.
        weight: scale of the collision potential: the modification's speed at contact, for a witness point on
            the foot, is about ``weight * slope`` [m/s].
        joint_limit_weight: scale of the swing leg's joint-limit potential in task space (the ``H_limit`` of (5.83);
            0: off, the default). The whole-body IK keeps the joint limits in its nullspace already; in task space
            the potential drags a foot stepping high over a box down and back towards it (a knee and hip near their
            flexion limits): at 0.5 it made 4 of 12 random courses touch a box top, at 0 none.
        joint_limit_activation: its ``d_a`` [rad].
        attractor: ``s_att`` [1/s] of (5.82).
        filter_time: time constant [s] of the first-order filter on the modification's rate.
        max_speed: largest modification speed [m/s].
        max_offset: largest modification [m] (each axis).
        return_time: the potentials switch off this long [s] before touchdown; the modification then returns to
            zero (sooner where a return this long would overshoot).
        min_return_time: the shortest return [s] (bounds its acceleration).
        gate: obstacles farther than this [m] (horizontally, from the swing foot's reference to their bounding
            box) are not evaluated: the distance computation is skipped while none is near.
    """

    activation_distance: float = 0.08
    slope: float = 10.0
    weight: float = 0.1
    joint_limit_weight: float = 0.0
    joint_limit_activation: float = 0.05
    attractor: float = 4.0
    filter_time: float = 0.02
    max_speed: float = 1.5
    max_offset: float = 0.15
    return_time: float = 0.15
    min_return_time: float = 0.06
    gate: float = 0.45

    def __post_init__(self) -> None:
        positive = ("activation_distance", "slope", "filter_time", "max_speed", "min_return_time")
        for f in fields(self):
            check_real(f.name, getattr(self, f.name), low=0.0, low_open=f.name in positive, error=ControllerError)
        if self.min_return_time > self.return_time:
            raise ControllerError("min_return_time must not exceed return_time")


class RcaState(NamedTuple):
    """The swing-foot modification after one :meth:`Rca.update`.

    Attributes:
        offset: ``w_col`` [m] (world x, y, z), added to the swing foot's position reference.
        velocity: its rate [m/s], added to the swing foot's velocity reference.
        acceleration: its second derivative [m/s^2].
        distance: smallest swept-sphere distance [m] between the swing leg and the obstacles in the kinematic
            model (inf when none was evaluated).
        active: the potentials acted this period (False: idle, or returning to the nominal).
        returning: the modification is on its return to zero before touchdown.
    """

    offset: NDArray[np.float64]
    velocity: NDArray[np.float64]
    acceleration: NDArray[np.float64]
    distance: float
    active: bool
    returning: bool


_ZERO = np.zeros(3)
_IDLE = RcaState(np.zeros(3), np.zeros(3), np.zeros(3), float("inf"), False, False)  # never written to
_IDLE.offset.flags.writeable = False
_IDLE.velocity.flags.writeable = False
_IDLE.acceleration.flags.writeable = False


class Rca:
    """Reactive swing-foot collision avoidance (5.80)-(5.83) for one robot and a set of obstacle volumes.

    Args:
        model: the floating-base model whose kinematics the whole-body IK integrates.
        soft_lower, soft_upper: the actuated joints' limits [rad] for the joint-limit potential.
        config: gains and timing.
        feet_frames: the sole frames (right, left): the swing foot's task coordinates ``w_F``.
        legs: collision segment names of the right and left leg (:data:`LEG_SEGMENTS`).
        sole_geoms: box geoms of the MJCF added to the legs' segments they move with, each as two TSS
            (:data:`SOLE_GEOMS`; ``()``: the segments' own volumes only). Obstacle avoidance only: the IK's
            self-collision model keeps the MJCF's volumes (the feet pass each other 30 mm apart by design).
    """

    def __init__(
        self,
        model: RobotModel,
        soft_lower: ArrayLike,
        soft_upper: ArrayLike,
        config: RcaConfig | None = None,
        *,
        feet_frames: tuple[str, str] = ("r_sole", "l_sole"),
        legs: tuple[tuple[str, ...], tuple[str, ...]] = LEG_SEGMENTS,
        sole_geoms: tuple[str, ...] = SOLE_GEOMS,
    ) -> None:
        self.model = model
        self.config = config or RcaConfig()
        self.feet_frames = feet_frames
        geometry = collision_geometry_from_mjcf(model)
        by_name = {s.name: s for s in geometry.robot}
        missing = [n for leg in legs for n in leg if n not in by_name]
        if missing:
            raise ControllerError(f"legs name unknown segments {missing}; the model has {sorted(by_name)}")
        covers = box_volumes(model, sole_geoms) if sole_geoms else {}
        foreign = sorted(set(covers) - {n for leg in legs for n in leg})
        if foreign:
            raise ControllerError(f"sole_geoms move with segments {foreign} that are not in legs {legs}")
        self._legs = tuple(
            tuple(
                Segment(n, by_name[n].volumes + covers[n], by_name[n].frame) if n in covers else by_name[n] for n in leg
            )
            for leg in legs
        )
        c = self.config
        lower, upper = np.asarray(soft_lower, dtype=np.float64), np.asarray(soft_upper, dtype=np.float64)
        self._limits = None
        if c.joint_limit_weight > 0.0:
            self._limits = ActuatedObjective(
                JointLimitObjective(
                    lower, upper, activation_distance=c.joint_limit_activation, slope=2.0, weight=c.joint_limit_weight
                ),
                model,
            )
        # the joint-limit gradient acts through the swing leg's joints only: the stance leg's limits are the IK's
        names = model.joint_names
        self._leg_columns = []
        nq, nv = model.base_dofs
        for side in ("r_", "l_"):
            mask = np.zeros(model.nv, dtype=bool)
            for i, name in enumerate(names[len(names) - (model.nv - nv) :]):
                if name.startswith(side) and "shoulder" not in name and "elbow" not in name:
                    mask[nv + i] = True
            self._leg_columns.append(mask)
        self._models: tuple[CollisionObjective, CollisionObjective] | None = None
        self._volumes: list[SSV] = []
        self._frame: tuple[NDArray[np.float64], NDArray[np.float64]] = (np.eye(3), np.zeros(3))
        self._lower = np.zeros((0, 3))
        self._upper = np.zeros((0, 3))
        self.reset()

    def reset(self) -> None:
        """Forget the modification (a new walk)."""
        self._w = np.zeros(3)
        self._v = np.zeros(3)
        self._a = np.zeros(3)
        self._return: tuple[float, float, NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]] | None = None
        self._step: int | None = None

    def set_obstacles(self, volumes: Sequence[SSV]) -> None:
        """The obstacle volumes the swing legs keep off (in the frame of :meth:`set_frame`, identity at first)."""
        volumes = list(volumes)
        self._volumes = volumes
        self._frame = (np.eye(3), np.zeros(3))
        if not volumes:
            self._models = None
            self._lower = np.zeros((0, 3))
            self._upper = np.zeros((0, 3))
            return
        environment = [Segment(f"obstacle_{i}", (v,)) for i, v in enumerate(volumes)]
        c = self.config
        self._models = tuple(  # type: ignore[assignment]
            CollisionObjective(
                CollisionModel(leg, environment, self_collision=False),
                activation_distance=c.activation_distance,
                slope=c.slope,
                weight=c.weight,
            )
            for leg in self._legs
        )
        self._bounds()

    def set_frame(self, rotation: ArrayLike, translation: ArrayLike) -> None:
        """Place the obstacles by ``x -> R x + p`` from the coordinates they were given in (the controller's map
        from the world into its plan's frame); the collision models move their volumes, nothing is rebuilt."""
        rotation, translation = np.asarray(rotation, dtype=np.float64), np.asarray(translation, dtype=np.float64)
        self._frame = (rotation, translation)
        if self._models is None:
            return
        for objective in self._models:
            for segment in objective.collision_model.environment:
                objective.collision_model.set_environment_placement(segment.name, rotation, translation)
        self._bounds()

    def _bounds(self) -> None:
        """The placed volumes' bounding boxes, for the gate."""
        rotation, translation = self._frame
        placed = [v.transformed(rotation, translation) for v in self._volumes]
        self._lower = np.array([v.points.min(axis=0) - v.radius for v in placed])
        self._upper = np.array([v.points.max(axis=0) + v.radius for v in placed])

    @property
    def state(self) -> RcaState:
        """The current modification (without a distance)."""
        if self._return is None and not self._w.any() and not self._v.any():
            return _IDLE
        return RcaState(self._w.copy(), self._v.copy(), self._a.copy(), float("inf"), False, self._return is not None)

    def _near(self, foot: NDArray[np.float64]) -> bool:
        if self._models is None:
            return False
        gap = np.maximum(np.maximum(self._lower[:, :2] - foot[:2], foot[:2] - self._upper[:, :2]), 0.0)
        return bool(np.any(np.hypot(gap[:, 0], gap[:, 1]) < self.config.gate))

    def modification_rate(self, q: NDArray[np.float64], side: int) -> tuple[NDArray[np.float64], float]:
        """``-[(S_F J_w)^#]^T (dH/dq)^T`` (5.80) of the swing leg ``side`` at ``q`` (the model updated to ``q``),
        and the smallest leg-obstacle distance [m]."""
        assert self._models is not None
        objective = self._models[side]
        gradient = objective.evaluate(self.model, q).gradient
        state = objective.last_state
        distance = float(np.min(state.distance)) if state is not None and state.distance.size else float("inf")
        if self._limits is not None:
            gradient = gradient + np.where(self._leg_columns[side], self._limits.evaluate(self.model, q).gradient, 0.0)
        if not np.any(gradient):
            return np.zeros(3), distance
        jacobian = self.model.frame_jacobian(self.feet_frames[side], "translational")
        # (J J^T)^-1 J g: the transpose of the least-squares map applied to the gradient (algorithm 10: Cholesky)
        gram = jacobian @ jacobian.T
        chol = np.linalg.cholesky(gram + 1e-9 * np.eye(3))
        rate = -np.linalg.solve(chol.T, np.linalg.solve(chol, jacobian @ gradient))
        return rate, distance

    def update(
        self,
        q: NDArray[np.float64],
        side: int,
        step: int,
        remaining: float,
        dt: float,
        foot: NDArray[np.float64],
        ground: float,
    ) -> RcaState:
        """Advance the modification of swing foot ``side`` (0 right, 1 left) by one period ``dt`` [s].

        Args:
            q: the kinematic model's configuration (the IK's ``q``).
            side: the swinging foot; ``step`` the pattern's step index (a new step starts from zero).
            remaining: single support left [s] (touchdown at 0); <= 0 in double support.
            dt: control period [s].
            foot: the swing foot's (unmodified) position reference [m], for the gate and the floor.
            ground: the ground height [m]: the modified foot never goes below the reference's height above it.
        """
        c = self.config
        if remaining <= 0.0:  # double support: the modification returned to zero before touchdown
            self.reset()
            return self.state
        if step != self._step:  # a new swing starts from the nominal
            self.reset()
            self._step = step
        if remaining <= c.return_time + 1e-12 or self._return is not None:
            return self._returning(remaining, dt)
        near = self._near(foot)
        if not near and not self._w.any() and not self._v.any():
            self._a = _ZERO.copy()
            return _IDLE  # nothing near and nothing to return from: the common case, without the arithmetic
        distance = float("inf")
        target = -c.attractor * self._w
        if near:
            self.model.update(q)
            rate, distance = self.modification_rate(q, side)
            target = target + rate
        speed = float(np.linalg.norm(target))
        if speed > c.max_speed:
            target *= c.max_speed / speed
        # first-order filter on the rate: the witness points of swept spheres jump (5.2.1)
        blend = dt / (c.filter_time + dt)
        v = self._v + blend * (target - self._v)
        w = self._w + dt * v
        w = np.clip(w, -c.max_offset, c.max_offset)
        w[2] = max(w[2], -(float(foot[2]) - ground))  # never below the nominal's height above the floor
        v = (w - self._w) / dt
        self._a = (v - self._v) / dt
        self._w, self._v = w, v
        return RcaState(w.copy(), v.copy(), self._a.copy(), distance, bool(np.isfinite(distance)), False)

    def _returning(self, remaining: float, dt: float) -> RcaState:
        """The quintic back to zero (C2 from the current state), ending at most ``remaining`` from now."""
        c = self.config
        if self._return is None:
            horizon = max(remaining - dt, dt)
            limit = min(
                return_quintic_no_overshoot_time(float(w), float(v), float(a))
                for w, v, a in zip(self._w, self._v, self._a, strict=False)
            )
            duration = min(horizon, max(limit, c.min_return_time))
            self._return = (0.0, duration, self._w.copy(), self._v.copy(), self._a.copy())
        elapsed, duration, w0, v0, a0 = self._return
        elapsed += dt
        self._return = (elapsed, duration, w0, v0, a0)
        tau = min(elapsed / duration, 1.0)
        sigma = 1.0 - tau**3 * (10.0 - 15.0 * tau + 6.0 * tau * tau)
        psi = tau * (1.0 - tau) ** 3 * (1.0 + 3.0 * tau)
        chi = 0.5 * tau * tau * (1.0 - tau) ** 3
        # derivatives with respect to tau
        d_sigma = -30.0 * tau * tau * (1.0 - tau) ** 2
        d_psi = (1.0 - tau) ** 2 * (1.0 + 2.0 * tau - 15.0 * tau * tau)
        d_chi = tau * (1.0 - tau) ** 2 * (1.0 - 2.5 * tau)
        dd_sigma = -60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau)
        dd_psi = -12.0 * tau * (1.0 - tau) * (3.0 - 5.0 * tau)
        dd_chi = (1.0 - tau) * (1.0 - 8.0 * tau + 10.0 * tau * tau)
        T = duration
        self._w = w0 * sigma + v0 * T * psi + a0 * T * T * chi
        self._v = (w0 * d_sigma + v0 * T * d_psi + a0 * T * T * d_chi) / T
        self._a = (w0 * dd_sigma + v0 * T * dd_psi + a0 * T * T * dd_chi) / (T * T)
        if tau >= 1.0:
            self._w, self._v, self._a = np.zeros(3), np.zeros(3), np.zeros(3)
        return RcaState(self._w.copy(), self._v.copy(), self._a.copy(), float("inf"), False, True)
