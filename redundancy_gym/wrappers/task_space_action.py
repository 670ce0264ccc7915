"""TaskSpaceAction: the learner commands the TCP's velocity; CLIK with avoidance in the nullspace moves the joints."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from ..controllers import ClikResult
from ..geometry import LSS, PSS, SSV, TSS, Segment
from ..policies import PolicyError, make_policy
from ..validation import check_real
from .action_check import check_action, normalized_box
from .exceptions import WrapperError

__all__ = ["TaskSpaceAction", "TaskSpaceActionConfig"]

# control periods over which the joint ranges are kept: the velocity servos take about one to reach a command
_LOOKAHEAD = 2.0
# sweeps of the cyclic projection onto the violated collision constraints
_PROJECTIONS = 10
# the fraction of a commanded velocity change the envs' servos make within one control period (measured on
# AgriReach's arm at its speed limits: 0.3-0.6)
_SERVO_RESPONSE = 0.35
# how far inside its range [rad or m] the wrapper keeps each joint, for the servos' overshoot
_RANGE_MARGIN = 0.01


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
        guard_distance: collision distance [m] below which a pair's approach speed is limited (0 < guard <= 0.2).
        stop_distance: the distance [m] at which the approach speed reaches zero (0 <= stop < guard). The
            nullspace avoidance cannot keep the TCP itself off an obstacle the learner drives it into; this
            velocity damper can, at the cost of the task where they conflict.
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


def _scene_obstacles(base: Any) -> list[Segment] | None:
    """One segment per hard plant part of the episode but the target (AgriReach's ``crop_row`` and
    ``target_index``: what the env counts as a collision), or None for an env without them."""
    row = getattr(base, "crop_row", None)
    target = getattr(base, "target_index", None)
    if row is None or target is None:
        return None
    segments = []
    for k in np.flatnonzero(np.asarray(row.hard)):
        if k == target:
            continue
        v, r, kind = row.vertices[k], float(row.radius[k]), int(row.kind[k])
        volume: SSV = PSS(v[0], r) if kind == 0 else (LSS(v[0], v[1], r) if kind == 1 else TSS(v[0], v[1], v[2], r))
        segments.append(Segment(f"part_{k}", (volume,)))
    return segments


class TaskSpaceAction(gym.Wrapper):
    """The action is a task-space velocity; the compiled CLIK of the ``clik`` reference, with joint-limit and
    collision avoidance (self and environment) in its nullspace, turns it into the env's joint command.

    ## Description
    Every control step the wrapper moves a TCP target by the commanded velocity and CLIK
    ``qdot = J# (wdot_d + K e) - alpha N dH/dq`` (5.5), (5.14) tracks it, with the reference's nullspace
    objectives: the joint-limit potential and the swept-sphere collision potential (5.49)-(5.61) on the robot's
    own segments and the env's obstacles (PlanarReach: the sphere; AgriReach: every stem, shoot and fruit of the
    episode but the target, since the learner may take the arm anywhere, not only near the K observed parts).
    A velocity damper on the pairs nearer than ``guard_distance`` limits how fast each may close in, so a
    command that drives the TCP itself at an obstacle (which no nullspace motion can avoid) slows to a stop. The learner never has to learn inverse kinematics or avoidance. The target is
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
        model = self.reference.model
        self._lower, self._upper = model.lower_limits + _RANGE_MARGIN, model.upper_limits - _RANGE_MARGIN
        self.action_space = normalized_box(5 if self._grasp else 2)
        self._obs: NDArray[np.float64] | None = None
        self.last_result: ClikResult | None = None  # the command of the last step, for diagnostics
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
        scene = _scene_obstacles(self.env.unwrapped)
        if scene is not None:  # the learner may take the arm anywhere: every hard plant part, not the K observed
            self.reference.controller = self.reference.build_controller(scene)
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
        """The CLIK step with a velocity damper on every collision pair nearer than ``guard_distance``: the
        pair's distance may shrink at most at ``max_speed`` times ``(d - stop_distance) / (guard_distance -
        stop_distance)`` (zero at ``stop_distance``, growing below it), enforced by projecting ``qdot`` onto each
        violated constraint in turn; then every joint is kept inside its range over ``_LOOKAHEAD`` periods."""
        controller = self.reference.controller
        result = controller.step(q, target, velocity)
        c = self.config
        distances, rows = self._close_pairs(controller, q, c.guard_distance)
        qdot = result.qdot
        top = float(np.max(np.abs(qdot) / self._speeds))
        changed = top > 1.0
        if changed:  # the env would clip each joint, turning the command: slower instead, same direction
            qdot = qdot / top
        if distances.size:
            floor = -c.max_speed * (distances - c.stop_distance) / (c.guard_distance - c.stop_distance)
            # the servos make only part of a velocity change within one period: ask for the rate that brings the
            # joints' actual velocity onto the floor by the next period
            actual = rows @ self._obs[self._layout["qdot"]]
            floor = (floor - (1.0 - _SERVO_RESPONSE) * actual) / _SERVO_RESPONSE
            norms = np.einsum("ij,ij->i", rows, rows)
            qdot = qdot.copy()
            for _ in range(_PROJECTIONS):
                violated = False
                for k in range(distances.size):
                    gap = floor[k] - float(rows[k] @ qdot)
                    if gap > 1e-12 and norms[k] > 1e-18:
                        qdot += (gap / norms[k]) * rows[k]
                        violated = changed = True
                if not violated:
                    break
            top = float(np.max(np.abs(qdot) / self._speeds))
            if top > 1.0:  # the projection may ask for more than the joints can do
                qdot /= top
        horizon = _LOOKAHEAD * self._dt
        actual = (1.0 - _SERVO_RESPONSE) * self._obs[self._layout["qdot"]]
        low = ((self._lower - q) / horizon - actual) / _SERVO_RESPONSE
        high = ((self._upper - q) / horizon - actual) / _SERVO_RESPONSE
        bounded = np.clip(qdot, np.minimum(low, 0.0), np.maximum(high, 0.0))
        if changed or not np.array_equal(bounded, qdot):
            return result._replace(qdot=bounded, limited=True)
        return result

    def _close_pairs(self, controller: Any, q: NDArray[np.float64], limit: float
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Distances and ``dd/dq`` rows of the collision pairs nearer than ``limit`` at ``q`` (the compiled
        controller's last step, or the Python controller's collision model)."""
        if hasattr(controller, "close_pairs"):
            return controller.close_pairs(limit)
        collision = self.reference.collision
        if collision is None:
            return np.zeros(0), np.zeros((0, q.size))
        model = collision.collision_model
        state = model.evaluate(self.reference.model)  # the step left the robot model at q
        near = np.flatnonzero(state.distance < limit)
        return state.distance[near], model.distance_gradient(self.reference.model, state, near)

    def step(self, action: Any) -> tuple[NDArray[np.floating], float, bool, bool, dict[str, Any]]:
        if self._obs is None:
            raise WrapperError("TaskSpaceAction: call reset() before step()")
        a = check_action(action, self.action_space, "TaskSpaceAction")
        result = self.last_result = self.command(a)
        joint_action = np.clip(result.qdot / self._speeds, -1.0, 1.0).astype(np.float32)
        obs, reward, terminated, truncated, info = self.env.step(joint_action)
        self._obs = np.asarray(obs, dtype=np.float64)
        lag = float(np.linalg.norm(self._position - self._tcp(self._obs)[0]))
        info = {**info, "clik_sigma_min": result.sigma_min, "clik_damping": result.damping,
                "clik_limited": result.limited, "target_lag": lag}
        return obs, reward, terminated, truncated, info
