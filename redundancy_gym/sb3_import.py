"""Importing stable-baselines3 (the ``learn`` extra) with a clear error when it is missing."""

from __future__ import annotations

from collections.abc import Callable
from types import ModuleType
from typing import Any

from .rendering_backend import guard_triton

__all__ = ["LEARN_EXTRA_HINT", "import_stable_baselines3", "install_hint", "set_torch_threads", "silent_logger"]


def install_hint(extra: str) -> str:
    """How to install an optional extra, for a clone and for an installed wheel (the package is installed from a
    clone or a wheel file, not from the package index)."""
    return (
        f"pip install -e '.[{extra}]' (in a clone, from the repository root) or "
        f"pip install 'redundancy_gym-<version>-py3-none-any.whl[{extra}]' (the wheel you installed)"
    )


LEARN_EXTRA_HINT = install_hint("learn")


def import_stable_baselines3() -> ModuleType:
    """Return the ``stable_baselines3`` module; raises ImportError naming the ``learn`` extra when it is missing.

    ``import redundancy_gym`` already keeps torch's triton safe from Mesa (:func:`guard_triton`); it is called
    again here for a process that imported MuJoCo under a Mesa backend between the two.
    """
    guard_triton()
    try:
        import stable_baselines3
    except ImportError as exc:
        raise ImportError(f"stable-baselines3 is not installed; {LEARN_EXTRA_HINT}") from exc
    return stable_baselines3


def silent_logger() -> Any:
    """An SB3 logger that writes nowhere, for a ``model.set_logger`` before ``learn``.

    With ``verbose=0`` and no TensorBoard folder, SB3 still creates an empty ``<tmp>/SB3-<date>`` folder on every
    ``learn()`` call (its logger's default); a learning curve calls ``learn`` once per segment and left dozens.
    """
    from stable_baselines3.common.logger import Logger

    return Logger(folder=None, output_formats=[])


def set_torch_threads(threads: int | None) -> Callable[[], None]:
    """Put torch on ``threads`` CPU threads (None: leave them as they are); returns what sets the previous count
    back, for the ``finally`` of the training that asked.

    One thread is the fastest for this package's small networks, and far the fastest on a machine busy with other
    work (torch's default, one per core, waits on descheduled threads).
    """
    import torch

    previous = torch.get_num_threads()
    if threads is not None:
        torch.set_num_threads(threads)
    return lambda: torch.set_num_threads(previous)
