"""The walking controller's per-period measurement as one compiled kernel call (:class:`CompiledMeasurement`).

What :meth:`~redundancy_gym.controllers.walking.WalkingController.step` did before its IK through some forty
pinocchio and NumPy calls on 3-vectors (about 40 us of Python per period, a third of the step): the MuJoCo
state in pinocchio's convention (:meth:`~redundancy_gym.model.RobotModel.from_mujoco_state`), the CoM, its
velocity and the ankle and sole placements (:meth:`~redundancy_gym.model.RobotModel.measure`), the rigid move
into the stance foot's planned pose (``WalkingController._in_stance_frame``) and the ZMP from the ankle wrenches
(:func:`~.zmp_estimator.estimate_zmp`). The same formulas in the same order, on the compiled kinematics of
:mod:`redundancy_gym.model.chain_kernels`: the results agree with the pinocchio/NumPy path to round-off (a test
holds them to 1e-12). That path stays the reference: the walking controller runs it with ``backend="python"``
(:class:`~redundancy_gym.controllers.walking.WalkingIkConfig`), this kernel with ``backend="compiled"``, and never
the one in place of the other.
"""

from __future__ import annotations

import math
import warnings
from typing import Any, NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ...kernel_options import JIT, LazyEntryPoint
from ...model import RobotModel
from ...model.chain_kernels import FREE, PRISMATIC, place_frame
from ..exceptions import ControllerError
from ..kernels.buffers import buffer_view, float_field, int_field, pack_fields
from ..kernels.chain_fields import (
    CHAIN_INT_FIELDS,
    CHAIN_PLACEMENT_FIELDS,
    CHAIN_STATE_FIELDS,
    chain_arrays,
    chain_indices,
    field_index,
    forward_chain,
)

__all__ = ["BAD_INPUT", "OK", "CompiledMeasurement", "MeasurementResult"]

FLOAT_FIELDS: tuple[str, ...] = (
    *CHAIN_PLACEMENT_FIELDS,
    "body_mass",
    "body_com",
    *CHAIN_STATE_FIELDS,
    "velocities",
    "frame_rotation",
    "frame_translation",
    "inputs",
    "outputs",
)
INT_FIELDS: tuple[str, ...] = ("dims", *CHAIN_INT_FIELDS, "frame_joint")
FRAMES = 4
"""Frames measured: the ankle sensors (right, left), then the soles (right, left)."""
PARAMETERS = ("mujoco", "stance_frame", "stance", "planned_x", "planned_y", "planned_yaw", "ground", "min_force")
"""Scalar inputs after ``q``, ``v`` and the ankle wrenches (12: right force, right torque, left force, left
torque): 1.0 where the state is MuJoCo's ``qpos``, ``qvel`` (else pinocchio's), 1.0 to move into the stance foot's
planned pose, the stance foot (0 right, 1 left), its planned sole position (x, y) [m] and heading [rad], the ground
height [m] and the ZMP's ``min_force`` [N]."""
OUTPUT_SIZES = (
    ("com", 3),
    ("com_velocity", 3),
    ("rotations", 9 * FRAMES),
    ("positions", 3 * FRAMES),
    ("turn", 9),
    ("shift", 3),
    ("zmp", 3),
    ("cop", 4),
    ("normal_force", 2),
    ("moment", 6),
)
"""After the pinocchio ``q`` (nq) and ``v`` (nv) in ``outputs``: the fields of :class:`MeasurementResult` (``zmp`` is x,
y and 1.0 where valid)."""
OK, BAD_INPUT = 0, 1

_F = field_index(FLOAT_FIELDS)
_F_BODY_MASS = _F["body_mass"]
_F_BODY_COM = _F["body_com"]
_F_VELOCITIES = _F["velocities"]
_F_FRAME_ROTATION = _F["frame_rotation"]
_F_FRAME_TRANSLATION = _F["frame_translation"]
_F_INPUTS = _F["inputs"]
_F_OUTPUTS = _F["outputs"]
_I = field_index(INT_FIELDS, len(FLOAT_FIELDS))
_I_DIMS = _I["dims"]
_CHAIN_FLOATS, _CHAIN_INTS = chain_indices(FLOAT_FIELDS, INT_FIELDS)  # in the order of kernels.chain_fields
_I_PARENT, _I_JOINT_TYPE, _I_Q_INDEX, _I_V_INDEX = _CHAIN_INTS
_I_FRAME_JOINT = _I["frame_joint"]

# JIT: the chain kernels' numerics contract (FMA contraction allowed): agreement to round-off, not bit for bit


@njit(**JIT)
def _from_mujoco(joint_type, q_index, v_index, q, v):
    """MuJoCo's free joint (``[x y z qw qx qy qz]``, ``[v_world; omega_body]``) in place into pinocchio's free flyer
    (``[x y z qx qy qz qw]``, ``[v_body; omega_body]``), as :meth:`RobotModel.from_mujoco_state`; returns False
    for a zero quaternion."""
    for j in range(joint_type.shape[0]):
        if joint_type[j] != FREE:
            continue
        a, b = q_index[j], v_index[j]
        w, x, y, z = q[a + 3], q[a + 4], q[a + 5], q[a + 6]
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        if not norm > 0.0:
            return False
        x, y, z, w = x / norm, y / norm, z / norm, w / norm
        q[a + 3], q[a + 4], q[a + 5], q[a + 6] = x, y, z, w
        # Eigen's Quaternion::toRotationMatrix, then v_body = R^T v_world
        tx, ty, tz = 2.0 * x, 2.0 * y, 2.0 * z
        twx, twy, twz = tx * w, ty * w, tz * w
        txx, txy, txz = tx * x, ty * x, tz * x
        tyy, tyz, tzz = ty * y, tz * y, tz * z
        r00, r01, r02 = 1.0 - (tyy + tzz), txy - twz, txz + twy
        r10, r11, r12 = txy + twz, 1.0 - (txx + tzz), tyz - twx
        r20, r21, r22 = txz - twy, tyz + twx, 1.0 - (txx + tyy)
        vx, vy, vz = v[b], v[b + 1], v[b + 2]
        v[b] = r00 * vx + r10 * vy + r20 * vz
        v[b + 1] = r01 * vx + r11 * vy + r21 * vz
        v[b + 2] = r02 * vx + r12 * vy + r22 * vz
    return True


@njit(**JIT)
def measure_step(f, i):
    """One measurement on the buffers: reads ``inputs`` (``q``, ``v``, forces, torques, :data:`PARAMETERS`) and
    writes ``outputs`` (pinocchio ``q``, ``v``, then :data:`OUTPUT_SIZES`); returns :data:`OK` or :data:`BAD_INPUT`
    (a non-finite input or a zero base quaternion; the outputs are then incomplete)."""
    dims = int_field(i, _I_DIMS)
    nj, nq, nv = dims[0], dims[1], dims[2]
    inputs = float_field(f, i, _F_INPUTS)
    n_state = nq + nv + 12
    for k in range(n_state):
        if not np.isfinite(inputs[k]):
            return BAD_INPUT
    params = inputs[n_state:]
    outputs = float_field(f, i, _F_OUTPUTS)
    q = outputs[:nq]
    v = outputs[nq : nq + nv]
    q[:] = inputs[:nq]
    v[:] = inputs[nq : nq + nv]
    joint_type = int_field(i, _I_JOINT_TYPE)
    if params[0] != 0.0 and not _from_mujoco(joint_type, int_field(i, _I_Q_INDEX), int_field(i, _I_V_INDEX), q, v):
        return BAD_INPUT
    chain = forward_chain(f, i, nj, q, _CHAIN_FLOATS, _CHAIN_INTS)
    rotation, position = chain[3], chain[4]
    o = nq + nv
    com = outputs[o : o + 3]
    com_velocity = outputs[o + 3 : o + 6]
    rotations = outputs[o + 6 : o + 6 + 9 * FRAMES].reshape((FRAMES, 3, 3))
    o += 6 + 9 * FRAMES
    positions = outputs[o : o + 3 * FRAMES].reshape((FRAMES, 3))
    o += 3 * FRAMES
    turn = outputs[o : o + 9].reshape((3, 3))
    shift = outputs[o + 9 : o + 12]
    zmp = outputs[o + 12 : o + 15]
    cop = outputs[o + 15 : o + 19].reshape((2, 2))
    normal_force = outputs[o + 19 : o + 21]
    moment = outputs[o + 21 : o + 27].reshape((2, 3))
    _com_and_velocity(
        chain,
        float_field(f, i, _F_BODY_MASS),
        float_field(f, i, _F_BODY_COM).reshape((nj, 3)),
        v,
        float_field(f, i, _F_VELOCITIES).reshape((nj, 6)),
        com,
        com_velocity,
    )
    frame_joint = int_field(i, _I_FRAME_JOINT)
    frame_rotation = float_field(f, i, _F_FRAME_ROTATION).reshape((FRAMES, 3, 3))
    frame_translation = float_field(f, i, _F_FRAME_TRANSLATION).reshape((FRAMES, 3))
    for k in range(FRAMES):
        place_frame(
            rotation, position, frame_joint[k], frame_rotation[k], frame_translation[k], rotations[k], positions[k]
        )
    # the stance frame (WalkingController._in_stance_frame): R_z(-yaw) and a horizontal shift that put the measured
    # stance sole on its planned position and heading
    turn[:, :] = 0.0
    turn[0, 0] = turn[1, 1] = turn[2, 2] = 1.0
    shift[:] = 0.0
    if params[1] != 0.0:
        stance = 2 + int(params[2])
        yaw = math.atan2(rotations[stance, 1, 0], rotations[stance, 0, 0])
        if params[5] != 0.0:
            yaw -= params[5]
        c, s = math.cos(yaw), math.sin(yaw)
        turn[0, 0], turn[0, 1], turn[1, 0], turn[1, 1] = c, s, -s, c
        rx, ry = positions[stance, 0], positions[stance, 1]
        shift[0] = params[3] - (c * rx + s * ry)
        shift[1] = params[4] - (-s * rx + c * ry)
        _turn_point(turn, com, shift)
        _turn_point(turn, com_velocity, shift[:0])
        for k in range(FRAMES):
            for col in range(3):
                x, y = rotations[k, 0, col], rotations[k, 1, col]
                rotations[k, 0, col] = c * x + s * y
                rotations[k, 1, col] = -s * x + c * y
            _turn_point(turn, positions[k], shift)
    # the ZMP from the ankle sensors (estimate_zmp): the ground reaction is minus the reading, in the world frame
    sensors = inputs[nq + nv : nq + nv + 12]  # rows right, left: force (3) then torque (3)
    ground, min_force = params[6], params[7]
    total = weighted_x = weighted_y = 0.0
    for side in range(2):
        r = rotations[side]
        a = 6 * side
        fx = -(r[0, 0] * sensors[a] + r[0, 1] * sensors[a + 1] + r[0, 2] * sensors[a + 2])
        fy = -(r[1, 0] * sensors[a] + r[1, 1] * sensors[a + 1] + r[1, 2] * sensors[a + 2])
        fz = -(r[2, 0] * sensors[a] + r[2, 1] * sensors[a + 1] + r[2, 2] * sensors[a + 2])
        for row in range(3):
            moment[side, row] = -(r[row, 0] * sensors[a + 3] + r[row, 1] * sensors[a + 4] + r[row, 2] * sensors[a + 5])
        normal_force[side] = fz
        cop[side, 0] = cop[side, 1] = np.nan
        if fz < min_force:
            continue
        h = positions[side, 2] - ground
        x = positions[side, 0] + -(moment[side, 1] + h * fx) / fz
        y = positions[side, 1] + (moment[side, 0] - h * fy) / fz
        cop[side, 0], cop[side, 1] = x, y
        total += fz
        weighted_x, weighted_y = weighted_x + fz * x, weighted_y + fz * y
    if total > 0.0:
        zmp[0], zmp[1], zmp[2] = weighted_x / total, weighted_y / total, 1.0
    else:
        zmp[0], zmp[1], zmp[2] = np.nan, np.nan, 0.0
    return OK


@njit(**JIT)
def _com_and_velocity(chain, body_mass, body_com, v, scratch, com, com_velocity):
    """The CoM [m] and its velocity [m/s] (world frame) after :func:`chain_forward`, as ``pinocchio.centerOfMass(q,
    v)``: each joint's angular velocity and its origin's velocity propagated from the root (``scratch[j, :6]``), then
    the mass-weighted mean of the bodies' CoMs and their velocities (no Jacobians, no composite inertias: cheaper
    than ``chain_centroidal``). ``chain``: the kinematics as :func:`~..kernels.chain_fields.chain_views` gives them."""
    parent, joint_type, v_index, rotation, position, world_axis = chain
    mass = 0.0
    cx = cy = cz = 0.0
    vx = vy = vz = 0.0
    for j in range(parent.shape[0]):
        p = parent[j]
        b = v_index[j]
        if joint_type[j] == FREE:
            # pinocchio's free flyer (the root: SerialChain's): v = [v_body; omega_body] of the joint frame, turned
            # into the world
            for r in range(3):
                scratch[j, r] = (
                    rotation[j, r, 0] * v[b + 3] + rotation[j, r, 1] * v[b + 4] + rotation[j, r, 2] * v[b + 5]
                )
                scratch[j, 3 + r] = (
                    rotation[j, r, 0] * v[b] + rotation[j, r, 1] * v[b + 1] + rotation[j, r, 2] * v[b + 2]
                )
        else:
            if p >= 0:
                _carry(scratch, position, p, j)
            else:
                for r in range(6):
                    scratch[j, r] = 0.0
            rate = v[b]
            if joint_type[j] == PRISMATIC:
                for r in range(3):
                    scratch[j, 3 + r] += world_axis[j, r] * rate
            else:
                for r in range(3):
                    scratch[j, r] += world_axis[j, r] * rate
        m = body_mass[j]
        if m == 0.0:
            continue
        # the body's CoM c and its velocity v_o + omega x (c - o)
        lx = (
            rotation[j, 0, 0] * body_com[j, 0] + rotation[j, 0, 1] * body_com[j, 1] + rotation[j, 0, 2] * body_com[j, 2]
        )
        ly = (
            rotation[j, 1, 0] * body_com[j, 0] + rotation[j, 1, 1] * body_com[j, 1] + rotation[j, 1, 2] * body_com[j, 2]
        )
        lz = (
            rotation[j, 2, 0] * body_com[j, 0] + rotation[j, 2, 1] * body_com[j, 1] + rotation[j, 2, 2] * body_com[j, 2]
        )
        wx, wy, wz = scratch[j, 0], scratch[j, 1], scratch[j, 2]
        mass += m
        cx += m * (position[j, 0] + lx)
        cy += m * (position[j, 1] + ly)
        cz += m * (position[j, 2] + lz)
        vx += m * (scratch[j, 3] + wy * lz - wz * ly)
        vy += m * (scratch[j, 4] + wz * lx - wx * lz)
        vz += m * (scratch[j, 5] + wx * ly - wy * lx)
    com[0], com[1], com[2] = cx / mass, cy / mass, cz / mass
    com_velocity[0], com_velocity[1], com_velocity[2] = vx / mass, vy / mass, vz / mass


@njit(**JIT)
def _carry(scratch, position, p, j):
    """Joint ``j``'s frame carried by its parent ``p`` (``scratch[k] = (omega, v_origin)``, world frame): the
    parent's angular velocity, and its origin's velocity plus ``omega_p x (o_j - o_p)``."""
    wx, wy, wz = scratch[p, 0], scratch[p, 1], scratch[p, 2]
    dx, dy, dz = position[j, 0] - position[p, 0], position[j, 1] - position[p, 1], position[j, 2] - position[p, 2]
    scratch[j, 0], scratch[j, 1], scratch[j, 2] = wx, wy, wz
    scratch[j, 3] = scratch[p, 3] + wy * dz - wz * dy
    scratch[j, 4] = scratch[p, 4] + wz * dx - wx * dz
    scratch[j, 5] = scratch[p, 5] + wx * dy - wy * dx


@njit(**JIT)
def _turn_point(turn, point, shift):
    """``point = turn @ point + shift`` in place for a yaw ``turn``; ``shift`` empty: no shift."""
    x, y = point[0], point[1]
    point[0] = turn[0, 0] * x + turn[0, 1] * y + turn[0, 2] * point[2]
    point[1] = turn[1, 0] * x + turn[1, 1] * y + turn[1, 2] * point[2]
    point[2] = turn[2, 0] * x + turn[2, 1] * y + turn[2, 2] * point[2]
    if shift.shape[0] == 3:
        for r in range(3):
            point[r] += shift[r]


class MeasurementResult(NamedTuple):
    """One :meth:`CompiledMeasurement.measure` (views of the kernel's outputs: valid until the next call).

    Attributes:
        q, v: the state in pinocchio's convention.
        com, com_velocity: CoM [m] and its velocity [m/s].
        rotations, positions: (4, 3, 3) and (4, 3) [m]: ankle sensors (right, left), soles (right, left).
        turn, shift: the map from the world into the plan's frame, ``x -> turn @ x + shift`` (identity and zero
            without the stance frame).
        zmp: ZMP (x, y) [m], or None when no foot carries ``min_force``.
        cop, normal_force, moment: as :class:`~.zmp_estimator.ZmpEstimate`.
    """

    q: NDArray[np.float64]
    v: NDArray[np.float64]
    com: NDArray[np.float64]
    com_velocity: NDArray[np.float64]
    rotations: NDArray[np.float64]
    positions: NDArray[np.float64]
    turn: NDArray[np.float64]
    shift: NDArray[np.float64]
    zmp: NDArray[np.float64] | None
    cop: NDArray[np.float64]
    normal_force: NDArray[np.float64]
    moment: NDArray[np.float64]


class CompiledMeasurement:
    """The walking controller's measurement (see the module docstring) as one kernel call.

    Args:
        model: the floating-base model (1-DoF joints and a free flyer: :meth:`RobotModel.serial_chain`).
        frames: the four frames measured (ankle sensors right, left, then soles right, left), names or indices.

    Raises:
        ModelError: a model the compiled kinematics do not cover (a joint other than 1-DoF or a free flyer).
        ControllerError: not four frames.
    """

    def __init__(self, model: RobotModel, frames: tuple[str | int, ...]) -> None:
        if len(frames) != FRAMES:
            raise ControllerError(f"CompiledMeasurement measures {FRAMES} frames, got {len(frames)}: {frames!r}")
        chain = model.serial_chain()
        nj, nq, nv = chain.num_joints, model.nq, model.nv
        frame_joint, frame_rotation, frame_translation = model.frame_attachments(frames)
        outputs = nq + nv + sum(size for _, size in OUTPUT_SIZES)
        floats, ints = chain_arrays(chain)
        floats |= {
            "body_mass": chain.body_mass,
            "body_com": chain.body_com,
            "velocities": np.zeros((nj, 6)),
            "frame_rotation": frame_rotation,
            "frame_translation": frame_translation,
            "inputs": np.zeros(nq + nv + 12 + len(PARAMETERS)),
            "outputs": np.zeros(outputs),
        }
        ints["dims"] = np.array([nj, nq, nv, FRAMES], dtype=np.int64)
        ints["frame_joint"] = frame_joint
        self._nq, self._nv = nq, nv
        self._f, self._i = pack_fields(floats, ints, FLOAT_FIELDS, INT_FIELDS)
        inputs = buffer_view(self._f, self._i, FLOAT_FIELDS, "inputs")
        out = buffer_view(self._f, self._i, FLOAT_FIELDS, "outputs")
        # views sliced once: measure() runs once per control period
        self._q_in, self._v_in = inputs[:nq], inputs[nq : nq + nv]
        self._sensors_in = inputs[nq + nv : nq + nv + 12]
        self._params = inputs[nq + nv + 12 :]
        views: dict[str, NDArray[np.float64]] = {"q": out[:nq], "v": out[nq : nq + nv]}
        o = nq + nv
        for name, size in OUTPUT_SIZES:
            views[name] = out[o : o + size]
            o += size
        self._views = views
        self._rotations = views["rotations"].reshape(FRAMES, 3, 3)
        self._positions = views["positions"].reshape(FRAMES, 3)
        self._turn = views["turn"].reshape(3, 3)
        self._cop = views["cop"].reshape(2, 2)
        self._moment = views["moment"].reshape(2, 3)
        self._kernel = LazyEntryPoint(self, "_kernel", measure_step, "int64(float64[::1], int64[::1])")

    def measure(
        self,
        q: NDArray[np.float64],
        v: NDArray[np.float64],
        sensors: NDArray[np.float64],
        *,
        mujoco: bool,
        stance_frame: bool,
        stance: int,
        planned: tuple[float, float, float],
        ground: float,
        min_force: float = 20.0,
    ) -> MeasurementResult | None:
        """Measure a state; None for a non-finite input or a zero base quaternion (nothing to read then).

        Args:
            q, v: the configuration and velocity, MuJoCo's ``qpos``, ``qvel`` (``mujoco``) or pinocchio's; float64
                arrays of the model's sizes (not checked here).
            sensors: the ankle wrenches [N, N m] in the sensor frames: 12 floats, ``(F_r, T_r, F_l, T_l)`` (the
                observation's order).
            mujoco: the state is MuJoCo's.
            stance_frame: move the measurement into the stance foot's planned pose.
            stance: the stance foot (0 right, 1 left).
            planned: the stance sole's planned position (x, y) [m] and heading [rad].
            ground: ground height [m].
            min_force: vertical force [N] below which a foot counts as unloaded.
        """
        self._q_in[:] = q
        self._v_in[:] = v
        self._sensors_in[:] = sensors
        self._params[:] = (
            1.0 if mujoco else 0.0,
            1.0 if stance_frame else 0.0,
            float(stance),
            *planned,
            ground,
            min_force,
        )
        if self._kernel(self._f, self._i) != OK:
            return None
        views = self._views
        zmp = views["zmp"]
        return MeasurementResult(
            views["q"],
            views["v"],
            views["com"],
            views["com_velocity"],
            self._rotations,
            self._positions,
            self._turn,
            views["shift"],
            zmp[:2] if zmp[2] != 0.0 else None,
            self._cop,
            views["normal_force"],
            self._moment,
        )


def renamed_attribute(module: str, name: str) -> Any:
    """The module ``__getattr__`` of ``module`` (this one and :mod:`redundancy_gym.controllers.walking`):
    ``Measurement``, the old name of :class:`MeasurementResult` (a result, not the measurement), kept for one
    release with a :class:`DeprecationWarning` (pointing at the caller of ``__getattr__``)."""
    if name == "Measurement":
        warnings.warn(
            f"{module}.Measurement is now MeasurementResult; the old name goes in redundancy_gym 0.3",
            DeprecationWarning,
            stacklevel=3,
        )
        return MeasurementResult
    raise AttributeError(f"module {module!r} has no attribute {name!r}")


def __getattr__(name: str) -> Any:
    """``Measurement``: the old name of :class:`MeasurementResult` (:func:`renamed_attribute`)."""
    return renamed_attribute(__name__, name)
