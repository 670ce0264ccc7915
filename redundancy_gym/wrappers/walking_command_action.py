"""WalkingCommandAction: the learner commands the walking velocity; the walking reference moves the joints."""

from __future__ import annotations

import functools
import time
from dataclasses import dataclass, field
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from ..policies import PolicyError, make_policy
from .action_check import check_action, check_int, check_policy_kwargs, check_real, normalized_box
from .exceptions import WrapperError
from .reference_wrapper import ReferenceActionWrapper

__all__ = ["WalkingCommandAction", "WalkingCommandActionConfig"]


@dataclass(frozen=True)
class WalkingCommandActionConfig:
    """Options of :class:`WalkingCommandAction`.

    Attributes:
        min_forward_speed, max_forward_speed: the forward speed of an action of -1 and +1 [m/s]
            (0 <= min < max <= 0.75, the fastest speed of the gait's 0.8 s steps).
        max_lateral_speed: the sideways speed of an action of +-1 [m/s] (0 <= max <= 0.1: faster, the feet of a
            sideways step come within 0.1 m of each other).
        max_yaw_rate: the yaw rate of an action of +-1 [rad/s] (+: turning left; 0 <= max <= 0.5, a heading change
            of 0.4 rad per 0.8 s step).
        command_period: control periods each action is held for (>= 1); the rewards of the periods are summed (and
            in ``info`` the reward terms and ``pseudoenergy``; contacts and falls of any period count, the peak
            joint speed and the clearances are the worst of the periods), and the episode still ends at the env's
            time limit (its ``max_episode_steps`` control periods).
        policy_kwargs: options of the ``walking`` reference (``WalkingPolicyConfig`` fields).
    """

    min_forward_speed: float = 0.2
    max_forward_speed: float = 0.6
    max_lateral_speed: float = 0.05
    max_yaw_rate: float = 0.3
    command_period: int = 1
    policy_kwargs: dict[str, Any] = field(default_factory=dict)


# info entries of one control period that an action held over several periods reports over all of them
_SUMMED = ("pseudoenergy",)  # and every reward term (reward_*), as the step's reward is their sum
_ANY = ("collision", "self_collision", "fell")
_MAX = ("peak_joint_speed",)
_MIN = ("min_clearance", "min_self_clearance")


def _hold(held: dict[str, Any], info: dict[str, Any]) -> None:
    """Fold one period's ``info`` into ``held``: sums, any, max and min over the periods so far."""
    summed, any_of, largest, smallest = _held_keys(tuple(info))
    for key in summed:
        held[key] = held.get(key, 0.0) + float(info[key])
    for key in any_of:
        held[key] = held.get(key, False) or bool(info[key])
    for key in largest:
        held[key] = max(held.get(key, -np.inf), float(info[key]))
    for key in smallest:
        held[key] = min(held.get(key, np.inf), float(info[key]))


@functools.lru_cache(maxsize=16)
def _held_keys(keys: tuple[str, ...]) -> tuple[tuple[str, ...], ...]:
    """The keys of an ``info`` (its keys in order: an env's are the same every step) that :func:`_hold` sums,
    takes any of, the largest and the smallest of: sorted once per key set, not per step."""
    return (
        tuple(k for k in keys if k in _SUMMED or k.startswith("reward_")),
        tuple(k for k in keys if k in _ANY and not (k in _SUMMED or k.startswith("reward_"))),
        tuple(k for k in keys if k in _MAX and k not in _SUMMED and k not in _ANY),
        tuple(k for k in keys if k in _MIN and k not in _SUMMED and k not in _ANY and k not in _MAX),
    )


class WalkingCommandAction(ReferenceActionWrapper):
    """The action is a walking velocity and yaw rate; the ``walking`` reference (DCM pattern, stabilizer, step
    adjustment, whole-body CLIK) turns it into the biped's joint targets every control period.

    ## Description
    Each action sets the velocity and the turning rate of the walk
    (:meth:`~redundancy_gym.controllers.walking.WalkingController.set_command`): the footholds after the landing
    of the step under way move so that each later step covers the commanded velocity times the step duration
    along the walker's heading, and turns that heading by the yaw rate times the step duration (the feet, the
    ZMP plan and the torso turn with it); the CoM plan is replanned from now on. The walk starts at ``reset``
    from the standing robot at the env's ``target_speed``, along +x. A learner chooses where to walk, not how.

    ## Action Space
    ``Box(-1, 1, (3,), float32)``: forward speed from ``min_forward_speed`` (-1) to ``max_forward_speed`` (+1)
    [m/s], sideways speed (+ to the left) times ``max_lateral_speed`` [m/s], and yaw rate (+ turning left,
    counter-clockwise seen from above) times ``max_yaw_rate`` [rad/s]; forward and sideways are in the frame of
    the walker's current heading. Non-finite actions raise :class:`WrapperError`.

    ## Observation Space, Rewards, Starting State, Episode End
    The env's: its reward and ``is_success`` still measure the walk against its ``target_speed``, not against
    the commanded speed (pass ``target_speed`` to ``gym.make`` for another); they reward progress along +x, so a
    walker that turns away from +x scores less. With ``command_period`` > 1 the
    rewards of the periods are summed (so are ``info``'s reward terms and ``pseudoenergy``; ``collision``,
    ``self_collision`` and ``fell`` hold if they held in any period, ``peak_joint_speed`` and the clearances are
    the worst of the periods), and the episode ends at the env's time limit in control periods (10 s). ``info``
    keeps every entry of the env's and adds ``commanded_forward_speed`` and ``commanded_lateral_speed`` [m/s],
    ``commanded_yaw_rate`` [rad/s] and ``step_adjusted`` (the push-recovery step adjustment acted in this period).

    ## Arguments
    ``env`` and the options (recorded as :class:`~redundancy_gym.wrappers.reference_wrapper.ReferenceActionWrapper`
    records them, instead of the env): the fields of :class:`WalkingCommandActionConfig` as keyword arguments.

    ## Version History
    - v0: initial version; the yaw rate (the action's third entry) was added later under the same id.
    """

    # reference: the ``walking`` policy this wrapper drives (WalkingPolicy: its controller, commands, episode start),
    # used by duck typing as the registry builds it

    def __init__(
        self,
        env: gym.Env,
        min_forward_speed: float = WalkingCommandActionConfig.min_forward_speed,
        max_forward_speed: float = WalkingCommandActionConfig.max_forward_speed,
        max_lateral_speed: float = WalkingCommandActionConfig.max_lateral_speed,
        max_yaw_rate: float = WalkingCommandActionConfig.max_yaw_rate,
        command_period: int = WalkingCommandActionConfig.command_period,
        policy_kwargs: dict[str, Any] | None = None,
    ) -> None:
        self._wrap(env)
        self.config = WalkingCommandActionConfig(
            min_forward_speed=check_real("min_forward_speed", min_forward_speed, low=0.0, high=0.75, unit="m/s"),
            max_forward_speed=check_real("max_forward_speed", max_forward_speed, low=0.0, high=0.75, unit="m/s"),
            max_lateral_speed=check_real("max_lateral_speed", max_lateral_speed, low=0.0, high=0.1, unit="m/s"),
            max_yaw_rate=check_real("max_yaw_rate", max_yaw_rate, low=0.0, high=0.5, unit="rad/s"),
            command_period=check_int("command_period", command_period, low=1, high=1000),
            policy_kwargs=check_policy_kwargs(policy_kwargs, "WalkingCommandAction"),
        )
        self._record(self.config)
        if self.config.min_forward_speed >= self.config.max_forward_speed:
            raise WrapperError(
                f"min_forward_speed={min_forward_speed!r} must be below max_forward_speed={max_forward_speed!r} [m/s]"
            )
        try:
            self.reference = make_policy("walking", env, **self.config.policy_kwargs)
        except PolicyError as exc:
            raise WrapperError(f"WalkingCommandAction: {exc}") from exc
        self.action_space = normalized_box(3)
        self._obs: NDArray[np.float64] | None = None
        self._periods = 0  # control periods of the episode so far

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.floating], dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        self._obs = np.asarray(obs, dtype=np.float64)
        self.reference.begin(self._obs)
        self._periods = 0
        return obs, info

    def _period_limit(self) -> int | None:
        """The env's time limit in control periods (its registered ``max_episode_steps``), or None."""
        spec = getattr(self.env.unwrapped, "spec", None)
        limit = getattr(spec, "max_episode_steps", None)
        base = (getattr(spec, "kwargs", None) or {}).get("env_id")  # a wrapped id's spec names its base env
        if not limit and isinstance(base, str) and base in gym.registry:
            limit = gym.spec(base).max_episode_steps
        return int(limit) if limit else None

    def velocity(self, action: NDArray[np.float64]) -> tuple[float, float, float]:
        """The (forward, lateral) speed [m/s] and the yaw rate [rad/s] of a normalized action."""
        c = self.config
        forward = c.min_forward_speed + 0.5 * (float(action[0]) + 1.0) * (c.max_forward_speed - c.min_forward_speed)
        return forward, float(action[1]) * c.max_lateral_speed, float(action[2]) * c.max_yaw_rate

    def step(self, action: Any) -> tuple[NDArray[np.floating], SupportsFloat, bool, bool, dict[str, Any]]:
        if self._obs is None:
            raise WrapperError("WalkingCommandAction: call reset() before step()")
        forward, lateral, yaw_rate = self.velocity(check_action(action, self.action_space, "WalkingCommandAction"))
        began = time.perf_counter_ns()
        # the controller's own work: a new command replans the walking pattern's coming steps
        self.reference.controller.set_command(forward, lateral, yaw_rate)
        elapsed_ns = time.perf_counter_ns() - began
        total = 0.0
        adjusted = False
        limit = self._period_limit() if self.config.command_period > 1 else None
        held: dict[str, Any] = {}  # the per-period info entries summed / worst over the periods of this action
        for _ in range(self.config.command_period):
            began = time.perf_counter_ns()
            joint_action = self.reference.command(self._obs)
            elapsed_ns += time.perf_counter_ns() - began
            adjusted |= self.reference.last_command.adjustment is not None
            obs, reward, terminated, truncated, info = self.env.step(joint_action)
            self._obs = np.asarray(obs, dtype=np.float64)
            self._periods += 1
            total += float(reward)
            if self.config.command_period > 1:  # one period's info is its own sum, any, max and min
                _hold(held, info)
            if limit is not None and self._periods >= limit:
                truncated = True  # the time limit counts this wrapper's steps, each command_period periods long
            if terminated or truncated:
                break
        info = {
            **info,
            **held,
            "commanded_forward_speed": forward,
            "commanded_lateral_speed": lateral,
            "commanded_yaw_rate": yaw_rate,
            "step_adjusted": adjusted,
        }
        self.controller_time_us = elapsed_ns * 1e-3
        return obs, total, terminated, truncated, info
