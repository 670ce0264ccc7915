"""The ``zero`` policy: always the zero action."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from .per_env_policy import PerEnvPolicy

__all__ = ["ZeroPolicy"]


class ZeroPolicy(PerEnvPolicy):
    """Always the zero action (for a velocity-commanded arm: hold still)."""

    def __init__(self, env: Any) -> None:
        self._action = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
        self._init_per_env(env, {})

    def _act(self, obs: NDArray[np.float64], starting: bool) -> NDArray[Any]:
        return self._action.copy()
