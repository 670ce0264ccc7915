"""A stable-baselines3 model loaded from a ``.zip`` as a policy.

A ``.zip`` is code, not data: stable-baselines3 unpickles the objects it holds (the policy class, schedules,
spaces), and unpickling can run any code the file's author put there. Loading one from outside the package's
shipped models (:data:`~redundancy_gym.policies.shipped_models.SHIPPED_MODELS_DIR`) logs where it came from, once
per file and process, so that a user sees which file ran.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..sb3_import import LEARN_EXTRA_HINT, import_stable_baselines3
from .exceptions import PolicyError
from .options import env_name
from .shipped_models import SHIPPED_MODELS_DIR

__all__ = ["SB3_ALGOS", "Sb3Policy", "is_shipped_model_file"]

SB3_ALGOS = ("PPO", "SAC", "TD3", "A2C", "DDPG")

_LOG = logging.getLogger(__name__)
# Without a logging configuration, Python's last-resort handler prints WARNING records to stderr: the CLI and a
# plain script show the line with no setup, and an application that configures logging routes or silences it.
_ANNOUNCED: set[Path] = set()


def is_shipped_model_file(path: str | Path) -> bool:
    """Whether ``path`` is one of the package's own shipped models (in ``SHIPPED_MODELS_DIR``, symlinks resolved)."""
    return Path(path).resolve().parent == SHIPPED_MODELS_DIR.resolve()


def _announce_origin(path: Path) -> None:
    """Log, once per file in this process, that ``path`` is loaded from outside the shipped models: unpickling it
    can run code from the file."""
    where = path.resolve()
    if is_shipped_model_file(where) or where in _ANNOUNCED:
        return
    _ANNOUNCED.add(where)
    _LOG.warning(
        "loading the policy %s (not one of redundancy_gym's shipped models): an SB3 .zip holds pickled objects "
        "and loading it can run code from the file; load only files you trust",
        where,
    )


class Sb3Policy:
    """A stable-baselines3 model loaded from a ``.zip``; ``predict`` is the model's own.

    Args:
        path: the ``.zip`` written by ``model.save``. Loading it can run code from the file (SB3 unpickles its
            objects): load only files you trust; one from outside the shipped models is logged with its path.
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
        _announce_origin(path)  # before the load: a file that runs code has been named by then
        names = (algo,) if algo else SB3_ALGOS
        errors = []
        for name in names:
            cls = getattr(sb3, name, None)
            if cls is None:
                raise PolicyError(f"unknown SB3 algorithm {name!r}; valid: {', '.join(SB3_ALGOS)}")
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
                raise PolicyError(
                    f"{path} was trained with {kind} shape {shapes[0]}, but {env_name(env)} has "
                    f"{shapes[1]}: it was trained on another env (or other env kwargs)"
                )

    def predict(
        self,
        observation: NDArray[np.floating],
        state: Any = None,
        episode_start: Any = None,
        deterministic: bool = True,
    ) -> tuple[NDArray[np.floating], Any]:
        """The SB3 model's action."""
        return self.model.predict(observation, state=state, episode_start=episode_start, deterministic=deterministic)
