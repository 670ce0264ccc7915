"""Policies with the stable-baselines3 ``predict`` signature: analytic reference controllers and learned models.

This module joins controllers and environments (DESIGN.md): it reads what it needs from the env by duck
typing (``OBSERVATION_LAYOUT``, ``ROBOT_XML``, ``TCP_FRAME``, ``TASK_AXES``, ``max_joint_speed``) and never
imports mujoco, so the same policy object can drive a robot fed with the same observation. Only the error for an
unsupported env reaches the simulation side: it builds the registered envs (gymnasium, lazily) to name those the
policy supports.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import asdict, dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ..geometry import PSS, GeometryError, Segment
from ..model import ModelError, RobotModel, collision_model_from_mjcf
from ..sb3_import import LEARN_EXTRA_HINT, import_stable_baselines3
from ..validation import check_int
from .clik import Clik, ClikResult
from .collision_objective import CollisionObjective
from .compiled_clik import CompiledClik
from .exceptions import ControllerError, PolicyError
from .frame_position_task import FramePositionTask
from .joint_limit_objective import JointLimitObjective
from .policy_options import config_from_options, env_with_attributes
from .posture_objective import PostureObjective

__all__ = ["POLICY_NAMES", "ClikPolicy", "ClikPolicyConfig", "PerEnvPolicy", "Policy", "RandomPolicy", "Sb3Policy",
           "ZeroPolicy", "env_name", "make_policy", "missing_capabilities", "observation_time_index",
           "policy_supports", "supported_env_ids", "supported_policies"]

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


_START_TIME = 1e-9
"""An observation whose time (or phase) is below this starts a new episode."""


def observation_time_index(layout: Mapping[str, slice] | None) -> int | None:
    """Index of the observation entry that tells how far the episode is: ``time`` [s], else ``phase``
    (PlanarReach: time over the line's duration); both are 0 at ``reset`` and never decrease within an episode.
    None when the layout has neither (then only ``episode_start`` starts an episode)."""
    for key in ("time", "phase"):
        if layout is not None and key in layout:
            return int(layout[key].start)
    return None


def _one_start(episode_start: Any) -> bool:
    """``episode_start`` of a single observation: None, a bool or one flag."""
    if type(episode_start) is np.ndarray and episode_start.size == 1:  # what harnesses pass: the hot path
        return bool(episode_start.item())
    if episode_start is None:
        return False
    flags = np.asarray(episode_start, dtype=bool).reshape(-1)
    if flags.size != 1:
        raise PolicyError(f"episode_start must have one entry for a single observation, got shape {flags.shape}")
    return bool(flags[0])


def _batch_starts(episode_start: Any, n: int) -> NDArray[np.bool_]:
    """``episode_start`` of a batch of ``n`` observations: None (no start) or ``n`` flags."""
    if episode_start is None:
        return np.zeros(n, dtype=bool)
    flags = np.asarray(episode_start, dtype=bool).reshape(-1)
    if flags.size != n:
        raise PolicyError(f"episode_start must have one entry per observation ({n}), got shape "
                          f"{np.shape(episode_start)}")
    return flags


class PerEnvPolicy:
    """The stable-baselines3 ``predict`` over one observation ``(obs_dim,)`` or a batch ``(n, obs_dim)`` (a VecEnv's),
    with one controller state per env index.

    A subclass implements :meth:`_act` for one float64 observation. The policy object is itself the controller
    state of env index 0, which a single observation also uses; index ``i > 0`` of a batch gets its own policy
    object (:meth:`core`, built with the same env and options the first time ``i`` appears), so env ``i``'s episode
    is independent of env ``j``'s. A batch gives actions ``(n, act_dim)``.

    A new episode of an index begins where its ``episode_start`` entry is True, and, in an env whose observation
    carries its time (:func:`observation_time_index`), where that time is ~0 or went back from the index's last
    observation: a policy reused for another episode (or after a ``reset`` mid-episode) without
    ``episode_start`` acts as a fresh one.
    """

    _env: Any
    _options: dict[str, Any]
    _obs_shape: tuple[int, ...] | None
    _cores: dict[int, PerEnvPolicy]
    _time_index: int | None
    _last_time: float

    def _init_per_env(self, env: Any, options: dict[str, Any], layout: Mapping[str, slice] | None = None) -> None:
        """Remember how this policy was built (``type(self)(env, **options)`` builds the other indices' states)
        and where the observation's time is (``layout``; None: the policy keeps no episode state)."""
        self._env = env
        self._options = dict(options)
        shape = getattr(getattr(env, "observation_space", None), "shape", None)
        self._obs_shape = tuple(shape) if shape else None
        self._cores = {0: self}
        self._time_index = observation_time_index(layout)
        self._last_time = -np.inf

    def _new_core(self, index: int) -> PerEnvPolicy:
        """A fresh controller state for env ``index`` (> 0)."""
        return type(self)(self._env, **self._options)

    def core(self, index: int) -> Any:
        """The policy object that keeps env ``index``'s controller state (``self`` for index 0; built on first use),
        e.g. for its diagnostics (``last_result``)."""
        core = self._cores.get(index)
        if core is None:
            if isinstance(index, bool) or not isinstance(index, (int, np.integer)) or index < 0:
                raise PolicyError(f"env index must be an int >= 0, got {index!r}")
            core = self._cores[int(index)] = self._new_core(int(index))
        return core

    def _new_episode(self, obs: NDArray[np.float64], starting: bool) -> bool:
        """Whether ``obs`` begins an episode: ``starting`` (``episode_start``), or the observation's time ~0 or
        earlier than at the last call."""
        index = self._time_index
        if index is None:
            return starting
        t = obs.item(index)
        last, self._last_time = self._last_time, t
        return starting or t < _START_TIME or t < last

    def _act(self, obs: NDArray[np.float64], starting: bool) -> NDArray[Any]:
        """The action for one observation of this env index; ``starting``: its ``episode_start``."""
        raise NotImplementedError

    def predict(self, observation: NDArray[np.floating], state: Any = None, episode_start: Any = None,
                deterministic: bool = True) -> tuple[NDArray[Any], Any]:
        """The action ``(act_dim,)`` for one observation, or the actions ``(n, act_dim)`` for a batch ``(n, obs_dim)``
        (row ``i``: env index ``i``); ``episode_start``: a flag per observation (True begins a new episode there);
        ``state`` comes back unchanged (no recurrent state); the policies are deterministic.

        An observation that is no state of the env (not numbers, a wrong shape, an obstacle slot that is no
        volume, a robot state the model rejects: NaN, a zero base quaternion) raises :class:`PolicyError`; a
        controller that rejects its input raises its :class:`ControllerError`."""
        try:
            obs = np.asarray(observation, dtype=np.float64)
        except (TypeError, ValueError) as exc:  # a dict, strings, None: not an observation
            raise PolicyError(f"observation must be an array of numbers, got {type(observation).__name__}") from exc
        try:
            if obs.shape == self._obs_shape or (self._obs_shape is None and obs.ndim == 1):  # one observation
                return self._act(obs, episode_start is not None and _one_start(episode_start)), state
        except GeometryError as exc:  # the obstacle slots of the observation do not describe a volume
            raise PolicyError(f"invalid obstacle in the observation: {exc}") from exc
        except ModelError as exc:  # the robot state of the observation is none (NaN, a zero base quaternion)
            raise PolicyError(f"invalid robot state in the observation: {exc}") from exc
        if obs.ndim != 2 or (self._obs_shape is not None and obs.shape[1:] != self._obs_shape):
            dim = "obs_dim" if self._obs_shape is None else self._obs_shape[0]
            raise PolicyError(f"observation must have shape {self._obs_shape or '(obs_dim,)'} or (n, {dim}), "
                              f"got {obs.shape}")
        starts = _batch_starts(episode_start, obs.shape[0])
        if obs.shape[0] == 0:
            return self._no_actions(), state
        try:
            return np.stack([self.core(i)._act(obs[i], bool(starts[i])) for i in range(obs.shape[0])]), state
        except GeometryError as exc:
            raise PolicyError(f"invalid obstacle in the observation: {exc}") from exc
        except ModelError as exc:
            raise PolicyError(f"invalid robot state in the observation: {exc}") from exc

    def _no_actions(self) -> NDArray[Any]:
        """The actions ``(0, act_dim)`` of an empty batch."""
        space = getattr(self._env, "action_space", None)
        shape = tuple(getattr(space, "shape", None) or (0,))
        return np.zeros((0, *shape), dtype=getattr(space, "dtype", np.float32))


class ZeroPolicy(PerEnvPolicy):
    """Always the zero action (for a velocity-commanded arm: hold still)."""

    def __init__(self, env: Any) -> None:
        self._action = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
        self._init_per_env(env, {})

    def _act(self, obs: NDArray[np.float64], starting: bool) -> NDArray[Any]:
        return self._action.copy()


class RandomPolicy(PerEnvPolicy):
    """Uniform random actions in the action box, from the policy's own seeded generator.

    In a batch, env index ``i`` draws from its own generator, seeded with ``seed + i`` (as ``make_vec_env``
    seeds its envs); a generator runs on over episodes (``episode_start`` does not reseed it).

    Args:
        env: the environment (its action space bounds are used).
        seed: seed of the generator: an int >= 0, or None for fresh entropy (anything else is a PolicyError).
    """

    def __init__(self, env: Any, seed: int | None = 0) -> None:
        space = env.action_space
        self._low = np.asarray(space.low, dtype=np.float64)
        self._high = np.asarray(space.high, dtype=np.float64)
        if not (np.all(np.isfinite(self._low)) and np.all(np.isfinite(self._high))):
            raise PolicyError("the random policy needs a bounded action space")
        self._dtype = space.dtype
        self._seed = check_int("seed", seed, low=0, optional=True, error=PolicyError)
        self._rng = np.random.default_rng(self._seed)
        self._init_per_env(env, {"seed": seed})

    def _new_core(self, index: int) -> PerEnvPolicy:
        return RandomPolicy(self._env, seed=None if self._seed is None else self._seed + index)

    def _act(self, obs: NDArray[np.float64], starting: bool) -> NDArray[Any]:
        """A uniform random action."""
        return self._rng.uniform(self._low, self._high).astype(self._dtype)


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


class ClikPolicy(PerEnvPolicy):
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
        self._init_per_env(env, kwargs)  # a velocity-level law: no episode state

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

    def _act(self, obs: NDArray[np.float64], starting: bool) -> NDArray[np.float32]:
        """Normalized joint velocity command for one observation."""
        self.update_obstacle(obs)
        result = self.controller.step(obs[self._layout["q"]], obs[self._layout["tcp_ref"]],
                                      obs[self._layout["tcp_ref_vel"]])
        self.last_result = result
        return np.clip(result.qdot / self._speed, -1.0, 1.0).astype(np.float32)

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
    if hasattr(env, "num_envs"):  # a VecEnv that is not a plain DummyVecEnv
        return PolicyError(f"policy {name!r} is built from one env, got the VecEnv {type(env).__name__}: pass one "
                           "of its envs (e.g. gym.make(env_id)); the policy then takes the VecEnv's batches")
    ids = supported_env_ids(name)
    supports = ", ".join(ids) if ids else "no registered env"
    base = getattr(env, "unwrapped", env)
    return PolicyError(f"policy {name!r} supports {supports}; got {env_name(env)} "
                       f"(for an env of your own: {type(base).__name__} lacks {', '.join(missing)})")


def _one_env(env: Any) -> Any:
    """The first env of a plain stable-baselines3 ``DummyVecEnv`` (its envs live in this process and are built
    alike), else ``env``. A wrapped VecEnv (VecNormalize, ...) is left as it is: its observations are not the
    env's, so an analytic policy must not take it."""
    envs = getattr(env, "envs", None)
    if hasattr(env, "num_envs") and not hasattr(env, "venv") and isinstance(envs, list) and envs:
        return envs[0]
    return env


def make_policy(name: str, env: Any, **kwargs: Any) -> Policy:
    """Build a policy for ``env``.

    Args:
        name: ``"clik"`` (reference controller: :class:`ClikPolicy`, or
            :class:`~redundancy_gym.controllers.grasp_clik_policy.GraspClikPolicy` for grasp tasks), ``"walking"``
            (:class:`~redundancy_gym.controllers.walking_policy.WalkingPolicy`, biped), ``"predictive"`` or ``"global"``
            (:class:`~redundancy_gym.controllers.predictive_policy.PredictivePolicy`, PlanarReach and AgriReach),
            ``"zero"``, ``"random"`` or the path of a stable-baselines3
            ``.zip``.
        env: the environment the policy will act in (or a stable-baselines3 ``DummyVecEnv`` of such envs). The
            policy takes one observation of it or a batch (a VecEnv's, one controller state per env index).
        **kwargs: options of the policy (``ClikPolicyConfig`` fields for ``clik``, ``seed`` for ``random``,
            ``algo`` for a ``.zip``).

    Raises:
        PolicyError: unknown name or options, an option value the policy or its controller rejects (the message
            names it), or an env the policy does not support (the message names the registered env ids it
            supports).
    """
    env = _one_env(env)
    missing = missing_capabilities(name, env)
    if missing:
        raise _unsupported(name, env, missing)
    try:
        return _build_policy(name, env, kwargs)
    except ControllerError as exc:  # an option the controller rejects (its message names it)
        raise PolicyError(f"invalid option for the {name} policy: {exc}") from exc


def _build_policy(name: str, env: Any, kwargs: dict[str, Any]) -> Policy:
    """The policy ``name`` on a supported ``env`` (see :func:`make_policy`)."""
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
