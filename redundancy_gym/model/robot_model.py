"""The controller's model of a robot, built by pinocchio from the same MJCF that MuJoCo simulates.

Every controller gets kinematic and dynamic quantities only through :class:`RobotModel`. The model keeps one
pinocchio ``Data``; :meth:`RobotModel.update` runs one recursive pass (forward kinematics with the joint
Jacobians) per configuration and the query methods read from that cache, so a control step that needs several
frames and Jacobians pays for that pass once.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path
from typing import Literal, NamedTuple, TypeGuard

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from ..validation import as_real_array, check_real
from .chain_kernels import FREE, PRISMATIC, REVOLUTE
from .exceptions import ModelError, UnknownFrameError
from .serial_chain import SerialChain

__all__ = ["AccelerationTerms", "JacobianKind", "RobotModel"]

JacobianKind = Literal["translational", "rotational", "full"]
_JACOBIAN_ROWS: dict[str, slice] = {"translational": slice(0, 3), "rotational": slice(3, 6), "full": slice(0, 6)}
_WORLD_ALIGNED = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
_FLOAT64 = np.dtype(np.float64)
_FRAME_TUPLES_CACHED = 64
"""Frame tuples whose indices a model keeps (:meth:`RobotModel.measure`); later ones are resolved on each call."""
# 1-DoF joints the compiled kinematics handle: short name -> (joint type, axis or None for "read it")
_CHAIN_JOINTS: dict[str, tuple[int, tuple[float, float, float] | None]] = {
    "JointModelRX": (REVOLUTE, (1.0, 0.0, 0.0)),
    "JointModelRY": (REVOLUTE, (0.0, 1.0, 0.0)),
    "JointModelRZ": (REVOLUTE, (0.0, 0.0, 1.0)),
    "JointModelRevoluteUnaligned": (REVOLUTE, None),
    "JointModelPX": (PRISMATIC, (1.0, 0.0, 0.0)),
    "JointModelPY": (PRISMATIC, (0.0, 1.0, 0.0)),
    "JointModelPZ": (PRISMATIC, (0.0, 0.0, 1.0)),
    "JointModelPrismaticUnaligned": (PRISMATIC, None),
}


class AccelerationTerms(NamedTuple):
    """What an acceleration-level controller of frames and the centroidal momentum reads at one state
    (:meth:`RobotModel.acceleration_terms`); world frame, Jacobians world-aligned at the frame origin.

    Attributes:
        rotation: the frames' orientations (k, 3, 3).
        position: their origins [m] (k, 3).
        jacobian: their full Jacobians ``[J_T; J_R]`` (k, 6, nv), as :meth:`RobotModel.frame_jacobian`.
        drift: their ``Jdot qdot`` [m/s^2, rad/s^2] (k, 6), as
            :meth:`RobotModel.frames_jacobian_derivative_times_velocity` (classical acceleration at zero
            joint acceleration).
        com: the centre of mass [m] (3).
        centroidal: the centroidal momentum matrix ``A_G`` (6 x nv, linear rows first), as
            :meth:`RobotModel.centroidal_momentum_matrix`.
        centroidal_drift: ``Adot_G qdot`` [N, N m] (6), as :meth:`RobotModel.centroidal_momentum_drift`.
    """

    rotation: NDArray[np.float64]
    position: NDArray[np.float64]
    jacobian: NDArray[np.float64]
    drift: NDArray[np.float64]
    com: NDArray[np.float64]
    centroidal: NDArray[np.float64]
    centroidal_drift: NDArray[np.float64]


class RobotModel:
    """Kinematics and momentum of a robot (frames, Jacobians, CoM, centroidal momentum, integration).

    The base is fixed, or free-floating when the MJCF's root body has a ``freejoint`` (pinocchio then makes
    its first joint a free flyer: 7 coordinates ``[x y z qx qy qz qw]`` and 6 velocities ``[v; omega]``, both
    in the base frame). :meth:`from_mujoco_state` and :meth:`to_mujoco_qpos` convert from and to MuJoCo's
    order, the one place where the two conventions meet.

    Frames are the MJCF bodies, joints and sites (pinocchio turns sites into frames). All Jacobians are
    expressed in the world-aligned frame at the frame origin (pinocchio's ``LOCAL_WORLD_ALIGNED``), so that
    ``J_T qdot`` is the world velocity of the frame origin [m/s] and ``J_R qdot`` its angular velocity [rad/s].

    Args:
        model: a pinocchio model.
        source: where the model came from (for messages).
    """

    def __init__(self, model: pin.Model, source: str = "<pinocchio model>") -> None:
        self._model = model
        self._data = model.createData()
        # read several times a control period by the controllers; nothing changes the inertias after loading
        self._total_mass = float(sum(inertia.mass for inertia in model.inertias))
        self.source = source
        self._frame_ids: dict[str, int] = {}
        for index, frame in enumerate(model.frames):
            self._frame_ids.setdefault(frame.name, index)
        self._q: NDArray[np.float64] | None = None
        # read on every control period (checks, conversions): fixed with the model, so kept as Python values
        self._nq, self._nv = int(model.nq), int(model.nv)
        self._floating_base = model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer"
        # the frame indices of frame tuples :meth:`measure` was given (the controller gives the same tuple each period)
        self._frame_tuples: dict[tuple[str | int, ...], tuple[int, ...]] = {}

    @classmethod
    def from_mjcf(cls, path: str | Path) -> RobotModel:
        """Build the model from an MJCF file (the same file MuJoCo loads)."""
        path = Path(path)
        if not path.is_file():
            raise ModelError(f"MJCF file not found: {path}")
        try:
            model = pin.buildModelFromMJCF(str(path))
        except Exception as exc:  # pinocchio raises plain RuntimeError/ValueError
            raise ModelError(f"pinocchio could not load {path}: {exc}") from exc
        _velocity_limits_from_actuators(model, path)
        return cls(model, source=str(path))

    # ------------------------------------------------------------------ description
    @property
    def pinocchio_model(self) -> pin.Model:
        """The underlying pinocchio model (read-only use; for tests and advanced users)."""
        return self._model

    @property
    def nq(self) -> int:
        """Number of generalized coordinates."""
        return self._nq

    @property
    def nv(self) -> int:
        """Number of generalized velocities."""
        return self._nv

    @property
    def floating_base(self) -> bool:
        """Whether the first joint is a free flyer (a free-floating base)."""
        return self._floating_base

    @property
    def base_dofs(self) -> tuple[int, int]:
        """``(nq, nv)`` of the base joint: ``(7, 6)`` for a free-floating base, else ``(0, 0)``."""
        return (7, 6) if self.floating_base else (0, 0)

    @property
    def joint_names(self) -> list[str]:
        """Names of the actuated joints in configuration order (the 'universe' joint excluded)."""
        return list(self._model.names)[1:]

    @property
    def frame_names(self) -> list[str]:
        """Every frame name the model knows."""
        return list(self._frame_ids)

    @property
    def lower_limits(self) -> NDArray[np.float64]:
        """Lower joint position limits [rad or m]."""
        return np.array(self._model.lowerPositionLimit, dtype=np.float64)

    @property
    def upper_limits(self) -> NDArray[np.float64]:
        """Upper joint position limits [rad or m]."""
        return np.array(self._model.upperPositionLimit, dtype=np.float64)

    @property
    def velocity_limits(self) -> NDArray[np.float64]:
        """Joint speed limits [rad/s or m/s] (nv), ``inf`` where the description gives none.

        pinocchio's ``velocityLimit``; for a model built by :meth:`from_mjcf`, each joint driven by a
        ``velocity`` or ``intvelocity`` actuator is limited to the smaller magnitude of that actuator's
        ``ctrlrange`` (the speed its servo accepts; MJCF has no joint speed limit of its own).
        """
        return np.array(self._model.velocityLimit, dtype=np.float64)

    @property
    def total_mass(self) -> float:
        """Total mass [kg] (summed over the bodies once, when the model is built)."""
        return self._total_mass

    def frame_id(self, name: str) -> int:
        """Index of a frame; raises :class:`UnknownFrameError` naming the valid frames."""
        try:
            return self._frame_ids[name]
        except KeyError:
            raise UnknownFrameError(
                f"unknown frame {name!r} in {self.source}; valid frames: {', '.join(self._frame_ids)}"
            ) from None

    def serial_chain(self) -> SerialChain:
        """The joints as flat arrays for compiled kinematics (:mod:`redundancy_gym.model.chain_kernels`).

        Raises :class:`ModelError` unless every joint is a 1-DoF revolute or prismatic joint, or a free flyer.
        """
        m = self._model
        names, parent, rot, pos, axes, types, q_index, v_index = [], [], [], [], [], [], [], []
        for j in range(1, m.njoints):
            joint = m.joints[j]
            kind = joint.shortname()
            axis: tuple[float, ...]
            if kind == "JointModelFreeFlyer":
                joint_type, axis = FREE, (0.0, 0.0, 0.0)
            elif kind in _CHAIN_JOINTS and joint.nq == 1 and joint.nv == 1:
                joint_type, fixed_axis = _CHAIN_JOINTS[kind]
                # an unaligned joint (fixed_axis None) carries its own axis
                given = np.asarray(joint.extract().axis if fixed_axis is None else fixed_axis, dtype=np.float64)
                axis = tuple(given / np.linalg.norm(given))
            else:
                raise ModelError(
                    f"joint {m.names[j]!r} is {kind}; compiled kinematics support "
                    f"{', '.join(_CHAIN_JOINTS)}, JointModelFreeFlyer"
                )
            names.append(m.names[j])
            parent.append(int(m.parents[j]) - 1)
            rot.append(m.jointPlacements[j].rotation)
            pos.append(m.jointPlacements[j].translation)
            axes.append(axis)
            types.append(joint_type)
            q_index.append(joint.idx_q)
            v_index.append(joint.idx_v)
        n = len(names)
        inertias = [m.inertias[j] for j in range(1, m.njoints)]
        return SerialChain(
            tuple(names),
            np.array(parent, dtype=np.int64).reshape(n),
            np.array(rot, dtype=np.float64).reshape(n, 3, 3),
            np.array(pos, dtype=np.float64).reshape(n, 3),
            np.array(axes, dtype=np.float64).reshape(n, 3),
            np.array(types, dtype=np.int64).reshape(n),
            np.array(q_index, dtype=np.int64),
            np.array(v_index, dtype=np.int64),
            np.array([i.mass for i in inertias], dtype=np.float64).reshape(n),
            np.array([i.lever for i in inertias], dtype=np.float64).reshape(n, 3),
            np.array([i.inertia for i in inertias], dtype=np.float64).reshape(n, 3, 3),
            self.nq,
            self.nv,
        )

    def frame_attachment(self, frame: str | int) -> tuple[int, NDArray[np.float64], NDArray[np.float64]]:
        """``(joint, R, p)``: the :meth:`serial_chain` joint a frame moves with (-1 for the world) and the
        frame's fixed rotation and position [m] in that joint's frame."""
        f = self._model.frames[self._resolve(frame)]
        return int(f.parentJoint) - 1, np.array(f.placement.rotation), np.array(f.placement.translation)

    def frame_attachments(
        self, frames: Sequence[str | int]
    ) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`frame_attachment` of each of ``frames``, stacked for a kernel: ``(joints (K,), rotations
        (K, 3, 3), positions (K, 3) [m])``."""
        attachments = [self.frame_attachment(f) for f in frames]
        return (
            np.array([j for j, _, _ in attachments], dtype=np.int64),
            np.array([r for _, r, _ in attachments], dtype=np.float64).reshape(len(attachments), 3, 3),
            np.array([p for _, _, p in attachments], dtype=np.float64).reshape(len(attachments), 3),
        )

    # ------------------------------------------------------------------ state
    def check_configuration(self, q: ArrayLike) -> NDArray[np.float64]:
        """Return ``q`` as a float array after checking its size and finiteness."""
        if not _is_float_vector(q, self._nq):  # a float64 array of the right size needs no conversion
            q = _as_float_array(q, "configuration")
        if q.shape != (self._nq,):
            raise ModelError(f"configuration must have shape ({self.nq},), got {q.shape}")
        if not math.isfinite(float(q.sum())):  # one reduction: NaN and inf survive a sum
            raise ModelError("configuration contains non-finite values")
        return q

    def update(self, q: ArrayLike) -> NDArray[np.float64]:
        """Forward kinematics and joint Jacobians at ``q``; later queries read this cache.

        Returns the checked configuration (a float copy of ``q``).
        """
        q = self.check_configuration(q)
        # computeJointJacobians runs the forward kinematics pass itself
        pin.computeJointJacobians(self._model, self._data, q)
        pin.updateFramePlacements(self._model, self._data)
        self._q = q.copy()
        return q

    @property
    def q(self) -> NDArray[np.float64]:
        """The configuration of the last :meth:`update`."""
        return self._require_update().copy()

    def _require_update(self) -> NDArray[np.float64]:
        if self._q is None:
            raise ModelError("call RobotModel.update(q) before querying frames or Jacobians")
        return self._q

    # ------------------------------------------------------------------ frames
    def frame_position(self, frame: str | int) -> NDArray[np.float64]:
        """World position of a frame origin [m]."""
        self._require_update()
        return self._data.oMf[self._resolve(frame)].translation.copy()

    def frame_rotation(self, frame: str | int) -> NDArray[np.float64]:
        """World orientation of a frame (3x3 rotation matrix)."""
        self._require_update()
        return self._data.oMf[self._resolve(frame)].rotation.copy()

    def frame_placement(self, frame: str | int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(R, p)``: world rotation and position of a frame."""
        self._require_update()
        placement = self._data.oMf[self._resolve(frame)]
        return placement.rotation.copy(), placement.translation.copy()

    def frame_jacobian(self, frame: str | int, kind: JacobianKind = "full") -> NDArray[np.float64]:
        """World-aligned frame Jacobian: ``translational`` (3 x nv), ``rotational`` (3 x nv) or ``full`` (6 x nv)."""
        rows = self._rows(kind)
        self._require_update()
        jac = pin.getFrameJacobian(self._model, self._data, self._resolve(frame), _WORLD_ALIGNED)
        return np.array(jac[rows], dtype=np.float64)

    def point_jacobian(self, frame: str | int, point: ArrayLike) -> NDArray[np.float64]:
        """Translational Jacobian (3 x nv) of a world point rigidly attached to ``frame``.

        ``J_p = J_T - [p - p_frame]_x J_R``: the velocity of a point ``p`` on the frame's body.
        """
        jac = self.frame_jacobian(frame, "full")
        offset = np.asarray(point, dtype=np.float64) - self.frame_position(frame)
        # v_p = v_o + omega x r = v_o - r x omega
        return jac[:3] - _skew(offset) @ jac[3:]

    def frame_jacobian_derivative_times_velocity(
        self, q: ArrayLike, qdot: ArrayLike, frame: str | int, kind: JacobianKind = "full"
    ) -> NDArray[np.float64]:
        """``Jdot qdot`` of the world-aligned frame Jacobian (the drift term of (5.18)).

        Computed as the frame's classical acceleration at zero joint acceleration, so it matches
        ``d/dt (J qdot)`` for the linear part (classical, not spatial, acceleration). Leaves the
        kinematic cache (placements and Jacobians) at ``q``.
        """
        return self.frames_jacobian_derivative_times_velocity(q, qdot, (frame,), kind)[0]

    def frames_jacobian_derivative_times_velocity(
        self, q: ArrayLike, qdot: ArrayLike, frames: Sequence[str | int], kind: JacobianKind = "full"
    ) -> NDArray[np.float64]:
        """:meth:`frame_jacobian_derivative_times_velocity` of several ``frames`` (rows in their order) from one
        kinematic pass."""
        rows = self._rows(kind)
        q = self.update(q)
        qdot = self._check_velocity(qdot)
        # same q: placements and the joint Jacobians of update() stay valid
        pin.forwardKinematics(self._model, self._data, q, qdot, np.zeros(self.nv))
        return np.array(
            [
                np.asarray(
                    pin.getFrameClassicalAcceleration(self._model, self._data, self._resolve(f), _WORLD_ALIGNED).vector
                )[rows]
                for f in frames
            ],
            dtype=np.float64,
        )

    def acceleration_terms(self, q: ArrayLike, qdot: ArrayLike, frames: Sequence[str | int]) -> AccelerationTerms:
        """The placements, Jacobians and ``Jdot qdot`` of ``frames`` and the CoM, ``A_G`` and ``Adot_G qdot`` at
        ``(q, qdot)`` from two recursive passes (:class:`AccelerationTerms`).

        Equals :meth:`update` followed by :meth:`frame_placement`, :meth:`frame_jacobian` (``"full"``),
        :meth:`frames_jacobian_derivative_times_velocity`, :meth:`com_and_centroidal_matrix` and
        :meth:`centroidal_momentum_drift`, up to round-off, for the price of about one of them. Leaves the
        kinematic cache (placements and joint Jacobians) at ``q``, as :meth:`update` does.
        """
        q = self.check_configuration(q)
        qdot = self._check_velocity(qdot)
        indices = self._frame_indices(frames if isinstance(frames, tuple) else tuple(frames))
        model, data = self._model, self._data
        # the frames' classical accelerations at zero joint acceleration (data.a); the centroidal pass below runs
        # the forward kinematics with (q, qdot) again, which leaves data.a as it is, and fills the joint Jacobians
        pin.forwardKinematics(model, data, q, qdot, np.zeros(self._nv))
        # pinocchio 4.1's computeCentroidalMapTimeVariation reads data.vcom[0] without computing it: without this
        # line Adot_G qdot used whatever CoM velocity an earlier call left (off by ~200 after another state's pass)
        pin.centerOfMass(model, data, pin.KinematicLevel.VELOCITY, False)
        centroidal_drift = np.asarray(pin.computeCentroidalMapTimeVariation(model, data, q, qdot)) @ qdot
        centroidal = np.array(data.Ag, dtype=np.float64)
        pin.updateFramePlacements(model, data)
        self._q = q.copy()
        k = len(indices)
        rotation, position = np.empty((k, 3, 3)), np.empty((k, 3))
        jacobian, drift = np.empty((k, 6, self._nv)), np.empty((k, 6))
        for i, f in enumerate(indices):
            placement = data.oMf[f]
            rotation[i] = placement.rotation
            position[i] = placement.translation
            jacobian[i] = pin.getFrameJacobian(model, data, f, _WORLD_ALIGNED)
            drift[i] = pin.getFrameClassicalAcceleration(model, data, f, _WORLD_ALIGNED).vector
        return AccelerationTerms(
            rotation, position, jacobian, drift, np.array(data.com[0], dtype=np.float64), centroidal, centroidal_drift
        )

    # ------------------------------------------------------------------ mass properties and momentum
    def com(self) -> NDArray[np.float64]:
        """Position of the centre of mass [m] at the configuration of the last :meth:`update`."""
        q = self._require_update()
        return np.array(pin.centerOfMass(self._model, self._data, q, False), dtype=np.float64)

    def com_jacobian(self) -> NDArray[np.float64]:
        """Jacobian of the centre of mass (3 x nv) [m/rad]."""
        q = self._require_update()
        return np.array(pin.jacobianCenterOfMass(self._model, self._data, q, False), dtype=np.float64)

    def centroidal_momentum_matrix(self) -> NDArray[np.float64]:
        """Centroidal momentum matrix ``A_G`` (6 x nv): ``[p; L_G] = A_G qdot`` (linear first, about the CoM)."""
        q = self._require_update()
        return np.array(pin.computeCentroidalMap(self._model, self._data, q), dtype=np.float64)

    def com_and_centroidal_matrix(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(c, A_G)`` from one pass: CoM [m] and centroidal momentum matrix (6 x nv, linear rows first).

        ``A_G[:3] / total_mass`` is the CoM Jacobian and ``A_G[5]`` the Jacobian ``J_Lz`` of the vertical
        angular momentum about the CoM used by (5.62).
        """
        q = self._require_update()
        ag = np.array(pin.computeCentroidalMap(self._model, self._data, q), dtype=np.float64)
        return np.array(self._data.com[0], dtype=np.float64), ag

    def measure(
        self, q: ArrayLike, v: ArrayLike, frames: Sequence[str | int] = ()
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """``(c, c_dot, R, p)`` of a measured state in one forward pass: CoM [m], its velocity [m/s] and the
        world rotations (k, 3, 3) and positions (k, 3) [m] of ``frames``.

        Cheaper than :meth:`update` (no Jacobians); it leaves the cache empty, so call :meth:`update` before
        the next Jacobian query.
        """
        # The per-period measurement of the walking controller: its cost is mostly Python and conversions, so it
        # updates only the placements of ``frames`` (the cache is left empty anyway) and resolves a frame tuple once.
        q = self.check_configuration(q)
        v = self._check_velocity(v)
        self._q = None
        model, data = self._model, self._data
        com = np.array(pin.centerOfMass(model, data, q, v, False), dtype=np.float64)
        com_velocity = np.array(data.vcom[0], dtype=np.float64)
        if len(frames) == 0:
            return com, com_velocity, np.empty((0, 3, 3)), np.empty((0, 3))
        indices = self._frame_indices(frames)
        placements = np.array([pin.updateFramePlacement(model, data, f).homogeneous for f in indices], dtype=np.float64)
        # copies: C-contiguous, and not views of one another's array
        return com, com_velocity, placements[:, :3, :3].copy(), placements[:, :3, 3].copy()

    def _frame_indices(self, frames: Sequence[str | int]) -> tuple[int, ...]:
        """The indices of ``frames`` (:meth:`_resolve` each), cached per hashable tuple of frames."""
        if isinstance(frames, tuple):  # another sequence (a list) is resolved each time
            try:
                return self._frame_tuples[frames]
            except (KeyError, TypeError):  # TypeError: a tuple holding an unhashable item
                pass
        indices = tuple(self._resolve(f) for f in frames)
        if isinstance(frames, tuple) and len(self._frame_tuples) < _FRAME_TUPLES_CACHED:
            self._frame_tuples[frames] = indices
        return indices

    def mass_matrix(self) -> NDArray[np.float64]:
        """Joint-space inertia matrix (nv x nv)."""
        q = self._require_update()
        mass = pin.crba(self._model, self._data, q)
        return np.triu(mass) + np.triu(mass, 1).T

    def centroidal_momentum_drift(self, q: ArrayLike, qdot: ArrayLike) -> NDArray[np.float64]:
        """``Adot_G qdot`` (6: linear, then angular about the CoM), the drift of the centroidal momentum's rate
        ``hdot_G = A_G qddot + Adot_G qdot``. Updates the model at ``q``; the kinematic cache stays valid there."""
        q = self.update(q)
        qdot = self._check_velocity(qdot)
        # the CoM velocity at (q, qdot) first: pinocchio 4.1's computeCentroidalMapTimeVariation reads data.vcom[0]
        pin.centerOfMass(self._model, self._data, q, qdot, False)
        rate = pin.computeCentroidalMapTimeVariation(self._model, self._data, q, qdot)
        return np.array(rate, dtype=np.float64) @ qdot

    def nonlinear_effects(self, q: ArrayLike, qdot: ArrayLike) -> NDArray[np.float64]:
        """``h(q, qdot)`` of ``M qddot + h = tau`` (5.92): Coriolis, centrifugal and gravity terms [N m or N] (nv).

        Updates the model at ``q`` (as :meth:`update`); the kinematic cache stays valid there.
        """
        q = self.update(q)
        qdot = self._check_velocity(qdot)
        return np.array(pin.nonLinearEffects(self._model, self._data, q, qdot), dtype=np.float64)

    def inverse_dynamics(self, q: ArrayLike, qdot: ArrayLike, qddot: ArrayLike) -> NDArray[np.float64]:
        """``M(q) qddot + h(q, qdot)`` of (5.92) by the recursive Newton-Euler algorithm [N m or N] (nv): the
        generalized forces that produce ``qddot``, without contact forces, rotor inertias (armature) included.

        Updates the model at ``q`` (as :meth:`update`); the kinematic cache stays valid there.
        """
        q = self.update(q)
        qdot = self._check_velocity(qdot)
        qddot = self._check_velocity(qddot)
        return np.array(pin.rnea(self._model, self._data, q, qdot, qddot), dtype=np.float64)

    @property
    def joint_damping(self) -> NDArray[np.float64]:
        """Viscous joint damping [N m s/rad or N s/m] per velocity (nv) as the model file gives it (0 for the
        free base); :meth:`inverse_dynamics` leaves it out."""
        return np.array(self._model.damping, dtype=np.float64)

    @property
    def armature(self) -> NDArray[np.float64]:
        """Rotor inertia [kg m^2 or kg] per velocity (nv) as the model file gives it (0 for the free base);
        :meth:`inverse_dynamics` adds ``armature * qddot``."""
        return np.array(self._model.armature, dtype=np.float64)

    @property
    def gravity(self) -> NDArray[np.float64]:
        """The world's gravity [m/s^2] (3) that :meth:`inverse_dynamics` and :meth:`nonlinear_effects` include."""
        return np.array(self._model.gravity.linear, dtype=np.float64)

    # ------------------------------------------------------------------ integration
    def integrate(self, q: ArrayLike, qdot: ArrayLike, dt: float) -> NDArray[np.float64]:
        """Configuration reached from ``q`` after moving with ``qdot`` for ``dt`` [s] (on the configuration
        manifold)."""
        q = self.check_configuration(q)
        qdot = self._check_velocity(qdot)
        duration = check_real("dt", dt, unit="s", error=ModelError)
        assert duration is not None  # not optional: a float or ModelError
        step = qdot * duration
        if not math.isfinite(float(step.sum())):
            raise ModelError(f"qdot * dt overflows (dt = {dt!r})")
        q_next = np.array(pin.integrate(self._model, q, step), dtype=np.float64)
        if not math.isfinite(float(q_next.sum())):
            raise ModelError(f"integrating qdot over dt = {dt!r} s gives a non-finite configuration")
        return q_next

    def difference(self, q0: ArrayLike, q1: ArrayLike) -> NDArray[np.float64]:
        """Tangent vector ``v`` with ``integrate(q0, v, 1) == q1``."""
        return np.array(pin.difference(self._model, self.check_configuration(q0), self.check_configuration(q1)))

    def from_mujoco_state(self, qpos: ArrayLike, qvel: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(q, v)`` in pinocchio's convention from MuJoCo's ``qpos`` and ``qvel`` of the same MJCF.

        MuJoCo's free joint is ``qpos = [x y z qw qx qy qz]`` and ``qvel = [v_world; omega_body]``; pinocchio's
        free flyer is ``q = [x y z qx qy qz qw]`` and ``v = [v_body; omega_body]``. Fixed-base models pass
        through unchanged.
        """
        q = np.array(qpos, dtype=np.float64)
        v = np.array(qvel, dtype=np.float64)
        if q.shape != (self._nq,) or v.shape != (self._nv,):
            raise ModelError(f"qpos and qvel must have shapes ({self._nq},), ({self._nv},); got {q.shape}, {v.shape}")
        if self._floating_base:
            # the quaternion in Python floats (called once per control period; the same operations as on arrays)
            w, x, y, z = q[3:7].tolist()
            norm = math.sqrt(w * w + x * x + y * y + z * z)
            if not norm > 0.0:
                raise ModelError("the base quaternion of qpos is zero")
            x, y, z, w = x / norm, y / norm, z / norm, w / norm
            q[3:7] = (x, y, z, w)
            rotation = pin.Quaternion(w, x, y, z).toRotationMatrix()
            v[:3] = rotation.T @ v[:3]
        return q, v

    def to_mujoco_qpos(self, q: ArrayLike) -> NDArray[np.float64]:
        """MuJoCo's ``qpos`` for a pinocchio configuration (the inverse of :meth:`from_mujoco_state` for q)."""
        q = self.check_configuration(q).copy()
        if self.floating_base:
            q[3:7] = q[[6, 3, 4, 5]]
        return q

    def clamp(self, q: ArrayLike) -> NDArray[np.float64]:
        """``q`` clipped into the joint limits; a free-floating base's pose is left as it is (pinocchio's
        placeholder limits of a free flyer are not limits)."""
        q = self.check_configuration(q)
        base = self.base_dofs[0]
        return np.concatenate([q[:base], np.clip(q[base:], self.lower_limits[base:], self.upper_limits[base:])])

    # ------------------------------------------------------------------ helpers
    def _check_velocity(self, qdot: ArrayLike) -> NDArray[np.float64]:
        if not _is_float_vector(qdot, self._nv):  # a float64 array of the right size needs no conversion
            qdot = _as_float_array(qdot, "velocity")
        if qdot.shape != (self._nv,):
            raise ModelError(f"velocity must have shape ({self.nv},), got {qdot.shape}")
        if not math.isfinite(float(qdot.sum())):
            raise ModelError("velocity contains non-finite values")
        return qdot

    def _resolve(self, frame: str | int) -> int:
        if isinstance(frame, str):
            return self.frame_id(frame)
        if not 0 <= int(frame) < len(self._model.frames):
            raise UnknownFrameError(f"frame index {frame} out of range [0, {len(self._model.frames)})")
        return int(frame)

    @staticmethod
    def _rows(kind: str) -> slice:
        try:
            return _JACOBIAN_ROWS[kind]
        except KeyError:
            raise ModelError(f"unknown Jacobian kind {kind!r}; valid kinds: {', '.join(_JACOBIAN_ROWS)}") from None


def _velocity_limits_from_actuators(model: pin.Model, path: Path) -> None:
    """Set ``model.velocityLimit`` of each 1-DoF joint driven by a ``velocity``/``intvelocity`` actuator with an
    explicit ``ctrlrange`` in the MJCF (the smaller magnitude of the range, when it contains zero; the smallest
    over several such actuators). Leaves the model unchanged when the file cannot be parsed."""
    try:
        root = ET.parse(path).getroot()
    except (ET.ParseError, OSError):
        return
    limits = np.array(model.velocityLimit, dtype=np.float64)
    changed = False
    for actuator in root.iterfind("actuator/*"):
        if actuator.tag not in ("velocity", "intvelocity") or actuator.get("ctrllimited") == "false":
            continue
        joint, ctrlrange = actuator.get("joint"), actuator.get("ctrlrange")
        if joint is None or ctrlrange is None or not model.existJointName(joint):
            continue
        try:
            low, high = (float(v) for v in ctrlrange.split())
        except ValueError:
            continue
        pin_joint = model.joints[model.getJointId(joint)]
        if not (low < 0.0 < high) or pin_joint.nv != 1:
            continue
        k = pin_joint.idx_v
        limits[k] = min(limits[k], -low, high)
        changed = True
    if changed:
        model.velocityLimit = limits


def _skew(v: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def _is_float_vector(value: object, size: int) -> TypeGuard[NDArray[np.float64]]:
    """Whether ``value`` is a float64 array of shape ``(size,)`` (what :func:`_as_float_array` would return as is)."""
    return type(value) is np.ndarray and value.dtype == _FLOAT64 and value.shape == (size,)


def _as_float_array(value: ArrayLike, name: str) -> NDArray[np.float64]:
    """``value`` as a float64 array; strings, None, mappings and other non-numbers raise :class:`ModelError`."""
    return as_real_array(name, value, error=ModelError)
