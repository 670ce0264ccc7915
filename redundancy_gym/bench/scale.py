"""``redundancy-gym bench scale``: how evaluation and vectorized stepping scale with processes on this machine.

- **eval**: episodes per second of :func:`~redundancy_gym.eval.evaluate.evaluate` with 1 worker (the serial loop)
  and with ``--workers`` 2, ... (the same episodes split across processes, fork start), measured in alternating
  rounds (serial, parallel, serial, ...) after one untimed episode, for 200 and 1000 AgriReach ``clik`` episodes
  and 20 BipedWalk ones. The time is the wall time of the whole ``evaluate`` call, as a user pays it: building
  the env and the policy, the warm-up (the serial loop's warm-up episode, the parallel run's warm-up call),
  starting the workers and merging their results. The speedup's median over rounds gives the serial fraction
  ``f`` of Amdahl's law, ``S(n) = 1 / (f + (1 - f) / n)``, solved for the largest measured ``n``, and what that
  ``f`` predicts for 64 cores. Each round also compares the two runs' JSON, timings excepted (``json_equal``:
  equal in every round).
- **Ray**: the same against Ray actors on a local instance started with ``num_cpus`` 4 and 8 (``--ray-workers``);
  on a 2-core machine the actors share the cores, so this shows Ray's overhead, not a larger machine's speedup.
- **make_vec**: env steps per second of ``gym.make_vec(id, num_envs=n, vectorization_mode="sync" | "async")``
  with random actions, per env step summed over the ``n`` envs.
"""

from __future__ import annotations

import os
import resource
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

__all__ = [
    "SCALE_CASES",
    "TIMING_SUFFIXES",
    "WITHOUT_RAY",
    "amdahl_serial_fraction",
    "amdahl_speedup",
    "format_scale_bench",
    "run_scale_bench",
    "without_timings",
]

SCALE_CASES: dict[str, tuple[str, str, dict[str, Any], int]] = {
    "agri_reach": ("redundancy_gym/AgriReach-v0", "clik", {}, 200),
    "agri_reach_1000": ("redundancy_gym/AgriReach-v0", "clik", {}, 1000),
    "biped_walk": ("redundancy_gym/BipedWalk-v0", "walking", {}, 20),
}
"""label -> (env id, policy, env kwargs, episodes per run) of the eval scaling runs: an AgriReach episode with clik
takes about 60 ms here (CPU time), a 10 s BipedWalk episode about 0.8 s, so the runs take about 12 s, 60 s and
16 s serially."""

WITHOUT_RAY = frozenset({"agri_reach_1000"})
"""Cases measured without the Ray rows: those show Ray's start-up cost, which the 200-episode case shows too, and
on 1000 episodes they would add about 10 min."""

TIMING_SUFFIXES = ("_us", "_ms", "_time_s")
"""The evaluation contract names its compute timings by their unit (``step_time_us``,
``compute_time_per_episode_ms``, ``sb3_predict_us``, ``per_episode``'s ``first_step_us``, ``compile_time_s``: numba
compiling or loading kernels, in every process that runs episodes); they differ between runs, and no other field
ends so."""


def amdahl_serial_fraction(speedup: float, n: int) -> float:
    """The serial fraction ``f`` with ``1 / (f + (1 - f) / n) = speedup`` (clipped into [0, 1])."""
    if n < 2:
        raise BenchError(f"the serial fraction needs n >= 2 processes, got {n}")
    f = (n / speedup - 1.0) / (n - 1.0)
    return float(min(1.0, max(0.0, f)))


def amdahl_speedup(f: float, n: int) -> float:
    """Amdahl's speedup on ``n`` processes with serial fraction ``f``."""
    return 1.0 / (f + (1.0 - f) / n)


def without_timings(contract: dict[str, Any]) -> dict[str, Any]:
    """An evaluation-contract object without its timings (the fields named with :data:`TIMING_SUFFIXES`, at the
    top and in ``per_episode``): what a parallel run must give exactly as the serial one does."""
    out = {k: v for k, v in contract.items() if not k.endswith(TIMING_SUFFIXES)}
    out["per_episode"] = [
        {k: v for k, v in row.items() if not k.endswith(TIMING_SUFFIXES)} for row in out["per_episode"]
    ]
    return out


def _busy_cpu_seconds() -> float | None:
    """CPU seconds [s] all processes of this machine have used since boot (``/proc/stat``); None where it is
    absent."""
    try:
        with open("/proc/stat") as stat:
            ticks = [int(x) for x in stat.readline().split()[1:]]
    except (OSError, ValueError):
        return None
    return (sum(ticks) - ticks[3] - ticks[4]) / os.sysconf("SC_CLK_TCK")  # all but idle and iowait


def _own_cpu_seconds() -> float:
    """CPU seconds [s] of this process and its finished children (the pool's workers, once joined)."""
    own, children = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + children.ru_utime + children.ru_stime


def _eval_run(
    env_id: str,
    policy: str,
    env_kwargs: dict[str, Any],
    episodes: int,
    seed: int,
    workers: int,
    ray_address: str | None = None,
) -> tuple[float, dict[str, Any], float | None]:
    """Episodes/s of one ``evaluate`` call (its whole wall time), its JSON, and the cores other processes used
    meanwhile on average (None without ``/proc/stat``): on a shared machine they take cores from the workers."""
    busy, own = _busy_cpu_seconds(), _own_cpu_seconds()
    start = time.perf_counter()
    report = evaluate(
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
    wall = time.perf_counter() - start
    busy_after = _busy_cpu_seconds()
    others = None if busy is None or busy_after is None else (busy_after - busy - _own_cpu_seconds() + own) / wall
    return episodes / wall, report.to_json(), None if others is None else max(0.0, others)


def _speedup_rounds(
    run: Callable[[int, str | None], tuple[float, dict[str, Any], float | None]],
    workers: int,
    ray_address: str | None,
    rounds: int,
    bar: Any,
) -> dict[str, Any]:
    """The serial loop and ``workers`` (local processes, or Ray actors at ``ray_address``) in ``rounds``
    alternating rounds, so that a load change hits both alike: their episodes/s and the speedup (medians over
    the rounds; the speedup's smallest and largest round), whether the parallel JSON was the serial one's,
    timings excepted, in every round, and the cores other processes used during the parallel runs (median over
    the rounds; a speedup below ``workers`` with those near 1 is the machine's, not the pool's).
    ``run(workers, ray_address)`` gives episodes/s, the JSON and the cores others used."""
    serial, parallel, equal, others = [], [], [], []
    for _ in range(rounds):
        serial_rate, serial_json, _ = run(1, None)
        parallel_rate, parallel_json, busy = run(workers, ray_address)
        serial.append(serial_rate)
        parallel.append(parallel_rate)
        equal.append(without_timings(parallel_json) == without_timings(serial_json))
        if busy is not None:
            others.append(busy)
        bar.update(1)
    speedups = [p / s for s, p in zip(serial, parallel, strict=True)]
    return {
        "serial_episodes_per_second": float(np.median(serial)),
        "episodes_per_second": float(np.median(parallel)),
        "speedup": float(np.median(speedups)),
        "speedup_min": float(min(speedups)),
        "speedup_max": float(max(speedups)),
        "json_equal": all(equal),
        "others_cores": float(np.median(others)) if others else None,
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
            the speedup is bounded by the core count); the Ray start is not timed. Not for :data:`WITHOUT_RAY`.
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
    ray_cases = sum(case not in WITHOUT_RAY for case in cases)
    total = (len(cases) * len(workers) + ray_cases * len(ray_workers)) * rounds + len(num_envs) * 2
    with tqdm(total=total, desc="bench scale", disable=not progress) as bar:
        for case in cases:
            env_id, policy, kwargs, own_episodes = SCALE_CASES[case]
            n_episodes = episodes or own_episodes
            # untimed: this process's first episode loads the compiled kernels, which the first round's serial
            # loop would pay alone (forked workers inherit them)
            evaluate(env_id, policy, episodes=1, seed=seed, env_kwargs=kwargs, progress=False)
            rate = partial(_eval_run, env_id, policy, kwargs, n_episodes, seed)
            rows = {}
            for n in workers:
                rows[str(n)] = _speedup_rounds(rate, n, None, rounds, bar)
            largest = max(workers)
            f = amdahl_serial_fraction(rows[str(largest)]["speedup"], largest)
            on_ray = {}
            for n in () if case in WITHOUT_RAY else ray_workers:
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
                "json_equal": all(r["json_equal"] for r in (*rows.values(), *on_ray.values())),
            }
        for mode in ("sync", "async"):
            rates = {}
            for n in num_envs:
                rates[str(n)] = _vec_rate(vec_env, n, mode, vec_steps, seed)
                bar.update(1)
            report["make_vec"][mode] = rates
    report["make_vec"]["env"] = vec_env
    report["json_equal"] = all(row["json_equal"] for row in report["eval"].values())
    return report


def format_scale_bench(report: dict[str, Any]) -> str:
    """The report as text."""
    m = report["machine"]
    lines = [
        f"machine: {m.get('cpu_model', m['processor'])}, {m['cores']} cores, load average "
        f"{', '.join(f'{x:.2f}' for x in m['load_average'])}",
        f"eval: {report['rounds']} alternating rounds, the whole evaluate call's wall time (build, warm-up, "
        "worker start); parallel JSON equal to the serial one's, timings excepted: "
        f"{'yes' if report['json_equal'] else 'NO'}",
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
                    f"(rounds {r['speedup_min']:.2f}-{r['speedup_max']:.2f}"
                    + ("" if r.get("others_cores") is None else f"; other processes used {r['others_cores']:.2f} cores")
                    + ")"
                    + ("" if r["json_equal"] else ", JSON differs from the serial run's")
                )
    vec = report["make_vec"]
    lines += ["", f"make_vec {vec['env']}: env steps/s (random actions) by num_envs"]
    for mode in ("sync", "async"):
        lines.append(f"  {mode:5s} " + "  ".join(f"{n}: {rate:.0f}" for n, rate in vec[mode].items()))
    return "\n".join(lines)
