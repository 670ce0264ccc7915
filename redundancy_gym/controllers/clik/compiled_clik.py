"""A :class:`Clik` compiled into one fused kernel call per control step (same results, a fraction of the time)."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...geometry import PackedVolumes
from ...kernel_options import LazyEntryPoint
from ...model import ModelError
from ..exceptions import ControllerError
from ..kernels.buffers import buffer_view
from ..kernels.chain_fields import chain_arrays
from ..objectives.collision_kernels import bounding_spheres, collision_fields, no_collision_arrays
from ..objectives.collision_objective import CollisionObjective
from ..objectives.joint_limit_objective import JointLimitObjective
from ..objectives.objective_fields import objective_arrays
from ..objectives.posture_objective import PostureObjective
from ..tasks.frame_axis_task import FrameAxisTask
from ..tasks.frame_position_task import FramePositionTask
from .clik import Clik, ClikResult
from .clik_kernels import (
    BAD_CONFIGURATION,
    BAD_INPUT,
    BAD_TARGET,
    BAD_VELOCITY,
    DIMS,
    FLOAT_FIELDS,
    METHOD_CODES,
    OK,
    OUTPUT_EXTRA,
    SCRATCH_SIZE,
    STATUS_NAMES,
    STEPPED,
    ZERO_AXIS,
    clik_close_pairs,
    clik_step,
    clik_step_arrays,
    pack_buffers,
)
from .redundancy_resolution import as_float_array, check_configuration, check_finite

__all__ = ["CompiledClik"]

SUPPORTED_TASKS = (FrameAxisTask, FramePositionTask)
_OptionalArray = ArrayLike | None
SUPPORTED_OBJECTIVES = (JointLimitObjective, PostureObjective, CollisionObjective)


def _vector(values: ArrayLike, name: str, size: int, error: type[Exception]) -> NDArray[np.float64]:
    """``values`` as a float64 vector of ``size`` entries (a float64 array of that shape passes as it is: the hot
    path); ``error`` naming ``name`` otherwise (finiteness is the kernel's check)."""
    if type(values) is np.ndarray and values.dtype == np.float64 and values.shape == (size,):
        return values
    array = as_float_array(values, name)
    if array.shape != (size,):
        what = "configuration" if name == "q" else name
        raise error(f"{what} must have shape ({size},), got {array.shape}")
    return array


class CompiledClik:
    """The step of a :class:`Clik` as one compiled kernel (:mod:`.clik_kernels`): kinematics of the robot's
    serial chain (:meth:`~redundancy_gym.model.RobotModel.serial_chain`), the task, every objective and the
    (damped) solve of Algorithm 10, (5.14), (5.22) with no Python in between.

    It gives the :meth:`Clik.step` result to round-off (a test holds it to that) for
    :class:`FrameAxisTask` or :class:`FramePositionTask`, diagonal weights, and any number of
    :class:`JointLimitObjective` and :class:`PostureObjective` plus at most one :class:`CollisionObjective`.
    Collision pairs are evaluated exactly wherever they can be closer than the activation distance (segment
    bounding spheres skip the others, which contribute nothing); the collision model's environment is read
    again whenever it changes (:attr:`~redundancy_gym.geometry.CollisionModel.version`). The command is bounded
    to the clik's speed limits and joint ranges as :meth:`Clik.solve` bounds it (same ``limited`` flag), and
    non-finite inputs raise the same :class:`ControllerError`. Build and solve are
    fused here, so there is no separate ``build``; use :class:`Clik` to inspect a :class:`ClikProblem`.

    Args:
        clik: the controller to compile.

    Raises:
        ControllerError: for a task, weight or objective the kernel does not cover (the message lists what
            it covers).
        ModelError: when the robot is not a chain of 1-DoF revolute and prismatic joints.
    """

    def __init__(self, clik: Clik) -> None:
        if not isinstance(clik, Clik):
            raise ControllerError(f"CompiledClik compiles a Clik, got {type(clik).__name__}")
        task = clik.task
        if not isinstance(task, SUPPORTED_TASKS):
            raise ControllerError(
                f"CompiledClik supports the tasks {', '.join(t.__name__ for t in SUPPORTED_TASKS)}"
                f", got {type(task).__name__}"
            )
        if clik.weights.diagonal is None:
            raise ControllerError("CompiledClik supports diagonal weights only; use Clik for a full W")
        unknown = [type(o).__name__ for o in clik.objectives if not isinstance(o, SUPPORTED_OBJECTIVES)]
        if unknown:
            raise ControllerError(
                f"CompiledClik supports the objectives "
                f"{', '.join(o.__name__ for o in SUPPORTED_OBJECTIVES)}, got {', '.join(unknown)}"
            )
        collisions = [o for o in clik.objectives if isinstance(o, CollisionObjective)]
        if len(collisions) > 1:
            raise ControllerError("CompiledClik supports at most one CollisionObjective")
        self.clik = clik
        self.model = clik.model
        chain = clik.model.serial_chain()
        nj = chain.num_joints
        nq, nv, m = clik.model.nq, clik.model.nv, task.dim
        self._nq, self._nv, self._m = nq, nv, m
        self._width = 6 if isinstance(task, FrameAxisTask) else m  # target entries: [p_d, a_d] or the rows
        joint, frame_rotation, frame_translation = clik.model.frame_attachment(task.frame)
        limits = [o for o in clik.objectives if isinstance(o, JointLimitObjective)]
        postures = [o for o in clik.objectives if isinstance(o, PostureObjective)]
        for o in limits:
            if o.lower.shape != (nq,):
                raise ControllerError(f"joint-limit objective has {o.lower.size} joints, the model {nq}")
        for p in postures:
            if p.reference.shape != (nq,):
                raise ControllerError(f"posture objective has {p.reference.size} joints, the model {nq}")
        self.collision: CollisionObjective | None = collisions[0] if collisions else None
        floats, ints = chain_arrays(chain)
        floats |= {
            "task_rotation": frame_rotation,
            "task_translation": frame_translation,
            "gain": clik.gain,
            "inverse_weights": 1.0 / clik.weights.diagonal,
            "scalars": np.array(
                [
                    clik.nullspace_gain,
                    clik.singular_threshold,
                    clik.dls_threshold,
                    clik.dls_max_damping,
                    clik.bounds.period or 0.0,
                ]
            ),
            **objective_arrays(limits, postures),
            "inputs": np.zeros(nq + 12 + nv),
            "outputs": np.zeros(nv + m + OUTPUT_EXTRA),
            "jacobian6": np.zeros((6, nv)),
            "jacobian": np.zeros((m, nv)),
            "gradient": np.zeros(nv),
            "scratch": np.zeros(SCRATCH_SIZE),
            "max_velocity": clik.bounds.max_velocity,
            "position_lower": clik.bounds.lower,
            "position_upper": clik.bounds.upper,
        }
        ints |= {
            "task_rows": task.rows if isinstance(task, FramePositionTask) else np.zeros(0, dtype=np.int64),
            "position_q_index": clik.bounds.q_index,
            "position_v_index": clik.bounds.v_index,
        }
        counts = self._collision_fields(floats, ints)
        dims = {
            "joints": nj,
            "nv": nv,
            "nq": nq,
            "task_dim": m,
            "limit_objectives": len(limits),
            "posture_objectives": len(postures),
            **counts,
            "task_kind": 1 if isinstance(task, FrameAxisTask) else 0,
            "task_joint": joint,
            "task_axis": task.axis if isinstance(task, FrameAxisTask) else 0,
            "method": METHOD_CODES[clik.method],
            "collision": int(self.collision is not None),
            "objectives": int(bool(clik.objectives)),
            "bounded_joints": int(clik.bounds.q_index.size),
        }
        ints["dims"] = np.array([dims[name] for name in DIMS], dtype=np.int64)
        self._f, self._i = pack_buffers(floats, ints)
        self._inputs = self._field("inputs")
        self._outputs = self._field("outputs")
        self._version = -1
        self._refresh_environment()
        self._kernel = LazyEntryPoint(self, "_kernel", clik_step, "int64(float64[::1], int64[::1], boolean, boolean)")
        # q, target and velocity in any layout (a strided view of an observation is read as it is)
        self._array_kernel = LazyEntryPoint(
            self,
            "_array_kernel",
            clik_step_arrays,
            "int64(float64[::1], int64[::1], float64[:], float64[:], float64[:], boolean)",
        )
        self._close_pairs = clik_close_pairs
        self._pair_distances = np.zeros(8)
        self._pair_rows = np.zeros((8, nv))
        self._no_velocity = np.zeros(self._width)  # passed (unread) when a step has no target velocity

    def _field(self, name: str) -> NDArray[np.float64]:
        """The view of one float field of the kernel buffer (writes reach the kernel)."""
        return buffer_view(self._f, self._i, FLOAT_FIELDS, name)

    def _collision_fields(
        self, floats: dict[str, NDArray[np.float64]], ints: dict[str, NDArray[np.int64]]
    ) -> dict[str, int]:
        """The collision model's segments, volumes and pairs into the kernel fields; returns their counts."""
        if self.collision is None:
            empty_floats, empty_ints, counts = no_collision_arrays()
            floats.update(empty_floats)
            ints.update(empty_ints)
            return counts
        fields = collision_fields(self.collision, self.model)
        floats.update(fields.floats)
        ints.update(fields.ints)
        self._world_fixed = list(fields.world_fixed)
        self._layout = fields.layout
        self._robot_segments = fields.robot_segments
        self._robot_volumes = int(fields.layout.segment_starts[fields.robot_segments])
        return dict(fields.counts)

    def _refresh_environment(self) -> None:
        """Environment volumes (world), all radii and every segment's bounding sphere from the collision model."""
        if self.collision is None:
            return
        model = self.collision.collision_model
        if model.version == self._version:
            return
        env: PackedVolumes = model.environment_volumes()
        layout = self._layout
        nr = self._robot_volumes
        self._field("vertices").reshape(-1, 3, 3)[nr:] = env.vertices
        radii = self._field("radii")
        radii[nr:] = env.radii
        # bounding spheres: robot segments in their frame, environment segments in the world
        local = layout.local.copy()
        local[nr:] = env.vertices
        centers, bounds = bounding_spheres(local, layout.kinds, radii, layout.segment_starts)
        self._field("segment_center")[:] = centers.reshape(-1)
        self._field("segment_radius")[:] = bounds
        world = self._field("segment_world_center").reshape(-1, 3)
        world[self._robot_segments :] = centers[self._robot_segments :]
        vertices = self._field("vertices").reshape(-1, 3, 3)
        for s, rotation, translation in self._world_fixed:
            sl = slice(layout.segment_starts[s], layout.segment_starts[s + 1])
            vertices[sl] = layout.local[sl] @ rotation.T + translation
            world[s] = rotation @ centers[s] + translation
        self._version = model.version

    def kernel_buffers(self) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
        """The float and int buffers that :func:`~.clik_kernels.clik_step` reads and writes, with the collision
        model's environment brought up to date: for a caller that runs ``clik_step`` inside its own compiled
        function (call it before every such step, since the environment may have moved; build the result of a
        step with :meth:`result`)."""
        if self.collision is not None and self.collision.collision_model.version != self._version:
            self._refresh_environment()
        return self._f, self._i

    @property
    def output_size(self) -> int:
        """Entries of the kernel's ``outputs`` field (qdot, task error, diagnostics), as :meth:`result` reads
        them."""
        return int(self._outputs.size)

    def result(self, outputs: NDArray[np.float64] | None = None) -> ClikResult:
        """The :class:`ClikResult` of the last step's ``outputs`` (or of a copy of them, ``outputs``)."""
        out = self._outputs if outputs is None else outputs
        nv, m = self._nv, self._m
        norm, sigma, damping, value, status, _, limited, _ = out[nv + m :].tolist()
        name = STATUS_NAMES[int(status)]
        return ClikResult(
            out[:nv].copy(),
            out[nv : nv + m].copy(),
            norm,
            sigma,
            damping,
            value,
            name != "singular",
            name,
            limited != 0.0,
        )

    def step(
        self,
        q: ArrayLike,
        target: ArrayLike,
        target_velocity: _OptionalArray = None,
        nullspace_input: _OptionalArray = None,
    ) -> ClikResult:
        """:meth:`Clik.step` (same arguments, same result to round-off) in one kernel call."""
        if self.collision is not None and self.collision.collision_model.version != self._version:
            self._refresh_environment()
        width = self._width
        q = _vector(q, "q", self._nq, ModelError)
        target = _vector(target, "target", width, ControllerError)
        has_velocity = target_velocity is not None
        velocity = (
            self._no_velocity
            if target_velocity is None
            else _vector(target_velocity, "target_velocity", width, ControllerError)
        )
        if nullspace_input is None:  # the common step: the arrays go straight to the kernel
            code = self._array_kernel(self._f, self._i, q, target, velocity, has_velocity)
        else:
            code = self._step_with_input(q, target, velocity, has_velocity, nullspace_input)
        if code != OK:
            self._raise(code, q, target, target_velocity)
        return self.result()

    def _step_with_input(
        self,
        q: NDArray[np.float64],
        target: NDArray[np.float64],
        velocity: NDArray[np.float64],
        has_velocity: bool,
        nullspace_input: ArrayLike,
    ) -> int:
        """The kernel call of a step with a nullspace input ``u`` (5.100); returns its code."""
        nq, width, nv = self._nq, self._width, self._nv
        inputs = self._inputs
        inputs[:nq] = q
        inputs[nq : nq + width] = target
        if has_velocity:
            inputs[nq + 6 : nq + 6 + width] = velocity
        if getattr(nullspace_input, "shape", None) != (nv,):  # an array of nv is the fast path
            try:
                nullspace_input = np.asarray(nullspace_input, dtype=np.float64)
            except (TypeError, ValueError):
                nullspace_input = np.zeros(0)
            if nullspace_input.shape != (nv,):
                raise ControllerError(f"nullspace_input must be finite with shape ({nv},), got {nullspace_input.shape}")
        try:  # the kernel checks finiteness (BAD_INPUT)
            inputs[nq + 12 : nq + 12 + nv] = nullspace_input
        except (TypeError, ValueError) as exc:  # an array of strings or objects
            raise ControllerError("nullspace_input must be an array of finite numbers") from exc
        return int(self._kernel(self._f, self._i, has_velocity, True))

    @staticmethod
    def _raise(
        code: int, q: NDArray[np.float64], target: NDArray[np.float64], target_velocity: ArrayLike | None
    ) -> None:
        """The :class:`ControllerError` of a kernel return code, worded as :meth:`Clik.step` words it."""
        if code == BAD_CONFIGURATION:
            check_configuration(q, "q")
        elif code == BAD_TARGET:
            check_finite(target, "target")
        elif code == BAD_VELOCITY:
            check_finite(np.asarray(target_velocity, dtype=np.float64), "target_velocity")
        elif code == BAD_INPUT:
            raise ControllerError("nullspace_input must be finite")
        elif code == ZERO_AXIS:
            raise ControllerError("the target axis must not be zero")
        raise ControllerError(f"the CLIK kernel returned code {code}")  # not reached: each check above raises

    @property
    def last_gradient(self) -> NDArray[np.float64]:
        """``(dH/dq)^T`` of the summed objectives at the last step's configuration (nv), as :class:`ClikProblem`
        gives it (zeros when the controller has no objectives)."""
        return self._field("gradient").copy()

    def close_pairs(self, limit: float, capacity: int = 8) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The collision pairs nearer than ``limit`` [m] at the configuration of the last :meth:`step`: their
        distances [m] (k) and gradients ``dd/dq`` (5.61) (k x nv), at most ``capacity`` of them (the nearest).
        Empty when the controller has no collision objective (or no step was made yet)."""
        nv = self._nv
        if self.collision is None or self._outputs[nv + self._m + STEPPED] != 1.0:  # no step, or a failed one
            return np.zeros(0), np.zeros((0, nv))
        if self._pair_rows.shape[0] != capacity:
            self._pair_distances = np.zeros(capacity)
            self._pair_rows = np.zeros((capacity, nv))
        count = self._close_pairs(self._f, self._i, float(limit), self._pair_distances, self._pair_rows)
        return self._pair_distances[:count].copy(), self._pair_rows[:count].copy()

    @property
    def last_min_distance(self) -> float:
        """Smallest distance [m] among the collision pairs the last step computed exactly (those whose
        segments' bounding spheres came within the activation distance); +inf when there were none."""
        return float(self._outputs[self._nv + self._m + 5])
