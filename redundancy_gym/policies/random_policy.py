"""The ``random`` policy: uniform random actions from the policy's own seeded generator."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..validation import check_int
from .exceptions import PolicyError
from .per_env_policy import PerEnvPolicy

__all__ = ["RandomPolicy", "RandomPolicyConfig"]


@dataclass(frozen=True)
class RandomPolicyConfig:
    """Options of the random policy.

    Attributes:
        seed: seed of the generator: an int >= 0, or None for fresh entropy.
    """

    seed: int | None = 0


class RandomPolicy(PerEnvPolicy):
    """Uniform random actions in the action box, from the policy's own seeded generator.

    In a batch, env index ``i`` draws from its own generator, seeded with ``seed + i`` (as ``make_vec_env``
    seeds its envs); a generator runs on over episodes (``episode_start`` does not reseed it; :meth:`reseed`
    does, and ``eval`` calls it with each episode's seed).

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

    def reseed(self, seed: int) -> None:
        """Restart the generator from ``seed``. ``eval`` does so before every episode with the episode's seed, so
        that an episode's actions depend on its seed only, not on the episodes before it (the same in a serial run
        and on parallel workers)."""
        self._seed = check_int("seed", seed, low=0, error=PolicyError)
        self._rng = np.random.default_rng(self._seed)

    def _act(self, obs: NDArray[np.float64], starting: bool) -> NDArray[Any]:
        """A uniform random action."""
        return self._rng.uniform(self._low, self._high).astype(self._dtype)
