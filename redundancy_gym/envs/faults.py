"""Fault injection shared by the envs: external pushes on a body (the biped's ``push`` argument).

:class:`PushSchedule` turns the ``push`` argument (an explicit list of pushes, or a random push process) into
the force to apply at each control step. Every random draw comes from the generator the env passes (its own
``np_random``), so ``reset(seed=...)`` reproduces the pushes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .exceptions import EnvConfigError
from .validation import check_choice, check_range_pair, check_real, check_real_array

__all__ = ["PUSH_DIRECTIONS", "PushSchedule"]

PUSH_DIRECTIONS = ("lateral", "forward", "any")
"""Directions of the random push process: ``lateral`` (+-y), ``forward`` (+-x, along the walking direction, either
sign), ``any`` (a uniform horizontal direction)."""
_EPS = 1e-9  # [s] tolerance of the window bounds against the accumulated env time


def _keys(name: str, entry: Mapping[str, Any], allowed: tuple[str, ...], required: tuple[str, ...]) -> None:
    unknown = sorted(set(entry) - set(allowed))
    if unknown:
        raise EnvConfigError(f"{name} has unknown key(s) {', '.join(map(str, unknown))}; valid: {', '.join(allowed)}")
    missing = [k for k in required if k not in entry]
    if missing:
        raise EnvConfigError(f"{name} needs the key(s) {', '.join(missing)}")


class PushSchedule:
    """External pushes: an explicit schedule or a seeded random push process.

    Args:
        push: the env's ``push`` argument, either

            - a list of pushes, each a dict ``{"time": t0 [s] >= 0, "force": (fx, fy, fz) [N] (world frame),
              "duration": d [s] > 0, "body": name (optional)}``: the force acts during ``[t0, t0 + d)``;
            - a random process, a dict ``{"rate": pushes per second > 0, "force": (min, max) [N] >= 0,
              "duration": d [s] > 0, "body": name (optional), "direction": "lateral" | "forward" | "any"
              (optional, default "any")}``: after each reset, and after each push ends, the wait until the next
              push is exponential with mean ``1 / rate``; its magnitude is uniform in ``(min, max)`` and its
              horizontal direction as :data:`PUSH_DIRECTIONS` says.
        default_body: the body of pushes that name none.
        name: the argument's name in error messages.

    The env calls :meth:`reset` at each reset and :meth:`force_at` at the start of each control step.
    """

    def __init__(self, push: Any, default_body: str, name: str = "push") -> None:
        self.random = isinstance(push, Mapping)
        self.bodies: list[str] = []
        if self.random:
            _keys(name, push, ("rate", "force", "duration", "body", "direction"), ("rate", "force", "duration"))
            self.rate = check_real(f"{name}['rate']", push["rate"], low=0.0, low_open=True, unit="1/s")
            self.magnitude = check_range_pair(f"{name}['force']", push["force"], low=0.0, unit="N")
            self.duration = check_real(f"{name}['duration']", push["duration"], low=0.0, low_open=True, unit="s")
            self.direction = check_choice(f"{name}['direction']", push.get("direction", "any"), PUSH_DIRECTIONS)
            self.bodies.append(self._body(push.get("body", default_body), f"{name}['body']"))
            self.pushes: list[tuple[float, float, NDArray[np.float64], int]] = []
        else:
            if isinstance(push, (str, bytes)) or not isinstance(push, Sequence):
                raise EnvConfigError(
                    f"{name} must be None, a list of pushes (dicts with time, force, duration, body) "
                    f"or a random push process (a dict with rate, force, duration, body, direction), "
                    f"got {push!r} ({type(push).__name__})"
                )
            self.pushes = []
            for i, entry in enumerate(push):
                where = f"{name}[{i}]"
                if not isinstance(entry, Mapping):
                    raise EnvConfigError(f"{where} must be a dict with time, force, duration and body, got {entry!r}")
                _keys(where, entry, ("time", "force", "duration", "body"), ("time", "force", "duration"))
                start = check_real(f"{where}['time']", entry["time"], low=0.0, unit="s")
                force = check_real_array(
                    f"{where}['force']",
                    entry["force"],
                    shape=(3,),
                    unit="N",
                    what="(fx, fy, fz), 3 finite real numbers",
                )
                duration = check_real(f"{where}['duration']", entry["duration"], low=0.0, low_open=True, unit="s")
                body = self._body(entry.get("body", default_body), f"{where}['body']")
                if body not in self.bodies:
                    self.bodies.append(body)
                self.pushes.append((start, start + duration, force, self.bodies.index(body)))
            self.pushes.sort(key=lambda p: p[0])
        self._next = 0
        self._active: tuple[float, float, NDArray[np.float64], int] | None = None

    @staticmethod
    def _body(body: Any, name: str) -> str:
        if not isinstance(body, str):
            raise EnvConfigError(f"{name} must be a body's name (a str), got {body!r} ({type(body).__name__})")
        return body

    def reset(self, rng: np.random.Generator) -> None:
        """Start a new episode at time 0 (the random process draws the time of its first push)."""
        self._active = None
        self._next = 0
        if self.random:
            self._next_start = float(rng.exponential(1.0 / self.rate))

    def force_at(self, time: float, rng: np.random.Generator) -> tuple[NDArray[np.float64], int] | None:
        """The push acting at ``time`` [s] (the start of a control step): ``(force [N], body index into
        :attr:`bodies`)``, or None when none acts."""
        active = self._active
        if active is not None and time < active[1] - _EPS:
            return active[2], active[3]
        self._active = None
        if self.random:
            if time >= self._next_start - _EPS:
                start = self._next_start
                magnitude = float(rng.uniform(*self.magnitude))
                if self.direction == "lateral":
                    unit = np.array([0.0, 1.0 if rng.random() < 0.5 else -1.0, 0.0])
                elif self.direction == "forward":
                    unit = np.array([1.0 if rng.random() < 0.5 else -1.0, 0.0, 0.0])
                else:
                    angle = float(rng.uniform(0.0, 2.0 * np.pi))
                    unit = np.array([np.cos(angle), np.sin(angle), 0.0])
                end = start + self.duration
                self._next_start = end + float(rng.exponential(1.0 / self.rate))
                if time < end - _EPS:
                    self._active = (start, end, magnitude * unit, 0)
        else:
            while self._next < len(self.pushes) and self.pushes[self._next][1] <= time + _EPS:
                self._next += 1  # windows already over (or shorter than a control step and skipped)
            if self._next < len(self.pushes) and self.pushes[self._next][0] <= time + _EPS:
                self._active = self.pushes[self._next]
                self._next += 1
        if self._active is None:
            return None
        return self._active[2], self._active[3]
