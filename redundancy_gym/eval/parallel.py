"""The episodes of one evaluation across worker processes. A setup (``eval``: build the env and the policy, warm
their kernels up) runs once per run: in the parent before the workers fork, so that they inherit its result with
its compiled kernels and caches, or, where workers are spawned (torch loaded) or Ray actors, once in each worker.
The workers then stream the seeds in chunks that shrink towards the end (guided scheduling: few messages, and
the last ones one episode long, so no worker idles while another finishes a long chunk). Every episode keeps its
seed, so the evaluation's JSON is the serial run's, timings excepted.

A worker that raises inside an episode fails that episode; a worker that dies (killed, out of memory) fails the
episodes of the chunks it had not returned. Those seeds run again in a fresh pool ``retries`` times, and a run
that still has failed episodes raises :class:`ParallelEvalError` naming them, never a partial table.
"""

from __future__ import annotations

import functools
import multiprocessing
import os
import sys
import traceback
from collections import deque
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from typing import Any

from ..sb3_import import install_hint
from .exceptions import EvalError

__all__ = [
    "CHUNKS_PER_WORKER",
    "LOCAL_RAY",
    "RAY_EXTRA_HINT",
    "EpisodeFailure",
    "ParallelEvalError",
    "chunks",
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


CHUNKS_PER_WORKER = 4
"""Guided scheduling's divisor: each chunk is the remaining seeds over ``CHUNKS_PER_WORKER * workers`` (at least
one), so the first chunk is an eighth of the run with 2 workers and the last ones are single episodes."""

# the worker's episode runner, built once per process by _init_worker (or inherited from the parent by _adopt)
_WORKER: dict[str, Any] = {}


def _init_worker(setup: Callable[[], Callable[[int], Any]]) -> None:
    try:
        _WORKER.update(run=setup())
    except Exception:  # every episode of this worker reports it (an initializer's exception breaks the pool mutely)
        _WORKER.update(error=traceback.format_exc())
    _one_torch_thread()


def _adopt(run: Callable[[int], Any]) -> None:
    """A forked worker's initializer: ``run`` is the parent's, built and warmed before the fork (fork passes it by
    memory, not by pickle)."""
    _WORKER.clear()
    _WORKER.update(run=run)
    _one_torch_thread()


def _one_torch_thread() -> None:
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


def _run_chunk(seeds: Sequence[int]) -> list[Any]:
    """The outcomes of a chunk's episodes, in its order: one message back per chunk, not per episode."""
    return [_task(seed) for seed in seeds]


def chunks(seeds: Sequence[int], workers: int) -> list[list[int]]:
    """``seeds`` in consecutive chunks of guided sizes: the remaining seeds over ``CHUNKS_PER_WORKER * workers``, at
    least 1 (1000 seeds on 2 workers: 125, 109, 95, ..., then single seeds; 48 chunks)."""
    out: list[list[int]] = []
    start = 0
    while start < len(seeds):
        size = max(1, (len(seeds) - start) // (CHUNKS_PER_WORKER * workers))
        out.append(list(seeds[start : start + size]))
        start += size
    return out


def _start_method() -> str:
    """``fork`` starts a worker in milliseconds (``spawn``: seconds of imports), but a forked child that runs torch
    hangs when the parent has run torch before (its OpenMP pool does not survive a fork): spawn once torch is in
    this process."""
    if "torch" in sys.modules or "fork" not in multiprocessing.get_all_start_methods():
        return "spawn"
    return "fork"


LOCAL_RAY = "local"
"""``ray_address`` of a Ray instance started on this machine (``ray.init()`` without an address)."""
RAY_EXTRA_HINT = f"Ray is not installed; {install_hint('ray')}"


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

    def run(self, seeds: Sequence[int]) -> list[Any]:
        return _run_chunk(seeds)


def _keep(
    seeds: Sequence[int],
    outcomes: Sequence[Any],
    results: dict[int, Any],
    failures: dict[int, EpisodeFailure],
    progress: Callable[[int], object] | None,
) -> None:
    """File a chunk's outcomes: a traceback (text) is a failure, anything else the episode's result; one progress
    update per chunk (a per-episode one costs the parent, which shares the cores with the workers)."""
    finished = 0
    for seed, outcome in zip(seeds, outcomes, strict=True):
        if isinstance(outcome, str):
            failures[seed] = EpisodeFailure(seed, outcome)
        else:
            results[seed] = outcome
            finished += 1
    if progress is not None and finished:
        progress(finished)


def _ray_attempt(
    setup: Callable[[], Callable[[int], Any]],
    workers: int,
    address: str,
    progress: Callable[[int], object] | None,
    pending: Sequence[int],
) -> tuple[dict[int, Any], dict[int, EpisodeFailure]]:
    ray = init_ray(address)
    actor = ray.remote(num_cpus=1)(_RayWorker)
    queue = deque(chunks(pending, workers))
    idle = [actor.remote(setup) for _ in range(min(workers, len(queue)))]
    actors = list(idle)
    running: dict[Any, tuple[Any, list[int]]] = {}
    results: dict[int, Any] = {}
    failures: dict[int, EpisodeFailure] = {}
    try:
        while queue or running:
            while queue and idle:  # a chunk to each free actor: a fast actor takes more chunks than a slow one
                a, chunk = idle.pop(), queue.popleft()
                running[a.run.remote(chunk)] = (a, chunk)
            if not running:  # every actor died: nothing left to run the queued chunks
                for chunk in queue:
                    failures.update((s, EpisodeFailure(s, "a Ray worker died: no actor left")) for s in chunk)
                break
            done, _ = ray.wait(list(running), num_returns=1)
            a, chunk = running.pop(done[0])
            try:
                outcomes = ray.get(done[0])
            except ray.exceptions.RayError as exc:  # the actor died (killed, out of memory) or its task broke
                why = f"a Ray worker died: {type(exc).__name__}: {str(exc).strip().splitlines()[0]}"
                failures.update((s, EpisodeFailure(s, why)) for s in chunk)
                continue  # not given another chunk
            idle.append(a)
            _keep(chunk, outcomes, results, failures, progress)
    finally:
        for a in actors:
            ray.kill(a)
    return results, failures


def _pool_attempt(
    initializer: Callable[..., None],
    initargs: tuple[Any, ...],
    workers: int,
    context: Any,
    progress: Callable[[int], object] | None,
    pending: Sequence[int],
) -> tuple[dict[int, Any], dict[int, EpisodeFailure]]:
    results: dict[int, Any] = {}
    failures: dict[int, EpisodeFailure] = {}
    work = chunks(pending, workers)
    with ProcessPoolExecutor(
        max_workers=min(workers, len(work)), mp_context=context, initializer=initializer, initargs=initargs
    ) as pool:
        # all submitted at once, largest first: the pool's queue hands them out in this order as workers free up
        futures = {pool.submit(_run_chunk, chunk): chunk for chunk in work}
        for future in as_completed(futures):
            chunk = futures[future]
            try:
                outcomes = future.result()
            except BrokenProcessPool as exc:
                why = f"a worker process died (pid {os.getpid()}'s pool): {exc}"
                failures.update((s, EpisodeFailure(s, why)) for s in chunk)
                continue
            _keep(chunk, outcomes, results, failures, progress)
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
    validate: Callable[[], object] | None = None,
) -> list[Any]:
    """Run one episode per seed on ``workers`` processes (or Ray actors); returns each seed's result, in ``seeds``'
    order.

    Args:
        setup: returns the function that runs the episode of a seed (building the env and the policy and warming
            them up is the setup's work). With ``fork`` it runs once, in this process, before the workers start
            (its exceptions propagate from here), and the workers inherit what it returned; a ``close`` method of
            that is called when the run ends. With ``spawn`` or Ray it runs once in each worker, so it must be a
            module-level function or a ``functools.partial`` of one (picklable).
        retries: how many times failed episodes run again, each time in a fresh pool (fresh actors).
        start_method: ``fork`` (default where the platform has it and torch is not loaded) or ``spawn``; not for
            Ray.
        progress: called with the number of episodes finished, once per chunk.
        ray_address: run on Ray actors instead of local processes: a cluster's address, or :data:`LOCAL_RAY` for
            a local instance (started once, with one CPU per core, unless the process started Ray itself).
        validate: called in this process first where ``setup`` does not run here (``spawn``, Ray), so that a bad
            argument raises its own error before any worker starts.

    Raises:
        ParallelEvalError: episodes failed on every attempt (named by seed).
        EvalError: ``workers`` < 1, ``retries`` < 0, an unknown ``start_method``, or ``ray_address`` without Ray
            installed (naming the extra).
    """
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise EvalError(f"workers must be an int >= 1, got {workers!r}")
    if isinstance(retries, bool) or not isinstance(retries, int) or retries < 0:
        raise EvalError(f"retries must be an int >= 0, got {retries!r}")
    methods = multiprocessing.get_all_start_methods()
    if start_method is not None and start_method not in methods:
        raise EvalError(f"start_method must be one of {', '.join(methods)}, got {start_method!r}")
    method = start_method or _start_method()
    inherited: Callable[[int], Any] | None = None
    if ray_address is None and method == "fork":
        inherited = setup()
        if start_method is None and _start_method() != "fork":  # the setup loaded torch here: a fork would hang
            _close(inherited)
            inherited, method = None, "spawn"
    elif validate is not None:
        validate()
    try:
        if ray_address is not None:
            attempt = functools.partial(_ray_attempt, setup, workers, ray_address, progress)
        elif inherited is not None:
            context = multiprocessing.get_context(method)
            attempt = functools.partial(_pool_attempt, _adopt, (inherited,), workers, context, progress)
        else:
            context = multiprocessing.get_context(method)
            attempt = functools.partial(_pool_attempt, _init_worker, (setup,), workers, context, progress)
        results: dict[int, Any] = {}
        pending = list(seeds)
        failures: dict[int, EpisodeFailure] = {}
        for _ in range(1 + retries):
            done, failures = attempt(pending)
            results.update(done)
            pending = sorted(failures)
            if not pending:
                break
    finally:
        if inherited is not None:
            _close(inherited)
    if failures:
        raise ParallelEvalError(list(failures.values()), 1 + retries)
    return [results[seed] for seed in seeds]


def _close(run: Callable[[int], Any]) -> None:
    close = getattr(run, "close", None)
    if callable(close):
        close()
