"""The linear-algebra core shared by velocity- and acceleration-level CLIK (Algorithm 10, (5.14), (5.22), (5.24)).

Solves ``min 1/2 x^T W x + z^T x  s.t.  J x = b`` (5.7) without forming a pseudoinverse: with
``B = J W^-1 J^T`` (Cholesky), ``B lambda = b + J W^-1 z`` and ``x = W^-1 (J^T lambda - z)``. This equals
``x = J#_W b - N_W W^-1 z`` (5.14)-(5.16); setting ``z = alpha (dH/dq)^T`` gives Liegeois' nullspace descent.

Algorithm 10 as printed uses ``p = wdot_d - J z``; the optimality conditions (5.9), (5.10) it solves give
``p = wdot_d + J W^-1 z`` for its own update ``qdot = W^-1 (J^T lambda - z)``, which is what is implemented (and
tested against (5.14)).
"""

from __future__ import annotations

from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .exceptions import ControllerError

__all__ = ["Method", "METHODS", "Resolution", "WeightMatrix", "resolve"]

Method = Literal["pseudoinverse", "dls", "transpose"]
METHODS: tuple[str, ...] = ("pseudoinverse", "dls", "transpose")


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
            self._factor = None
        elif w.shape == (n, n):
            if not np.allclose(w, w.T) or not np.all(np.isfinite(w)):
                raise ControllerError("the weight matrix must be finite and symmetric")
            try:
                self._factor = np.linalg.cholesky(w)
            except np.linalg.LinAlgError:
                raise ControllerError("the weight matrix must be positive definite") from None
            self.diagonal = None
        else:
            raise ControllerError(f"weights must be a scalar, a vector of length {n} or an {n}x{n} matrix, got {w.shape}")
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


def resolve(jacobian: NDArray[np.float64], rhs: NDArray[np.float64], z: NDArray[np.float64] | None,
            weights: WeightMatrix, *, method: str = "pseudoinverse", singular_threshold: float = 1e-6,
            dls_threshold: float = 0.05, dls_max_damping: float = 0.01) -> Resolution:
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
        return Resolution(weights.solve(jacobian.T @ rhs), sigma, 0.0, True, "ok")
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
