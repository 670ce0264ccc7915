"""A :class:`ServoFeedforward` with its wrench split and torques in one compiled kernel (the same results to
round-off, held equal by ``tests/controllers/walking/test_servo_feedforward.py``).

The Python reference spends most of its time on small NumPy operations around pinocchio's RNEA (about 70 us a
call against 7 us of RNEA and Jacobians); here the model gives the RNEA torques and the soles' Jacobians and one
kernel does the rest (damping, the base rows' least-squares split (5.92), ``J^T F``, the offsets).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ...kernel_options import JIT
from ..exceptions import ControllerError
from ..kernels.linalg import cholesky_factor, cholesky_solve
from .servo_feedforward import MIN_LOAD, ServoFeedforward, ServoFeedforwardTorques

__all__ = ["CompiledServoFeedforward"]


@njit(**JIT)
def _split(
    tau: np.ndarray,
    qdot: np.ndarray,
    damping: np.ndarray,
    jacobians: np.ndarray,
    loads: np.ndarray,
    gain: float,
    stiffness: np.ndarray,
    wrenches: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, float]:  # pragma: no cover - compiled
    """``(joint torques, offsets, base residual)`` from the RNEA torques ``tau``; ``loads[i]`` > 0 marks a sole
    that carries that share of the weight (its Jacobian ``jacobians[i]``, 6 x nv); the wrenches go into
    ``wrenches`` (2, 6). A base block that is not positive definite gives a NaN residual."""
    nv = tau.shape[0]
    t = tau + damping * qdot
    normal = np.zeros((6, 6))
    used = False
    for i in range(2):
        w = loads[i]
        if w <= 0.0:
            continue
        used = True
        for a in range(6):
            for b in range(6):
                s = 0.0
                for k in range(6):
                    s += jacobians[i, k, a] * jacobians[i, k, b]
                normal[a, b] += w * s
    wrenches[:] = 0.0
    if used:
        low = np.zeros((6, 6))
        if cholesky_factor(normal, 6, low) == 0.0:
            return t[6:] * gain, t[6:] * gain / stiffness, math.nan
        multiplier = t[:6].copy()
        cholesky_solve(low, 6, multiplier)
        for i in range(2):
            w = loads[i]
            if w <= 0.0:
                continue
            for k in range(6):
                f = 0.0
                for a in range(6):
                    f += jacobians[i, k, a] * multiplier[a]
                wrenches[i, k] = w * f
            for j in range(nv):
                s = 0.0
                for k in range(6):
                    s += jacobians[i, k, j] * wrenches[i, k]
                t[j] -= s
    residual = 0.0
    for a in range(6):
        residual = max(residual, abs(t[a]))
    joint = t[6:] * gain
    return joint, joint / stiffness, residual


class CompiledServoFeedforward(ServoFeedforward):
    """:class:`ServoFeedforward` with the split of the contact wrenches and the torques compiled (same arguments,
    same results to round-off): its :meth:`~ServoFeedforward.torques`, with one kernel after the RNEA."""

    def _balance(
        self, tau: NDArray[np.float64], qdot: NDArray[np.float64], contact: tuple[bool, bool], right_load: float
    ) -> ServoFeedforwardTorques:
        model = self.model
        loads = np.array((right_load, 1.0 - right_load))
        jacobians = np.zeros((2, 6, model.nv))
        for i in range(2):
            if contact[i] and loads[i] > MIN_LOAD:
                jacobians[i] = model.frame_jacobian(self._feet[i])
            else:
                loads[i] = 0.0
        wrenches = np.empty((2, 6))
        joint, offsets, residual = _split(
            tau, np.ascontiguousarray(qdot), self._damping, jacobians, loads, self.gain, self.stiffness, wrenches
        )
        if math.isnan(residual):
            raise ControllerError("the soles' Jacobians give a singular base block: no contact wrench balances it")
        return ServoFeedforwardTorques(joint, offsets, wrenches, float(residual))
