"""Importing stable-baselines3 safely next to MuJoCo's headless OSMesa renderer."""

from __future__ import annotations

import sys
from types import ModuleType

__all__ = ["import_stable_baselines3"]


def import_stable_baselines3() -> ModuleType:
    """Return the ``stable_baselines3`` module (raises ImportError without the ``learn`` extra).

    With ``MUJOCO_GL=osmesa`` MuJoCo loads Mesa, whose bundled LLVM clashes with the LLVM inside triton: torch
    imports triton lazily (when an optimizer is built) and the process segfaults. Triton only compiles GPU
    kernels and our agents run on the CPU, so when Mesa is already loaded and triton is not, triton is marked
    unavailable; torch then takes its no-triton path.
    """
    if "mujoco.osmesa" in sys.modules and "triton" not in sys.modules:
        sys.modules["triton"] = None  # type: ignore[assignment]  # import raises ImportError from now on
    import stable_baselines3

    return stable_baselines3
