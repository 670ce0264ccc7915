"""Parameters of the walking pattern: step timing and geometry, the reduced model, the swing foot."""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from ..exceptions import ControllerError

__all__ = ["GaitConfig"]


@dataclass(frozen=True)
class GaitConfig:
    """Step sequence, CoM and swing-foot parameters of :class:`~redundancy_gym.controllers.walking.WalkingPattern`.

    Attributes:
        step_duration: ``T`` [s], time from one touchdown to the next (single plus double support).
        double_support_ratio: share of ``T`` with both feet on the ground, in (0, 1).
        step_width: lateral distance of the two footholds [m].
        max_step_length: longest step [m]; faster commands shorten ``T`` (down to ``min_step_duration``).
        min_step_duration: shortest ``T`` [s] a fast command may use.
        step_height: apex of the swing foot above the ground [m].
        swing_pitch: largest toes-down pitch of the swing foot [rad], in [0, 0.6] (lift-off without over-bending
            the ankle).
        swing_pitch_peak: share of the single support at which the swing pitch peaks, in (0, swing_pitch_flat).
        toe_length: distance from the sole point to the tip of the toe [m]; the pitched swing foot turns about it.
        swing_pitch_flat: share of the single support from which the swing foot is flat again, in (0, 1).
        swing_settle: share of the single support at its end in which the swing foot only comes down, in [0, 0.5):
            its horizontal motion ends before, so a foot that touches down early (it tracks its height a centimetre
            or two low) lands on its foothold rather than short of it while still moving forward.
        com_height: ``z_c`` of the LIPM, height of the CoM above the ground [m].
        start_duration: double support at the start, while the weight moves onto the first stance foot [s].
        heel_toe_shift: the ZMP rolls from ``-shift`` to ``+shift`` along the stance foot in single support [m].
        zmp_inset: lateral shift of the ZMP from the foot centre towards the walking line [m].
        preview_steps: steps planned ahead of the current one (the DCM converges as ``e^(-omega T)`` per step).
    """

    step_duration: float = 0.8
    double_support_ratio: float = 0.2
    step_width: float = 0.18
    max_step_length: float = 0.6
    min_step_duration: float = 0.6
    step_height: float = 0.07
    swing_pitch: float = 0.25
    swing_pitch_peak: float = 0.3
    swing_pitch_flat: float = 0.75
    toe_length: float = 0.165
    swing_settle: float = 0.1
    com_height: float = 0.91
    start_duration: float = 0.4
    heel_toe_shift: float = 0.02
    zmp_inset: float = 0.01
    preview_steps: int = 4

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            wanted = (int, np.integer) if f.name == "preview_steps" else (int, float, np.integer, np.floating)
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, wanted):
                kind = "an int" if f.name == "preview_steps" else "a real number"
                raise ControllerError(f"{f.name} must be {kind}, got {value!r} ({type(value).__name__})")
        positive = (
            "step_duration",
            "step_width",
            "max_step_length",
            "min_step_duration",
            "step_height",
            "com_height",
            "start_duration",
        )
        for name in positive:
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0.0:
                raise ControllerError(f"{name} must be finite and > 0, got {value!r}")
        if not 0.0 < self.double_support_ratio < 1.0:
            raise ControllerError(f"double_support_ratio must lie in (0, 1), got {self.double_support_ratio!r}")
        if self.min_step_duration > self.step_duration:
            raise ControllerError("min_step_duration must not exceed step_duration")
        for name in ("heel_toe_shift", "zmp_inset", "toe_length"):
            value = getattr(self, name)
            if not np.isfinite(value) or value < 0.0:
                raise ControllerError(f"{name} must be finite and >= 0, got {value!r}")
        if not 0.0 < self.swing_pitch_peak < self.swing_pitch_flat < 1.0:
            raise ControllerError(
                "need 0 < swing_pitch_peak < swing_pitch_flat < 1, got "
                f"{self.swing_pitch_peak!r}, {self.swing_pitch_flat!r}"
            )
        if not 0.0 <= self.swing_settle < 0.5:
            raise ControllerError(f"swing_settle must lie in [0, 0.5), got {self.swing_settle!r}")
        if not 0.0 <= self.swing_pitch <= 0.6:  # toes up would turn the heel below the ground about the toe tip
            raise ControllerError(f"swing_pitch must lie in [0, 0.6] rad (toes down), got {self.swing_pitch!r}")
        if not isinstance(self.preview_steps, (int, np.integer)) or self.preview_steps < 2:
            raise ControllerError(f"preview_steps must be an int >= 2, got {self.preview_steps!r}")

    def timing(self, speed: float) -> tuple[float, float]:
        """``(step_length [m], step_duration [s])`` for a forward speed [m/s] (>= 0).

        Steps get longer with speed up to ``max_step_length``, then shorter in time down to
        ``min_step_duration``; beyond that the speed is what the longest, quickest step gives.
        """
        if not np.isfinite(speed) or speed < 0.0:
            raise ControllerError(f"speed must be finite and >= 0, got {speed!r}")
        duration = self.step_duration
        if speed * duration > self.max_step_length:
            duration = max(self.max_step_length / speed, self.min_step_duration)
        return min(speed * duration, self.max_step_length), duration
