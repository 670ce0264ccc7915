"""NullspaceAction: CLIK follows the env's reference path; the learner gives only the nullspace input ``u`` (5.100)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from ..controllers import ClikResult
from ..policies import PolicyError, make_policy
from .action_check import check_action, check_bool, check_policy_kwargs, check_real, normalized_box
from .exceptions import WrapperError
from .glue_kernels import joint_command
from .reference_wrapper import ReferenceActionWrapper

__all__ = ["NullspaceAction", "NullspaceActionConfig"]

# the fractions of u tried, in turn, when the full u would make a joint exceed its speed limit: the controller would
# then slow the whole command down, task included; scaling u alone keeps the task
_SHRINK = (0.5, 0.25, 0.125, 0.0)


@dataclass(frozen=True)
class NullspaceActionConfig:
    """Options of :class:`NullspaceAction`.

    Attributes:
        max_nullspace_speed: the bound of ``u`` as a fraction of each joint's speed limit: ``u = a *
            max_nullspace_speed * max_joint_speeds`` (> 0, <= 1).
        objectives: add the ``clik`` reference's nullspace objectives (joint-limit and collision avoidance,
            (5.14)) to the learner's ``u``; False: ``u`` alone (``u = 0`` is then the minimum-norm tracker).
        policy_kwargs: options of the ``clik`` reference the task, gain and (with ``objectives``) the objectives
            come from (``ClikPolicyConfig`` / ``GraspClikConfig`` fields).
    """

    max_nullspace_speed: float = 0.1
    objectives: bool = False
    policy_kwargs: dict[str, Any] = field(default_factory=dict)


def _without_objectives(env: gym.Env) -> dict[str, Any]:
    """``clik`` options that switch its nullspace objectives off (the arms' two kinds of ``clik``)."""
    grasp = "grasp_position" in getattr(env.unwrapped, "observation_layout", {})
    return {"joint_limit_weight": 0.0, "collision_avoidance": "off", **({} if grasp else {"posture_weight": 0.0})}


class NullspaceAction(ReferenceActionWrapper):
    """The redundancy resolution as the action: CLIK tracks the env's reference, the learner chooses ``u``.

    ## Description
    Every control step ``qdot = J# (wdot_d + K e) + N u`` (5.5), (5.100), computed by the compiled CLIK of the
    ``clik`` reference policy (PlanarReach: the line; AgriReach: the reference path to the pre-grasp pose and
    the radial approach). ``N u`` leaves the task velocity unchanged (``J N = 0``), so any bounded ``u`` keeps the
    tracking; the learner chooses only how the arm uses its redundancy (here: to keep clear of the obstacle, the
    stems, the joint limits). When ``J# (...) + N u`` would exceed a joint's speed limit, ``u`` is scaled down
    (by 1/2, 1/4, 1/8, then 0) instead of the whole command, so the task is still tracked.

    ``u = 0`` is the minimum-norm tracker without objectives (on PlanarReach it runs into the obstacle, as the
    plain line tracker does); ``objectives=True`` adds the reference's joint-limit and collision gradients to
    ``u``, so ``a = 0`` is then the ``clik`` reference itself.

    ## Action Space
    ``Box(-1, 1, (nv,), float32)``: ``u`` in units of ``max_nullspace_speed`` times each joint's speed limit
    (PlanarReach 4, AgriReach 9). Non-finite actions raise :class:`WrapperError`.

    ## Observation Space, Rewards, Starting State, Episode End
    The env's. ``info`` keeps every entry of the env's and adds ``clik_sigma_min`` (smallest singular value of
    the task Jacobian), ``clik_damping`` (DLS damping), ``clik_limited`` (the command was bounded) and
    ``nullspace_fraction`` (the fraction of ``u`` applied, 1 unless a speed limit scaled it).

    ## Arguments
    ``env`` and the options (recorded as :class:`~redundancy_gym.wrappers.reference_wrapper.ReferenceActionWrapper`
    records them, instead of the env): the fields of :class:`NullspaceActionConfig` as keyword arguments.

    ## Version History
    - v0: initial version.
    """

    # reference: the ``clik`` policy this wrapper drives (ClikPolicy on PlanarReach, GraspClikPolicy on AgriReach: their
    # controller, task reference and joint speeds), used by duck typing as the registry builds it

    def __init__(
        self,
        env: gym.Env,
        max_nullspace_speed: float = NullspaceActionConfig.max_nullspace_speed,
        objectives: bool = False,
        policy_kwargs: dict[str, Any] | None = None,
    ) -> None:
        self._wrap(env)
        self.config = NullspaceActionConfig(
            max_nullspace_speed=check_real(
                "max_nullspace_speed", max_nullspace_speed, low=0.0, high=1.0, low_open=True
            ),
            objectives=check_bool("objectives", objectives),
            policy_kwargs=check_policy_kwargs(policy_kwargs, "NullspaceAction"),
        )
        self._record(self.config)
        options = (
            dict(self.config.policy_kwargs) if objectives else {**_without_objectives(env), **self.config.policy_kwargs}
        )
        try:
            self.reference = make_policy("clik", env, **options)
        except PolicyError as exc:
            raise WrapperError(f"NullspaceAction: {exc}") from exc
        self._speeds = self.reference.max_joint_speeds
        self._scale = self.config.max_nullspace_speed * self._speeds
        self.action_space = normalized_box(self._speeds.size)
        self._obs: NDArray[np.float64] | None = None
        self._starting = True

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.floating], dict[str, Any]]:
        obs, info = self.env.reset(seed=seed, options=options)
        self._obs = np.asarray(obs, dtype=np.float64)
        self._starting = True
        return obs, info

    def command(self, u: NDArray[np.float64]) -> tuple[ClikResult, float]:
        """The CLIK result for the nullspace input ``u`` [rad/s or m/s] at the last observation, and the fraction
        of ``u`` applied."""
        assert self._obs is not None
        q, target, velocity = self.reference.task_reference(self._obs, self._starting)
        self._starting = False
        controller = self.reference.controller
        result = controller.step(q, target, velocity, nullspace_input=u)
        fraction = 1.0
        # beyond the env's joint speeds (which may be below the model's, which the controller bounds to)
        if np.any(u) and np.max(np.abs(result.qdot) / self._speeds) >= 1.0 - 1e-9:
            for fraction in _SHRINK:
                result = controller.step(q, target, velocity, nullspace_input=fraction * u)
                if np.max(np.abs(result.qdot) / self._speeds) < 1.0 - 1e-9:
                    break
        return result, fraction

    def step(self, action: Any) -> tuple[NDArray[np.floating], SupportsFloat, bool, bool, dict[str, Any]]:
        if self._obs is None:
            raise WrapperError("NullspaceAction: call reset() before step()")
        a = check_action(action, self.action_space, "NullspaceAction")
        began = time.perf_counter_ns()
        result, fraction = self.command(a * self._scale)
        self.controller_time_us = (time.perf_counter_ns() - began) * 1e-3
        joint_action = joint_command(result.qdot, self._speeds)
        obs, reward, terminated, truncated, info = self.env.step(joint_action)
        self._obs = obs if obs.dtype == np.float64 else obs.astype(np.float64)
        info.update(
            clik_sigma_min=result.sigma_min,
            clik_damping=result.damping,
            clik_limited=result.limited,
            nullspace_fraction=fraction,
        )
        return obs, reward, terminated, truncated, info
