"""The reference path of grasp-approach tasks: a quintic rest-to-rest move from the start pose to the pre-grasp
pose (tool axis turned on the great circle), then a straight quintic approach to the grasp pose.

It lives in the lowest layer because two sides use the same path: the AgriReach env, which measures tracking
error against it, and the ``clik`` reference policy, which follows it.
"""

from __future__ import annotations

import warnings
from typing import Any, NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

# packed kernels are copied into numba's cache when their module is defined, which kernel_options sets up
from .. import kernel_options  # noqa: F401

__all__ = ["GraspPath", "GraspPathTiming", "grasp_path_durations", "sample_grasp_path"]


class GraspPathTiming(NamedTuple):
    """How fast the reference path moves.

    Attributes:
        max_speed: average TCP speed of the move to the pre-grasp pose [m/s].
        max_turn_rate: average tool-axis turn rate of that move [rad/s].
        min_duration: shortest move to the pre-grasp pose [s].
        approach_speed: average TCP speed of the straight approach [m/s].
    """

    max_speed: float = 0.35
    max_turn_rate: float = 0.8
    min_duration: float = 1.5
    approach_speed: float = 0.12

    def durations(self, move_distance: float, turn: float, approach_distance: float) -> tuple[float, float]:
        """Durations [s] of the move to the pre-grasp pose (``move_distance`` [m] with a turn of the tool axis by
        ``turn`` [rad]) and of the straight approach (``approach_distance`` [m], at least 0.5 s)."""
        move = max(self.min_duration, move_distance / self.max_speed, turn / self.max_turn_rate)
        return move, max(0.5, approach_distance / self.approach_speed)


# one shared default instead of a call in the signatures (ruff B008); a NamedTuple is immutable, so sharing it is safe
_DEFAULT_TIMING = GraspPathTiming()


def grasp_path_durations(*args: Any, **kwargs: Any) -> tuple[float, float]:
    """Deprecated: the durations of ``GraspPath.plan(start, start_axis, pregrasp, grasp, approach, timing)``
    (its ``move_duration`` and ``approach_duration``; :meth:`GraspPathTiming.durations` from the distances)."""
    warnings.warn(
        "grasp_path_durations is deprecated; use GraspPath.plan(...).move_duration and .approach_duration, or "
        "GraspPathTiming.durations(move_distance, turn, approach_distance)",
        DeprecationWarning,
        stacklevel=2,
    )
    path = GraspPath.plan(*args, **kwargs)
    return path.move_duration, path.approach_duration


class GraspPath:
    """Quintic rest-to-rest move from the start pose to the pre-grasp pose (tool axis turned on the great
    circle), then a straight quintic approach to the grasp pose along the fixed approach axis.

    Args:
        start, pregrasp, grasp: TCP positions [m]; start_axis, approach: unit tool axes.
        move_duration, approach_duration: [s].
    """

    def __init__(
        self,
        start: NDArray[np.float64],
        start_axis: NDArray[np.float64],
        pregrasp: NDArray[np.float64],
        grasp: NDArray[np.float64],
        approach: NDArray[np.float64],
        move_duration: float,
        approach_duration: float,
    ) -> None:
        self.start, self.pregrasp, self.grasp = start.copy(), pregrasp.copy(), grasp.copy()
        self.start_axis = start_axis / np.linalg.norm(start_axis)
        self.approach = approach / np.linalg.norm(approach)
        self.move_duration, self.approach_duration = float(move_duration), float(approach_duration)
        cross = np.cross(self.start_axis, self.approach)
        sin, cos = float(np.linalg.norm(cross)), float(self.start_axis @ self.approach)
        self.turn_angle = float(np.arctan2(sin, cos))
        if sin > 1e-9:
            self.turn_axis = cross / sin
        else:  # parallel or antiparallel: any axis orthogonal to the start axis
            helper = np.array([0.0, 0.0, 1.0]) if abs(self.start_axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
            self.turn_axis = np.cross(self.start_axis, helper)
            self.turn_axis /= np.linalg.norm(self.turn_axis)
            if cos > 0.0:
                self.turn_angle = 0.0

        # the constants of __call__ in one buffer for the compiled sampler
        k, a0 = self.turn_axis, self.start_axis
        self._params = np.concatenate(
            [
                self.start,
                self.pregrasp,
                self.grasp,
                self.approach,
                a0,
                np.cross(k, a0),
                k * (k @ a0),
                k,
                [self.move_duration, self.approach_duration, self.turn_angle],
            ]
        )
        self._out = np.empty(12)
        if not sample_grasp_path.signatures:
            sample_grasp_path.compile("void(float64[::1], float64, float64[::1])")
        self._sampler = sample_grasp_path.get_overload(sample_grasp_path.signatures[0])

    @classmethod
    def plan(
        cls,
        start: NDArray[np.float64],
        start_axis: NDArray[np.float64],
        pregrasp: NDArray[np.float64],
        grasp: NDArray[np.float64],
        approach: NDArray[np.float64],
        timing: GraspPathTiming = _DEFAULT_TIMING,
    ) -> GraspPath:
        """The path with durations from :meth:`GraspPathTiming.durations`."""
        axis = start_axis / np.linalg.norm(start_axis)
        turn = float(np.arccos(np.clip(axis @ approach / np.linalg.norm(approach), -1.0, 1.0)))
        move_distance, approach_distance = (
            float(np.linalg.norm(pregrasp - start)),
            float(np.linalg.norm(grasp - pregrasp)),
        )
        durations = timing.durations(move_distance, turn, approach_distance)
        return cls(start, start_axis, pregrasp, grasp, approach, *durations)

    @property
    def params(self) -> NDArray[np.float64]:
        """The path's constants as :func:`sample_grasp_path` reads them (27; read-only), for a compiled caller that
        samples the path inside its own kernel."""
        view = self._params.view()
        view.flags.writeable = False
        return view

    @property
    def duration(self) -> float:
        """End of the approach [s]."""
        return self.move_duration + self.approach_duration

    def position(self, t: float) -> tuple[float, float, float]:
        """Target TCP position at time ``t`` [s], as floats (no array allocated: the env samples it every step)."""
        self._sampler(self._params, float(t), self._out)
        out = self._out
        return float(out[0]), float(out[1]), float(out[2])

    def __call__(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Target ``[p, a]`` and target velocity ``[v, omega]`` at time ``t`` [s]."""
        self._sampler(self._params, float(t), self._out)
        return self._out[:6].copy(), self._out[6:].copy()


@njit(cache=True)
def _law(t: float, duration: float) -> tuple[float, float]:
    """Quintic rest-to-rest time law ``s(t)`` in [0, 1] and ``ds/dt`` [1/s]."""
    tau = min(max(t / duration, 0.0), 1.0)
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    sdot = 30.0 * tau**2 * (1.0 - tau) ** 2 / duration if tau < 1.0 else 0.0
    return s, sdot


@njit(cache=True)
def sample_grasp_path(params: NDArray[np.float64], t: float, out: NDArray[np.float64]) -> None:
    """:meth:`GraspPath.__call__` on the path's constants (:attr:`GraspPath.params`): the target ``[p, a]`` and its
    velocity ``[v, omega]`` at time ``t`` [s] into ``out`` (12). Compiled: callable from other kernels."""
    start, pregrasp, grasp, approach = params[0:3], params[3:6], params[6:9], params[9:12]
    a0, k_cross_a0, k_k_a0, k = params[12:15], params[15:18], params[18:21], params[21:24]
    move, approach_time, turn = params[24], params[25], params[26]
    if t < move:
        s, sdot = _law(t, move)
        angle = s * turn
        c, sn = np.cos(angle), np.sin(angle)
        for r in range(3):  # Rodrigues' rotation of the start axis about k
            out[r] = start[r] + s * (pregrasp[r] - start[r])
            out[3 + r] = a0[r] * c + k_cross_a0[r] * sn + k_k_a0[r] * (1.0 - c)
            out[6 + r] = sdot * (pregrasp[r] - start[r])
            out[9 + r] = sdot * turn * k[r]
        return
    s, sdot = _law(t - move, approach_time)
    for r in range(3):
        out[r] = pregrasp[r] + s * (grasp[r] - pregrasp[r])
        out[3 + r] = approach[r]
        out[6 + r] = sdot * (grasp[r] - pregrasp[r])
        out[9 + r] = 0.0
