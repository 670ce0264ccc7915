"""The stable-baselines3 ``predict`` signature and :class:`PerEnvPolicy`, the base of the reference policies: one
observation or a VecEnv's batch, one controller state per env index, a new episode noticed by itself."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from ..geometry import GeometryError
from ..model import ModelError
from .exceptions import PolicyError

__all__ = ["PerEnvPolicy", "Policy", "observation_time_index"]


@runtime_checkable
class Policy(Protocol):
    """The stable-baselines3 prediction signature shared by every policy."""

    def predict(
        self,
        observation: NDArray[np.floating],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.floating], Any]:
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
        raise PolicyError(
            f"episode_start must have one entry per observation ({n}), got shape {np.shape(episode_start)}"
        )
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
        # the concrete policy's constructor (the mixin itself declares none)
        build: Callable[..., PerEnvPolicy] = type(self)
        return build(self._env, **self._options)

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

    def predict(
        self,
        observation: NDArray[np.floating],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[Any], Any]:
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
            raise PolicyError(
                f"observation must have shape {self._obs_shape or '(obs_dim,)'} or (n, {dim}), got {obs.shape}"
            )
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
