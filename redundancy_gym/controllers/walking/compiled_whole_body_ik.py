"""A :class:`WholeBodyIk` compiled into one fused kernel call per control period (same results, a fraction of
the time)."""

from __future__ import annotations

import math
from typing import TypeGuard

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...kernel_options import LazyEntryPoint
from ...model import ModelError
from ..exceptions import ControllerError
from ..kernels.buffers import buffer_view, pack_fields
from ..kernels.chain_fields import chain_arrays
from ..objectives.actuated_objective import ActuatedObjective
from ..objectives.collision_kernels import bounding_spheres, collision_fields, no_collision_arrays
from ..objectives.collision_objective import CollisionObjective
from ..objectives.joint_limit_objective import JointLimitObjective
from ..objectives.objective_fields import objective_arrays
from ..objectives.posture_objective import PostureObjective
from .whole_body_ik import Reference, WholeBodyIk, WholeBodyIkResult, WholeBodyReference
from .whole_body_kernels import (
    BAD_INPUT,
    DIMS,
    FLOAT_FIELDS,
    INT_FIELDS,
    OUTPUT_EXTRA,
    REFERENCE_SIZE,
    SCALARS,
    SCRATCH_SIZE,
    whole_body_step,
)

__all__ = ["CompiledWholeBodyIk"]

_FLOAT64 = np.dtype(np.float64)
_REFERENCE_SHAPE = (REFERENCE_SIZE,)


def _is_float_array(value: object, shape: tuple[int, ...]) -> TypeGuard[NDArray[np.float64]]:
    """Whether ``value`` is a float64 array of ``shape`` (copied into the kernel's buffer as it is)."""
    return type(value) is np.ndarray and value.dtype == _FLOAT64 and value.shape == shape


class CompiledWholeBodyIk:
    """The step of a :class:`WholeBodyIk` as one compiled kernel (:mod:`.whole_body_kernels`).

    It gives the :meth:`WholeBodyIk.step` result to round-off (a test holds it to that) for nullspace
    objectives that are :class:`ActuatedObjective` of a :class:`JointLimitObjective` or
    :class:`PostureObjective`, plus at most one self-collision :class:`CollisionObjective` (robot segments
    only). The model's kinematics come from :meth:`~redundancy_gym.model.RobotModel.serial_chain` (a free
    flyer and 1-DoF joints).

    Args:
        ik: the whole-body IK to compile.

    Raises:
        ControllerError: for an objective the kernel does not cover (the message lists what it covers).
    """

    def __init__(self, ik: WholeBodyIk) -> None:
        if not isinstance(ik, WholeBodyIk):
            raise ControllerError(f"CompiledWholeBodyIk compiles a WholeBodyIk, got {type(ik).__name__}")
        model = ik.model
        chain = model.serial_chain()
        nj, nq, nv = chain.num_joints, model.nq, model.nv
        base_nq, base_nv = model.base_dofs
        na = nv - base_nv
        limits, postures, collisions = [], [], []
        for objective in ik.objectives:
            inner = objective.objective if isinstance(objective, ActuatedObjective) else None
            if isinstance(inner, JointLimitObjective) and inner.lower.shape == (na,):
                limits.append(inner)
            elif isinstance(inner, PostureObjective) and inner.reference.shape == (na,):
                postures.append(inner)
            elif isinstance(objective, CollisionObjective) and not objective.collision_model.environment:
                collisions.append(objective)
            else:
                raise ControllerError(
                    "CompiledWholeBodyIk supports ActuatedObjective(JointLimitObjective or PostureObjective over the "
                    f"{na} actuated joints) and one CollisionObjective without environment segments; got "
                    f"{type(objective).__name__}"
                )
        if len(collisions) > 1:
            raise ControllerError("CompiledWholeBodyIk supports at most one CollisionObjective")
        self.ik = ik
        self.model = model
        self._nq, self._nv = nq, nv
        self._q_shape = (nq,)
        frame_joint, frame_rotation, frame_translation = model.frame_attachments((*ik.feet_frames, ik.torso_frame))
        floats, ints = chain_arrays(chain)
        floats |= {
            "body_mass": chain.body_mass,
            "body_com": chain.body_com,
            "body_inertia": chain.body_inertia,
            "composite": np.zeros((nj, 13)),
            "frame_rotation": frame_rotation,
            "frame_translation": frame_translation,
            **objective_arrays(limits, postures),
            "scalars": np.zeros(len(SCALARS)),
            "inputs": np.zeros(nq + 2 * REFERENCE_SIZE),
            "outputs": np.zeros(nq + nv + OUTPUT_EXTRA),
            "jacobian": np.zeros((18, nv)),
            "jacobian6": np.zeros((6, nv)),
            "jacobian_com": np.zeros((3, nv)),
            "jacobian_angular": np.zeros((3, nv)),
            "error": np.zeros(18),
            "rhs": np.zeros(18),
            "gradient": np.zeros(nv),
            "scratch": np.zeros(SCRATCH_SIZE),
        }
        ints["frame_joint"] = frame_joint
        self.collision: CollisionObjective | None = collisions[0] if collisions else None
        if self.collision is None:
            empty_floats, empty_ints, counts = no_collision_arrays()
            floats.update(empty_floats)
            ints.update(empty_ints)
        else:
            fields = collision_fields(self.collision, model)
            if fields.world_fixed:
                raise ControllerError("CompiledWholeBodyIk needs every collision segment on a moving joint")
            layout = fields.layout
            centers, bounds = bounding_spheres(layout.local, layout.kinds, layout.radii, layout.segment_starts)
            fields.floats["segment_center"] = centers
            fields.floats["segment_radius"] = bounds
            floats.update(fields.floats)
            ints.update(fields.ints)
            counts = fields.counts
        dims = {
            "joints": nj,
            "nq": nq,
            "nv": nv,
            "base_nq": base_nq,
            "base_nv": base_nv,
            "limit_objectives": len(limits),
            "posture_objectives": len(postures),
            **counts,
            "collision": int(self.collision is not None),
            "momentum_minimization": int(ik.momentum_minimization),
        }
        ints["dims"] = np.array([dims[name] for name in DIMS], dtype=np.int64)
        self._f, self._i = pack_fields(floats, ints, FLOAT_FIELDS, INT_FIELDS)
        self._inputs = self._field("inputs")
        self._outputs = self._field("outputs")
        self._scalars = self._field("scalars")
        # views of the kernel's inputs and outputs, sliced once: step() runs once per control period, where
        # numpy's per-call overhead is a noticeable part of the wrapper's cost
        self._q_input = self._inputs[:nq]
        self._reference_inputs = (
            self._inputs[nq : nq + REFERENCE_SIZE],
            self._inputs[nq + REFERENCE_SIZE : nq + 2 * REFERENCE_SIZE],
        )
        self._q_output, self._qdot_output = self._outputs[:nq], self._outputs[nq : nq + nv]
        self._extra_output = self._outputs[nq + nv :]
        self._scalars[:] = [
            ik.gain,
            ik.gamma,
            ik.beta,
            ik.nullspace_gain,
            ik.damping,
            ik.singular_threshold,
            ik.max_velocity,
            0.0,
        ]
        self._kernel = LazyEntryPoint(self, "_kernel", whole_body_step, "int64(float64[::1], int64[::1])")

    def _field(self, name: str) -> NDArray[np.float64]:
        """The view of one float field of the kernel buffer (writes reach the kernel)."""
        return buffer_view(self._f, self._i, FLOAT_FIELDS, name)

    def step(self, q: ArrayLike, start: Reference, end: Reference, dt: float) -> WholeBodyIkResult:
        """:meth:`WholeBodyIk.step` (same arguments, same result to round-off) in one kernel call; the references
        may be given packed (:meth:`WholeBodyReference.to_array`), which saves their conversion."""
        if (
            type(dt) is float
            and 0.0 < dt < math.inf
            and _is_float_array(q, self._q_shape)
            and _is_float_array(start, _REFERENCE_SHAPE)
            and _is_float_array(end, _REFERENCE_SHAPE)
        ):
            # the walking controller's inputs (float64 arrays of the right shapes): copied in without conversions
            self._q_input[...] = q
            self._reference_inputs[0][...] = start
            self._reference_inputs[1][...] = end
        else:
            q = self._checked_inputs(q, start, end, dt)
        self._scalars[-1] = dt
        if self._kernel(self._f, self._i) == BAD_INPUT:
            if not np.all(np.isfinite(q)):
                raise ModelError("configuration contains non-finite values")
            raise ControllerError("the references must be finite")
        error, lz, sigma, success, _, _, limited = self._extra_output.tolist()
        return WholeBodyIkResult(
            self._q_output.copy(), self._qdot_output.copy(), error, lz, sigma, bool(success), bool(limited)
        )

    def _checked_inputs(self, q: ArrayLike, start: Reference, end: Reference, dt: float) -> NDArray[np.float64]:
        """Check and copy :meth:`step`'s inputs of any type into the kernel's buffer; returns ``q`` as an array."""
        if not (isinstance(dt, float) and 0.0 < dt < math.inf):  # the usual float dt passes without numpy
            if not np.isfinite(dt) or dt <= 0.0:
                raise ControllerError(f"dt must be finite and > 0, got {dt!r}")
        nq = self._nq
        q = np.asarray(q, dtype=np.float64)
        if q.shape != (nq,):
            raise ModelError(f"configuration must have shape ({nq},), got {q.shape}")
        self._q_input[...] = q
        for reference, view in zip((start, end), self._reference_inputs, strict=False):
            packed = reference.to_array() if isinstance(reference, WholeBodyReference) else reference
            shape = packed.shape if type(packed) is np.ndarray else np.shape(packed)
            if shape != (REFERENCE_SIZE,):
                raise ControllerError(f"a packed reference has shape ({REFERENCE_SIZE},), got {shape}")
            view[...] = packed
        return q

    @property
    def last_min_distance(self) -> float:
        """Smallest self-collision distance [m] the last step computed exactly (pairs whose segments' bounding
        spheres came within the activation distance); +inf when there were none or no collision objective."""
        return float(self._outputs[self._nq + self._nv + 4])
