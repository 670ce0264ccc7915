"""Policies with the stable-baselines3 ``predict`` signature: analytic reference controllers and learned models.

This module joins controllers and environments (DESIGN.md): it reads what it needs from the env by duck
typing (``OBSERVATION_LAYOUT``, ``ROBOT_XML``, ``TCP_FRAME``, ``TASK_AXES``, ``max_joint_speed``) and never
imports mujoco, so the same policy object can drive a robot fed with the same observation. Only the error for an
unsupported env reaches the simulation side: it builds the registered envs (gymnasium, lazily) to name those the
policy supports.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ..geometry import PSS, Segment
from ..model import RobotModel, collision_model_from_mjcf
from ..sb3_import import LEARN_EXTRA_HINT, import_stable_baselines3
from .clik import Clik, ClikResult
from .collision_objective import CollisionObjective
from .compiled_clik import CompiledClik
from .exceptions import PolicyError
from .frame_position_task import FramePositionTask
from .joint_limit_objective import JointLimitObjective
from .policy_options import config_from_options, env_with_attributes
from .posture_objective import PostureObjective

__all__ = ["POLICY_NAMES", "ClikPolicy", "ClikPolicyConfig", "Policy", "RandomPolicy", "Sb3Policy", "ZeroPolicy",
           "env_name", "make_policy", "missing_capabilities", "policy_supports", "supported_env_ids",
           "supported_policies"]

POLICY_NAMES: tuple[str, ...] = ("clik", "walking", "predictive", "global", "zero", "random")
_SB3_ALGOS = ("PPO", "SAC", "TD3", "A2C", "DDPG")

# What each reference policy reads from the (unwrapped) env; mirrors the checks of the policy constructors
# (ClikPolicy, GraspClikPolicy, WalkingPolicy, PredictivePolicy) so that a policy's support for an env is known
# without building it.
_CLIK_NEEDS = ("OBSERVATION_LAYOUT", "ROBOT_XML", "TCP_FRAME", "TASK_AXES", "max_joint_speed")
_GRASP_CLIK_NEEDS = ("observation_layout", "ROBOT_XML", "TCP_FRAME", "max_joint_speeds")
_WALKING_NEEDS = ("OBSERVATION_LAYOUT", "ROBOT_XML", "SOFT_LIMIT_MARGIN", "joint_limits", "nominal_configuration",
                  "action_scale", "dt")
_WALKING_LAYOUT = ("base_position", "q", "base_linear_velocity", "qdot", "right_force", "left_torque", "command")


@runtime_checkable
class Policy(Protocol):
    """The stable-baselines3 prediction signature shared by every policy."""

    def predict(self, observation: NDArray[np.floating], state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[NDArray[np.floating], Any]:
        """Action for an observation, and the (unused) recurrent state."""
        ...


class ZeroPolicy:
    """Always the zero action (for a velocity-commanded arm: hold still)."""

    def __init__(self, env: Any) -> None:
        self._action = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)

    def predict(self, observation: NDArray[np.floating], state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[NDArray[np.floating], Any]:
        """The zero action."""
        return self._action.copy(), state


class RandomPolicy:
    """Uniform random actions in the action box, from the policy's own seeded generator.

    Args:
        env: the environment (its action space bounds are used).
        seed: seed of the generator.
    """

    def __init__(self, env: Any, seed: int | None = 0) -> None:
        space = env.action_space
        self._low = np.asarray(space.low, dtype=np.float64)
        self._high = np.asarray(space.high, dtype=np.float64)
        if not (np.all(np.isfinite(self._low)) and np.all(np.isfinite(self._high))):
            raise PolicyError("the random policy needs a bounded action space")
        self._dtype = space.dtype
        self._rng = np.random.default_rng(seed)

    def predict(self, observation: NDArray[np.floating], state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[NDArray[np.floating], Any]:
        """A uniform random action."""
        return self._rng.uniform(self._low, self._high).astype(self._dtype), state


@dataclass(frozen=True)
class ClikPolicyConfig:
    """Defaults of the CLIK reference policy (see :class:`~redundancy_gym.controllers.Clik`).

    Attributes:
        method: ``"pseudoinverse"``, ``"dls"`` or ``"transpose"``.
        gain: task-space feedback ``K`` [1/s] of (5.5).
        nullspace_gain: ``alpha`` of (5.14).
        joint_limit_activation: ``d_a`` of the joint-limit potential [rad].
        joint_limit_slope: slope of the joint-limit potential at the limit.
        joint_limit_weight: weight of the joint-limit objective (0 switches it off).
        posture_weight: weight of a pull towards the env's starting posture (0 switches it off).
        dls_threshold: ``eps`` of the DLS damping law.
        dls_max_damping: ``k_max`` of the DLS damping law.
        collision_avoidance: ``"auto"`` (on when the env has an obstacle), ``"on"`` or ``"off"``: the
            nullspace collision objective (5.49)-(5.61) on the robot's geoms and the env's obstacle.
        collision_activation: ``d_a`` of the collision potential [m].
        collision_slope: slope of the collision potential at contact [1/m].
        collision_weight: weight of the collision objective.
        self_collision: also avoid robot-robot pairs (non-adjacent links).
        backend: ``"compiled"`` (:class:`~redundancy_gym.controllers.CompiledClik`, one fused kernel per step)
            or ``"python"`` (:class:`~redundancy_gym.controllers.Clik`); same commands to round-off.
    """

    method: str = "dls"
    gain: float = 20.0
    nullspace_gain: float = 1.0
    joint_limit_activation: float = 0.35
    joint_limit_slope: float = 1.0
    joint_limit_weight: float = 1.0
    posture_weight: float = 0.0
    dls_threshold: float = 0.05
    dls_max_damping: float = 0.01
    collision_avoidance: str = "auto"
    collision_activation: float = 0.15
    collision_slope: float = 5.0
    collision_weight: float = 1.0
    self_collision: bool = True
    backend: str = "compiled"


COLLISION_MODES = ("auto", "on", "off")
OBSTACLE_SEGMENT = "obstacle"


class ClikPolicy:
    """Velocity-level CLIK (5.14) on the env's task, as a policy: observation in, normalized joint velocities out.

    The joint configuration and the task reference (position and velocity) are read from the observation;
    the model is the env's robot MJCF loaded by pinocchio. The last :class:`ClikResult` is kept in
    :attr:`last_result` for diagnostics.

    Args:
        env: an env exposing ``OBSERVATION_LAYOUT`` (with ``q``, ``tcp_ref``, ``tcp_ref_vel``), ``ROBOT_XML``,
            ``TCP_FRAME``, ``TASK_AXES`` and ``max_joint_speed`` (e.g. PlanarReach-v0).
        **kwargs: fields of :class:`ClikPolicyConfig`.
    """

    def __init__(self, env: Any, **kwargs: Any) -> None:
        self.config = config_from_options(ClikPolicyConfig, kwargs)
        base = env_with_attributes(env, ("OBSERVATION_LAYOUT", "ROBOT_XML", "TCP_FRAME", "TASK_AXES",
                                         "max_joint_speed"), "clik")
        self._layout = base.OBSERVATION_LAYOUT
        self._speed = float(base.max_joint_speed)
        self.model = RobotModel.from_mjcf(base.ROBOT_XML)
        objectives = []
        if self.config.joint_limit_weight > 0.0:
            objectives.append(JointLimitObjective.from_model(
                self.model, activation_distance=self.config.joint_limit_activation,
                slope=self.config.joint_limit_slope, weight=self.config.joint_limit_weight))
        if self.config.posture_weight > 0.0:
            reference = getattr(base, "nominal_configuration", None)
            if reference is None:
                raise PolicyError("posture_weight > 0 needs an env with nominal_configuration")
            objectives.append(PostureObjective(reference, self.config.posture_weight))
        self.collision: CollisionObjective | None = None
        self._obstacle_slices: tuple[slice, slice] | None = None
        self._obstacle_seen: tuple[float, ...] | None = None
        if self.config.collision_avoidance not in COLLISION_MODES:
            raise PolicyError(f"unknown collision_avoidance {self.config.collision_avoidance!r}; valid: "
                              f"{', '.join(COLLISION_MODES)}")
        has_obstacle = bool(getattr(base, "has_obstacle", False))
        wanted = self.config.collision_avoidance == "on" or (self.config.collision_avoidance == "auto" and has_obstacle)
        if wanted:
            self.collision = self._collision_objective(base, has_obstacle)
            objectives.append(self.collision)
        clik = Clik(self.model, FramePositionTask(base.TCP_FRAME, base.TASK_AXES), method=self.config.method,
                    gain=self.config.gain, nullspace_gain=self.config.nullspace_gain, objectives=objectives,
                    dls_threshold=self.config.dls_threshold, dls_max_damping=self.config.dls_max_damping)
        self.controller: Clik | CompiledClik = CompiledClik(clik) if self.config.backend == "compiled" else clik
        self.last_result: ClikResult | None = None

    def _collision_objective(self, base: Any, has_obstacle: bool) -> CollisionObjective:
        """Robot segments from the robot MJCF; the obstacle (a sphere, read from the observation) as a PSS."""
        environment = []
        if has_obstacle:
            if "obstacle_center" not in self._layout or "obstacle_radius" not in self._layout:
                raise PolicyError(f"{type(base).__name__} has an obstacle but no obstacle_center/obstacle_radius "
                                  "in OBSERVATION_LAYOUT")
            # a unit sphere at the origin, moved and scaled from the observation in predict()
            environment.append(Segment(OBSTACLE_SEGMENT, (PSS(np.zeros(3), 1.0),)))
            self._obstacle_slices = (self._layout["obstacle_center"], self._layout["obstacle_radius"])
        model = collision_model_from_mjcf(self.model, environment, self_collision=self.config.self_collision)
        return CollisionObjective(model, activation_distance=self.config.collision_activation,
                                  slope=self.config.collision_slope, weight=self.config.collision_weight)

    def update_obstacle(self, obs: NDArray[np.float64]) -> None:
        """Place the collision model's obstacle where the observation says (done by :meth:`predict`)."""
        if self.collision is None or self._obstacle_slices is None:
            return
        center_slice, radius_slice = self._obstacle_slices
        center = obs[center_slice]
        radius = float(obs[radius_slice][0])
        seen = (*center.tolist(), radius)
        if seen == self._obstacle_seen:  # placing the environment again would only redo the same transforms
            return
        self._obstacle_seen = seen
        # planar envs give (x, z); the sphere is scaled by its radius about the origin, then moved
        position = np.array([center[0], 0.0, center[1]]) if center.size == 2 else np.asarray(center, dtype=np.float64)
        self.collision.collision_model.set_environment_placement(OBSTACLE_SEGMENT, np.eye(3), position)
        self.collision.collision_model.set_environment_radius(OBSTACLE_SEGMENT, max(radius, 0.0))

    def predict(self, observation: NDArray[np.floating], state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[NDArray[np.float32], Any]:
        """Normalized joint velocity command for one observation."""
        obs = np.asarray(observation, dtype=np.float64)
        self.update_obstacle(obs)
        result = self.controller.step(obs[self._layout["q"]], obs[self._layout["tcp_ref"]],
                                      obs[self._layout["tcp_ref_vel"]])
        self.last_result = result
        action = np.clip(result.qdot / self._speed, -1.0, 1.0)
        return action.astype(np.float32), state

    def describe(self) -> dict[str, Any]:
        """The configuration, for reports."""
        return asdict(self.config)


class Sb3Policy:
    """A stable-baselines3 model loaded from a ``.zip``; ``predict`` is the model's own.

    Args:
        path: the ``.zip`` written by ``model.save``.
        env: the environment (checked against the model's spaces by SB3).
        algo: the SB3 algorithm class name; tried in the order PPO, SAC, TD3, A2C, DDPG when omitted.
    """

    def __init__(self, path: str | Path, env: Any = None, algo: str | None = None) -> None:
        path = Path(path)
        if not path.is_file():
            raise PolicyError(f"policy file not found: {path}")
        try:
            sb3 = import_stable_baselines3()
        except ImportError as exc:  # the 'learn' extra
            raise PolicyError(f"loading a .zip policy needs stable-baselines3: {LEARN_EXTRA_HINT}") from exc
        names = (algo,) if algo else _SB3_ALGOS
        errors = []
        for name in names:
            cls = getattr(sb3, name, None)
            if cls is None:
                raise PolicyError(f"unknown SB3 algorithm {name!r}; valid: {', '.join(_SB3_ALGOS)}")
            try:
                self.model = cls.load(str(path), device="cpu")
                self.algo = name
                break
            except Exception as exc:  # SB3 raises assorted errors for a class mismatch
                errors.append(f"{name}: {type(exc).__name__}")
        else:
            raise PolicyError(f"{path} is not a stable-baselines3 model of {', '.join(names)} ({'; '.join(errors)})")
        if env is not None:
            self._check_spaces(path, env)

    def _check_spaces(self, path: Path, env: Any) -> None:
        """A model trained on another env fails here, naming both, instead of at its first ``predict``."""
        for kind in ("observation", "action"):
            trained = getattr(self.model, f"{kind}_space", None)
            here = getattr(env, f"{kind}_space", None)
            shapes = (getattr(trained, "shape", None), getattr(here, "shape", None))
            if None not in shapes and shapes[0] != shapes[1]:
                raise PolicyError(f"{path} was trained with {kind} shape {shapes[0]}, but {env_name(env)} has "
                                  f"{shapes[1]}: it was trained on another env (or other env kwargs)")

    def predict(self, observation: NDArray[np.floating], state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[NDArray[np.floating], Any]:
        """The SB3 model's action."""
        return self.model.predict(observation, state=state, episode_start=episode_start, deterministic=deterministic)


def _is_grasp_task(base: Any) -> bool:
    return "grasp_position" in getattr(base, "observation_layout", {})


def missing_capabilities(name: str, env: Any) -> list[str]:
    """What ``env`` lacks for the policy ``name`` (empty when the policy supports it), without building the policy.

    Args:
        name: a name of :data:`POLICY_NAMES` or the path of an SB3 ``.zip`` (which only needs matching spaces,
            checked when it is loaded).
        env: the environment (wrapped or not).

    Raises:
        PolicyError: for an unknown policy name.
    """
    base = getattr(env, "unwrapped", env)
    if name in ("clik", "predictive", "global"):
        if _is_grasp_task(base):
            return [a for a in _GRASP_CLIK_NEEDS if not hasattr(base, a)]
        missing = [a for a in _CLIK_NEEDS if not hasattr(base, a)]
        if name != "clik":
            missing += [a for a in ("dt",) if not hasattr(base, a)]
            if not callable(getattr(base, "reference", None)):
                missing.append("reference(t) or a grasp task")
        return missing
    if name == "walking":
        missing = [a for a in _WALKING_NEEDS if not hasattr(base, a)]
        if not missing:
            keys = [k for k in _WALKING_LAYOUT if k not in base.OBSERVATION_LAYOUT]
            if keys:
                missing.append(f"OBSERVATION_LAYOUT entries {', '.join(keys)}")
        return missing
    if name == "zero":
        return [] if getattr(getattr(env, "action_space", None), "shape", None) is not None else ["action_space"]
    if name == "random":
        space = getattr(env, "action_space", None)
        low, high = getattr(space, "low", None), getattr(space, "high", None)
        if low is None or high is None or not (np.all(np.isfinite(low)) and np.all(np.isfinite(high))):
            return ["a bounded action space"]
        return []
    if name.endswith(".zip") or Path(name).is_file():
        return []
    raise PolicyError(f"unknown policy {name!r}; valid: {', '.join(POLICY_NAMES)} or the path of an SB3 .zip")


def policy_supports(name: str, env: Any) -> bool:
    """Whether :func:`make_policy` can build the policy ``name`` for ``env`` (its options aside)."""
    return not missing_capabilities(name, env)


def supported_policies(env: Any) -> tuple[str, ...]:
    """The names of :data:`POLICY_NAMES` that support ``env`` (an SB3 ``.zip`` fits any env with its spaces)."""
    return tuple(name for name in POLICY_NAMES if policy_supports(name, env))


def env_name(env: Any) -> str:
    """The env's registered id (``env.spec.id``) when it has one, else its class name."""
    spec = getattr(env, "spec", None) or getattr(getattr(env, "unwrapped", env), "spec", None)
    env_id = getattr(spec, "id", None)
    return str(env_id) if env_id else type(getattr(env, "unwrapped", env)).__name__


@lru_cache(maxsize=1)
def _registered_support() -> dict[str, tuple[str, ...]]:
    """Supported policies of every env id redundancy_gym registers (each env is built once, with its defaults)."""
    try:  # the join layer reads the registry only here, for messages and `redundancy-gym list`
        import gymnasium as gym

        from ..registration import ENV_IDS
    except ImportError:
        return {}
    support = {}
    for env_id in ENV_IDS:
        try:
            env = gym.make(env_id)
        except Exception:  # an env that cannot be built here (a missing optional dependency) is left out
            continue
        try:
            support[env_id] = supported_policies(env)
        finally:
            env.close()
    return support


def supported_env_ids(name: str) -> tuple[str, ...]:
    """The registered env ids on which the policy ``name`` can be built."""
    return tuple(env_id for env_id, names in _registered_support().items() if name in names)


def _unsupported(name: str, env: Any, missing: list[str]) -> PolicyError:
    ids = supported_env_ids(name)
    supports = ", ".join(ids) if ids else "no registered env"
    base = getattr(env, "unwrapped", env)
    return PolicyError(f"policy {name!r} supports {supports}; got {env_name(env)} "
                       f"(for an env of your own: {type(base).__name__} lacks {', '.join(missing)})")


def make_policy(name: str, env: Any, **kwargs: Any) -> Policy:
    """Build a policy for ``env``.

    Args:
        name: ``"clik"`` (reference controller: :class:`ClikPolicy`, or
            :class:`~redundancy_gym.controllers.grasp_clik_policy.GraspClikPolicy` for grasp tasks), ``"walking"``
            (:class:`~redundancy_gym.controllers.walking_policy.WalkingPolicy`, biped), ``"predictive"`` or ``"global"``
            (:class:`~redundancy_gym.controllers.predictive_policy.PredictivePolicy`, PlanarReach and AgriReach),
            ``"zero"``, ``"random"`` or the path of a stable-baselines3
            ``.zip``.
        env: the environment the policy will act in.
        **kwargs: options of the policy (``ClikPolicyConfig`` fields for ``clik``, ``seed`` for ``random``,
            ``algo`` for a ``.zip``).

    Raises:
        PolicyError: unknown name or options, or an env the policy does not support (the message names the
            registered env ids it supports).
    """
    missing = missing_capabilities(name, env)
    if missing:
        raise _unsupported(name, env, missing)
    if name == "clik":
        base = getattr(env, "unwrapped", env)
        if "grasp_position" in getattr(base, "observation_layout", {}):
            from .grasp_clik_policy import GraspClikPolicy

            return GraspClikPolicy(env, **kwargs)
        return ClikPolicy(env, **kwargs)
    if name in ("predictive", "global"):
        from .predictive_policy import PredictivePolicy

        return PredictivePolicy(env, mode=name, **kwargs)
    if name == "walking":
        from .walking_policy import WalkingPolicy

        return WalkingPolicy(env, **kwargs)
    if name == "zero":
        _no_options(name, kwargs)
        return ZeroPolicy(env)
    if name == "random":
        unknown = set(kwargs) - {"seed"}
        if unknown:
            raise PolicyError(f"unknown random-policy option(s) {', '.join(sorted(unknown))}; valid: seed")
        return RandomPolicy(env, **kwargs)
    if name.endswith(".zip") or Path(name).is_file():
        unknown = set(kwargs) - {"algo"}
        if unknown:
            raise PolicyError(f"unknown option(s) {', '.join(sorted(unknown))} for a .zip policy; valid: algo")
        return Sb3Policy(name, env, **kwargs)
    raise PolicyError(f"unknown policy {name!r}; valid: {', '.join(POLICY_NAMES)} or the path of an SB3 .zip")


def _no_options(name: str, kwargs: dict[str, Any]) -> None:
    if kwargs:
        raise PolicyError(f"the {name} policy takes no options, got {', '.join(sorted(kwargs))}")
