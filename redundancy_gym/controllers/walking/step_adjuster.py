"""Push recovery by stepping: the landing point and the timing of the current step from the measured DCM.

A push changes the CoM velocity, so the measured divergent component of motion ``xi_m = c + cdot / omega``
leaves the plan. In the LIPM the DCM runs away from the ZMP, ``xid = omega (xi - r)``; the ankle (the ZMP inside
the stance foot, :class:`Stabilizer`) can only hold an error up to the foot's edge. Beyond that the robot has
to step: put the next foothold where the DCM will be. The pattern's DCM at the current instant is affine in a
shift of the landing foot and all later footholds (:meth:`WalkingPattern.preview_dcm`), so one division gives
the shift for which the replanned DCM equals the measured one (Englsberger et al.'s capture-point step
adjustment on the previewed plan). Where that landing lies outside the reachable region (a step box around the
stance foot, no crossing of the feet), other timings are tried: a shorter single support lands the foot sooner,
when the DCM has run away less, a delayed one gives a late swing time to get there; the timing whose landing
comes nearest the one wanted is taken, clipped into the box, and the next step takes the rest. (Where the DCM
has gone past the stance foot's side, the swing foot cannot cross to catch it: these pushes are the ones still
lost, see ``bench push``.)

A DCM error within ``ankle_margin`` is left to the stabilizer's ZMP shift inside the stance foot (undisturbed
walking, whose errors stay inside it, is unchanged). An axis beyond it is stepped back to ``ankle_share`` of the
margin, and adjusted again whenever it leaves the margin again.
Another timing than the current one is chosen only when it brings the landing at least ``timing_gain`` nearer the
one wanted (against flip-flopping between timings from one period to the next).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ControllerError
from .walking_pattern import ADJUSTED_OVER, LEFT, MAX_SHIFT, WalkingPattern

__all__ = ["LAST_MOMENT", "MIN_SHIFT", "StepAdjuster", "StepAdjusterConfig", "StepAdjustment"]

LAST_MOMENT = 0.04
"""Single support left [s] below which a swing is no longer adjusted (the foot is about to touch down)."""
MIN_SHIFT = 0.005
"""Smallest landing move [m] worth an adjustment at the planned timing."""


@dataclass(frozen=True)
class StepAdjusterConfig:
    """Parameters of :class:`StepAdjuster` (lengths relative to the stance foot's sole point, in the stance foot's
    frame: x along its heading, y to its left).

    Attributes:
        enabled: adjust steps at all (False: the planned footholds and timing whatever happens).
        ankle_margin: DCM error (x, y) [m] left to the stabilizer's ZMP shift inside the stance foot.
        ankle_share: share of the margin an adjustment leaves on an axis that went beyond it, in [0, 1] (1: the
            error is brought back to the margin's edge; 0.5 did better on the tuning pushes, worse on held-out ones).
        error_filter: time constant [s] of the low-pass on the DCM error (0: none).
        timing_gain: how much nearer [m] another timing must bring the landing than the current one to be chosen.
        min_remaining: shortest single support left when a step is re-timed [s].
        max_delay: longest delay of a touchdown [s] (a late push needs time for the foot to get there).
        timing_candidates: how many timings are tried, from the planned one down to ``min_remaining``, then
            (where none reaches) up to ``max_delay`` later.
        max_forward: farthest landing ahead of the stance foot [m].
        max_backward: farthest landing behind it [m].
        min_width, max_width: nearest and farthest landing beside it [m] (the feet never cross).
        max_swing_acceleration: the swing foot's horizontal acceleration the new path may ask for [m/s^2]
            (quicker, farther steps throw the robot off its stance foot): a landing farther than
            ``a tau^2 / 5.77`` from where the foot would stop (``tau`` the time left to reach it) is out of reach.
    """

    enabled: bool = True
    ankle_margin: tuple[float, float] = (0.06, 0.035)
    ankle_share: float = 1.0
    error_filter: float = 0.02
    timing_gain: float = 0.05
    min_remaining: float = 0.2
    max_delay: float = 0.15
    timing_candidates: int = 5
    max_forward: float = 0.65
    max_backward: float = 0.3
    min_width: float = 0.16
    max_width: float = 0.45
    max_swing_acceleration: float = 40.0

    def __post_init__(self) -> None:
        margin = np.asarray(self.ankle_margin, dtype=object)
        if margin.shape != (2,) or not all(
            isinstance(v, (int, float, np.floating, np.integer))
            and not isinstance(v, bool)
            and np.isfinite(v)
            and v >= 0.0
            for v in margin
        ):
            raise ControllerError(
                f"step adjuster ankle_margin must be two finite reals >= 0, got {self.ankle_margin!r}"
            )
        if (
            not isinstance(self.ankle_share, (int, float, np.integer, np.floating))
            or isinstance(self.ankle_share, bool)
            or not 0.0 <= self.ankle_share <= 1.0
        ):
            raise ControllerError(f"step adjuster ankle_share must lie in [0, 1], got {self.ankle_share!r}")
        for name in (
            "error_filter",
            "timing_gain",
            "min_remaining",
            "max_delay",
            "max_forward",
            "max_backward",
            "min_width",
            "max_width",
            "max_swing_acceleration",
        ):
            value = getattr(self, name)
            if (
                isinstance(value, bool)
                or not isinstance(value, (int, float, np.floating, np.integer))
                or not np.isfinite(value)
                or value < 0.0
            ):
                raise ControllerError(f"step adjuster {name} must be a finite real >= 0, got {value!r}")
        if not isinstance(self.enabled, (bool, np.bool_)):
            raise ControllerError(f"step adjuster enabled must be a bool, got {self.enabled!r}")
        if (
            isinstance(self.timing_candidates, bool)
            or not isinstance(self.timing_candidates, (int, np.integer))
            or self.timing_candidates < 1
        ):
            raise ControllerError(
                f"step adjuster timing_candidates must be an int >= 1, got {self.timing_candidates!r}"
            )
        if self.min_width > self.max_width:
            raise ControllerError(f"min_width={self.min_width!r} exceeds max_width={self.max_width!r}")


class StepAdjustment(NamedTuple):
    """One adjustment made by :meth:`StepAdjuster.update`.

    Attributes:
        step: the step adjusted.
        shift: the landing's move (x, y) [m] (every later foothold moves with it).
        single: the step's new single-support duration [s].
        dcm_error: measured minus planned DCM before the adjustment [m].
        clipped: the landing was clipped into the reachable box (the DCM error is not fully taken).
    """

    step: int
    shift: NDArray[np.float64]
    single: float
    dcm_error: NDArray[np.float64]
    clipped: bool


class StepAdjuster:
    """Chooses the landing and timing of the current step from the measured DCM (see the module docstring).

    Args:
        config: parameters.
    """

    def __init__(self, config: StepAdjusterConfig | None = None) -> None:
        self.config = config or StepAdjusterConfig()
        self.reset()

    def reset(self) -> None:
        """Forget the filtered DCM error (a new walk)."""
        self._error: NDArray[np.float64] | None = None
        self._time = 0.0

    def update(
        self, pattern: WalkingPattern, t: float, dcm: ArrayLike, planned: NDArray[np.float64] | None = None
    ) -> StepAdjustment | None:
        """Adjust ``pattern``'s current step at time ``t`` [s] for the measured DCM (x, y) [m]; None if unchanged.

        ``planned`` is the pattern's DCM at ``t`` where the caller has sampled it already (else it is read here).
        """
        c = self.config
        if not c.enabled:
            return None
        k, s, remaining = pattern.swing_state(t)
        if k < 0 or remaining <= LAST_MOMENT:
            return None
        if pattern.swing_modification(k) is not None:
            # a swing over or around an obstacle (SSTA) keeps its path and its landing beside the obstacle: a
            # re-timed swing would take the plain path through it
            return None
        dcm = np.asarray(dcm, dtype=np.float64)[:2]
        point = dcm.tolist() if dcm.shape == (2,) else None
        if not (math.isfinite(point[0]) and math.isfinite(point[1]) if point is not None else np.all(np.isfinite(dcm))):
            raise ControllerError(f"the measured DCM must be finite, got {dcm!r}")
        planned = pattern.dcm(t) if planned is None else planned[:2]
        if point is not None and planned.shape == (2,) and (self._error is None or self._error.shape == (2,)):
            # Scalar math on the controller's 2-vectors: this runs every period and mostly ends at the margin test
            # below, where numpy's per-call overhead cost several times the arithmetic (the array form's
            # operations, elementwise: the same floats)
            (mx, my), (px, py) = point, planned.tolist()
            rx, ry = mx - px, my - py
            if self._error is None or c.error_filter <= 0.0:
                ex, ey = rx, ry
            else:  # the swing leg's lift-off and landing shake the measured DCM for a few periods
                fx, fy = self._error.tolist()
                w = min(1.0, (t - self._time) / c.error_filter)
                ex, ey = fx + w * (rx - fx), fy + w * (ry - fy)
            self._error = np.array((ex, ey))
            self._time = t
            if pattern.heading(k + 1) == 0.0 and abs(ex) <= c.ankle_margin[0] and abs(ey) <= c.ankle_margin[1]:
                return None  # within the ankle's margin (the stance frame is the world's: not turned)
        else:
            raw = dcm - planned
            if self._error is None or c.error_filter <= 0.0:
                self._error = raw
            else:  # the swing leg's lift-off and landing shake the measured DCM for a few periods
                self._error = self._error + min(1.0, (t - self._time) / c.error_filter) * (raw - self._error)
            self._time = t
        error = self._error
        dcm = planned + error
        # the margin and the step box lie in the stance foot's frame (turned by its heading about its sole point)
        heading = pattern.heading(k + 1)
        turn = None
        if heading != 0.0:
            ch, sh = np.cos(heading), np.sin(heading)
            turn = np.array([[ch, -sh], [sh, ch]])  # stance frame -> world
        local_error = error if turn is None else turn.T @ error
        margin = np.asarray(c.ankle_margin, dtype=np.float64)
        beyond = np.abs(local_error) > margin
        if not np.any(beyond):
            return None
        # an axis beyond the margin is stepped back to ankle_share of it (below 1, a hysteresis against
        # re-adjusting at the margin's edge); the other axis keeps its error for the stabilizer
        kept = np.where(beyond, np.clip(local_error, -c.ankle_share * margin, c.ankle_share * margin), local_error)
        wanted = dcm - (kept if turn is None else turn @ kept)
        stance, landing = pattern.foothold(k + 1)[:2], pattern.foothold(k + 2)[:2]
        side = 1.0 if (k + 2) % 2 == LEFT else -1.0
        foot, foot_velocity = pattern.swing_foot(t)
        if turn is None:
            low = np.array([stance[0] - c.max_backward, stance[1] + (c.min_width if side > 0 else -c.max_width)])
            high = np.array([stance[0] + c.max_forward, stance[1] + (c.max_width if side > 0 else -c.min_width)])
        else:  # the box about the stance foot's origin in its frame; the targets and the swing foot moved into it
            low = np.array([-c.max_backward, c.min_width if side > 0 else -c.max_width])
            high = np.array([c.max_forward, c.max_width if side > 0 else -c.min_width])
            foot, foot_velocity = turn.T @ (foot - stance), turn.T @ foot_velocity
        best: tuple[float, NDArray[np.float64], float] | None = None
        n = c.timing_candidates
        lefts = [remaining]
        if n > 1:
            if remaining > c.min_remaining:
                lefts += list(np.linspace(remaining, c.min_remaining, n)[1:])
            if c.max_delay > 0.0:
                lefts += list(remaining + np.linspace(0.0, c.max_delay, n)[1:])
        for left in lefts:
            single = s + float(left)
            if single > 2.0 * pattern.single_support:
                break
            base = pattern.preview_dcm(t, np.zeros(2), single)
            gain = pattern.preview_dcm(t, np.ones(2), single) - base
            if np.any(np.abs(gain) < 1e-9):  # the landing does not move the DCM (a walk stopped in front of a box)
                continue
            target = landing + (wanted - base) / gain
            if turn is None:
                reachable = self._reachable(target, low, high, foot, foot_velocity, ADJUSTED_OVER * left)
            else:
                local = self._reachable(
                    turn.T @ (target - stance), low, high, foot, foot_velocity, ADJUSTED_OVER * left
                )
                reachable = stance + turn @ local
            miss = float(np.linalg.norm(reachable - target))
            if best is None or miss < best[0] - c.timing_gain:
                best = (miss, reachable - landing, single)
            if miss <= 1e-9:
                break
        if best is None:
            return None
        miss, shift, single = best
        clipped = miss > 1e-9
        if float(np.max(np.abs(shift))) < MIN_SHIFT and single == s + remaining:
            return None  # nothing worth replanning the swing for
        if not float(np.max(np.abs(shift))) <= MAX_SHIFT:
            # a landing planned metres from the stance foot (a robot turned far off its plan, down on the ground):
            # no step reaches it, and the pattern would refuse the shift
            return None
        pattern.adjust_step(t, shift, single)
        self._error = dcm - pattern.dcm(t)  # what the new plan leaves
        return StepAdjustment(k, shift, single, error, clipped)

    def _reachable(
        self,
        target: NDArray[np.float64],
        low: NDArray[np.float64],
        high: NDArray[np.float64],
        foot: NDArray[np.float64],
        velocity: NDArray[np.float64],
        tau: float,
    ) -> NDArray[np.float64]:
        """The point nearest ``target`` inside the step box and within the swing's reach in ``tau`` [s]."""
        point = np.clip(target, low, high)
        centre = foot + 0.5 * tau * velocity  # where a quintic from this velocity to rest would go unforced
        radius = self.config.max_swing_acceleration * tau * tau / 5.77
        away = point - centre
        distance = float(np.linalg.norm(away))
        if distance > radius:
            # the disc's point nearest the box point, pulled back into the box (both convex: near enough)
            point = np.clip(centre + away * (radius / distance), low, high)
        return point
