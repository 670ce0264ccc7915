"""What a velocity-commanded arm's CLIK does about a plant that differs from its model (issue 36): a one-time
calibration of the robot's placement from the observed TCP, and a Smith predictor for actuation latency.

The env's ``dynamics`` randomization (:mod:`redundancy_gym.envs.dynamics`) moves the simulated robot's base and
delays its commands; the controllers keep the nominal model. Two measures bring the CLIK's task error back to what
it is on the nominal plant:

- **Placement calibration** (``base_calibration``): at an episode's first observation, the observed TCP less the
  model's TCP at the observed joints is the base's offset (a translation of the base moves the TCP by the same
  vector in every configuration); the CLIK then tracks its targets less that offset in the model's frame. On the
  nominal plant the offset is round-off (pinocchio's and MuJoCo's kinematics of the same MJCF).
- **Latency compensation** (``latency`` ``k`` control periods): the commands of the last ``k`` periods are still on
  their way to the actuators, so the joints where the next command starts acting are predicted as the observed
  ones plus the commands in flight times the period (:class:`DelayCompensation`), and the reference is taken ``k``
  periods ahead (extrapolated with its acceleration). With the plant's latency ``k`` this removes the delay from
  the loop (a Smith predictor); the controller must be told ``k`` (the hardware's nominal latency), it does not
  measure it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..model import RobotModel
from .exceptions import PolicyError

__all__ = ["MAX_LATENCY", "DelayCompensation", "delay_compensation", "tcp_offset"]

MAX_LATENCY = 10
"""Largest latency [control periods] a policy compensates (the env's ``dynamics`` draws at most as many)."""


def tcp_offset(
    model: RobotModel, frame: str, q: NDArray[np.float64], observed: NDArray[np.float64], axes: tuple[int, ...]
) -> NDArray[np.float64]:
    """The observed TCP position less the model's at ``q`` (the model's ``axes`` of the frame's position) [m]."""
    model.update(q)
    return np.asarray(observed, dtype=np.float64) - model.frame_position(frame)[list(axes)]


def delay_compensation(latency: int, period: float | None, nv: int) -> DelayCompensation:
    """A policy's :class:`DelayCompensation` of ``latency`` periods; PolicyError when the env has no control period
    ``period`` [s] (None) to predict over."""
    if latency and not period:
        raise PolicyError(f"latency={latency} needs an env with a control period (dt), got {period!r}")
    return DelayCompensation(latency, period or 0.0, nv)


class DelayCompensation:
    """A Smith predictor for joint velocity commands that the plant applies ``latency`` control periods late.

    Args:
        latency: control periods of delay (0: none, :meth:`predict` gives ``q`` back).
        period: the control period [s].
        nv: number of joint velocities.
    """

    def __init__(self, latency: int, period: float, nv: int) -> None:
        self.latency = int(latency)
        self.period = float(period)
        self._in_flight = np.zeros((max(self.latency, 1), nv))
        self._head = 0
        self._last_velocity: NDArray[np.float64] | None = None  # the reference's velocity one period before

    def reset(self) -> None:
        """A new episode: nothing in flight (the env fills its delay line with the reset's zero commands)."""
        self._in_flight[:] = 0.0
        self._head = 0
        self._last_velocity = None

    def ahead(
        self, target: NDArray[np.float64], velocity: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """A task reference ``latency`` periods ahead: position [m] and velocity [m/s] extrapolated with the
        reference's acceleration, its velocity's change over the last period (zero at an episode's start)."""
        horizon = self.latency * self.period
        last, self._last_velocity = self._last_velocity, velocity
        acceleration = np.zeros_like(velocity) if last is None else (velocity - last) / self.period
        return target + horizon * velocity + 0.5 * horizon**2 * acceleration, velocity + horizon * acceleration

    def predict(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """The joints [rad or m] when the next command starts acting: ``q`` plus the commands in flight over their
        periods."""
        if self.latency == 0:
            return q
        return q + self.period * self._in_flight.sum(axis=0)

    def sent(self, qdot: NDArray[np.float64]) -> None:
        """Record the joint velocities [rad/s or m/s] just commanded (as the env applies them: clipped)."""
        if self.latency == 0:
            return
        self._in_flight[self._head] = qdot
        self._head = (self._head + 1) % self.latency
