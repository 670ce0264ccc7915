"""``redundancy-gym bench envs``: env steps per second with a zero policy, ours against Gymnasium's MuJoCo envs.

Every env of ours and the peers (Gymnasium's ``Pusher-v5`` and ``Humanoid-v5``) is made with ``gym.make`` (so
the same wrappers apply) and stepped with the zero action (for BipedWalk-v0: stand in the nominal posture) for a fixed wall time, resetting when an episode ends
(resets count: they are part of what a training loop pays). Ratios ``<ours>_vs_<peer>`` compare rates measured
in the same run; ``agri_vs_pusher`` is AgriReach-v0 over Pusher-v5, ``biped_vs_humanoid`` BipedWalk-v0 over
Humanoid-v5 and ``biped_obstacles_vs_humanoid`` BipedObstacles-v0 (a random course per reset) over Humanoid-v5
(per env step; ``sim_seconds_per_second`` also compares simulated time, since the two step
different periods: 4 ms and 15 ms). Variants of our envs (by default
AgriReach with ``prune=False``, the whole crop row in the scene and the collision model) are measured too, and
``agri_prune_speedup`` is the pruned rate over the unpruned one. Every wrapped id (``<Env>-<Wrapper>-v0``) is
measured against its raw env in alternating windows (``wrapped``: the ratio wrapped / raw, median and range over
the rounds): what an action wrapper's controller costs per step.
"""

from __future__ import annotations

import platform
import time
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

from ..registration import BASE_ENV_IDS, WRAPPED_ENV_IDS
from .bench_ssv import write_ssv_bench as write_envs_bench
from .exceptions import EvalError

__all__ = ["PEERS", "VARIANTS", "format_envs_bench", "run_envs_bench", "write_envs_bench"]

PEERS = ("Pusher-v5", "Humanoid-v5")
VARIANTS = {"redundancy_gym/AgriReach-v0 (prune=False)": ("redundancy_gym/AgriReach-v0", {"prune": False},
                                                           "agri_prune_speedup")}
"""label -> (env id, gym.make kwargs, name of the ratio base rate / variant rate)."""
_SHORT = {"redundancy_gym/PlanarReach-v0": "planar", "redundancy_gym/AgriReach-v0": "agri",
          "redundancy_gym/BipedWalk-v0": "biped", "redundancy_gym/BipedObstacles-v0": "biped_obstacles",
          "Pusher-v5": "pusher", "Humanoid-v5": "humanoid"}


class _Stepper:
    """One env stepped with the zero action in timed windows, resetting when an episode ends."""

    def __init__(self, env_id: str, seed: int) -> None:
        self.env = gym.make(env_id)
        self.env.reset(seed=seed)
        self.action = np.zeros(self.env.action_space.shape, dtype=self.env.action_space.dtype)
        self.window(0.0, warmup=50)

    def window(self, seconds: float, warmup: int = 0) -> float:
        """Steps per second over about ``seconds`` (or ``warmup`` untimed steps)."""
        steps = 0
        start = time.perf_counter()
        while True:
            _, _, terminated, truncated, _ = self.env.step(self.action)
            steps += 1
            if terminated or truncated:
                self.env.reset()
            if warmup and steps >= warmup:
                return 0.0
            if not warmup and steps % 16 == 0 and time.perf_counter() - start >= seconds:
                return steps / (time.perf_counter() - start)


def wrapped_rates(wrapped: Sequence[str], *, seconds: float, rounds: int, seed: int,
                  progress: bool = False) -> dict[str, dict[str, Any]]:
    """Steps/s of every wrapped id against its raw env, measured in alternating windows (raw, wrapped, raw, ...;
    ``rounds`` pairs of ``seconds / rounds`` each, after a warm-up): the ratio wrapped / raw per round, its median
    and range, so that a slow moment of the machine hits both alike."""
    out = {}
    for wrapped_id in tqdm(wrapped, desc="bench envs (wrapped)", disable=not progress):
        raw_id = gym.spec(wrapped_id).kwargs["env_id"]
        raw, inner = _Stepper(raw_id, seed), _Stepper(wrapped_id, seed)
        try:
            pairs = [(raw.window(seconds / rounds), inner.window(seconds / rounds)) for _ in range(rounds)]
        finally:
            raw.env.close()
            inner.env.close()
        ratios = [w / r for r, w in pairs]
        out[wrapped_id] = {"raw": raw_id, "raw_steps_per_second": float(np.median([r for r, _ in pairs])),
                           "steps_per_second": float(np.median([w for _, w in pairs])),
                           "ratio": float(np.median(ratios)), "ratio_min": float(min(ratios)),
                           "ratio_max": float(max(ratios)), "rounds": rounds}
    return out


def _steps_per_second(env_id: str, seconds: float, seed: int, env_kwargs: dict[str, Any]) -> dict[str, float]:
    env = gym.make(env_id, **env_kwargs)
    try:
        env.reset(seed=seed)
        action = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
        for _ in range(50):  # warm caches and compiled kernels
            env.step(action)
        env.reset(seed=seed)
        steps = resets = 0
        start = time.perf_counter()
        while True:
            _, _, terminated, truncated, _ = env.step(action)
            steps += 1
            if terminated or truncated:
                env.reset()
                resets += 1
            if steps % 64 == 0 and time.perf_counter() - start >= seconds:
                break
        elapsed = time.perf_counter() - start
        dt = float(env.unwrapped.dt)
    finally:
        env.close()
    return {"steps_per_second": steps / elapsed, "steps": steps, "resets": resets, "seconds": elapsed,
            "control_period": dt, "sim_seconds_per_second": steps * dt / elapsed}


def run_envs_bench(*, seconds: float = 3.0, seed: int = 0, envs: Sequence[str] = BASE_ENV_IDS,
                   peers: Sequence[str] = PEERS, env_kwargs: dict[str, dict[str, Any]] | None = None,
                   variants: dict[str, tuple[str, dict[str, Any], str]] | None = None,
                   wrapped: Sequence[str] = WRAPPED_ENV_IDS, rounds: int = 5,
                   progress: bool = True) -> dict[str, Any]:
    """Steps per second of ``envs`` and ``peers`` (zero policy, ``seconds`` each), and of every ``wrapped`` id
    against its raw env (:func:`wrapped_rates`, ``rounds`` alternating pairs in ``seconds``); returns the report.

    Args:
        seconds: wall time per env (per wrapped id and per its raw env).
        seed: reset seed.
        envs: our env ids; peers: Gymnasium ids measured in the same run.
        env_kwargs: optional ``gym.make`` kwargs per id.
        variants: extra measurements ``label -> (id, kwargs, ratio name)`` (default :data:`VARIANTS`, those
            whose id is in ``envs``); the ratio is the id's rate over the variant's.
        wrapped: wrapped env ids (``<Env>-<Wrapper>-v0``) measured against their raw env.
        rounds: alternating raw/wrapped windows per wrapped id.
        progress: show a progress bar.
    """
    if seconds <= 0:
        raise EvalError(f"seconds must be > 0, got {seconds}")
    env_kwargs = env_kwargs or {}
    variants = {k: v for k, v in (VARIANTS if variants is None else variants).items() if v[0] in envs}
    runs = [(i, i, env_kwargs.get(i, {})) for i in (*envs, *peers)]
    runs += [(label, i, {**env_kwargs.get(i, {}), **kw}) for label, (i, kw, _) in variants.items()]
    rates: dict[str, dict[str, float]] = {}
    for label, env_id, kwargs in tqdm(runs, desc="bench envs", disable=not progress):
        rates[label] = _steps_per_second(env_id, seconds, seed, kwargs)
    ratios = {}
    for ours in envs:
        for peer in peers:
            name = f"{_SHORT.get(ours, ours)}_vs_{_SHORT.get(peer, peer)}"
            ratios[name] = rates[ours]["steps_per_second"] / rates[peer]["steps_per_second"]
    for label, (env_id, _, name) in variants.items():
        ratios[name] = rates[env_id]["steps_per_second"] / rates[label]["steps_per_second"]
    wrapped_report = wrapped_rates(wrapped, seconds=seconds, rounds=rounds, seed=seed, progress=progress)
    return {"benchmark": "envs", "seed": seed, "seconds_per_env": seconds, "policy": "zero",
            "machine": {"processor": platform.processor() or platform.machine(), "python": platform.python_version()},
            "envs": rates, "ratios": ratios, "wrapped": wrapped_report, **ratios}


def format_envs_bench(report: dict[str, Any]) -> str:
    """A plain-text table of steps/s and ratios."""
    lines = ["env | steps/s | resets", "-" * 40]
    for env_id, r in report["envs"].items():
        lines.append(f"{env_id} | {r['steps_per_second']:.0f} | {r['resets']}")
    lines += [f"{name} = {value:.2f}" for name, value in report["ratios"].items()]
    if report.get("wrapped"):
        lines += ["", "wrapped env | steps/s | raw steps/s | wrapped / raw (median, range over rounds)", "-" * 72]
        for env_id, r in report["wrapped"].items():
            lines.append(f"{env_id} | {r['steps_per_second']:.0f} | {r['raw_steps_per_second']:.0f} | "
                         f"{r['ratio']:.2f} ({r['ratio_min']:.2f}-{r['ratio_max']:.2f})")
    return "\n".join(lines)
