"""The linear-algebra core shared by velocity- and acceleration-level CLIK (Algorithm 10, (5.14), (5.22), (5.24)).

Solves ``min 1/2 x^T W x + z^T x  s.t.  J x = b`` (5.7) without forming a pseudoinverse: with
``B = J W^-1 J^T`` (Cholesky), ``B lambda = b + J W^-1 z`` and ``x = W^-1 (J^T lambda - z)``. This equals
``x = J#_W b - N_W W^-1 z`` (5.14)-(5.16); setting ``z = alpha (dH/dq)^T`` gives Liegeois' nullspace descent.

Algorithm 10 as printed uses ``p = wdot_d - J z``; the optimality conditions (5.9), (5.10) it solves give
``p = wdot_d + J W^-1 z`` for its own update ``qdot = W^-1 (J^T lambda - z)``, which is what is implemented (and
tested against (5.14)).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Generic, Literal, NamedTuple, TypedDict, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...model import RobotModel
from ...validation import as_real_array
from ..exceptions import ControllerError
from ..objectives.objective import Objective
from ..tasks.task import Task

__all__ = [
    "JointBounds",
    "MAX_COORDINATE",
    "Method",
    "METHODS",
    "Resolution",
    "ResolutionOptions",
    "ResolvedController",
    "WeightMatrix",
    "all_finite",
    "check_configuration",
    "check_finite",
    "resolve",
]

Method = Literal["pseudoinverse", "dls", "transpose"]
METHODS: tuple[str, ...] = ("pseudoinverse", "dls", "transpose")


def all_finite(values: NDArray[np.float64]) -> bool:
    """Whether every entry is finite, by one reduction (NaN and inf survive a sum; only an overflowing sum of
    finite entries needs the element-wise check)."""
    if values.size <= 32:  # a Python sum of a short list is a fraction of NumPy's call overhead
        return math.isfinite(sum(values.ravel().tolist())) or bool(np.isfinite(values).all())
    return math.isfinite(float(values.sum())) or bool(np.isfinite(values).all())


def as_float_array(values: ArrayLike, name: str) -> NDArray[np.float64]:
    """``values`` as a float64 array; :class:`ControllerError` naming ``name`` when they are not real numbers
    (strings, None, mappings, complex numbers, ragged sequences)."""
    return as_real_array(name, values, error=ControllerError)


def check_finite(values: ArrayLike, name: str) -> NDArray[np.float64]:
    """``values`` as a float array; :class:`ControllerError` naming ``name`` when an entry is NaN or inf."""
    arr = as_float_array(values, name)
    if not all_finite(arr):
        raise ControllerError(f"{name} must be finite, got {np.array2string(arr, threshold=12)}")
    return arr


# Largest |q| entry [rad or m] a controller accepts: beyond it a revolute angle has lost its meaning and the
# nullspace gradients (which grow with the distance to a joint limit or a posture) swamp the task's part of the
# command in round-off, so that the result would be noise (different noise in each backend).
MAX_COORDINATE = 1e6
# Relative round-off below which bounding a command is not reported as ``limited``: a component that is zero
# analytically (a joint whose Jacobian column is orthogonal to the task velocity) comes out as +-1e-16 with a
# round-off sign; on a joint at its limit the clamp of that noise is not a limit acting.
BOUND_ROUND_OFF = 1e-12


def check_configuration(q: ArrayLike, name: str = "q") -> NDArray[np.float64]:
    """``q`` as a float array; :class:`ControllerError` naming ``name`` when an entry is NaN, inf or beyond
    :data:`MAX_COORDINATE` in magnitude."""
    arr = as_float_array(q, name)
    if not all_finite(arr) or not bool(np.all(np.abs(arr) <= MAX_COORDINATE)):
        raise ControllerError(
            f"{name} must be finite, with every |entry| <= {MAX_COORDINATE:g} [rad or m], got "
            f"{np.array2string(arr, threshold=12)}"
        )
    return arr


class JointBounds:
    """The bounds every CLIK command is held to: joint speed limits and the joint ranges.

    :meth:`apply` first keeps each joint's velocity from pushing it out of its range (a joint at or beyond a
    limit gets no velocity towards it; with a control ``period`` known, ``q + qdot period`` stays inside the
    range), then scales the whole vector by one factor when a joint exceeds its speed limit, so that the
    command keeps its direction (and its task direction) and only slows down. Scaling towards zero never
    leaves the range bounds, since those always admit zero velocity. Holding a joint is reported as
    ``limited`` only when it changes the command by more than round-off (:data:`BOUND_ROUND_OFF` of the
    largest component, or of 1): the clamp of a component that is zero but for its round-off sign is no limit.

    Args:
        model: the robot model (its joint ranges, and its :attr:`~redundancy_gym.model.RobotModel.velocity_limits`
            when ``max_joint_velocity`` is None).
        max_joint_velocity: speed limit per velocity coordinate [rad/s or m/s] (nv) or one for all, > 0;
            ``inf`` for none; None takes the model's.
        period: control period [s] the command is integrated over, > 0; None when unknown (then only the joints
            at or beyond a limit are held).
    """

    def __init__(
        self, model: RobotModel, max_joint_velocity: ArrayLike | float | None = None, period: float | None = None
    ) -> None:
        nv = model.nv
        if max_joint_velocity is None:
            limits = np.asarray(model.velocity_limits, dtype=np.float64)
        else:
            try:
                if isinstance(max_joint_velocity, (bool, np.bool_, str)):
                    raise TypeError
                limits = np.broadcast_to(np.asarray(max_joint_velocity, dtype=np.float64), (nv,)).copy()
            except (TypeError, ValueError):
                raise ControllerError(
                    f"max_joint_velocity must be a number or {nv} numbers [rad/s or m/s], got {max_joint_velocity!r}"
                ) from None
        if limits.shape != (nv,) or np.any(np.isnan(limits)) or np.any(limits <= 0.0):
            raise ControllerError(f"max_joint_velocity must be > 0 (inf for none) with {nv} entries, got {limits}")
        if period is not None:
            if (
                isinstance(period, bool)
                or not isinstance(period, (int, float, np.floating, np.integer))
                or not math.isfinite(period)
                or period <= 0.0
            ):
                raise ControllerError(f"period must be a finite number > 0 [s] or None, got {period!r}")
            period = float(period)
        self.max_velocity = limits
        self.has_velocity_limits = bool(np.any(np.isfinite(limits)))
        self.period = period
        # position limits of the 1-DoF joints (a free flyer's placeholder limits are not limits)
        q_index, v_index, lower, upper = [], [], [], []
        lows, highs = model.lower_limits, model.upper_limits
        for joint in list(model.pinocchio_model.joints)[1:]:
            if joint.nq != 1 or joint.nv != 1:
                continue
            lo, hi = float(lows[joint.idx_q]), float(highs[joint.idx_q])
            if not (math.isfinite(lo) or math.isfinite(hi)) or not lo < hi:
                continue
            q_index.append(joint.idx_q)
            v_index.append(joint.idx_v)
            lower.append(lo)
            upper.append(hi)
        self.q_index = np.array(q_index, dtype=np.int64)
        self.v_index = np.array(v_index, dtype=np.int64)
        self.lower = np.array(lower, dtype=np.float64)
        self.upper = np.array(upper, dtype=np.float64)
        self.active = self.has_velocity_limits or self.q_index.size > 0
        self._joints = list(zip(q_index, v_index, lower, upper, strict=False))
        self._max_velocity = limits.tolist()

    def velocity_range(self, q: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(low, high)``: the velocities (of the bounded joints, :attr:`v_index`) that keep each joint from
        pushing out of its range; both contain zero."""
        qk = q[self.q_index]
        if self.period is not None:
            return (np.minimum((self.lower - qk) / self.period, 0.0), np.maximum((self.upper - qk) / self.period, 0.0))
        return np.where(qk > self.lower, -np.inf, 0.0), np.where(qk < self.upper, np.inf, 0.0)

    def apply(self, qdot: NDArray[np.float64], q: NDArray[np.float64]) -> tuple[NDArray[np.float64], bool]:
        """``(qdot, limited)``: the bounded command and whether it differs from the given one by more than
        round-off (the same arithmetic as the compiled kernel's ``_bound``; on Python floats, which beat NumPy
        at this size)."""
        if not self.active:
            return qdot, False
        x = qdot.tolist()
        qs = q.tolist()
        limited = changed = False
        tolerance = BOUND_ROUND_OFF * max(1.0, max([abs(v) for v in x]))
        period = self.period
        inf = math.inf
        for qi, vi, lower, upper in self._joints:
            qk, v = qs[qi], x[vi]
            if period is not None:
                low = min((lower - qk) / period, 0.0)
                high = max((upper - qk) / period, 0.0)
            else:
                low = -inf if qk > lower else 0.0
                high = inf if qk < upper else 0.0
            bounded = min(max(v, low), high)
            if bounded != v:
                x[vi] = bounded
                changed = True
                limited = limited or abs(bounded - v) > tolerance
        if self.has_velocity_limits:
            peak = max([abs(v) / m for v, m in zip(x, self._max_velocity, strict=False)])
            if peak > 1.0:
                x = [min(max(v / peak, -m), m) for v, m in zip(x, self._max_velocity, strict=False)]
                changed = limited = True
        return (np.array(x, dtype=np.float64) if changed else qdot), limited


class Resolution(NamedTuple):
    """Result of :func:`resolve`.

    Attributes:
        x: the solution (joint velocities or accelerations); zeros when ``success`` is False.
        sigma_min: smallest singular value of ``J W^-1/2`` (the task's distance to a singularity).
        damping: the damping ``k`` added to ``B`` (0 for the exact pseudoinverse).
        success: False when the pseudoinverse met a singularity (``sigma_min`` below the threshold).
        status: ``"ok"``, ``"damped"`` (DLS active) or ``"singular"``.
    """

    x: NDArray[np.float64]
    sigma_min: float
    damping: float
    success: bool
    status: str


class WeightMatrix:
    """The positive definite weight ``W`` of (5.6): a diagonal given as a vector, or a full symmetric matrix.

    Applies ``W^-1`` by division (diagonal) or by a Cholesky factor computed once (full, e.g. (5.62)).
    """

    def __init__(self, weights: ArrayLike | float, n: int) -> None:
        w = np.asarray(weights, dtype=np.float64)
        if w.ndim <= 1:
            w = np.broadcast_to(w, (n,)).copy()
            if not np.all(np.isfinite(w)) or np.any(w <= 0.0):
                raise ControllerError("diagonal weights must be finite and > 0")
            self.diagonal: NDArray[np.float64] | None = w
            self._factor: NDArray[np.float64] = np.zeros((0, 0))  # unused: W^-1 is a division
        elif w.shape == (n, n):
            if not np.allclose(w, w.T) or not np.all(np.isfinite(w)):
                raise ControllerError("the weight matrix must be finite and symmetric")
            try:
                self._factor = np.asarray(np.linalg.cholesky(w), dtype=np.float64)
            except np.linalg.LinAlgError:
                raise ControllerError("the weight matrix must be positive definite") from None
            self.diagonal = None
        else:
            raise ControllerError(
                f"weights must be a scalar, a vector of length {n} or an {n}x{n} matrix, got {w.shape}"
            )
        self.n = n

    def apply(self, v: NDArray[np.float64]) -> NDArray[np.float64]:
        """``W v``."""
        if self.diagonal is not None:
            return self.diagonal * v
        return self._factor @ (self._factor.T @ v)

    def solve(self, rhs: NDArray[np.float64]) -> NDArray[np.float64]:
        """``W^-1 rhs`` (vector or matrix with n rows)."""
        if self.diagonal is not None:
            return rhs / (self.diagonal if rhs.ndim == 1 else self.diagonal[:, None])
        y = np.linalg.solve(self._factor, rhs)
        return np.linalg.solve(self._factor.T, y)


def resolve(
    jacobian: NDArray[np.float64],
    rhs: NDArray[np.float64],
    z: NDArray[np.float64] | None,
    weights: WeightMatrix,
    *,
    method: str = "pseudoinverse",
    singular_threshold: float = 1e-6,
    dls_threshold: float = 0.05,
    dls_max_damping: float = 0.01,
) -> Resolution:
    """Solve ``J x = rhs`` for the weighted-minimum-norm ``x`` with nullspace vector ``z``.

    Args:
        jacobian: ``J`` (m x n).
        rhs: ``b`` (m).
        z: nullspace vector (n), e.g. ``alpha (dH/dq)^T``; ``None`` for none.
        weights: ``W``.
        method: ``"pseudoinverse"`` (Algorithm 10; reports a singularity when ``sigma_min < singular_threshold``
            and returns zeros instead of NaN), ``"dls"`` (damped least squares (5.22) with
            ``k = k_max (1 - (sigma_min/eps)^2)`` below ``eps = dls_threshold``, zero above) or ``"transpose"``
            (``x = W^-1 J^T rhs``, (5.24); ``z`` is ignored because there is no projector to keep it out of the task).
        singular_threshold: ``sigma_min`` below which the pseudoinverse gives up.
        dls_threshold: ``eps`` of the damping law [same unit as ``sigma_min``].
        dls_max_damping: ``k_max`` of the damping law.
    """
    m, n = jacobian.shape
    zero = np.zeros(n)
    if method == "transpose":
        b_mat = jacobian @ weights.solve(jacobian.T)
        sigma = _sigma_min(b_mat)
        x = weights.solve(jacobian.T @ rhs)
        if not all_finite(x):
            return Resolution(zero, sigma, 0.0, False, "singular")
        return Resolution(x, sigma, 0.0, True, "ok")
    if method not in ("pseudoinverse", "dls"):
        raise ControllerError(f"unknown method {method!r}; valid methods: {', '.join(METHODS)}")
    winv_jt = weights.solve(jacobian.T)
    b_mat = jacobian @ winv_jt
    sigma = _sigma_min(b_mat)
    damping = 0.0
    status = "ok"
    if method == "dls":
        if sigma < dls_threshold:
            damping = dls_max_damping * (1.0 - (sigma / dls_threshold) ** 2)
            status = "damped"
        b_mat = b_mat + damping * np.eye(m)
    elif not sigma >= singular_threshold:
        return Resolution(zero, sigma, 0.0, False, "singular")
    p = np.array(rhs, dtype=np.float64)
    winv_z = None
    if z is not None:
        winv_z = weights.solve(z)
        p = p + jacobian @ winv_z
    try:
        factor = np.linalg.cholesky(b_mat)
    except np.linalg.LinAlgError:
        return Resolution(zero, sigma, damping, False, "singular")
    lam = np.linalg.solve(factor.T, np.linalg.solve(factor, p))
    x = winv_jt @ lam
    if winv_z is not None:
        x = x - winv_z
    if not np.all(np.isfinite(x)):
        return Resolution(zero, sigma, damping, False, "singular")
    return Resolution(x, sigma, damping, True, status)


def _sigma_min(b_mat: NDArray[np.float64]) -> float:
    # sigma_min(J W^-1/2)^2 = lambda_min(J W^-1 J^T); clip round-off below zero
    eig = np.linalg.eigvalsh(b_mat)
    return float(np.sqrt(max(eig[0], 0.0)))


TaskT = TypeVar("TaskT", bound=Task)


class ResolutionOptions(TypedDict, total=False):
    """The keyword options every :class:`ResolvedController` takes alike (defaults: ``_read_options``)."""

    objectives: Sequence[Objective]
    """Nullspace objectives ``H`` (summed); default none."""
    singular_threshold: float
    """Smallest singular value below which ``"pseudoinverse"`` reports a singularity (default 1e-6)."""
    dls_threshold: float
    """``eps`` of the DLS damping law (default 0.05)."""
    dls_max_damping: float
    """``k_max`` of the DLS damping law (default 0.01)."""
    max_joint_velocity: ArrayLike | float | None
    """Joint speed limits [rad/s or m/s]; None (default): the model's."""
    period: float | None
    """Control period [s] the command is bounded for, or None (default)."""


class ResolvedController(Generic[TaskT]):
    """The settings of a controller that resolves its task with :func:`resolve` (velocity- and acceleration-level
    CLIK), set and used in one place so that both read them alike."""

    model: RobotModel
    task: TaskT
    method: str
    weights: WeightMatrix
    nullspace_gain: float
    objectives: tuple[Objective, ...]
    singular_threshold: float
    dls_threshold: float
    dls_max_damping: float
    bounds: JointBounds

    def _read_options(
        self, options: ResolutionOptions
    ) -> tuple[Sequence[Objective], tuple[float, float, float], ArrayLike | float | None, float | None]:
        """``(objectives, (singular_threshold, dls_threshold, dls_max_damping), max_joint_velocity, period)`` of
        ``options`` with the defaults filled in (unchecked); ``TypeError`` for an unknown option, as Python words it
        for an explicit signature."""
        for name in options:
            if name not in ResolutionOptions.__optional_keys__:
                raise TypeError(f"{type(self).__name__}.__init__() got an unexpected keyword argument {name!r}")
        thresholds = (
            options.get("singular_threshold", 1e-6),
            options.get("dls_threshold", 0.05),
            options.get("dls_max_damping", 0.01),
        )
        return options.get("objectives", ()), thresholds, options.get("max_joint_velocity"), options.get("period")

    def _set_resolution(
        self, model: RobotModel, task: TaskT, method: str, weights: ArrayLike | float, nullspace_gain: float
    ) -> None:
        """Store the (already checked) settings but :class:`ResolutionOptions` (:meth:`_set_options`)."""
        self.model = model
        self.task = task
        self.method = method
        self.weights = WeightMatrix(weights, model.nv)
        self.nullspace_gain = float(nullspace_gain)

    def _set_options(
        self,
        objectives: Sequence[Objective],
        thresholds: tuple[float, float, float],
        max_joint_velocity: ArrayLike | float | None,
        period: float | None,
    ) -> None:
        """Store the (already checked) :meth:`_read_options`, after :meth:`_set_resolution`."""
        self.objectives = tuple(objectives)
        self.singular_threshold, self.dls_threshold, self.dls_max_damping = (float(t) for t in thresholds)
        self.bounds = JointBounds(self.model, max_joint_velocity, period)

    def _resolve(
        self, jacobian: NDArray[np.float64], rhs: NDArray[np.float64], z: NDArray[np.float64] | None
    ) -> Resolution:
        """:func:`resolve` with this controller's weights, method and thresholds."""
        return resolve(
            jacobian,
            rhs,
            z,
            self.weights,
            method=self.method,
            singular_threshold=self.singular_threshold,
            dls_threshold=self.dls_threshold,
            dls_max_damping=self.dls_max_damping,
        )
