"""``redundancy-gym bench envs``: env steps per second with a zero policy, ours against Gymnasium's MuJoCo envs.

Every env of ours and the peers (Gymnasium's ``Pusher-v5`` and ``Humanoid-v5``) is made with ``gym.make`` (so
the same wrappers apply) and stepped with the zero action (for BipedWalk-v0: stand in the nominal posture),
resetting when an episode ends (resets count: they are part of what a training loop pays). All of them are open
at once and stepped in alternating rounds (:func:`~redundancy_gym.bench.timing.alternating_rounds`: one
warm-up round, then ``rounds`` rounds in which every env runs one window of ``seconds / rounds``, in the list's
order and reversed every other round), so that a slow moment of the machine hits ours and the peer alike. An env's
``steps_per_second`` is the median over the rounds; a ratio ``<ours>_vs_<peer>`` is the median over the rounds of
the two rates measured in the same round (``ratio_rounds``: its median, min, max and spread ``(max - min) /
median``). ``agri_vs_pusher`` is AgriReach-v0 over Pusher-v5, ``biped_vs_humanoid`` BipedWalk-v0 over
Humanoid-v5 and ``biped_obstacles_vs_humanoid`` BipedObstacles-v0 (a random course per reset) over Humanoid-v5
(per env step; ``sim_seconds_per_second`` also compares simulated time, since the two step
different periods: 4 ms and 15 ms). Variants of our envs (by default
AgriReach with ``prune=False``, the whole crop row in the scene and the collision model) are measured in the same
rounds, and ``agri_prune_speedup`` is the pruned rate over the unpruned one. Every wrapped id
(``<Env>-<Wrapper>-v0``) is measured against its raw env in alternating rounds too (``wrapped``: the ratio
wrapped / raw, median and range over the rounds): what an action wrapper's controller costs per step.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from functools import partial
from typing import Any, Protocol, cast

import gymnasium as gym
import numpy as np
from gymnasium import spaces
from tqdm.auto import tqdm

from ..eval.machine import finish_machine_info, machine_info
from ..registration import BASE_ENV_IDS, WRAPPED_ENV_IDS
from .exceptions import BenchError
from .timing import CLOCK, alternating_rounds

__all__ = ["PEERS", "VARIANTS", "format_envs_bench", "run_envs_bench"]

PEERS = ("Pusher-v5", "Humanoid-v5")
VARIANTS = {
    "redundancy_gym/AgriReach-v0 (prune=False)": ("redundancy_gym/AgriReach-v0", {"prune": False}, "agri_prune_speedup")
}
"""label -> (env id, gym.make kwargs, name of the ratio base rate / variant rate)."""
_SHORT = {
    "redundancy_gym/PlanarReach-v0": "planar",
    "redundancy_gym/AgriReach-v0": "agri",
    "redundancy_gym/BipedWalk-v0": "biped",
    "redundancy_gym/BipedObstacles-v0": "biped_obstacles",
    "Pusher-v5": "pusher",
    "Humanoid-v5": "humanoid",
}


class _ControlPeriod(Protocol):
    """What :class:`_Stepper` reads of a base env beside gymnasium's ``Env``: every env benchmarked here (ours and
    gymnasium's MuJoCo envs) has a control period."""

    @property
    def dt(self) -> float:
        """Seconds of simulated time per step [s]."""


class _Stepper:
    """One env stepped with the zero action in timed windows, resetting when an episode ends; keeps each window's
    steps, resets and duration."""

    def __init__(self, env_id: str, seed: int, env_kwargs: dict[str, Any] | None = None) -> None:
        self.env = gym.make(env_id, **(env_kwargs or {}))
        self.env.reset(seed=seed)
        space = self.env.action_space
        assert isinstance(space, spaces.Box)  # every env benchmarked here takes a Box action
        self.action = np.zeros(space.shape, dtype=space.dtype)
        self.dt = float(cast(_ControlPeriod, self.env.unwrapped).dt)
        self.windows: list[tuple[int, int, float]] = []
        self._run(0.0, warmup=50)  # compiled kernels and caches
        self.env.reset(seed=seed)

    def window(self, seconds: float) -> float:
        """One window of about ``seconds`` [s]; returns its time per step [s] (resets included)."""
        steps, resets, elapsed = self._run(seconds)
        self.windows.append((steps, resets, elapsed))
        return elapsed / steps

    def totals(self, skip: int) -> tuple[int, int, float]:
        """Steps, resets and seconds of the windows after the first ``skip`` (the warm-up)."""
        kept = self.windows[skip:]
        return sum(w[0] for w in kept), sum(w[1] for w in kept), sum(w[2] for w in kept)

    def _run(self, seconds: float, warmup: int = 0) -> tuple[int, int, float]:
        """Steps, resets and time [s] (the smaller of wall-clock and process CPU time, as
        :func:`~redundancy_gym.bench.timing.timed_call`) of one window of about ``seconds`` wall time."""
        steps = resets = 0
        cpu = time.process_time()
        start = time.perf_counter()
        while True:
            _, _, terminated, truncated, _ = self.env.step(self.action)
            steps += 1
            if terminated or truncated:
                self.env.reset()
                resets += 1
            if warmup and steps >= warmup:
                break
            if not warmup and steps % 16 == 0 and time.perf_counter() - start >= seconds:
                break
        wall = time.perf_counter() - start
        return steps, resets, min(wall, time.process_time() - cpu)

    def close(self) -> None:
        """Close the env."""
        self.env.close()


def wrapped_rates(
    wrapped: Sequence[str], *, seconds: float, rounds: int, seed: int, progress: bool = False
) -> dict[str, dict[str, Any]]:
    """Steps/s of every wrapped id against its raw env, measured in alternating windows (raw, wrapped / wrapped,
    raw / ...; a warm-up pair, then ``rounds`` pairs of ``seconds / rounds`` each): the ratio wrapped / raw per
    round, its median, range and spread, so that a slow moment of the machine hits both alike."""
    out = {}
    for wrapped_id in tqdm(wrapped, desc="bench envs (wrapped)", disable=not progress):
        raw_id = gym.spec(wrapped_id).kwargs["env_id"]
        raw, inner = _Stepper(raw_id, seed), _Stepper(wrapped_id, seed)
        try:
            timed = alternating_rounds(
                # partial binds this iteration's steppers (a closure would read the loop's latest)
                {"raw": partial(raw.window, seconds / rounds), "wrapped": partial(inner.window, seconds / rounds)},
                rounds=rounds,
            )
        finally:
            raw.close()
            inner.close()
        stats = timed.ratio("raw", "wrapped")  # time per step raw / wrapped = rate wrapped / raw
        out[wrapped_id] = {
            "raw": raw_id,
            "raw_steps_per_second": 1.0 / timed.median("raw"),
            "steps_per_second": 1.0 / timed.median("wrapped"),
            "ratio": stats.median,
            "ratio_min": stats.min,
            "ratio_max": stats.max,
            "ratio_spread": stats.spread,
            "rounds": rounds,
        }
    return out


def run_envs_bench(
    *,
    seconds: float = 3.0,
    seed: int = 0,
    envs: Sequence[str] = BASE_ENV_IDS,
    peers: Sequence[str] = PEERS,
    env_kwargs: dict[str, dict[str, Any]] | None = None,
    variants: dict[str, tuple[str, dict[str, Any], str]] | None = None,
    wrapped: Sequence[str] = WRAPPED_ENV_IDS,
    rounds: int = 7,
    progress: bool = True,
) -> dict[str, Any]:
    """Steps per second of ``envs``, ``peers`` and ``variants`` (zero policy, ``seconds`` each, in ``rounds``
    alternating windows), and of every ``wrapped`` id against its raw env (:func:`wrapped_rates`); returns the report.

    Args:
        seconds: wall time per env over all rounds [s] (per wrapped id and per its raw env too).
        seed: reset seed.
        envs: our env ids; peers: Gymnasium ids measured in the same rounds.
        env_kwargs: optional ``gym.make`` kwargs per id.
        variants: extra measurements ``label -> (id, kwargs, ratio name)`` (default :data:`VARIANTS`, those
            whose id is in ``envs``); the ratio is the id's rate over the variant's.
        wrapped: wrapped env ids (``<Env>-<Wrapper>-v0``) measured against their raw env.
        rounds: alternating rounds (one window per env each) after a warm-up round.
        progress: show a progress bar.

    Raises:
        BenchError: ``seconds <= 0`` or ``rounds < 1``.
    """
    if not np.isfinite(seconds) or seconds <= 0:
        raise BenchError(f"seconds must be finite and > 0, got {seconds}")
    if int(rounds) != rounds or rounds < 1:
        raise BenchError(f"rounds must be an integer >= 1, got {rounds!r}")
    machine = machine_info()
    env_kwargs = env_kwargs or {}
    variants = {k: v for k, v in (VARIANTS if variants is None else variants).items() if v[0] in envs}
    runs = [(i, i, env_kwargs.get(i, {})) for i in (*envs, *peers)]
    runs += [(label, i, {**env_kwargs.get(i, {}), **kw}) for label, (i, kw, _) in variants.items()]
    steppers: dict[str, _Stepper] = {}
    try:
        for label, env_id, kwargs in runs:
            steppers[label] = _Stepper(env_id, seed, kwargs)
        window = seconds / rounds
        timed = alternating_rounds(
            {label: partial(stepper.window, window) for label, stepper in steppers.items()},
            rounds=rounds,
            progress=progress,
            desc="bench envs rounds",
        )
    finally:
        for stepper in steppers.values():
            stepper.close()
    rates: dict[str, dict[str, float]] = {}
    for label, stepper in steppers.items():
        steps, resets, elapsed = stepper.totals(timed.warmup)
        rate = 1.0 / timed.median(label)
        rates[label] = {
            "steps_per_second": rate,
            "steps": steps,
            "resets": resets,
            "seconds": elapsed,
            "control_period": stepper.dt,
            "sim_seconds_per_second": rate * stepper.dt,
        }
    stats = {}
    for ours in envs:
        for peer in peers:
            stats[f"{_SHORT.get(ours, ours)}_vs_{_SHORT.get(peer, peer)}"] = timed.ratio(peer, ours)
    for label, (env_id, _, name) in variants.items():
        stats[name] = timed.ratio(label, env_id)
    ratios = {name: s.median for name, s in stats.items()}
    wrapped_report = wrapped_rates(wrapped, seconds=seconds, rounds=rounds, seed=seed, progress=progress)
    return {
        "benchmark": "envs",
        "seed": seed,
        "seconds_per_env": seconds,
        "policy": "zero",
        "timing": {
            "rounds": rounds,
            "warmup": timed.warmup,
            "window_s": window,
            "clock": CLOCK,
            "orders": timed.orders,
        },
        "machine": finish_machine_info(machine),
        "envs": rates,
        "ratios": ratios,
        "ratio_rounds": {name: s.to_json() for name, s in stats.items()},
        "wrapped": wrapped_report,
        **ratios,
    }


def format_envs_bench(report: dict[str, Any]) -> str:
    """A plain-text table of steps/s and ratios."""
    lines = ["env | steps/s | resets", "-" * 40]
    for env_id, r in report["envs"].items():
        lines.append(f"{env_id} | {r['steps_per_second']:.0f} | {r['resets']}")
    spread = report.get("ratio_rounds", {})
    lines += [
        f"{name} = {value:.2f}"
        + (f"  (rounds {spread[name]['min']:.2f}-{spread[name]['max']:.2f})" if name in spread else "")
        for name, value in report["ratios"].items()
    ]
    if report.get("wrapped"):
        lines += ["", "wrapped env | steps/s | raw steps/s | wrapped / raw (median, range over rounds)", "-" * 72]
        for env_id, r in report["wrapped"].items():
            lines.append(
                f"{env_id} | {r['steps_per_second']:.0f} | {r['raw_steps_per_second']:.0f} | "
                f"{r['ratio']:.2f} ({r['ratio_min']:.2f}-{r['ratio_max']:.2f})"
            )
    return "\n".join(lines)
