"""Ground contact by force: the feet's heights follow the load the plan gives each foot (foot force difference
control).

A position-controlled foot lands where its joint targets put it; on stiff ground a few millimetres of sag or tilt
decide whether it touches early (an impact, then a bounce) or late (no load where the plan moves the weight onto
it), and the ZMP cannot follow the plan's weight transfer either way. The monograph's walking controller puts the
ground contact under force control (4.6); for a position-controlled robot the feet's heights are the inputs
(Kajita et al. 2010, foot force difference control): the difference of the feet's heights
``delta = z_left - z_right`` moves with the difference of the measured normal forces from the planned ones,

    d delta / dt = k ((f_l - f_r) - (f_l,d - f_r,d)) - delta / T,

each foot taking half of it (the left raised by ``delta / 2``, the right lowered by as much). A foot carrying more
than its share rises, one carrying less is pressed down; ``T`` pulls the feet back to the plan when the forces
agree (in single support, where the swing foot should carry nothing and the stance foot everything). The desired
forces are the plan's load share (:attr:`PatternSample.right_load`) of the measured total.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..exceptions import ControllerError

__all__ = ["FootForceControl", "FootForceGains"]


@dataclass(frozen=True)
class FootForceGains:
    """Gains of :class:`FootForceControl`.

    Attributes:
        gain: ``k`` [m/(N s)], normal-force error to the rate of the height difference (0 switches it off).
        time_constant: ``T`` [s] of the return to the plan's heights (> 0).
        max_offset: largest height difference ``|delta|`` [m] (each foot moves at most half of it).
        force_filter: time constant [s] of the first-order low-pass on the force error (0: unfiltered; the feet's
            forces ring at the touchdowns, and unfiltered gains above 1e-4 made the double support's ZMP worse).
    """

    gain: float = 0.0
    time_constant: float = 0.1
    max_offset: float = 0.06
    force_filter: float = 0.01

    def __post_init__(self) -> None:
        for name, low, strict in (
            ("gain", 0.0, False),
            ("time_constant", 0.0, True),
            ("max_offset", 0.0, False),
            ("force_filter", 0.0, False),
        ):
            value = getattr(self, name)
            if (
                not isinstance(value, (int, float))
                or not math.isfinite(value)
                or value < low
                or (strict and value == low)
            ):
                bound = "> 0" if strict else ">= 0"
                raise ControllerError(f"foot force {name} must be a finite number {bound}, got {value!r}")

    @property
    def active(self) -> bool:
        """Whether the control moves the feet."""
        return self.gain > 0.0 and self.max_offset > 0.0


class FootForceControl:
    """The feet's height offsets from their normal forces (see the module docstring).

    Args:
        gains: the control's gains.
    """

    def __init__(self, gains: FootForceGains) -> None:
        self.gains = gains
        self.offset = 0.0  # delta = z_left - z_right [m]
        self.rate = 0.0  # its rate [m/s]
        self.error: float | None = None  # the filtered force-difference error [N]

    def reset(self) -> None:
        """Back to the plan's heights."""
        self.offset = self.rate = 0.0
        self.error = None

    def update(self, dt: float, right_force: float, left_force: float, right_load: float) -> tuple[float, float]:
        """One control period: ``(delta [m], its rate [m/s])`` from the measured normal forces [N] (right, left)
        and the plan's share of the weight on the right foot ``right_load`` in [0, 1]."""
        gains = self.gains
        total = right_force + left_force
        desired = (1.0 - 2.0 * right_load) * total  # f_l,d - f_r,d
        error = (left_force - right_force) - desired
        if self.error is not None and gains.force_filter > 0.0:
            error = self.error + (error - self.error) * (dt / (gains.force_filter + dt))
        self.error = error
        rate = gains.gain * error - self.offset / gains.time_constant
        offset = self.offset + rate * dt
        limit = gains.max_offset
        if offset > limit or offset < -limit:
            offset = math.copysign(limit, offset)
            rate = (offset - self.offset) / dt
        self.offset, self.rate = offset, rate
        return offset, rate
