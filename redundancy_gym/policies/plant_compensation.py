"""What a velocity-commanded arm's CLIK does about a plant that differs from its model (issue 36): a one-time
calibration of the robot's placement from the observed TCP, and a Smith predictor for actuation latency.

The env's ``dynamics`` randomization (:mod:`redundancy_gym.envs.dynamics`) moves the simulated robot's base and
delays its commands; the controllers keep the nominal model. Two measures bring the CLIK's task error back to what
it is on the nominal plant:

- **Placement calibration** (``base_calibration``): at an episode's first observation, the observed TCP less the
  model's TCP at the observed joints is the base's offset (a translation of the base moves the TCP by the same
  vector in every configuration); the CLIK then tracks its targets less that offset in the model's frame. On the
  nominal plant the offset is round-off (pinocchio's and MuJoCo's kinematics of the same MJCF).
- **Latency compensation** (``latency`` ``k`` control periods, or measured at each episode's start): the
  commands of the last ``k`` periods are still on their way to the actuators, so the joints where the next command
  starts acting are predicted as the observed ones plus the commands in flight times the period
  (:class:`DelayCompensation`), and the reference is taken ``k`` periods ahead (extrapolated with its
  acceleration). With the plant's latency ``k`` this removes the delay from the loop (a Smith predictor). By
  default the policy measures ``k`` while the robot starts from rest (the periods until its first command shows in
  the observed joint velocities); a given ``k`` (the hardware's nominal latency) is used as it is.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..model import RobotModel
from .exceptions import PolicyError

__all__ = ["MAX_LATENCY", "RESPONSE", "RESTING", "DelayCompensation", "delay_compensation", "tcp_offset"]

MAX_LATENCY = 10
"""Largest latency [control periods] a policy compensates (the env's ``dynamics`` draws at most as many)."""
RESTING = 1e-9
"""A joint speed [rad/s or m/s] below which a command or an observed velocity is round-off (a robot at rest)."""
RESPONSE = 1e-3
"""The share of the first command's speed that an observed joint speed must reach to count as its response."""


def tcp_offset(
    model: RobotModel, frame: str, q: NDArray[np.float64], observed: NDArray[np.float64], axes: tuple[int, ...]
) -> NDArray[np.float64]:
    """The observed TCP position less the model's at ``q`` (the model's ``axes`` of the frame's position) [m]."""
    model.update(q)
    return np.asarray(observed, dtype=np.float64) - model.frame_position(frame)[list(axes)]


def delay_compensation(latency: int | None, period: float | None, nv: int) -> DelayCompensation:
    """A policy's :class:`DelayCompensation` of ``latency`` periods (None: measured at each episode's start); without
    a control period ``period`` [s] (None) none is measured, and a given latency > 0 raises PolicyError."""
    if not period:  # nothing to predict over: a given latency is an error, a measured one stays off
        if latency:
            raise PolicyError(f"latency={latency} needs an env with a control period (dt), got {period!r}")
        latency = 0
    return DelayCompensation(latency, period or 0.0, nv)


class DelayCompensation:
    """A Smith predictor for joint velocity commands that the plant applies ``latency`` control periods late.

    With ``latency=None`` the delay is measured at each episode's start, where the robot rests: the joints' observed
    velocities stay at round-off until the first command that moves them arrives, so the periods between that
    command and the first observation that moves (:data:`RESPONSE` of the command's speed) are the latency; until
    then the periods waited so far are its lower bound. A robot that moves before any command (or noisy velocity
    sensors) gives 0: no compensation.

    Args:
        latency: control periods of delay (0: none, :meth:`predict` gives ``q`` back); None: measured.
        period: the control period [s].
        nv: number of joint velocities.
    """

    def __init__(self, latency: int | None, period: float, nv: int) -> None:
        self.measured = latency is None
        self.given = 0 if latency is None else int(latency)
        self.latency = self.given
        self.period = float(period)
        self._sent = np.zeros((MAX_LATENCY, nv))  # the last MAX_LATENCY commands, newest at _head - 1
        self._head = 0
        self._last_velocity: NDArray[np.float64] | None = None  # the reference's velocity one period before
        self._steps = 0  # commands sent this episode
        self._first: int | None = None  # the index of the first command that moves the robot
        self._response = RESTING  # the observed joint speed that answers it
        self._settled = not self.measured
        self._time: float | None = None  # the time of the last observation
        self._repeat = False  # this period's observation was seen before (a second predict on it)

    def reset(self) -> None:
        """A new episode: nothing in flight (the env fills its delay line with the reset's zero commands)."""
        self._sent[:] = 0.0
        self._head = 0
        self._last_velocity = None
        self._steps = 0
        self._first = None
        self.latency = self.given
        self._settled = not self.measured
        self._time = None
        self._repeat = False

    @property
    def idle(self) -> bool:
        """Whether nothing is left to measure or compensate this episode (no latency, measured or given)."""
        return self._settled and self.latency == 0

    def observe(self, qdot: NDArray[np.float64], time: float | None = None) -> None:
        """The joints' observed velocities [rad/s or m/s] before this period's command (measures the latency), at
        the observation's ``time`` (any clock that advances with the periods; None: every call is a new period). An
        observation whose time did not advance is the last one again: it measures nothing, and the command that
        follows replaces the last one sent."""
        self._repeat = time is not None and self._time is not None and time <= self._time
        if not self._repeat:
            self._time = time
        if self._settled or self._repeat:
            return
        moving = float(np.max(np.abs(qdot))) > self._threshold
        if self._first is None:
            if moving:  # moving before any command: nothing to measure
                self._settled = True
            return
        waited = self._steps - self._first  # periods since the first command, this observation included
        if moving:
            self.latency, self._settled = waited - 1, True
        else:
            self.latency = min(waited, MAX_LATENCY)
            self._settled = waited >= MAX_LATENCY

    @property
    def _threshold(self) -> float:
        return RESTING if self._first is None else self._response

    def reference(
        self, target: NDArray[np.float64], velocity: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The task reference ``latency`` periods ahead: position [m] and velocity [m/s] extrapolated with the
        reference's acceleration, its velocity's change over the last period (zero at an episode's start); the
        reference itself without latency."""
        last, self._last_velocity = self._last_velocity, velocity
        if self.latency == 0:
            return target, velocity
        horizon = self.latency * self.period
        acceleration = np.zeros_like(velocity) if last is None else (velocity - last) / self.period
        return target + horizon * velocity + 0.5 * horizon**2 * acceleration, velocity + horizon * acceleration

    def predict(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """The joints [rad or m] when the next command starts acting: ``q`` plus the commands in flight over their
        periods."""
        if self.latency == 0:
            return q
        newest = (self._head - 1 - np.arange(self.latency)) % MAX_LATENCY
        return q + self.period * self._sent[newest].sum(axis=0)

    def sent(self, qdot: NDArray[np.float64]) -> None:
        """Record the joint velocities [rad/s or m/s] just commanded (as the env applies them: clipped)."""
        if self.idle:
            return
        if self._repeat and self._steps:  # the same period's command again: it replaces the last one
            self._head = (self._head - 1) % MAX_LATENCY
            self._steps -= 1
            if self._first == self._steps:
                self._first = None
        if self._first is None and not self._settled:
            speed = float(np.max(np.abs(qdot)))
            if speed > RESTING:
                self._first, self._response = self._steps, RESPONSE * speed
        self._sent[self._head] = qdot
        self._head = (self._head + 1) % MAX_LATENCY
        self._steps += 1
