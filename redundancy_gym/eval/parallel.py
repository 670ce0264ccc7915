"""The episodes of one evaluation across worker processes: each worker runs a setup once (``eval`` builds the env and
the policy and runs the warm-up episodes there), then one episode per seed it is given. Every episode keeps its seed,
so the evaluation's JSON is the serial run's, timings excepted.

A worker that raises inside an episode, or dies (killed, out of memory), fails the episodes it had not finished;
those seeds run again in a fresh pool ``retries`` times, and a run that still has failed episodes raises
:class:`ParallelEvalError` naming them, never a partial table.
"""

from __future__ import annotations

import functools
import multiprocessing
import os
import sys
import traceback
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

from .exceptions import EvalError

__all__ = [
    "LOCAL_RAY",
    "RAY_EXTRA_HINT",
    "EpisodeFailure",
    "ParallelEvalError",
    "import_ray",
    "init_ray",
    "ray_cpus",
    "run_parallel",
]


@dataclass(frozen=True)
class EpisodeFailure:
    """One episode that did not finish: its seed and why (the exception's traceback, or the worker's death)."""

    seed: int
    error: str


class ParallelEvalError(EvalError):
    """Episodes of a parallel evaluation failed after every retry; ``failures`` names them by seed."""

    def __init__(self, failures: Sequence[EpisodeFailure], attempts: int) -> None:
        self.failures = tuple(sorted(failures, key=lambda f: f.seed))
        seeds = ", ".join(str(f.seed) for f in self.failures)
        first = self.failures[0].error.strip().splitlines()[-1] if self.failures else ""
        super().__init__(
            f"{len(self.failures)} episode(s) failed after {attempts} attempt(s): seeds {seeds} "
            f"(first: {first}); --retries K runs failed episodes again"
        )


# the worker's episode runner, built once per process by _init_worker
_WORKER: dict[str, Any] = {}


def _init_worker(setup: Callable[[], Callable[[int], Any]]) -> None:
    try:
        _WORKER.update(run=setup())
    except Exception:  # every episode of this worker reports it (an initializer's exception breaks the pool mutely)
        _WORKER.update(error=traceback.format_exc())
    torch = sys.modules.get("torch")  # only where the policy brought it: importing torch costs a worker ~1 s
    if torch is not None:
        torch.set_num_threads(1)  # one process per core: torch's own pool would oversubscribe them


def _run_seed(seed: int) -> Any:
    """One episode in this worker: the runner's result, or the failure's traceback as text."""
    if "error" in _WORKER:
        return _WORKER["error"]
    try:
        return _WORKER["run"](seed)
    except Exception:  # reported by seed in the parent; the worker stays usable
        return traceback.format_exc()


def _task(seed: int) -> Any:
    # looks _run_seed up when it runs, in the worker (a fault-injecting test replaces it before the fork)
    return _run_seed(seed)


def _start_method() -> str:
    """``fork`` starts a worker in milliseconds (``spawn``: seconds of imports), but a forked child that runs torch
    hangs when the parent has run torch before (its OpenMP pool does not survive a fork): spawn once torch is in
    this process."""
    if "torch" in sys.modules or "fork" not in multiprocessing.get_all_start_methods():
        return "spawn"
    return "fork"


LOCAL_RAY = "local"
"""``ray_address`` of a Ray instance started on this machine (``ray.init()`` without an address)."""
RAY_EXTRA_HINT = "Ray is not installed; pip install -e '.[ray]' (in a clone) or pip install 'redundancy-gym[ray]'"


def import_ray() -> Any:
    """The ``ray`` module; an EvalError saying how to install it when it is missing."""
    try:
        import ray
    except ImportError:
        raise EvalError(RAY_EXTRA_HINT) from None
    return ray


def ray_cpus(address: str) -> int:
    """The CPUs of the Ray cluster at ``address`` (:data:`LOCAL_RAY`: a local instance), starting Ray if needed."""
    ray = init_ray(address)
    return max(1, int(ray.cluster_resources().get("CPU", 1)))


def init_ray(address: str) -> Any:
    """Connect to the Ray cluster at ``address`` (:data:`LOCAL_RAY`: start a local instance) unless this process
    already did; returns the ``ray`` module."""
    ray = import_ray()
    if not ray.is_initialized():
        ray.init(
            address=None if address == LOCAL_RAY else address,
            include_dashboard=False,
            log_to_driver=False,
            ignore_reinit_error=True,
        )
    return ray


class _RayWorker:
    """A Ray actor holding one worker's env and policy (its own process, so the module's _WORKER is its own)."""

    def __init__(self, setup: Callable[[], Callable[[int], Any]]) -> None:
        _init_worker(setup)

    def run(self, seed: int) -> Any:
        return _task(seed)


def _keep(
    seed: int,
    outcome: Any,
    results: dict[int, Any],
    failures: dict[int, EpisodeFailure],
    progress: Callable[[int], object] | None,
) -> None:
    """File a worker's outcome for ``seed``: a traceback (text) is a failure, anything else the episode's result."""
    if isinstance(outcome, str):
        failures[seed] = EpisodeFailure(seed, outcome)
        return
    results[seed] = outcome
    if progress is not None:
        progress(1)


def _ray_attempt(
    setup: Callable[[], Callable[[int], Any]],
    workers: int,
    address: str,
    progress: Callable[[int], object] | None,
    pending: Sequence[int],
) -> tuple[dict[int, Any], dict[int, EpisodeFailure]]:
    ray = init_ray(address)
    actor = ray.remote(num_cpus=1)(_RayWorker)
    actors = [actor.remote(setup) for _ in range(min(workers, len(pending)))]
    refs = {actors[k % len(actors)].run.remote(seed): seed for k, seed in enumerate(pending)}
    results: dict[int, Any] = {}
    failures: dict[int, EpisodeFailure] = {}
    remaining = list(refs)
    try:
        while remaining:
            done, remaining = ray.wait(remaining, num_returns=1)
            seed = refs[done[0]]
            try:
                outcome = ray.get(done[0])
            except ray.exceptions.RayError as exc:  # the actor died (killed, out of memory) or its task broke
                failures[seed] = EpisodeFailure(
                    seed, f"a Ray worker died: {type(exc).__name__}: {str(exc).strip().splitlines()[0]}"
                )
                continue
            _keep(seed, outcome, results, failures, progress)
    finally:
        for a in actors:
            ray.kill(a)
    return results, failures


def _pool_attempt(
    setup: Callable[[], Callable[[int], Any]],
    workers: int,
    context: Any,
    progress: Callable[[int], object] | None,
    pending: Sequence[int],
) -> tuple[dict[int, Any], dict[int, EpisodeFailure]]:
    results: dict[int, Any] = {}
    failures: dict[int, EpisodeFailure] = {}
    with ProcessPoolExecutor(
        max_workers=min(workers, len(pending)), mp_context=context, initializer=_init_worker, initargs=(setup,)
    ) as pool:
        futures = {pool.submit(_task, seed): seed for seed in pending}
        for future in as_completed(futures):
            seed = futures[future]
            try:
                outcome = future.result()
            except BrokenProcessPool as exc:
                failures[seed] = EpisodeFailure(seed, f"a worker process died (pid {os.getpid()}'s pool): {exc}")
                continue
            _keep(seed, outcome, results, failures, progress)
    return results, failures


def run_parallel(
    setup: Callable[[], Callable[[int], Any]],
    seeds: Sequence[int],
    *,
    workers: int,
    retries: int = 0,
    start_method: str | None = None,
    progress: Callable[[int], object] | None = None,
    ray_address: str | None = None,
) -> list[Any]:
    """Run one episode per seed on ``workers`` processes (or Ray actors); returns each seed's result, in ``seeds``'
    order.

    Args:
        setup: called once in each worker (a module-level function or a ``functools.partial`` of one, so that a
            spawned worker can unpickle it); returns the function that runs the episode of a seed (building the
            env and the policy and running any warm-up is the setup's work).
        retries: how many times failed episodes run again, each time in a fresh pool (fresh actors).
        start_method: ``fork`` (default where the platform has it) or ``spawn``; not for Ray.
        progress: called with the number of episodes finished by each result.
        ray_address: run on Ray actors instead of local processes: a cluster's address, or :data:`LOCAL_RAY` for
            a local instance (started once, with one CPU per core, unless the process started Ray itself).

    Raises:
        ParallelEvalError: episodes failed on every attempt (named by seed).
        EvalError: ``ray_address`` without Ray installed (naming the extra).
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise EvalError(f"workers must be an int >= 1, got {workers!r}")
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise EvalError(f"retries must be an int >= 0, got {retries!r}")
    if ray_address is not None:
        attempt = functools.partial(_ray_attempt, setup, workers, ray_address, progress)
    else:
        attempt = functools.partial(
            _pool_attempt, setup, workers, multiprocessing.get_context(start_method or _start_method()), progress
        )
    results: dict[int, Any] = {}
    pending = list(seeds)
    failures: dict[int, EpisodeFailure] = {}
    for _ in range(1 + retries):
        done, failures = attempt(pending)
        results.update(done)
        pending = sorted(failures)
        if not pending:
            break
    if failures:
        raise ParallelEvalError(list(failures.values()), 1 + retries)
    return [results[seed] for seed in seeds]
