"""Predictive inverse kinematics (monograph 5.6): the nullspace input over a horizon by Pontryagin's principle
and the conjugate gradient method (algorithm 11).

The problem (5.100)-(5.103), (5.130) on ``N`` samples of ``dt``: find the nullspace inputs ``u_k`` that
minimize ``Phi = sum_k dt [w_v qdot_k^T qdot_k + H_jl(q_k) + H_c(q_k)]`` with ``qdot_k = J# wdot_k + N u_k``
and ``q_{k+1} = q_k + dt qdot_k`` from the measured ``q_0`` (5.111)-(5.116). A forward integration gives the
trajectory and the cost, a backward integration of the adjoint gives the exact gradient of the cost with
respect to every input (:mod:`.predictive_kernels`), and the conjugate gradient method (Fletcher-Reeves, as
printed in algorithm 11; steepest descent for comparison) with a backtracking (Armijo) step size improves
the inputs.

With ``augmented=True`` the state is ``(q, u)`` and the input is ``udot`` (5.120)-(5.129): ``u_0 = u_b`` is
fixed (the input applied last), so the joint velocity stays continuous from one update to the next; the
cost adds ``w_a udot^T udot`` (A.62).
"""

from __future__ import annotations

import warnings
from typing import Any, NamedTuple, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...kernel_options import DEFAULT_BACKEND
from ...model import RobotModel
from ...validation import check_backend, check_real
from ..clik.redundancy_resolution import as_float_array
from ..exceptions import ControllerError
from ..objectives.collision_kernels import bounding_spheres, collision_fields
from ..objectives.collision_objective import CollisionObjective
from ..objectives.joint_limit_objective import JointLimitObjective
from ..tasks.frame_axis_task import FrameAxisTask
from ..tasks.frame_position_task import FramePositionTask
from .predictive_kernels import (
    METHODS,
    OVERFLOW,
    SINGULAR,
    SLOTS,
    STATUS,
    pik_command,
    pik_gradient,
    pik_optimize,
    pik_rollout,
    slot_size,
)

__all__ = ["DESCENT_METHODS", "PredictiveIk", "PredictiveResult", "PredictiveRollout"]

DESCENT_METHODS = METHODS
"""Descent directions of :meth:`PredictiveIk.optimize` ("fletcher_reeves", "polak_ribiere", "steepest_descent")."""


def resolve_backend(backend: str, compiled: bool | None, *, stacklevel: int) -> str:
    """``backend`` checked (:func:`~redundancy_gym.validation.check_backend`), or the one that the deprecated
    ``compiled`` keyword names (with a :class:`DeprecationWarning`; ``stacklevel`` points it at the caller's call).

    Raises:
        ControllerError: an unknown ``backend``, a ``compiled`` that is no bool, or ``compiled`` contradicting a
            ``backend`` other than the default.
    """
    backend = check_backend("backend", backend, error=ControllerError)
    if compiled is None:
        return backend
    if not isinstance(compiled, (bool, np.bool_)):
        raise ControllerError(f"compiled must be a bool (deprecated: use backend=), got {compiled!r}")
    implied = "compiled" if compiled else "python"
    warnings.warn(
        f"compiled={bool(compiled)} is deprecated and goes in redundancy_gym 0.3; use backend={implied!r}",
        DeprecationWarning,
        stacklevel=stacklevel,
    )
    # the default backend cannot be told from one left out, so only another backend contradicts compiled
    if backend != DEFAULT_BACKEND and backend != implied:
        raise ControllerError(f"compiled={bool(compiled)} contradicts backend={backend!r}; pass backend only")
    return implied


class PredictiveRollout(NamedTuple):
    """A forward integration (5.112).

    Attributes:
        q: configurations ``q_0 .. q_N`` (N + 1, n) [rad or m].
        qdot: joint velocities of each sample (N, n).
        u: the nullspace inputs of each sample (N, n).
        cost: total cost ``Phi``.
        terms: the cost's parts: velocity (5.131), joint limits (5.58), collision (5.49), input rate (A.62).
    """

    q: NDArray[np.float64]
    qdot: NDArray[np.float64]
    u: NDArray[np.float64]
    cost: float
    terms: dict[str, float]

    def follow(self, k: int, q: ArrayLike, gain: float, fraction: float = 0.0) -> NDArray[np.float64]:
        """The nullspace input that follows this plan at ``fraction`` (in [0, 1)) of sample ``k`` from the
        measured ``q``: ``u_k + K (q_plan - q)`` with ``q_plan`` interpolated between ``q_k`` and ``q_{k+1}``
        (after the last sample ``K (q_N - q)``).

        The plan's inputs alone are open loop in the nullspace: the self-motion has no restoring term, so a
        small drift of the executed configuration from the planned one can grow (on the fig. 5.10 move of the
        9-DoF arm, 1 mm became 1.7 rad within 0.5 s). The feedback term ties the self-motion to the planned
        joint path; its task-space part is projected out by ``N`` like the rest of ``u``.
        """
        if not np.isfinite(gain) or gain < 0.0:
            raise ControllerError(f"gain must be finite and >= 0, got {gain!r}")
        q = np.asarray(q, dtype=np.float64)
        steps = self.u.shape[0]
        if k < 0 or q.shape != self.q.shape[1:] or not 0.0 <= fraction < 1.0:
            raise ControllerError(
                f"k must be >= 0, fraction in [0, 1) and q of shape {self.q.shape[1:]}, got {k!r}, "
                f"{fraction!r} and {q.shape}"
            )
        if k >= steps:
            return gain * (self.q[-1] - q)
        planned = self.q[k] + fraction * (self.q[k + 1] - self.q[k])
        return self.u[k] + gain * (planned - q)


class PredictiveResult(NamedTuple):
    """Result of :meth:`PredictiveIk.optimize`.

    Attributes:
        params: the optimized decision variables (``u`` (N, n), or ``udot`` when augmented).
        rollout: the trajectory of ``params``.
        costs: the cost after each iteration, the initial cost first.
        iterations: descent steps taken.
        status: why it stopped: ``"converged"`` (relative decrease below the tolerance), ``"max_iterations"``
            or ``"no_decrease"`` (the line search found no lower cost: a minimum to the step size's resolution).
        success: False only when the kinematics failed (singular ``J J^T + rho I``).
        step: the step size the next line search would start from (twice the last accepted one), for a warm
            start of the next optimization.
        rollouts: forward integrations (5.112) run, each line-search trial counted (also those the compiled loop
            stopped early above the Armijo threshold).
    """

    params: NDArray[np.float64]
    rollout: PredictiveRollout
    costs: tuple[float, ...]
    iterations: int
    status: str
    success: bool
    step: float = float("nan")
    rollouts: int = 0


class PredictiveIk:
    """The optimal control problem of predictive IK on one robot and task; build once, optimize per update.

    Args:
        model: a fixed-base robot (1-DoF joints, :meth:`~redundancy_gym.model.RobotModel.serial_chain`).
        task: a :class:`FramePositionTask` or :class:`FrameAxisTask`.
        velocity_weight: ``w_v`` of the pseudoenergy term (5.131), >= 0.
        joint_limits: the joint-limit potential (5.58), or None.
        collision: the collision potential (5.49) (its model's environment is read at each call), or None.
        augmented: optimize ``udot`` with ``u`` as a state (5.120)-(5.129).
        input_weight: ``w_a`` of ``udot^T udot`` in the augmented problem, >= 0.
        damping: ``rho`` in ``J# = J^T (J J^T + rho I)^-1`` (keeps the prediction finite near singularities).
    """

    def __init__(
        self,
        model: RobotModel,
        task: FramePositionTask | FrameAxisTask,
        *,
        velocity_weight: float = 1.0,
        joint_limits: JointLimitObjective | None = None,
        collision: CollisionObjective | None = None,
        augmented: bool = False,
        input_weight: float = 0.0,
        damping: float = 1e-6,
    ) -> None:
        if model.floating_base:
            raise ControllerError("PredictiveIk needs a fixed-base model")
        velocity_weight, input_weight, damping = (
            cast(float, check_real(name, value, low=0.0, error=ControllerError))  # None only with optional=True
            for name, value in (
                ("velocity_weight", velocity_weight),
                ("input_weight", input_weight),
                ("damping", damping),
            )
        )
        if not isinstance(task, (FramePositionTask, FrameAxisTask)):
            raise ControllerError(
                f"PredictiveIk supports FramePositionTask and FrameAxisTask, got {type(task).__name__}"
            )
        chain = model.serial_chain()
        self.model, self.task = model, task
        self.n = model.nv
        self.m = task.dim
        self.velocity_weight, self.input_weight = float(velocity_weight), float(input_weight)
        self.augmented, self.damping = bool(augmented), float(damping)
        self.joint_limits, self.collision = joint_limits, collision
        self._work: NDArray[np.float64] = np.empty(0)  # pik_optimize's rollout slots, sized at the first call
        joint, rotation, translation = model.frame_attachment(task.frame)
        if isinstance(task, FramePositionTask):
            header = [0, joint, 0, *task.rows.tolist()]
        else:
            header = [1, joint, task.axis]
        self._task_i = np.array(header, dtype=np.int64)
        self._task_f = np.concatenate([rotation.reshape(-1), translation])
        self._chain_f = (chain.placement_rotation, chain.placement_translation, chain.axis)
        self._chain_i = (chain.parent, chain.joint_type, chain.q_index, chain.v_index)
        if joint_limits is not None and joint_limits.lower.shape != (self.n,):
            raise ControllerError(f"the joint-limit objective has {joint_limits.lower.size} joints, the model {self.n}")
        lower = joint_limits.lower if joint_limits else np.zeros(self.n)
        upper = joint_limits.upper if joint_limits else np.ones(self.n)
        potential = (
            (
                joint_limits.potential.activation_distance,
                joint_limits.potential.slope,
                joint_limits.potential.switch_ratio,
                joint_limits.weight,
            )
            if joint_limits
            else (1.0, 1.0, 0.5, 0.0)
        )
        self._objective_f = np.concatenate([[self.damping, self.velocity_weight], lower, upper, potential])
        self._collision_setup()

    # ------------------------------------------------------------------ collision model
    def _collision_setup(self) -> None:
        if self.collision is None:
            empty_i, empty_f = np.zeros(0, dtype=np.int64), np.zeros(0)
            self._coll_i = (
                empty_i,
                np.zeros(1, dtype=np.int64),
                empty_i,
                np.zeros((0, 2), dtype=np.int64),
                np.zeros(1, dtype=np.int64),
                empty_i,
                empty_i,
            )
            self._coll_f = (
                np.zeros((0, 3, 3)),
                np.zeros((0, 3)),
                np.zeros((0, 3)),
                empty_f,
                np.zeros((0, 3)),
                np.zeros((0, 3, 3)),
                np.zeros((0, 3, 3)),
                empty_f,
            )
            self._coll_p = np.zeros(4)
            return
        fields = collision_fields(self.collision, self.model)
        f, i = fields.floats, fields.ints
        ns, nvol = fields.counts["segments"], fields.counts["volumes"]
        self._fields = fields
        self._coll_i = (
            i["segment_joint"],
            i["segment_starts"],
            i["kinds"],
            i["segment_pairs"].reshape(-1, 2),
            i["pair_starts"],
            i["volume_a"],
            i["volume_b"],
        )
        self._coll_f = (
            f["segment_rotation"].reshape(ns, 3, 3),
            f["segment_translation"].reshape(ns, 3),
            f["segment_center"].reshape(ns, 3),
            f["segment_radius"],
            f["segment_world_center"].reshape(ns, 3),
            f["local"].reshape(nvol, 3, 3),
            f["vertices"].reshape(nvol, 3, 3),
            f["radii"].copy(),
        )
        self._coll_p = f["collision_parameters"]
        self._version = -1
        self._refresh_environment()

    def _refresh_environment(self) -> None:
        """World vertices, radii and bounding spheres of the environment (and world-fixed robot) segments."""
        if self.collision is None or self.collision.collision_model.version == self._version:
            return
        model = self.collision.collision_model
        fields = self._fields
        layout = fields.layout
        robot_volumes = int(layout.segment_starts[fields.robot_segments])
        env = model.environment_volumes()
        _, _, center, radius, world, local, vertices, radii = self._coll_f
        vertices[robot_volumes:] = env.vertices
        radii[robot_volumes:] = env.radii
        radii[:robot_volumes] = layout.radii[:robot_volumes]
        placed = layout.local.copy()
        placed[robot_volumes:] = env.vertices
        centers, bounds = bounding_spheres(placed, layout.kinds, radii, layout.segment_starts)
        center[:] = centers
        radius[:] = bounds
        world[fields.robot_segments :] = centers[fields.robot_segments :]
        for s, rotation, translation in fields.world_fixed:
            sl = slice(layout.segment_starts[s], layout.segment_starts[s + 1])
            vertices[sl] = layout.local[sl] @ rotation.T + translation
            world[s] = rotation @ centers[s] + translation
        self._version = model.version

    # ------------------------------------------------------------------ problem
    def _problem(self) -> tuple[Any, ...]:
        """The arguments that state the problem to every kernel of :mod:`.predictive_kernels`, in their order: the
        chain, the task, the objectives and the collision fields (arrays the kernels read; the environment's are
        updated in place by :meth:`_refresh_environment`), and whether there is a collision objective."""
        return (
            self._chain_f,
            self._chain_i,
            self._task_i,
            self._task_f,
            self._objective_f,
            self._coll_i,
            self._coll_f,
            self._coll_p,
            self.collision is not None,
        )

    def inputs(self, params: ArrayLike, dt: float, u_b: ArrayLike | None = None) -> NDArray[np.float64]:
        """The nullspace inputs ``u`` (N, n) of the decision variables: ``params`` itself, or for the augmented
        problem ``u_k = u_b + dt sum_{l<k} udot_l``."""
        params = as_float_array(params, "the inputs")
        if not self.augmented:
            return params
        start = self._start(u_b)
        u = np.empty_like(params)
        u[0] = start
        u[1:] = start + dt * np.cumsum(params[:-1], axis=0)
        return u

    def _start(self, u_b: ArrayLike | None) -> NDArray[np.float64]:
        """The checked input ``u_b`` at the start of the horizon (5.127) [rad/s or m/s], zeros when None."""
        start = np.zeros(self.n) if u_b is None else as_float_array(u_b, "u_b")
        if start.shape != (self.n,) or not np.all(np.isfinite(start)):
            raise ControllerError(f"u_b must be finite with shape ({self.n},), got {np.array2string(start)}")
        return np.ascontiguousarray(start)

    def _check(
        self, q0: ArrayLike, params: ArrayLike, wdot: ArrayLike, dt: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        q0 = np.ascontiguousarray(as_float_array(q0, "q0"))
        params = np.ascontiguousarray(as_float_array(params, "the inputs"))
        wdot = np.ascontiguousarray(as_float_array(wdot, "wdot"))
        if q0.shape != (self.n,) or params.ndim != 2 or params.shape[1] != self.n or params.shape[0] < 1:
            raise ControllerError(
                f"q0 must have shape ({self.n},) and the inputs (N, {self.n}), got {q0.shape} and {params.shape}"
            )
        if wdot.shape != (params.shape[0], 6):
            raise ControllerError(
                f"wdot must have shape ({params.shape[0]}, 6) (task velocity rows first), got {wdot.shape}"
            )
        if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(params)) and np.all(np.isfinite(wdot))):
            raise ControllerError("q0, the inputs and wdot must be finite")
        if (
            isinstance(dt, (bool, np.bool_))
            or not isinstance(dt, (int, float, np.integer, np.floating))
            or not np.isfinite(dt)
            or dt <= 0.0
        ):
            raise ControllerError(f"dt must be finite and > 0, got {dt!r}")
        return q0, params, wdot

    def rollout(
        self, q0: ArrayLike, params: ArrayLike, wdot: ArrayLike, dt: float, u_b: ArrayLike | None = None
    ) -> PredictiveRollout:
        """Forward integration (5.112) and the cost (5.130) for the decision variables ``params`` (N, n).

        ``wdot`` (N, 6) is the task velocity at each sample: the task's rows for a :class:`FramePositionTask`
        (then zeros), ``[v_d, omega_d]`` for a :class:`FrameAxisTask`.
        """
        roll = self._rollout(*self._check(q0, params, wdot, dt), dt, u_b)
        if not (np.isfinite(roll.cost) and np.all(np.isfinite(roll.q)) and np.all(np.isfinite(roll.qdot))):
            raise ControllerError(f"the rollout overflowed (cost {roll.cost!r}): the inputs, u_b or wdot are too large")
        return roll

    def _rollout(
        self,
        q0: NDArray[np.float64],
        params: NDArray[np.float64],
        wdot: NDArray[np.float64],
        dt: float,
        u_b: ArrayLike | None,
    ) -> PredictiveRollout:
        """:meth:`rollout` of checked arrays; an overflowing rollout comes back with its infinite cost (the line
        search of :meth:`optimize` rejects it like any step that does not decrease the cost)."""
        self._refresh_environment()
        u = np.ascontiguousarray(self.inputs(params, dt, u_b))
        steps = params.shape[0]
        q, qdot, terms = np.empty((steps + 1, self.n)), np.empty((steps, self.n)), np.zeros(3)
        ok = pik_rollout(
            self._problem(),
            q0,
            u,
            wdot,
            float(dt),
            q,
            qdot,
            terms,
        )
        if not ok:
            raise ControllerError("J J^T + rho I is singular along the rollout; raise damping")
        rate = dt * self.input_weight * float(np.sum(params * params)) if self.augmented else 0.0
        parts = {
            "velocity": float(terms[0]),
            "joint_limits": float(terms[1]),
            "collision": float(terms[2]),
            "input_rate": rate,
        }
        cost = float(terms.sum()) + rate
        if not np.isfinite(cost) or not (np.all(np.isfinite(q)) and np.all(np.isfinite(qdot))):
            cost = np.inf
        return PredictiveRollout(q, qdot, u, cost, parts)

    def gradient(
        self,
        q0: ArrayLike,
        params: ArrayLike,
        wdot: ArrayLike,
        dt: float,
        u_b: ArrayLike | None = None,
        rollout: PredictiveRollout | None = None,
    ) -> tuple[PredictiveRollout, NDArray[np.float64]]:
        """The rollout and the exact gradient ``dPhi/dparams`` (N, n) by the adjoint (5.113), (5.119), (A.53)-(A.63).

        ``rollout`` may be the :meth:`rollout` of the same arguments, done already (it is not done again).
        """
        roll = rollout if rollout is not None else self.rollout(q0, params, wdot, dt, u_b)
        params = np.ascontiguousarray(params, dtype=np.float64)
        wdot = np.ascontiguousarray(wdot, dtype=np.float64)
        grad_u, lam0 = np.empty_like(roll.u), np.empty(self.n)
        ok = pik_gradient(
            self._problem(),
            roll.q,
            roll.u,
            wdot,
            float(dt),
            grad_u,
            lam0,
        )
        if not ok:
            raise ControllerError("J J^T + rho I is singular along the rollout; raise damping")
        if not self.augmented:
            return roll, grad_u
        # u_k depends on udot_l for l < k (5.121): the adjoint of u (5.126) is the reverse cumulative sum
        tail = np.zeros_like(grad_u)
        tail[:-1] = np.cumsum(grad_u[:0:-1], axis=0)[::-1]
        return roll, dt * tail + 2.0 * dt * self.input_weight * params

    def command(
        self, q: ArrayLike, u: ArrayLike, target: ArrayLike, target_velocity: ArrayLike, gain: float
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(qdot, e)``: the CLIK command ``J# (wdot + K e) + N u`` at ``q`` with the nullspace input ``u``
        (5.5), (5.100), and the task error ``e``.

        ``target`` and ``target_velocity`` are the task's rows (:class:`FramePositionTask`) or ``[p_d, a_d]``
        and ``[v_d, omega_d]`` (:class:`FrameAxisTask`), as for :meth:`Clik.step`.
        """
        q = np.ascontiguousarray(as_float_array(q, "q"))
        u = np.ascontiguousarray(as_float_array(u, "u"))
        width = self.m if isinstance(self.task, FramePositionTask) else 6
        target = as_float_array(target, "target")
        velocity = as_float_array(target_velocity, "target_velocity")
        if (
            isinstance(gain, (bool, np.bool_))
            or not isinstance(gain, (int, float, np.integer, np.floating))
            or not np.isfinite(gain)
            or gain < 0.0
        ):
            raise ControllerError(f"gain must be finite and >= 0, got {gain!r}")
        if q.shape != (self.n,) or u.shape != (self.n,) or target.shape != (width,) or velocity.shape != (width,):
            raise ControllerError(f"q and u must have shape ({self.n},), the target and its velocity ({width},)")
        if not (
            np.all(np.isfinite(q))
            and np.all(np.isfinite(u))
            and np.all(np.isfinite(target))
            and np.all(np.isfinite(velocity))
        ):
            raise ControllerError("q, u, the target and its velocity must be finite")
        if width == 6 and not np.linalg.norm(target[3:]) > 1e-9:
            raise ControllerError("the target axis must not be zero")
        wdot = np.zeros(6)
        wdot[:width] = velocity
        padded = np.zeros(6)
        padded[:width] = target
        qdot, error = np.empty(self.n), np.empty(self.m)
        if not pik_command(
            self._chain_f,
            self._chain_i,
            self._task_i,
            self._task_f,
            self.damping,
            q,
            u,
            wdot,
            padded,
            float(gain),
            qdot,
            error,
        ):
            raise ControllerError("J J^T + rho I is singular; raise damping")
        return qdot, error

    # ------------------------------------------------------------------ algorithm 11
    def optimize(
        self,
        q0: ArrayLike,
        wdot: ArrayLike,
        dt: float,
        initial: ArrayLike,
        *,
        u_b: ArrayLike | None = None,
        max_iterations: int = 20,
        tolerance: float = 1e-4,
        method: str = "fletcher_reeves",
        step: float = 1.0,
        backend: str = DEFAULT_BACKEND,
        compiled: bool | None = None,
    ) -> PredictiveResult:
        """Algorithm 11 from the initial decision variables ``initial`` (N, n).

        Args:
            q0: the configuration at the start of the horizon (5.114).
            wdot: the task velocity reference at each sample (see :meth:`rollout`).
            dt: sample time [s].
            initial: the first guess (the last solution, shifted, in a receding horizon).
            u_b: the input at the start of the horizon for the augmented problem (5.127).
            max_iterations: ``j_max``.
            tolerance: ``epsilon``: stop when the relative cost decrease of an iteration falls below it.
            method: ``"fletcher_reeves"`` (conjugate gradient) or ``"steepest_descent"``.
            step: first trial step size ``alpha`` of the backtracking line search (in the function-space
                gradient's units: the input changes by ``alpha`` times the gradient of the Hamiltonian).
            backend: ``"compiled"`` (the default) runs the whole loop in one compiled call
                (:func:`.predictive_kernels.pik_optimize`, about twice as fast); ``"python"`` runs it in Python on
                the separate rollout and adjoint kernels, the reference: the same steps to round-off. Round-off
                grows along the conjugate directions (through the parabolic step's curvature, a difference of
                nearly equal costs), so over hundreds of iterations the two may stop at different iterates of about
                the same cost: the global plans (the ``global`` policy, the bench's) ask for the reference.
            compiled: deprecated (goes in redundancy_gym 0.3): ``True`` is ``backend="compiled"``, ``False``
                ``backend="python"``.

        Raises:
            ControllerError: an unknown ``backend`` (naming the choices), ``compiled`` contradicting ``backend``, or
                an option out of its range.
        """
        if method not in DESCENT_METHODS:
            raise ControllerError(f"unknown method {method!r}; valid: {', '.join(DESCENT_METHODS)}")
        if not isinstance(max_iterations, (int, np.integer)) or max_iterations < 0:
            raise ControllerError(f"max_iterations must be an int >= 0, got {max_iterations!r}")
        if not np.isfinite(step) or step <= 0.0 or not np.isfinite(tolerance) or tolerance < 0.0:
            raise ControllerError(f"step must be > 0 and tolerance >= 0, got {step!r}, {tolerance!r}")
        if resolve_backend(backend, compiled, stacklevel=3) == "compiled":
            return self._optimize_compiled(
                q0, wdot, dt, initial, u_b, int(max_iterations), float(tolerance), method, float(step)
            )
        roll, grad = self.gradient(q0, initial, wdot, dt, u_b)
        q0, params, wdot = self._check(q0, initial, wdot, dt)
        params = params.copy()
        costs = [roll.cost]
        hamiltonian = grad / dt  # dH/du: the function-space gradient (5.119)
        direction = -hamiltonian
        previous_norm = float(dt * np.sum(hamiltonian * hamiltonian))  # <g, g> as the integral of algorithm 11
        alpha = float(step)
        status = "max_iterations"
        rollouts = 1
        for _j in range(max_iterations):
            slope = float(np.sum(grad * direction))
            if not slope < 0.0:  # not a descent direction (round-off): restart along the gradient
                direction = -hamiltonian
                slope = float(np.sum(grad * direction))
                if not slope < 0.0:
                    status = "converged"
                    break
            trial_cost, trial = np.inf, None
            for _ in range(30):  # backtracking with the Armijo condition
                candidate = params + alpha * direction
                trial = self._rollout(q0, candidate, wdot, dt, u_b)
                rollouts += 1
                trial_cost = trial.cost
                if trial_cost <= roll.cost + 1e-4 * alpha * slope:
                    break
                alpha *= 0.5
            else:
                status = "no_decrease"
                break
            # the minimum of the parabola through the cost at 0 and alpha with the slope at 0
            curvature = trial_cost - roll.cost - slope * alpha
            if curvature > 0.0:
                best = -slope * alpha * alpha / (2.0 * curvature)
                if 0.0 < best < 4.0 * alpha and abs(best - alpha) > 1e-3 * alpha:
                    other = self._rollout(q0, params + best * direction, wdot, dt, u_b)
                    rollouts += 1
                    if other.cost < trial_cost:
                        candidate, trial, trial_cost, alpha = params + best * direction, other, other.cost, best
            decrease = (roll.cost - trial_cost) / max(abs(roll.cost), 1e-300)
            params = candidate
            roll, grad = self.gradient(q0, params, wdot, dt, u_b, rollout=trial)
            costs.append(roll.cost)
            alpha *= 2.0  # start the next search a little further out
            if decrease < tolerance:
                status = "converged"
                break
            previous = hamiltonian
            hamiltonian = grad / dt
            norm = float(dt * np.sum(hamiltonian * hamiltonian))
            beta = 0.0
            if method == "fletcher_reeves" and previous_norm > 0.0:
                beta = norm / previous_norm
            elif method == "polak_ribiere" and previous_norm > 0.0:  # PR+, restarts by itself
                beta = max(0.0, float(dt * np.sum(hamiltonian * (hamiltonian - previous))) / previous_norm)
            direction = -hamiltonian + beta * direction
            previous_norm = norm
        return PredictiveResult(params, roll, tuple(costs), len(costs) - 1, status, True, alpha, rollouts)

    def _optimize_compiled(
        self,
        q0: ArrayLike,
        wdot: ArrayLike,
        dt: float,
        initial: ArrayLike,
        u_b: ArrayLike | None,
        max_iterations: int,
        tolerance: float,
        method: str,
        step: float,
    ) -> PredictiveResult:
        """:meth:`optimize` (its options checked already) in one call of :func:`.predictive_kernels.pik_optimize`."""
        q0, params, wdot = self._check(q0, initial, wdot, dt)
        start = self._start(u_b) if self.augmented else np.zeros(self.n)
        self._refresh_environment()
        steps, n = params.shape
        nj, m = self._chain_i[0].shape[0], (self._task_i.shape[0] - 3 if self._task_i[0] == 0 else 5)
        size = SLOTS * int(slot_size(steps, n, nj, m))
        if self._work.shape[0] != size:
            self._work = np.empty(size)  # kept between calls: a receding horizon has the same N every update
        costs = np.empty(max_iterations + 1)
        out = (np.empty((steps, n)), np.empty((steps, n)), np.empty((steps + 1, n)), np.empty((steps, n)), np.empty(4))
        code, iterations, alpha, rollouts = pik_optimize(
            self._problem(),
            q0,
            wdot,
            float(dt),
            self.augmented,
            start,
            self.input_weight,
            params,
            max_iterations,
            tolerance,
            METHODS.index(method),
            step,
            self._work,
            costs,
            *out,
        )
        if code == SINGULAR:
            raise ControllerError("J J^T + rho I is singular along the rollout; raise damping")
        if code == OVERFLOW:
            raise ControllerError("the rollout overflowed (cost inf): the inputs, u_b or wdot are too large")
        params_out, u, q, qdot, terms = out
        parts = {
            "velocity": float(terms[0]),
            "joint_limits": float(terms[1]),
            "collision": float(terms[2]),
            "input_rate": float(terms[3]),
        }
        rollout = PredictiveRollout(q, qdot, u, float(costs[iterations]), parts)
        return PredictiveResult(
            params_out,
            rollout,
            tuple(costs[: iterations + 1].tolist()),
            int(iterations),
            STATUS[code],
            True,
            float(alpha),
            int(rollouts),
        )
