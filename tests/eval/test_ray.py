"""eval on Ray (a local instance with 2 CPUs, no network): the JSON of the serial run, timings excepted; a killed
actor fails its seeds and --retries completes the run; without Ray, --ray says how to install it."""

from __future__ import annotations

import functools
import importlib
import os
import sys
from pathlib import Path

import pytest

from redundancy_gym.cli import main
from redundancy_gym.eval.evaluate import evaluate
from redundancy_gym.eval.parallel import LOCAL_RAY, ParallelEvalError, run_parallel

ray = pytest.importorskip("ray")

evaluate_module = importlib.import_module("redundancy_gym.eval.evaluate")  # the module, not the function
TIMINGS = ("step_time_us", "sb3_predict_us", "compute_time_per_episode_ms", "compile_time_s")


def _without_timings(report: dict) -> dict:
    out = {k: v for k, v in report.items() if k not in TIMINGS}
    out["per_episode"] = [{k: v for k, v in row.items() if k != "first_step_us"} for row in report["per_episode"]]
    return out


@pytest.fixture(scope="module", autouse=True)
def local_ray():
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    # the fault-injecting setup below lives in this module, which Ray's workers cannot import: send it by value
    ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
    yield
    ray.shutdown()


@pytest.mark.parametrize(
    ("env_id", "policy", "episodes", "env_kwargs"),
    [
        ("redundancy_gym/PlanarReach-v0", "clik", 4, {"obstacle": True}),
        ("redundancy_gym/AgriReach-v0", "clik", 3, {}),
        ("redundancy_gym/BipedWalk-v0", "walking", 2, {"max_episode_steps": 300}),
    ],
)
def test_ray_gives_the_serial_json(env_id: str, policy: str, episodes: int, env_kwargs: dict) -> None:
    serial = evaluate(env_id, policy, episodes=episodes, seed=50, env_kwargs=env_kwargs, progress=False).to_json()
    remote = evaluate(
        env_id,
        policy,
        episodes=episodes,
        seed=50,
        env_kwargs=env_kwargs,
        progress=False,
        workers=2,
        ray_address=LOCAL_RAY,
    ).to_json()
    assert _without_timings(remote) == _without_timings(serial)


def _dying_setup(marker: str, kill_seed: int, inner):
    run = inner()

    def maybe_die(seed: int):
        if seed == kill_seed and os.path.exists(marker):
            os.remove(marker)
            os._exit(1)  # the actor's process dies mid-run
        return run(seed)

    return maybe_die


def test_a_killed_ray_actor_fails_its_seeds_and_a_retry_completes(tmp_path: Path) -> None:
    env_id, kwargs = "redundancy_gym/PlanarReach-v0", {"obstacle": False}
    serial = evaluate(env_id, "clik", episodes=4, seed=7, env_kwargs=kwargs, progress=False)
    inner = functools.partial(evaluate_module._EpisodeRunner, env_id, "clik", kwargs, {}, 0, 7)
    marker = tmp_path / "kill"
    setup = functools.partial(_dying_setup, str(marker), 9, inner)
    marker.touch()
    with pytest.raises(ParallelEvalError, match="seeds .*9") as failed:
        run_parallel(setup, [7, 8, 9, 10], workers=2, ray_address=LOCAL_RAY)
    assert all("Ray worker died" in f.error for f in failed.value.failures)
    marker.touch()
    outcomes = run_parallel(setup, [7, 8, 9, 10], workers=2, retries=1, ray_address=LOCAL_RAY)
    assert not marker.exists()
    assert [s.episode_return for s, _ in outcomes] == [e.episode_return for e in serial.summaries]


def test_cli_ray_uses_the_clusters_cpus(tmp_path: Path, capsys) -> None:
    path = tmp_path / "ray.json"
    assert (
        main(
            [
                "eval",
                "redundancy_gym/PlanarReach-v0",
                "--policy",
                "zero",
                "--episodes",
                "3",
                "--ray",
                "--json",
                str(path),
                "--no-progress",
            ]
        )
        == 0
    )
    assert path.is_file()


def test_without_ray_the_option_says_how_to_install_it(monkeypatch, capsys) -> None:
    monkeypatch.setitem(sys.modules, "ray", None)  # import ray now raises ImportError
    assert (
        main(
            [
                "eval",
                "redundancy_gym/PlanarReach-v0",
                "--policy",
                "zero",
                "--episodes",
                "1",
                "--ray",
                "1.2.3.4:6379",
                "--no-progress",
            ]
        )
        == 2
    )
    assert "pip install -e '.[ray]'" in capsys.readouterr().err


def test_seed_sweep_on_ray_trains_each_seed_as_a_serial_run_would(tmp_path: Path, capsys) -> None:
    """train --ray --seeds: each seed's model is the one a serial train with that seed makes, and the sweep JSON
    holds each seed's held-out evaluation and the spread over seeds."""
    import json

    import numpy as np
    from stable_baselines3 import PPO

    from redundancy_gym.learning.training import train

    config = tmp_path / "ppo.yaml"
    config.write_text(
        "redundancy_gym/PlanarReach-v0:\n  n_timesteps: 128\n  n_envs: 1\n  n_steps: 128\n"
        "  batch_size: 64\n  n_epochs: 1\n"
    )
    out = tmp_path / "sweep.zip"
    assert (
        main(
            [
                "train",
                "redundancy_gym/PlanarReach-v0",
                "--config",
                str(config),
                "--ray",
                "--seeds",
                "0",
                "3",
                "--out",
                str(out),
                "--no-progress",
            ]
        )
        == 0
    )
    sweep = json.loads((tmp_path / "sweep_sweep.json").read_text())
    assert set(sweep["rows"]) == {"0", "3"} and sweep["failed"] == {}
    assert sweep["rows"]["3"]["report"]["seed"] == 20000 and sweep["rows"]["3"]["training"]["env_steps"] == 128
    serial = train(
        "redundancy_gym/PlanarReach-v0",
        "ppo",
        128,
        tmp_path / "serial3.zip",
        seed=3,
        hyperparameters={"n_steps": 128, "batch_size": 64, "n_epochs": 1},
        progress_bar=False,
        log=None,
    )
    a, b = PPO.load(serial, device="cpu"), PPO.load(tmp_path / "sweep_seed3.zip", device="cpu")
    for x, y in zip(a.policy.parameters(), b.policy.parameters(), strict=True):
        np.testing.assert_array_equal(x.detach().numpy(), y.detach().numpy())
    assert "success over seeds" in capsys.readouterr().out


def test_baselines_on_ray_write_models_and_records(tmp_path: Path, capsys) -> None:
    from redundancy_gym.learning.training_record import read_training_record

    # one rollout instead of the file's budget (a smoke run)
    assert main(["baselines", "ppo-residual-planar_reach", "--ray", "--steps", "1", "--models", str(tmp_path)]) == 0
    path = tmp_path / "ppo-residual-planar_reach.zip"
    record = read_training_record(path)
    assert path.is_file() and record is not None and record.env_steps == 8192
    assert f"wrote {path}" in capsys.readouterr().out


def test_bench_learned_on_ray_gives_the_local_table(tmp_path: Path) -> None:
    from redundancy_gym.bench.learned import run_learned_bench

    local = run_learned_bench(episodes=1, envs=["planar_reach"], progress=False, log=None)
    remote = run_learned_bench(
        episodes=1, envs=["planar_reach"], progress=False, log=None, workers=2, ray_address=LOCAL_RAY
    )
    for label, row in local["envs"]["planar_reach"]["rows"].items():
        other = remote["envs"]["planar_reach"]["rows"][label]
        assert _without_timings(other["report"]) == _without_timings(row["report"])
