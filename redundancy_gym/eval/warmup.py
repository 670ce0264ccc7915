"""Fill numba's on-disk cache ahead of use (``redundancy-gym warmup [ENV...]``), so that a first episode, a test
run or a fresh cluster worker loads compiled kernels instead of compiling them.

A kernel compiles at its first call (:class:`~redundancy_gym.kernel_options.LazyEntryPoint`), so the warm-up
makes each env, resets it, builds every analytic policy the env supports (``clik``, ``predictive``, ``global``,
``walking``), calls its ``predict`` and steps the env with it (a wrapped id: with a zero action, which runs the
wrapper's reference). numba writes the cache where :func:`numba_cache_location` says: ``NUMBA_CACHE_DIR`` when set,
else ``__pycache__`` folders beside the package's sources, else (a read-only install) its per-user cache folder. A
worker that shares the folder (or the installed package) shares the cache; the cache is valid for the same
package sources, Python, numba and CPU.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path
from typing import NamedTuple

from .compile_clock import COMPILE_CLOCK
from .exceptions import EvalError

__all__ = ["WarmupRow", "numba_cache_location", "warmup", "warmup_env"]


class WarmupRow(NamedTuple):
    """One env id warmed up: its wall time [s], of which numba compiled [s], and the policies it ran."""

    env_id: str
    seconds: float
    compile_s: float
    policies: tuple[str, ...]


def numba_cache_location() -> str:
    """Where numba keeps this package's compiled kernels in this process (``NUMBA_CACHE_DIR`` overrides it)."""
    from numba.core import config

    cache_dir = getattr(config, "CACHE_DIR", "")  # numba's reading of NUMBA_CACHE_DIR
    if cache_dir:
        return str(cache_dir)
    from ..controllers.clik.clik_kernels import clik_step

    # numba's own choice for a kernel of this package: beside its source, or per user where that is read-only
    # (a private attribute of numba's dispatcher: a numba without it gets the general answer)
    cache_path = getattr(getattr(clik_step, "_cache", None), "_cache_path", None)
    if cache_path is None:
        return "numba's default: __pycache__ beside the sources, or its per-user cache folder where they are read-only"
    path = Path(cache_path)
    package = Path(__file__).resolve().parents[1]
    if package in path.resolve().parents:
        return f"__pycache__ folders beside the sources in {package}"
    return str(path.parents[1])


def _check_env_ids(ids: Sequence[str]) -> None:
    from ..registration import ENV_IDS

    unknown = [e for e in ids if e not in ENV_IDS]
    if unknown:
        raise EvalError(f"unknown env id {', '.join(unknown)}; valid: {', '.join(ENV_IDS)}")


def warmup_env(env_id: str) -> WarmupRow:
    """Compile (or load) every kernel that ``env_id`` and its analytic policies run (module docstring)."""
    import gymnasium as gym
    import numpy as np

    from ..policies import GENERIC_POLICIES, make_policy, supported_policies

    _check_env_ids([env_id])
    start, compiled = time.perf_counter(), COMPILE_CLOCK.compiling_seconds
    env = gym.make(env_id)
    ran: list[str] = []
    try:
        obs, _ = env.reset(seed=0)
        env.step(np.zeros(env.action_space.shape, dtype=env.action_space.dtype))
        policies = [p for p in supported_policies(env) if p not in GENERIC_POLICIES]
        for name in policies:
            obs, _ = env.reset(seed=0)
            policy = make_policy(name, env)
            action, _ = policy.predict(obs, deterministic=True)
            env.step(action)
            ran.append(name)
    finally:
        env.close()
    return WarmupRow(env_id, time.perf_counter() - start, COMPILE_CLOCK.compiling_seconds - compiled, tuple(ran))


def warmup(env_ids: Sequence[str] | None = None, *, workers: int = 1, progress: bool = True) -> list[WarmupRow]:
    """:func:`warmup_env` for each env id (default: every registered one), in ``workers`` processes."""
    from ..registration import ENV_IDS

    ids = list(ENV_IDS if env_ids is None else env_ids)
    _check_env_ids(ids)
    if workers < 1:
        raise EvalError(f"workers must be >= 1, got {workers!r}")
    from tqdm.auto import tqdm

    rows: list[WarmupRow] = []
    with tqdm(total=len(ids), desc="warmup", unit="env", disable=not progress) as bar:
        if workers == 1:
            for env_id in ids:
                rows.append(warmup_env(env_id))
                bar.update(1)
        else:
            with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as pool:
                for row in pool.map(warmup_env, ids):
                    rows.append(row)
                    bar.update(1)
    return rows
