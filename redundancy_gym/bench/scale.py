"""``redundancy-gym bench scale``: how evaluation and vectorized stepping scale with processes on this machine.

- **eval**: episodes per second of :func:`~redundancy_gym.eval.evaluate.evaluate` with 1 worker (the serial loop)
  and with ``--workers`` 2, ... (the same episodes split across processes, fork start), measured in alternating
  rounds (serial, parallel, serial, ...). The wall time includes starting the workers and their warm-up episode,
  as a user's run does. The speedup's median over rounds gives the serial fraction ``f`` of Amdahl's law,
  ``S(n) = 1 / (f + (1 - f) / n)``, solved for the largest measured ``n``, and what that ``f`` predicts for
  64 cores.
- **Ray**: the same against Ray actors on a local instance started with ``num_cpus`` 4 and 8 (``--ray-workers``);
  on a 2-core machine the actors share the cores, so this shows Ray's overhead, not a larger machine's speedup.
- **make_vec**: env steps per second of ``gym.make_vec(id, num_envs=n, vectorization_mode="sync" | "async")``
  with random actions, per env step summed over the ``n`` envs.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable, Sequence
from functools import partial
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

from ..eval.evaluate import evaluate
from ..eval.parallel import LOCAL_RAY, import_ray
from ..learning.training_record import machine
from .exceptions import BenchError

__all__ = ["SCALE_CASES", "amdahl_serial_fraction", "amdahl_speedup", "format_scale_bench", "run_scale_bench"]

SCALE_CASES: dict[str, tuple[str, str, dict[str, Any], int]] = {
    "agri_reach": ("redundancy_gym/AgriReach-v0", "clik", {}, 200),
    "biped_walk": ("redundancy_gym/BipedWalk-v0", "walking", {}, 20),
}
"""label -> (env id, policy, env kwargs, episodes per run) of the eval scaling runs: an AgriReach episode with clik
takes about 20 ms here, a 10 s BipedWalk episode about 0.8 s, so a run is about 4 s and 16 s serially."""


def amdahl_serial_fraction(speedup: float, n: int) -> float:
    """The serial fraction ``f`` with ``1 / (f + (1 - f) / n) = speedup`` (clipped into [0, 1])."""
    if n < 2:
        raise BenchError(f"the serial fraction needs n >= 2 processes, got {n}")
    f = (n / speedup - 1.0) / (n - 1.0)
    return float(min(1.0, max(0.0, f)))


def amdahl_speedup(f: float, n: int) -> float:
    """Amdahl's speedup on ``n`` processes with serial fraction ``f``."""
    return 1.0 / (f + (1.0 - f) / n)


def _eval_rate(
    env_id: str,
    policy: str,
    env_kwargs: dict[str, Any],
    episodes: int,
    seed: int,
    workers: int,
    ray_address: str | None = None,
) -> float:
    start = time.perf_counter()
    evaluate(
        env_id,
        policy,
        episodes=episodes,
        seed=seed,
        env_kwargs=env_kwargs,
        progress=False,
        warmup=1,
        workers=workers,
        ray_address=ray_address,
    )
    return episodes / (time.perf_counter() - start)


def _speedup_rounds(
    rate: Callable[[int, str | None], float], workers: int, ray_address: str | None, rounds: int, bar: Any
) -> dict[str, float]:
    """The serial loop and ``workers`` (local processes, or Ray actors at ``ray_address``) in ``rounds``
    alternating rounds, so that a load change hits both alike: their episodes/s and the speedup (medians over
    the rounds; the speedup's smallest and largest round). ``rate(workers, ray_address)`` measures episodes/s."""
    serial, parallel = [], []
    for _ in range(rounds):
        serial.append(rate(1, None))
        parallel.append(rate(workers, ray_address))
        bar.update(1)
    speedups = [p / s for s, p in zip(serial, parallel, strict=True)]
    return {
        "serial_episodes_per_second": float(np.median(serial)),
        "episodes_per_second": float(np.median(parallel)),
        "speedup": float(np.median(speedups)),
        "speedup_min": float(min(speedups)),
        "speedup_max": float(max(speedups)),
    }


def _vec_rate(env_id: str, num_envs: int, mode: str, steps: int, seed: int) -> float:
    envs = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode=mode)
    try:
        envs.reset(seed=seed)
        envs.action_space.seed(seed)
        for _ in range(10):  # warm-up: the workers' first steps compile and build
            envs.step(envs.action_space.sample())
        start = time.perf_counter()
        for _ in range(steps):
            envs.step(envs.action_space.sample())
        return steps * num_envs / (time.perf_counter() - start)
    finally:
        envs.close()


def run_scale_bench(
    *,
    workers: Sequence[int] = (2,),
    episodes: int | None = None,
    rounds: int = 3,
    seed: int = 0,
    vec_env: str = "redundancy_gym/AgriReach-v0",
    num_envs: Sequence[int] = (1, 2, 4),
    vec_steps: int = 300,
    cases: Sequence[str] = tuple(SCALE_CASES),
    ray_workers: Sequence[int] = (),
    progress: bool = True,
) -> dict[str, Any]:
    """Measure eval's episodes/s against workers and make_vec's steps/s against ``num_envs``; returns the report.

    Args:
        workers: the parallel worker counts compared with the serial loop (each >= 2).
        episodes: episodes per measurement (seeds ``seed`` onwards); None: each case's own (:data:`SCALE_CASES`).
        rounds: alternating serial / parallel rounds per worker count.
        vec_env, num_envs, vec_steps: the make_vec measurement: env, env counts, vector steps per measurement.
        cases: keys of :data:`SCALE_CASES`.
        ray_workers: Ray actor counts measured as well, each on a local Ray instance started with that many
            ``num_cpus`` (more than the machine's cores simulates a larger node: the actors then share the cores, so
            the speedup is bounded by the core count); the Ray start is not timed.
    """
    if any(n < 2 for n in workers):
        raise BenchError(f"workers must each be >= 2 (1 is the serial loop measured beside them), got {list(workers)}")
    for case in cases:
        if case not in SCALE_CASES:
            raise BenchError(f"unknown case {case!r}; valid: {', '.join(SCALE_CASES)}")
    report: dict[str, Any] = {
        "machine": {**machine(), "load_average": list(os.getloadavg())},
        "rounds": rounds,
        "eval": {},
        "make_vec": {},
    }
    total = len(cases) * (len(workers) + len(ray_workers)) * rounds + len(num_envs) * 2
    with tqdm(total=total, desc="bench scale", disable=not progress) as bar:
        for case in cases:
            env_id, policy, kwargs, own_episodes = SCALE_CASES[case]
            n_episodes = episodes or own_episodes
            rate = partial(_eval_rate, env_id, policy, kwargs, n_episodes, seed)
            rows = {}
            for n in workers:
                rows[str(n)] = _speedup_rounds(rate, n, None, rounds, bar)
            largest = max(workers)
            f = amdahl_serial_fraction(rows[str(largest)]["speedup"], largest)
            on_ray = {}
            for n in ray_workers:
                ray = import_ray()
                ray.shutdown()
                ray.init(num_cpus=n, include_dashboard=False, log_to_driver=False)
                try:
                    on_ray[str(n)] = {
                        "num_cpus": n,
                        **_speedup_rounds(rate, n, LOCAL_RAY, rounds, bar),
                    }
                finally:
                    ray.shutdown()
            report["eval"][case] = {
                "ray": on_ray,
                "env": env_id,
                "policy": policy,
                "episodes": n_episodes,
                "workers": rows,
                "serial_fraction": f,
                "predicted_speedup_64": amdahl_speedup(f, 64),
            }
        for mode in ("sync", "async"):
            rates = {}
            for n in num_envs:
                rates[str(n)] = _vec_rate(vec_env, n, mode, vec_steps, seed)
                bar.update(1)
            report["make_vec"][mode] = rates
    report["make_vec"]["env"] = vec_env
    return report


def format_scale_bench(report: dict[str, Any]) -> str:
    """The report as text."""
    m = report["machine"]
    lines = [
        f"machine: {m.get('cpu_model', m['processor'])}, {m['cores']} cores, load average "
        f"{', '.join(f'{x:.2f}' for x in m['load_average'])}",
        f"eval: {report['rounds']} alternating rounds, wall time with worker start and warm-up",
        "",
    ]
    for case, row in report["eval"].items():
        lines.append(
            f"{case} ({row['policy']}, {row['episodes']} episodes per run): "
            f"serial fraction {row['serial_fraction']:.3f}, "
            f"predicted speedup on 64 cores {row['predicted_speedup_64']:.1f}x"
        )
        for kind, rows in (("workers", row["workers"]), ("Ray actors (num_cpus as many)", row.get("ray", {}))):
            for n, r in rows.items():
                lines.append(
                    f"  {n} {kind}: {r['episodes_per_second']:.2f} episodes/s against "
                    f"{r['serial_episodes_per_second']:.2f} serial, speedup {r['speedup']:.2f}x "
                    f"(rounds {r['speedup_min']:.2f}-{r['speedup_max']:.2f})"
                )
    vec = report["make_vec"]
    lines += ["", f"make_vec {vec['env']}: env steps/s (random actions) by num_envs"]
    for mode in ("sync", "async"):
        lines.append(f"  {mode:5s} " + "  ".join(f"{n}: {rate:.0f}" for n, rate in vec[mode].items()))
    return "\n".join(lines)
