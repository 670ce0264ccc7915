"""ResidualAction: the learner's action is a correction added to the env's reference policy."""

from __future__ import annotations

import os
import time
from dataclasses import asdict, dataclass, field
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from ..policies import POLICY_NAMES, PolicyError, make_policy, supported_policies
from .action_check import check_action, check_bool, check_policy_kwargs, check_real
from .exceptions import WrapperError
from .glue_kernels import residual_applied

__all__ = ["REFERENCE_POLICIES", "ResidualAction", "ResidualActionConfig"]

REFERENCE_POLICIES: tuple[str, ...] = ("clik", "walking")
"""The reference policies a residual is added to, in the order they are tried (the first the env supports)."""


@dataclass(frozen=True)
class ResidualActionConfig:
    """Options of :class:`ResidualAction`.

    Attributes:
        scale: the residual's bound as a fraction of half the env's action range: the applied action is
            ``clip(reference + scale * half_range * a)`` for ``a`` in ``[-1, 1]`` (> 0, <= 2; ``half_range`` is 1
            for a ``[-1, 1]`` box).
        policy: the reference policy: a registered name, or the path of a stable-baselines3 ``.zip`` (a
            ``pathlib.Path`` is kept as its ``str``); None: the first of :data:`REFERENCE_POLICIES` that the env
            supports (``clik`` on the arms, ``walking`` on the biped).
        policy_kwargs: options of the reference policy.
        observe_reference: append the reference action to the observation.
    """

    scale: float = 0.2
    policy: str | None = None
    policy_kwargs: dict[str, Any] = field(default_factory=dict)
    observe_reference: bool = False


def _policy_name(policy: Any) -> str | None:
    """``policy`` as a name: a path as its ``str``, so that the recorded constructor arguments (``env.spec``) stay
    JSON-friendly; the name itself is checked when the policy is built.

    Raises:
        WrapperError: neither None, a name nor a path (a policy object: the spec could not rebuild it).
    """
    if policy is None or isinstance(policy, str):
        return policy
    if isinstance(policy, os.PathLike):
        return os.fsdecode(policy)
    raise WrapperError(
        f"ResidualAction: policy must be a registered policy name ({', '.join(POLICY_NAMES)}), the path of a "
        f"stable-baselines3 .zip, or None, got {policy!r} ({type(policy).__name__})"
    )


class ResidualAction(gym.Wrapper, gym.utils.RecordConstructorArgs):
    """Residual learning on an analytic controller: the applied action is the reference policy's action plus a
    bounded correction.

    ## Description
    Every step the reference policy (``clik`` on PlanarReach and AgriReach, ``walking`` on BipedWalk) computes its
    action from the current observation; the env receives ``clip(reference + scale * a, low, high)``. With
    ``a = 0`` the episode is the reference policy's, bit for bit, so a learner starts from the analytic
    controller and learns what it lacks.

    ## Action Space
    ``Box(-1, 1, (n,), float32)`` with ``n`` the env's action dimension: the residual in units of ``scale`` times
    half the env's action range (1 for a ``[-1, 1]`` box). Non-finite actions raise :class:`WrapperError`.

    ## Observation Space
    The env's; with ``observe_reference=True`` the reference action (``n`` entries in the env's action bounds)
    is appended.

    ## Rewards, Starting State, Episode End
    The env's. ``info`` keeps every entry of the env's and adds ``reference_action`` (the reference policy's
    action of this step) and ``residual_action`` (the applied minus the reference action, after clipping).

    ## Arguments
    ``env`` and the fields of :class:`ResidualActionConfig` as keyword arguments: ``scale``, ``policy``,
    ``policy_kwargs``, ``observe_reference``.

    The wrapper records these arguments (``gymnasium.utils.RecordConstructorArgs``), checked and with their defaults
    filled in (``policy_kwargs=None`` as ``{}``, a path ``policy`` as its ``str``; ``policy=None`` stays None and
    is resolved again on a rebuild), not the env: ``env.spec`` lists them, so ``gym.make(env.spec)`` rebuilds the
    whole stack and Gymnasium's ``check_env`` accepts the wrapper applied by hand. A relative ``.zip`` path is
    recorded as given: a rebuild from another working directory does not find it.

    ## Version History
    - v0: initial version.
    """

    # the action is no longer the env's joint command: no reference policy reads it (redundancy_gym.policies)
    CAPABILITIES: frozenset[str] = frozenset()

    def __init__(
        self,
        env: gym.Env,
        scale: float = ResidualActionConfig.scale,
        policy: str | os.PathLike[str] | None = None,
        policy_kwargs: dict[str, Any] | None = None,
        observe_reference: bool = False,
    ) -> None:
        gym.Wrapper.__init__(self, env)
        self.config = ResidualActionConfig(
            scale=check_real("scale", scale, low=0.0, high=2.0, low_open=True),
            policy=_policy_name(policy),
            policy_kwargs=check_policy_kwargs(policy_kwargs, "ResidualAction"),
            observe_reference=check_bool("observe_reference", observe_reference),
        )
        # the validated options, not the env: env.spec lists them, so gym.make(env.spec) rebuilds this wrapper
        gym.utils.RecordConstructorArgs.__init__(self, _disable_deepcopy=True, **asdict(self.config))
        space = env.action_space
        if not isinstance(space, spaces.Box) or not (
            np.all(np.isfinite(space.low)) and np.all(np.isfinite(space.high))
        ):
            raise WrapperError(f"ResidualAction needs a bounded Box action space, got {space}")
        policy = self.config.policy
        if policy is None:
            offered = supported_policies(env)
            policy = next((p for p in REFERENCE_POLICIES if p in offered), None)
            if policy is None:
                raise WrapperError(
                    f"ResidualAction: the env offers none of the reference policies "
                    f"{', '.join(REFERENCE_POLICIES)} (it offers {', '.join(offered)})"
                )
        try:
            self.reference = make_policy(policy, env, **self.config.policy_kwargs)
        except PolicyError as exc:
            raise WrapperError(f"ResidualAction: {exc}") from exc
        self.policy_name = policy
        self._low = space.low.astype(space.dtype)
        self._high = space.high.astype(space.dtype)
        self._dtype = space.dtype
        self._range = (space.high.astype(np.float64) - space.low.astype(np.float64)) / 2.0
        self._scaled_range = self.config.scale * self._range  # [action units] of a residual of 1
        self.action_space = spaces.Box(-1.0, 1.0, shape=space.shape, dtype=np.float32)
        if self.config.observe_reference:
            obs = env.observation_space
            if not isinstance(obs, spaces.Box):
                raise WrapperError(f"ResidualAction: observe_reference=True needs a Box observation space, got {obs}")
            self.observation_space = spaces.Box(
                np.concatenate([obs.low, space.low]).astype(obs.dtype),
                np.concatenate([obs.high, space.high]).astype(obs.dtype),
                dtype=obs.dtype,
            )
        self._reference_action: NDArray[Any] | None = None
        self.controller_time_us = 0.0
        """Compute time of the reference action computed last [us] (``CONTROLLER_TIME_ATTRIBUTE``): after a step, the
        next step's, from the step's observation, so that it is the controller time spent inside the step call
        (after ``reset``, the reset's)."""
        self._starting = True

    def _observe(self, obs: NDArray[np.floating], starting: bool) -> NDArray[np.floating]:
        """Compute the reference action of ``obs`` (kept for the next step) and the wrapper's observation."""
        began = time.perf_counter_ns()
        action, _ = self.reference.predict(obs, episode_start=np.array([starting]))
        self.controller_time_us = (time.perf_counter_ns() - began) * 1e-3
        self._reference_action = np.asarray(action, dtype=self._dtype)
        if self.config.observe_reference:
            return np.concatenate([obs, self._reference_action.astype(obs.dtype)])
        return obs

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.floating], dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        return self._observe(obs, True), info

    def step(self, action: Any) -> tuple[NDArray[np.floating], SupportsFloat, bool, bool, dict[str, Any]]:
        if self._reference_action is None:
            raise WrapperError("ResidualAction: call reset() before step()")
        a = check_action(action, self.action_space, "ResidualAction")
        reference = self._reference_action
        # in the env's dtype, so that a = 0 gives the reference action bit for bit
        applied, residual = residual_applied(reference, self._scaled_range, a, self._low, self._high)
        obs, reward, terminated, truncated, info = self.env.step(applied)
        info = {**info, "reference_action": reference, "residual_action": residual}
        return self._observe(obs, False), reward, terminated, truncated, info
