"""TaskSpaceAction: the learner commands the TCP's velocity; CLIK with avoidance in the nullspace moves the joints."""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from ..controllers import ClikResult
from ..geometry import SSV, Segment
from ..policies import PolicyError, make_policy
from .action_check import check_action, check_policy_kwargs, check_real, normalized_box
from .exceptions import WrapperError
from .glue_kernels import joint_command
from .reference_wrapper import ReferenceActionWrapper

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
_NO_PAIRS = (np.zeros(0), np.zeros((0, 0)))


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


# Small 3-vector algebra on Python floats: numpy's per-call overhead on 3 entries is larger than the arithmetic
Vec = tuple[float, float, float]


def _vec(entries: Iterable[float]) -> Vec:
    """Three floats as a :data:`Vec`."""
    x, y, z = entries
    return (x, y, z)


def _tool_axis(quaternion: NDArray[np.float64]) -> Vec:
    """The x axis of the rotation ``(w, x, y, z)``."""
    w, x, y, z = quaternion.tolist()
    n = 1.0 / (w * w + x * x + y * y + z * z)
    return (1.0 - 2.0 * n * (y * y + z * z), 2.0 * n * (x * y + w * z), 2.0 * n * (x * z - w * y))


def _cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _dot(a: Vec, b: Vec) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _unit(a: Vec) -> Vec:
    n = math.sqrt(_dot(a, a))
    return (a[0] / n, a[1] / n, a[2] / n)


def _rotate(vector: Vec, rotation: Vec) -> Vec:
    """``vector`` turned by the rotation vector ``rotation`` (Rodrigues)."""
    angle = math.sqrt(_dot(rotation, rotation))
    if angle < 1e-12:
        return vector
    k = (rotation[0] / angle, rotation[1] / angle, rotation[2] / angle)
    c, s = math.cos(angle), math.sin(angle)
    kxv, kv = _cross(k, vector), _dot(k, vector) * (1.0 - c)
    return _vec(vector[i] * c + kxv[i] * s + k[i] * kv for i in range(3))


def _perpendicular_basis(axis: Vec) -> tuple[Vec, Vec]:
    """Two unit vectors orthogonal to ``axis`` and to each other (right-handed with it)."""
    helper = (0.0, 0.0, 1.0) if abs(axis[2]) < 0.9 else (1.0, 0.0, 0.0)
    u = _unit(_cross(helper, axis))
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
        volume = SSV.from_kind(int(row.kind[k]), row.vertices[k], float(row.radius[k]))
        segments.append(Segment(f"part_{k}", (volume,)))
    return segments


class TaskSpaceAction(ReferenceActionWrapper):
    """The action is a task-space velocity; the compiled CLIK of the ``clik`` reference, with joint-limit and
    collision avoidance (self and environment) in its nullspace, turns it into the env's joint command.

    ## Description
    Every control step the wrapper moves a TCP target by the commanded velocity and CLIK
    ``qdot = J# (wdot_d + K e) - alpha N dH/dq`` (5.5), (5.14) tracks it, with the reference's nullspace
    objectives: the joint-limit potential and the swept-sphere collision potential (5.49)-(5.61) on the robot's
    own segments and the env's obstacles (PlanarReach: the sphere; AgriReach: every stem, shoot and fruit of the
    episode but the target, since the learner may take the arm anywhere, not only near the K observed parts).
    A velocity damper on the pairs nearer than ``guard_distance`` limits how fast each may close in, so a
    command that drives the TCP itself at an obstacle (which no nullspace motion can avoid) slows to a stop. The
    learner never has to learn inverse kinematics or avoidance. The target is kept within ``max_lead`` of the TCP,
    so a command the arm cannot follow does not wind up.

    ## Action Space
    ``Box(-1, 1, (k,), float32)``, scaled by the bounds:

    - PlanarReach, k = 2: the TCP velocity along x and z, times ``max_speed`` [m/s].
    - AgriReach, k = 5: the TCP velocity along x, y, z times ``max_speed`` [m/s]; the tool-axis turn rate about
      two directions orthogonal to the current tool axis, times ``max_turn_rate`` [rad/s].

    Non-finite actions raise :class:`WrapperError`.

    ## Observation Space, Rewards, Starting State, Episode End
    The env's. ``info`` keeps every entry of the env's and adds ``clik_sigma_min``, ``clik_damping``,
    ``clik_limited`` and ``target_lag`` (distance of the TCP target from the TCP [m]).

    ## Arguments
    ``env`` and the options (recorded as :class:`~redundancy_gym.wrappers.reference_wrapper.ReferenceActionWrapper`
    records them, instead of the env): the fields of :class:`TaskSpaceActionConfig` as keyword arguments.

    ## Version History
    - v0: initial version.
    """

    # reference: the ``clik`` policy this wrapper drives (ClikPolicy on PlanarReach, GraspClikPolicy on AgriReach: their
    # controller, model, collision model and obstacle planning differ), used by duck typing as the registry builds it

    def __init__(
        self,
        env: gym.Env,
        max_speed: float = TaskSpaceActionConfig.max_speed,
        max_turn_rate: float = TaskSpaceActionConfig.max_turn_rate,
        max_lead: float = TaskSpaceActionConfig.max_lead,
        max_lead_angle: float = TaskSpaceActionConfig.max_lead_angle,
        guard_distance: float = TaskSpaceActionConfig.guard_distance,
        stop_distance: float = TaskSpaceActionConfig.stop_distance,
        policy_kwargs: dict[str, Any] | None = None,
    ) -> None:
        self._wrap(env)
        self.config = TaskSpaceActionConfig(
            max_speed=check_real("max_speed", max_speed, low=0.0, high=2.0, low_open=True, unit="m/s"),
            max_turn_rate=check_real("max_turn_rate", max_turn_rate, low=0.0, high=6.0, low_open=True, unit="rad/s"),
            max_lead=check_real("max_lead", max_lead, low=0.0, high=0.5, low_open=True, unit="m"),
            max_lead_angle=check_real("max_lead_angle", max_lead_angle, low=0.0, high=1.5, low_open=True, unit="rad"),
            guard_distance=check_real("guard_distance", guard_distance, low=0.0, high=0.2, low_open=True, unit="m"),
            stop_distance=check_real("stop_distance", stop_distance, low=0.0, unit="m"),
            policy_kwargs=check_policy_kwargs(policy_kwargs, "TaskSpaceAction"),
        )
        self._record(self.config)
        if self.config.stop_distance >= self.config.guard_distance:
            raise WrapperError(f"stop_distance={stop_distance!r} must be below guard_distance={guard_distance!r} [m]")
        options = {"collision_avoidance": "on", **self.config.policy_kwargs}
        try:
            self.reference = make_policy("clik", env, **options)
        except PolicyError as exc:
            raise WrapperError(f"TaskSpaceAction: {exc}") from exc
        base: Any = env.unwrapped  # read by duck typing: the attributes the tcp_tracking/grasp_task envs offer
        self._layout = dict(getattr(base, "observation_layout", None) or base.OBSERVATION_LAYOUT)
        self._grasp = "grasp_position" in self._layout
        self._dt = float(base.dt)
        self._speeds = self.reference.max_joint_speeds
        model = self.reference.model
        # whether the controller's speed bound (the model's) lets a command exceed the env's joint speeds
        self._model_faster = bool(np.any(np.asarray(model.velocity_limits) > self._speeds))
        self._lower, self._upper = model.lower_limits + _RANGE_MARGIN, model.upper_limits - _RANGE_MARGIN
        # farther from its range than this, no joint can reach it within the look-ahead, whatever its speed
        reach = float(np.max(self._speeds)) * _LOOKAHEAD * self._dt / _SERVO_RESPONSE
        self._safe_lower, self._safe_upper = (self._lower + reach).tolist(), (self._upper - reach).tolist()
        self.action_space = normalized_box(5 if self._grasp else 2)
        self._obs: NDArray[np.float64] | None = None
        self.last_result: ClikResult | None = None  # the command of the last step, for diagnostics
        self._position: list[float] = [0.0] * (3 if self._grasp else 2)  # the TCP target [m]
        self._axis: Vec = (1.0, 0.0, 0.0)  # the tool-axis target

    def _tcp(self, obs: NDArray[np.float64]) -> list[float]:
        """The observed TCP position [m]."""
        return obs[self._layout["tcp_position" if self._grasp else "tcp"]].tolist()

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.floating], dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        self._obs = np.asarray(obs, dtype=np.float64)
        if self._grasp:  # the controller of this episode's obstacles (PlanarReach's is placed in command())
            scene = _scene_obstacles(self.env.unwrapped)
            if scene is not None:  # the learner may take the arm anywhere: every hard plant part, not the K observed
                self.reference.controller = self.reference.build_controller(scene)
            else:  # an env without its crop row: the observed obstacles, as the reference plans them
                self.reference.plan(self._obs)
        self._position = self._tcp(self._obs)
        if self._grasp:
            self._axis = _tool_axis(self._obs[self._layout["tcp_quaternion"]])
        return obs, info

    def command(self, a: NDArray[np.float64]) -> ClikResult:
        """The CLIK result for the normalized task velocity ``a`` at the last observation (moves the target)."""
        assert self._obs is not None
        c, obs, lay = self.config, self._obs, self._layout
        entries = a.tolist()
        q = obs[lay["q"]]
        if not self._grasp:
            position = obs[lay["tcp"]].tolist()
        else:
            position = obs[lay["tcp_position"]].tolist()
        n = len(position)
        velocity = [entries[i] * c.max_speed for i in range(n)]
        target = [self._position[i] + velocity[i] * self._dt for i in range(n)]
        lead = [target[i] - position[i] for i in range(n)]
        distance = math.hypot(*lead)
        if distance > c.max_lead:
            target = [position[i] + lead[i] * (c.max_lead / distance) for i in range(n)]
        self._position = target
        if not self._grasp:
            self.reference.update_obstacle(obs)
            return self._guarded(q, np.array(target), np.array(velocity))
        axis = _tool_axis(obs[lay["tcp_quaternion"]])
        u, v = _perpendicular_basis(axis)
        rate = c.max_turn_rate
        omega = _vec((entries[3] * u[i] + entries[4] * v[i]) * rate for i in range(3))
        target_axis = _rotate(self._axis, _vec(w * self._dt for w in omega))
        angle = math.acos(max(-1.0, min(1.0, _dot(target_axis, axis))))
        if angle > c.max_lead_angle:  # turn the target axis back towards the tool axis, onto the allowed cone
            turn = _cross(axis, target_axis)
            norm = math.sqrt(_dot(turn, turn))
            if norm > 1e-12:
                target_axis = _rotate(axis, _vec(x / norm * c.max_lead_angle for x in turn))
        self._axis = _unit(target_axis)
        return self._guarded(q, np.array([*target, *self._axis]), np.array([*velocity, *omega]))

    def _guarded(
        self, q: NDArray[np.float64], target: NDArray[np.float64], velocity: NDArray[np.float64]
    ) -> ClikResult:
        """The CLIK step with a velocity damper on every collision pair nearer than ``guard_distance``: the
        pair's distance may shrink at most at ``max_speed`` times ``(d - stop_distance) / (guard_distance -
        stop_distance)`` (zero at ``stop_distance``, growing below it), enforced by projecting ``qdot`` onto each
        violated constraint in turn; then every joint is kept inside its range over ``_LOOKAHEAD`` periods."""
        assert self._obs is not None
        controller = self.reference.controller
        result = controller.step(q, target, velocity)
        c = self.config
        closest = getattr(controller, "last_min_distance", 0.0)  # the compiled kernel's: no pair is nearer
        distances, rows = (
            self._close_pairs(controller, q, c.guard_distance) if closest < c.guard_distance else _NO_PAIRS
        )
        qdot = result.qdot
        # the controller bounds the command to the model's joint speeds, the env's may be lower (AgriReach: half):
        # the env would clip each joint, turning the command; slower instead, in the same direction
        changed = False
        if self._model_faster:
            top = float(np.max(np.abs(qdot) / self._speeds))
            changed = top > 1.0
            if changed:
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
        if any(not lo < x < hi for x, lo, hi in zip(q.tolist(), self._safe_lower, self._safe_upper, strict=True)):
            horizon = _LOOKAHEAD * self._dt
            actual = (1.0 - _SERVO_RESPONSE) * self._obs[self._layout["qdot"]]
            low = ((self._lower - q) / horizon - actual) / _SERVO_RESPONSE
            high = ((self._upper - q) / horizon - actual) / _SERVO_RESPONSE
            bounded = np.clip(qdot, np.minimum(low, 0.0), np.maximum(high, 0.0))
            changed = changed or not np.array_equal(bounded, qdot)
            qdot = bounded
        return result._replace(qdot=qdot, limited=True) if changed else result

    def _close_pairs(
        self, controller: Any, q: NDArray[np.float64], limit: float
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

    def step(self, action: Any) -> tuple[NDArray[np.floating], SupportsFloat, bool, bool, dict[str, Any]]:
        if self._obs is None:
            raise WrapperError("TaskSpaceAction: call reset() before step()")
        a = check_action(action, self.action_space, "TaskSpaceAction")
        began = time.perf_counter_ns()
        result = self.last_result = self.command(a)
        self.controller_time_us = (time.perf_counter_ns() - began) * 1e-3
        joint_action = joint_command(result.qdot, self._speeds)
        obs, reward, terminated, truncated, info = self.env.step(joint_action)
        self._obs = obs if obs.dtype == np.float64 else obs.astype(np.float64)
        lag = math.dist(self._position, self._tcp(self._obs))
        info.update(
            clik_sigma_min=result.sigma_min, clik_damping=result.damping, clik_limited=result.limited, target_lag=lag
        )
        return obs, reward, terminated, truncated, info
