"""Training on Ray: a seed sweep of one config (``redundancy-gym train ... --ray --seeds 0 1 2``) and the learned
baselines (``redundancy-gym baselines --ray``) as Ray tasks, one CPU each.

A task trains on its node, evaluates its model there, and sends the model back as bytes, so the driver writes every
file itself, on a cluster as on one machine. A task that fails is named (by seed or baseline), and the run exits
non-zero after writing what did finish.
"""

from __future__ import annotations

import math
import tempfile
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from ..eval.json_writer import write_json
from ..eval.parallel import init_ray
from .exceptions import LearningError
from .training_record import record_path

__all__ = ["SweepError", "train_baselines_on_ray", "train_seed_sweep"]


class SweepError(LearningError):
    """Tasks of a sweep failed; ``failures`` maps each (seed or baseline name) to its error."""

    def __init__(self, failures: dict[str, str]) -> None:
        self.failures = dict(failures)
        first = next(iter(failures.values())).strip().splitlines()[-1] if failures else ""
        super().__init__(f"{len(failures)} task(s) failed: {', '.join(failures)} (first: {first})")


def _train_task(
    env_id: str, algo: str, steps: int, seed: int, train_kwargs: dict[str, Any], eval_episodes: int, eval_seed: int
) -> dict[str, Any]:
    """One seed on a Ray worker: train, evaluate on held-out seeds, return the model, its record and the row."""
    from ..eval.evaluate import evaluate
    from .training import train

    with tempfile.TemporaryDirectory() as tmp:
        path = train(
            env_id, algo, steps, Path(tmp) / f"seed{seed}.zip", seed=seed, progress_bar=False, log=None, **train_kwargs
        )
        report = evaluate(
            env_id,
            str(path),
            episodes=eval_episodes,
            seed=eval_seed,
            env_kwargs=train_kwargs.get("env_kwargs"),
            progress=False,
        ).to_json()
        return {"model": path.read_bytes(), "record": record_path(path).read_text(), "report": report}


def _gather(ray: Any, refs: dict[Any, str], log: Callable[[str], None] | None) -> tuple[dict[str, Any], dict[str, str]]:
    done: dict[str, Any] = {}
    failures: dict[str, str] = {}
    remaining = list(refs)
    while remaining:
        ready, remaining = ray.wait(remaining, num_returns=1)
        name = refs[ready[0]]
        try:
            done[name] = ray.get(ready[0])
        except ray.exceptions.RayError as exc:
            failures[name] = str(exc)
            if log is not None:
                log(f"{name}: failed: {str(exc).strip().splitlines()[-1]}")
            continue
        if log is not None:
            log(f"{name}: done ({len(done)}/{len(refs)})")
    return done, failures


def train_seed_sweep(
    env_id: str,
    algo: str,
    steps: int,
    out: str | Path,
    seeds: Sequence[int],
    *,
    ray_address: str = "local",
    train_kwargs: dict[str, Any] | None = None,
    eval_episodes: int = 10,
    eval_seed: int = 20000,
    log: Callable[[str], None] | None = print,
) -> dict[str, Any]:
    """Train one config with each of ``seeds`` as Ray tasks; write ``<out>_seed<s>.zip`` (with its record) per seed
    and ``<out>_sweep.json``; returns the sweep: per seed the evaluation on ``eval_episodes`` held-out episodes
    from ``eval_seed``, and the mean and spread of success rate and return over the seeds.

    Raises:
        SweepError: seeds whose task failed (after the others' files are written).
    """
    import json

    if not seeds:
        raise LearningError("give at least one seed")
    if algo not in ("ppo", "sac"):
        raise LearningError(f"a seed sweep trains ppo or sac, got {algo!r}")
    ray = init_ray(ray_address)
    task = ray.remote(num_cpus=1)(_train_task)
    kwargs = dict(train_kwargs or {})
    refs = {task.remote(env_id, algo, steps, seed, kwargs, eval_episodes, eval_seed): str(seed) for seed in seeds}
    done, failures = _gather(ray, refs, log)
    stem = Path(out).with_suffix("") if Path(out).suffix == ".zip" else Path(out)
    stem.parent.mkdir(parents=True, exist_ok=True)
    rows = {}
    for seed in sorted(done, key=int):
        result = done[seed]
        model = stem.with_name(f"{stem.name}_seed{seed}.zip")
        model.write_bytes(result["model"])
        record_path(model).write_text(result["record"])
        report = result["report"]
        rows[seed] = {
            "model": str(model),
            "success_rate": report["success_rate"],
            "episode_return": report["episode_return"],
            "report": report,
            "training": {
                k: v for k, v in json.loads(result["record"]).items() if k in ("env_steps", "wall_s", "cpu_s")
            },
        }
    successes = [r["success_rate"] for r in rows.values()]
    returns = [r["episode_return"] for r in rows.values()]
    sweep = {
        "env": env_id,
        "algo": algo,
        "steps": steps,
        "seeds": list(seeds),
        "eval_seed": eval_seed,
        "eval_episodes": eval_episodes,
        "rows": rows,
        "failed": failures,
        "success_mean": _mean(successes),
        "success_std": _std(successes),
        "return_mean": _mean(returns),
        "return_std": _std(returns),
    }
    path = write_json(sweep, stem.with_name(f"{stem.name}_sweep.json"))
    if log is not None:
        log(f"wrote {path}")
    if failures:
        raise SweepError(failures)
    return sweep


def _train_baseline_task(name: str, steps: int | None) -> dict[str, Any]:
    from .baselines import baselines, train_baseline

    (baseline,) = baselines([name])
    with tempfile.TemporaryDirectory() as tmp:
        path = train_baseline(
            baseline, work_dir=Path(tmp) / "work", tensorboard_log=None, models_dir=tmp, log=None, steps=steps
        )
        return {"model": path.read_bytes(), "record": record_path(path).read_text()}


def train_baselines_on_ray(
    names: Sequence[str],
    models_dir: str | Path,
    *,
    ray_address: str = "local",
    steps: int | None = None,
    log: Callable[[str], None] | None = print,
) -> list[Path]:
    """Train the baselines ``names`` (``baselines/*.yaml``) as Ray tasks, one CPU each, and write their models and
    records into ``models_dir``; returns the models written. ``steps``: a PPO/SAC budget instead of the files'
    (a smoke run's).

    Raises:
        SweepError: baselines whose task failed (after the others' files are written).
    """
    ray = init_ray(ray_address)
    task = ray.remote(num_cpus=1)(_train_baseline_task)
    done, failures = _gather(ray, {task.remote(name, steps): name for name in names}, log)
    written = []
    for name, result in done.items():
        model = Path(models_dir) / f"{name}.zip"
        model.parent.mkdir(parents=True, exist_ok=True)
        model.write_bytes(result["model"])
        record_path(model).write_text(result["record"])
        written.append(model)
    if failures:
        raise SweepError(failures)
    return written


def _mean(values: Sequence[float]) -> float | None:
    return sum(values) / len(values) if values else None


def _std(values: Sequence[float]) -> float | None:
    if not values:
        return None
    m = sum(values) / len(values)
    return math.sqrt(sum((v - m) ** 2 for v in values) / len(values))
