"""TaskSpaceAction: the learner commands the TCP's velocity; CLIK with avoidance in the nullspace moves the joints."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from ..controllers import ClikResult
from ..policies import PolicyError, make_policy
from ..validation import check_real
from .action_check import check_action, normalized_box
from .exceptions import WrapperError

__all__ = ["TaskSpaceAction", "TaskSpaceActionConfig"]

# control periods over which the guard looks ahead: the velocity servos take about one to reach a command
_LOOKAHEAD = 3.0


@dataclass(frozen=True)
class TaskSpaceActionConfig:
    """Options of :class:`TaskSpaceAction`.

    Attributes:
        max_speed: TCP speed of an action of 1 per axis [m/s] (> 0, <= 2).
        max_turn_rate: tool-axis turn rate of an action of 1 (AgriReach) [rad/s] (> 0, <= 6).
        max_lead: how far the commanded TCP target may run ahead of the TCP [m] (> 0, <= 0.5): where the arm
            cannot follow (a joint limit, an obstacle, the workspace's edge) the target waits for it instead of
            winding up.
        max_lead_angle: the same for the tool axis [rad] (> 0, <= 1.5).
        guard_distance: collision distance [m] below which each command is checked ahead (0 < guard <= 0.2).
        stop_distance: the distance [m] the guard keeps (0 <= stop < guard): a command that would bring a pair
            nearer than this is slowed down, to a stop if need be. The nullspace avoidance cannot keep the TCP
            itself off an obstacle the learner drives it into; this guard does.
        policy_kwargs: options of the ``clik`` reference whose controller (task gain, joint-limit and collision
            objectives, self-collision) turns the command into joint velocities.
    """

    max_speed: float = 0.3
    max_turn_rate: float = 1.0
    max_lead: float = 0.02
    max_lead_angle: float = 0.1
    guard_distance: float = 0.04
    stop_distance: float = 0.01
    policy_kwargs: dict[str, Any] = field(default_factory=dict)


def _tool_axis(quaternion: NDArray[np.float64]) -> NDArray[np.float64]:
    """The x axis of the rotation ``(w, x, y, z)``."""
    w, x, y, z = quaternion / np.linalg.norm(quaternion)
    return np.array([1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)])


def _cross(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a x b`` of two 3-vectors (``np.cross`` costs tens of microseconds on such small arrays)."""
    a0, a1, a2 = a.tolist()
    b0, b1, b2 = b.tolist()
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def _rotate(vector: NDArray[np.float64], rotation: NDArray[np.float64]) -> NDArray[np.float64]:
    """``vector`` turned by the rotation vector ``rotation`` (Rodrigues)."""
    angle = float(np.linalg.norm(rotation))
    if angle < 1e-12:
        return vector.copy()
    k = rotation / angle
    return (vector * np.cos(angle) + _cross(k, vector) * np.sin(angle)
            + k * (k @ vector) * (1.0 - np.cos(angle)))


def _perpendicular_basis(axis: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Two unit vectors orthogonal to ``axis`` and to each other (right-handed with it)."""
    helper = np.array([0.0, 0.0, 1.0]) if abs(axis[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    u = _cross(helper, axis)
    u /= np.linalg.norm(u)
    return u, _cross(axis, u)


class TaskSpaceAction(gym.Wrapper):
    """The action is a task-space velocity; the compiled CLIK of the ``clik`` reference, with joint-limit and
    collision avoidance (self and environment) in its nullspace, turns it into the env's joint command.

    ## Description
    Every control step the wrapper moves a TCP target by the commanded velocity and CLIK
    ``qdot = J# (wdot_d + K e) - alpha N dH/dq`` (5.5), (5.14) tracks it, with the reference's nullspace
    objectives: the joint-limit potential and the swept-sphere collision potential (5.49)-(5.61) on the robot's
    own segments and the env's obstacles (PlanarReach: the sphere; AgriReach: stems and fruits, and leaves when
    the reference avoids them). The learner never has to learn inverse kinematics or avoidance. The target is
    kept within ``max_lead`` of the TCP, so a command the arm cannot follow does not wind up.

    ## Action Space
    ``Box(-1, 1, (k,), float32)``, scaled by the bounds:

    | env | k | entries |
    |-----|---|---------|
    | PlanarReach | 2 | TCP velocity along x and z, times ``max_speed`` [m/s] |
    | AgriReach | 5 | TCP velocity x, y, z times ``max_speed`` [m/s]; tool-axis turn rate about two directions orthogonal to the current tool axis, times ``max_turn_rate`` [rad/s] |

    Non-finite actions raise :class:`WrapperError`.

    ## Observation Space, Rewards, Starting State, Episode End
    The env's. ``info`` keeps every entry of the env's and adds ``clik_sigma_min``, ``clik_damping``,
    ``clik_limited`` and ``target_lag`` (distance of the TCP target from the TCP [m]).

    ## Arguments
    ``env`` and the fields of :class:`TaskSpaceActionConfig` as keyword arguments.

    ## Version History
    - v0: initial version.
    """

    # the action is no longer the env's joint command: no reference policy reads it (redundancy_gym.policies)
    CAPABILITIES: frozenset[str] = frozenset()

    def __init__(self, env: gym.Env, max_speed: float = TaskSpaceActionConfig.max_speed,
                 max_turn_rate: float = TaskSpaceActionConfig.max_turn_rate,
                 max_lead: float = TaskSpaceActionConfig.max_lead,
                 max_lead_angle: float = TaskSpaceActionConfig.max_lead_angle,
                 guard_distance: float = TaskSpaceActionConfig.guard_distance,
                 stop_distance: float = TaskSpaceActionConfig.stop_distance,
                 policy_kwargs: dict[str, Any] | None = None) -> None:
        super().__init__(env)
        self.config = TaskSpaceActionConfig(
            max_speed=check_real("max_speed", max_speed, low=0.0, high=2.0, low_open=True, unit="m/s",
                                 error=WrapperError),
            max_turn_rate=check_real("max_turn_rate", max_turn_rate, low=0.0, high=6.0, low_open=True, unit="rad/s",
                                     error=WrapperError),
            max_lead=check_real("max_lead", max_lead, low=0.0, high=0.5, low_open=True, unit="m", error=WrapperError),
            max_lead_angle=check_real("max_lead_angle", max_lead_angle, low=0.0, high=1.5, low_open=True, unit="rad",
                                      error=WrapperError),
            guard_distance=check_real("guard_distance", guard_distance, low=0.0, high=0.2, low_open=True, unit="m",
                                      error=WrapperError),
            stop_distance=check_real("stop_distance", stop_distance, low=0.0, unit="m", error=WrapperError),
            policy_kwargs=dict(policy_kwargs or {}))
        if self.config.stop_distance >= self.config.guard_distance:
            raise WrapperError(f"stop_distance={stop_distance!r} must be below guard_distance={guard_distance!r} [m]")
        options = {"collision_avoidance": "on", **self.config.policy_kwargs}
        try:
            self.reference: Any = make_policy("clik", env, **options)
        except PolicyError as exc:
            raise WrapperError(f"TaskSpaceAction: {exc}") from exc
        base = env.unwrapped
        self._layout = dict(getattr(base, "observation_layout", None) or base.OBSERVATION_LAYOUT)
        self._grasp = "grasp_position" in self._layout
        self._dt = float(base.dt)
        self._speeds = self.reference.max_joint_speeds
        self.action_space = normalized_box(5 if self._grasp else 2)
        self._obs: NDArray[np.float64] | None = None
        self._position = np.zeros(3 if self._grasp else 2)
        self._axis = np.array([1.0, 0.0, 0.0])

    def _tcp(self, obs: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64] | None]:
        """The observed TCP position and (AgriReach) tool axis."""
        if self._grasp:
            return obs[self._layout["tcp_position"]], _tool_axis(obs[self._layout["tcp_quaternion"]])
        return obs[self._layout["tcp"]], None

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[NDArray[np.floating], dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        self._obs = np.asarray(obs, dtype=np.float64)
        # the reference plans its episode here (AgriReach: the controller with the observed obstacles)
        self.reference.task_reference(self._obs, True)
        position, axis = self._tcp(self._obs)
        self._position = position.copy()
        if axis is not None:
            self._axis = axis
        return obs, info

    def command(self, a: NDArray[np.float64]) -> ClikResult:
        """The CLIK result for the normalized task velocity ``a`` at the last observation (moves the target)."""
        assert self._obs is not None
        c = self.config
        position, axis = self._tcp(self._obs)
        velocity = a[:self._position.size] * c.max_speed
        target = self._position + velocity * self._dt
        lead = target - position
        distance = float(np.linalg.norm(lead))
        if distance > c.max_lead:
            target = position + lead * (c.max_lead / distance)
        self._position = target
        q = self._obs[self._layout["q"]]
        if not self._grasp:
            self.reference.update_obstacle(self._obs)
            return self._guarded(q, target, velocity)
        assert axis is not None
        u, v = _perpendicular_basis(axis)
        omega = (a[3] * u + a[4] * v) * c.max_turn_rate
        target_axis = _rotate(self._axis, omega * self._dt)
        angle = float(np.arccos(np.clip(target_axis @ axis, -1.0, 1.0)))
        if angle > c.max_lead_angle:  # turn the target axis back towards the tool axis, onto the allowed cone
            turn = _cross(axis, target_axis)
            norm = float(np.linalg.norm(turn))
            if norm > 1e-12:
                target_axis = _rotate(axis, turn / norm * c.max_lead_angle)
        self._axis = target_axis / np.linalg.norm(target_axis)
        return self._guarded(q, np.concatenate([target, self._axis]), np.concatenate([velocity, omega]))

    def _guarded(self, q: NDArray[np.float64], target: NDArray[np.float64],
                 velocity: NDArray[np.float64]) -> ClikResult:
        """The CLIK step, slowed down where it would bring the robot nearer than ``stop_distance`` to an obstacle
        or itself: once the smallest collision distance is below ``guard_distance``, the distance at the
        configuration the command reaches in ``_LOOKAHEAD`` periods is checked (one more kernel call each), and
        the command is scaled by 1/2, 1/4, then 0 until it no longer closes in past ``stop_distance``."""
        controller = self.reference.controller
        result = controller.step(q, target, velocity)
        c = self.config
        closest = self._closest(controller, q)
        if not closest < c.guard_distance:
            return result
        horizon = _LOOKAHEAD * self._dt
        floor = min(closest, c.stop_distance)
        for scale in (1.0, 0.5, 0.25):
            qdot = scale * result.qdot
            controller.step(q + qdot * horizon, target, velocity)
            ahead = self._closest(controller, q + qdot * horizon)
            if ahead >= floor or ahead >= closest:
                return result if scale == 1.0 else result._replace(qdot=qdot, limited=True)
        return result._replace(qdot=np.zeros_like(result.qdot), limited=True)

    def _closest(self, controller: Any, q: NDArray[np.float64]) -> float:
        """The smallest collision distance [m] at ``q``, which the controller's last step was evaluated at."""
        closest = getattr(controller, "last_min_distance", None)
        if closest is not None:
            return float(closest)
        collision = self.reference.collision  # the Python backend: its collision model at the model's q
        return np.inf if collision is None else float(
            np.min(collision.collision_model.evaluate(self.reference.model).distance, initial=np.inf))

    def step(self, action: Any) -> tuple[NDArray[np.floating], float, bool, bool, dict[str, Any]]:
        if self._obs is None:
            raise WrapperError("TaskSpaceAction: call reset() before step()")
        a = check_action(action, self.action_space, "TaskSpaceAction")
        result = self.command(a)
        joint_action = np.clip(result.qdot / self._speeds, -1.0, 1.0).astype(np.float32)
        obs, reward, terminated, truncated, info = self.env.step(joint_action)
        self._obs = np.asarray(obs, dtype=np.float64)
        lag = float(np.linalg.norm(self._position - self._tcp(self._obs)[0]))
        info = {**info, "clik_sigma_min": result.sigma_min, "clik_damping": result.damping,
                "clik_limited": result.limited, "target_lag": lag}
        return obs, reward, terminated, truncated, info
