"""eval --workers: the episodes split across processes give the serial run's JSON, timings excepted; a worker that
raises or dies fails its episodes by seed, and --retries runs them again."""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

import redundancy_gym.eval.parallel as parallel
from redundancy_gym.cli import main
from redundancy_gym.eval.evaluate import evaluate
from redundancy_gym.eval.parallel import ParallelEvalError

TIMINGS = ("step_time_us", "compute_time_per_episode_ms")


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
