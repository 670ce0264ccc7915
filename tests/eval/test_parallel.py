"""eval --workers: the episodes split across processes give the serial run's JSON, timings excepted; a worker that
raises or dies fails its episodes by seed, and --retries runs them again."""

from __future__ import annotations

import dataclasses
import functools
import json
import os
import sys
import types
from pathlib import Path
from typing import Any, cast

import numpy as np
import pytest

import redundancy_gym.eval.parallel as parallel
from redundancy_gym.cli import main
from redundancy_gym.eval.evaluate import evaluate
from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.eval.parallel import ParallelEvalError

TIMINGS = ("step_time_us", "compute_time_per_episode_ms", "compile_time_s")  # compile_time_s: cache loads too


def _without_timings(report: dict) -> dict:
    out = {k: v for k, v in report.items() if k not in TIMINGS}
    out["per_episode"] = [{k: v for k, v in row.items() if k != "first_step_us"} for row in report["per_episode"]]
    return out


@pytest.mark.parametrize(
    ("env_id", "policy", "episodes", "env_kwargs"),
    [
        ("redundancy_gym/PlanarReach-v0", "clik", 5, {"obstacle": True}),
        ("redundancy_gym/PlanarReach-v0", "random", 3, {}),  # reseeded per episode: order does not matter
        ("redundancy_gym/AgriReach-v0", "clik", 3, {}),
        ("redundancy_gym/BipedWalk-v0", "walking", 2, {"max_episode_steps": 300}),
    ],
)
def test_workers_give_the_serial_json(env_id: str, policy: str, episodes: int, env_kwargs: dict) -> None:
    serial = evaluate(env_id, policy, episodes=episodes, seed=40, env_kwargs=env_kwargs, progress=False).to_json()
    split = evaluate(
        env_id, policy, episodes=episodes, seed=40, env_kwargs=env_kwargs, progress=False, workers=2
    ).to_json()
    assert _without_timings(split) == _without_timings(serial)
    assert split["step_time_us"]["steps"] == serial["step_time_us"]["steps"]


@pytest.mark.parametrize(
    ("env_id", "policy", "episodes", "env_kwargs"),
    [
        ("redundancy_gym/AgriReach-v0", "clik", 9, {}),  # chunks of several episodes, then single ones
        ("redundancy_gym/PlanarReach-v0", "random", 4, {}),
    ],
)
def test_workers_with_a_warmup_and_traces_give_the_serial_json_and_traces(
    env_id: str, policy: str, episodes: int, env_kwargs: dict
) -> None:
    """warmup=1 as bench and demo run it: the serial loop's warm-up episode and the workers' warm-up call leave
    every episode as its seed makes it; the traces sent back packed are the serial ones, step times excepted."""
    kwargs: dict[str, Any] = dict(
        episodes=episodes, seed=3, env_kwargs=env_kwargs, progress=False, warmup=1, keep_traces=True
    )
    serial = evaluate(env_id, policy, **kwargs)
    split = evaluate(env_id, policy, workers=2, **kwargs)
    assert _without_timings(split.to_json()) == _without_timings(serial.to_json())
    assert len(split.traces) == len(serial.traces) == episodes
    for a, b in zip(split.traces, serial.traces, strict=True):
        for f in dataclasses.fields(a):
            if f.name != "step_time_us":
                np.testing.assert_array_equal(getattr(a, f.name), getattr(b, f.name), err_msg=f.name)
        assert a.step_time_us.shape == b.step_time_us.shape and np.all(a.step_time_us > 0)
    assert split.step_times_us.shape == serial.step_times_us.shape
    without = evaluate(env_id, policy, workers=2, **{**kwargs, "keep_traces": False})
    assert without.traces == [] and without.step_times_us.shape == serial.step_times_us.shape


def test_chunks_are_guided_consecutive_and_cover_every_seed_once() -> None:
    seeds = list(range(5, 1005))
    work = parallel.chunks(seeds, 2)
    assert [s for chunk in work for s in chunk] == seeds
    sizes = [len(chunk) for chunk in work]
    assert sizes[0] == 1000 // (parallel.CHUNKS_PER_WORKER * 2)
    assert sizes == sorted(sizes, reverse=True) and sizes[-parallel.CHUNKS_PER_WORKER :] == [1] * 4
    assert len(work) <= 60  # tens of messages for 1000 episodes, not 1000
    assert parallel.chunks([1, 2, 3], 8) == [[1], [2], [3]] and parallel.chunks([], 2) == []


def _whose(setup_pid: int, seed: int) -> tuple[int, int, int]:
    return seed, setup_pid, os.getpid()


class _Closing:
    """A setup's result with a close method, recording in the parent that it was closed."""

    def __init__(self, closed: list[int]) -> None:
        self.closed = closed

    def __call__(self, seed: int) -> tuple[int, int, int]:
        return _whose(-1, seed)

    def close(self) -> None:
        self.closed.append(os.getpid())


def test_forked_workers_inherit_the_setup_run_once_here_and_it_is_closed_after(monkeypatch) -> None:
    calls: list[int] = []
    closed: list[int] = []

    def setup() -> _Closing:
        calls.append(os.getpid())
        return _Closing(closed)

    progress: list[int] = []
    seeds = list(range(30))
    out = parallel.run_parallel(setup, seeds, workers=2, start_method="fork", progress=progress.append)
    assert calls == [os.getpid()] and closed == [os.getpid()]  # once, here; closed here after the run
    assert [seed for seed, _, _ in out] == seeds
    assert os.getpid() not in {pid for _, _, pid in out}  # the episodes ran in the workers
    assert sum(progress) == len(seeds) and len(progress) == len(parallel.chunks(seeds, 2)) < len(seeds)


def _setup_that_loads_torch(parent_pid: int):
    if os.getpid() == parent_pid:  # here as a policy's import would: the run must not fork after this
        sys.modules["torch"] = cast(types.ModuleType, types.SimpleNamespace(set_num_threads=lambda n: None))
    return functools.partial(_whose, os.getpid())


def test_a_setup_that_loads_torch_here_makes_the_workers_spawn_and_set_up_themselves(monkeypatch) -> None:
    monkeypatch.delitem(sys.modules, "torch", raising=False)
    monkeypatch.setattr(parallel, "_start_method", lambda: "spawn" if "torch" in sys.modules else "fork")
    try:
        out = parallel.run_parallel(functools.partial(_setup_that_loads_torch, os.getpid()), [1, 2, 3], workers=2)
    finally:
        sys.modules.pop("torch", None)
    assert [seed for seed, _, _ in out] == [1, 2, 3]
    assert all(setup_pid == pid != os.getpid() for _, setup_pid, pid in out)  # set up in each spawned worker


def test_an_unknown_start_method_is_named() -> None:
    with pytest.raises(EvalError, match="start_method must be one of .*fork.*, got 'threads'"):
        parallel.run_parallel(lambda: int, [1], workers=2, start_method="threads")


def _dies_once(marker: Path, seed_to_kill: int):
    original = parallel._run_seed

    def run(seed: int):
        if seed == seed_to_kill and marker.exists():
            marker.unlink()
            os._exit(1)  # the worker process dies mid-run, as a killed one does
        return original(seed)

    return run


def test_a_killed_worker_fails_its_seeds_and_a_retry_completes_the_serial_json(tmp_path, monkeypatch) -> None:
    env_id, kwargs = "redundancy_gym/PlanarReach-v0", {"obstacle": False}
    serial = evaluate(env_id, "clik", episodes=4, seed=7, env_kwargs=kwargs, progress=False).to_json()
    marker = tmp_path / "kill"
    monkeypatch.setattr(parallel, "_start_method", lambda: "fork")  # clik only: no torch in the workers
    monkeypatch.setattr(parallel, "_run_seed", _dies_once(marker, 9))  # fork: the workers inherit the patch
    marker.touch()
    with pytest.raises(ParallelEvalError, match=r"failed after 1 attempt\(s\): seeds .*9") as failed:
        evaluate(env_id, "clik", episodes=4, seed=7, env_kwargs=kwargs, progress=False, workers=2)
    assert 9 in {f.seed for f in failed.value.failures}
    assert all("died" in f.error for f in failed.value.failures)
    marker.touch()
    retried = evaluate(env_id, "clik", episodes=4, seed=7, env_kwargs=kwargs, progress=False, workers=2, retries=1)
    assert not marker.exists()  # the worker did die once
    assert _without_timings(retried.to_json()) == _without_timings(serial)


def test_an_exception_in_an_episode_is_reported_with_its_seed_and_the_cli_exits_non_zero(
    tmp_path, monkeypatch, capsys
) -> None:
    original = parallel._run_seed

    def run(seed: int):
        if seed == 2:
            try:
                raise RuntimeError("simulated fault in episode 2")
            except RuntimeError:
                import traceback

                return traceback.format_exc()
        return original(seed)

    monkeypatch.setattr(parallel, "_start_method", lambda: "fork")  # the zero policy: no torch in the workers
    monkeypatch.setattr(parallel, "_run_seed", run)
    path = tmp_path / "eval.json"
    code = main(
        [
            "eval",
            "redundancy_gym/PlanarReach-v0",
            "--policy",
            "zero",
            "--episodes",
            "4",
            "--seed",
            "0",
            "--workers",
            "2",
            "--retries",
            "1",
            "--json",
            str(path),
            "--no-progress",
        ]
    )
    err = capsys.readouterr().err
    assert code == 2 and not path.exists()  # never a partial table
    assert "1 episode(s) failed after 2 attempt(s): seeds 2" in err and "simulated fault in episode 2" in err


def test_workers_spawn_once_torch_is_loaded(monkeypatch) -> None:
    """A forked child that runs torch hangs when the parent ran torch first (it did in the full test suite, on a
    bench learned run over the shipped models): with torch loaded, workers are spawned."""
    import sys

    monkeypatch.setitem(sys.modules, "torch", object())
    assert parallel._start_method() == "spawn"
    monkeypatch.delitem(sys.modules, "torch")
    assert parallel._start_method() == "fork"


def test_bad_arguments_are_named() -> None:
    with pytest.raises(Exception, match="workers must be an int >= 1, got 0"):
        evaluate("redundancy_gym/PlanarReach-v0", "zero", episodes=1, workers=0, progress=False)
    with pytest.raises(Exception, match="retries must be an int >= 0, got -1"):
        evaluate("redundancy_gym/PlanarReach-v0", "zero", episodes=1, workers=2, retries=-1, progress=False)


def test_cli_workers_write_the_serial_json(tmp_path) -> None:
    paths = [tmp_path / "serial.json", tmp_path / "split.json"]
    for path, workers in zip(paths, ("1", "2"), strict=True):
        assert (
            main(
                [
                    "eval",
                    "redundancy_gym/PlanarReach-v0",
                    "--policy",
                    "clik",
                    "--episodes",
                    "3",
                    "--workers",
                    workers,
                    "--json",
                    str(path),
                    "--no-progress",
                ]
            )
            == 0
        )
    serial, split = (json.loads(p.read_text()) for p in paths)
    assert _without_timings(split) == _without_timings(serial)


def test_a_random_episode_depends_on_its_seed_only() -> None:
    """eval reseeds the random policy with each episode's seed: episode 6 of a run from seed 5 is the episode of a
    run from seed 6 (before, the generator ran on from the episodes before it)."""
    both = evaluate("redundancy_gym/PlanarReach-v0", "random", episodes=2, seed=5, progress=False).to_json()
    alone = evaluate("redundancy_gym/PlanarReach-v0", "random", episodes=1, seed=6, progress=False).to_json()
    assert both["per_episode"][1]["return"] == alone["per_episode"][0]["return"]
    assert both["per_episode"][0]["return"] != both["per_episode"][1]["return"]
