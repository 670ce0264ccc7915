"""Minari datasets of a policy's episodes (seconds): Minari opens them, their metadata names policy, seeds and
success, their episodes replay in the recovered env bit for bit, action noise is seeded and keeps the policy's own
action as the label; bad arguments are refused by name."""

from __future__ import annotations

import json

import numpy as np
import pytest

import redundancy_gym  # noqa: F401 - registers the envs that Minari recovers
from redundancy_gym.cli import main
from redundancy_gym.datasets import DatasetError, collect_dataset, load_demonstrations

minari = pytest.importorskip("minari", reason="the dataset extra")

PLANAR = "redundancy_gym/PlanarReach-v0"


def _open(root, dataset_id, monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(root))
    return minari.load_dataset(dataset_id)


def _replays(dataset) -> list[bool]:
    """Per episode: the recovered env, reset with the episode's seed and stepped with its actions, gives its
    observations bit for bit."""
    env = dataset.recover_environment()
    seeds = [int(m["seed"]) for m in dataset.storage.get_episode_metadata(range(dataset.total_episodes))]
    same = []
    for seed, episode in zip(seeds, dataset.iterate_episodes(), strict=True):
        obs, _ = env.reset(seed=seed)
        equal = np.array_equal(obs, episode.observations[0])
        for t, action in enumerate(episode.actions):
            obs, *_ = env.step(action)
            equal = equal and np.array_equal(obs, episode.observations[t + 1])
        same.append(equal)
    env.close()
    return same


def test_a_dataset_opens_in_minari_names_its_source_and_replays_bit_for_bit(tmp_path, monkeypatch):
    summary = collect_dataset(PLANAR, tmp_path, episodes=2, seed=7, progress=False)
    assert summary.path == tmp_path / "redundancy_gym/PlanarReach/clik-v0" and summary.size_bytes > 0
    dataset = _open(tmp_path, summary.dataset_id, monkeypatch)
    assert dataset.total_episodes == 2 and dataset.total_steps == summary.steps == 500
    meta = dataset.storage.metadata
    assert meta["policy"] == "clik" and meta["env_id"] == PLANAR and meta["seeds"] == [7, 8]
    assert meta["success_rate"] == summary.success_rate == 1.0 and meta["action_noise"] == 0.0
    assert json.loads(meta["env_spec"])["id"] == PLANAR
    assert _replays(dataset) == [True, True]
    episode = next(iter(dataset.iterate_episodes()))
    # the env's metrics, one entry per observation, the success flag a flag
    assert len(episode.infos["tracking_error"]) == len(episode.observations) == 251
    assert episode.infos["is_success"].dtype == np.bool_ and bool(episode.infos["is_success"][-1])
    assert "expert_action" not in episode.infos  # no noise: the actions are the policy's


def test_env_kwargs_and_a_wrapped_id_are_recovered(tmp_path, monkeypatch):
    summary = collect_dataset(
        "redundancy_gym/PlanarReach-Residual-v0",
        tmp_path,
        policy="zero",
        env_kwargs={"obstacle": False},
        episodes=1,
        progress=False,
    )
    dataset = _open(tmp_path, summary.dataset_id, monkeypatch)
    env = dataset.recover_environment()
    assert env.spec.id == "redundancy_gym/PlanarReach-Residual-v0" and env.spec.kwargs["obstacle"] is False
    assert _replays(dataset) == [True]


def test_a_walk_replays_bit_for_bit(tmp_path, monkeypatch):
    # the walking reference keeps state between periods; a short walk from the recovered env's own spec
    summary = collect_dataset(
        "redundancy_gym/BipedWalk-v0", tmp_path, env_kwargs={"max_episode_steps": 40}, episodes=1, progress=False
    )
    dataset = _open(tmp_path, summary.dataset_id, monkeypatch)
    assert dataset.total_steps == 40 and dataset.storage.metadata["policy"] == "walking"
    assert _replays(dataset) == [True]


def test_action_noise_is_seeded_and_the_policy_s_action_is_the_label(tmp_path):
    first = collect_dataset(PLANAR, tmp_path / "a", episodes=1, action_noise=0.1, progress=False)
    again = collect_dataset(PLANAR, tmp_path / "b", episodes=1, action_noise=0.1, progress=False)
    clean = collect_dataset(PLANAR, tmp_path / "c", episodes=1, progress=False)
    noisy, twin, plain = (load_demonstrations(s.path) for s in (first, again, clean))
    assert np.array_equal(noisy.observations, twin.observations) and np.array_equal(noisy.actions, twin.actions)
    assert not np.array_equal(noisy.observations, plain.observations)  # the noise moved the arm
    dataset = minari.MinariDataset(noisy.path)
    episode = next(iter(dataset.iterate_episodes()))
    stepped, labels = episode.actions, episode.infos["expert_action"]
    assert len(labels) == len(stepped) + 1  # the final observation is labelled too
    assert np.array_equal(noisy.actions, labels[:-1]) and not np.allclose(stepped, labels[:-1])
    assert np.all(np.abs(stepped) <= 1.0)  # clipped into the action space
    assert noisy.metadata["action_noise"] == 0.1


@pytest.mark.parametrize(
    ("kwargs", "named"),
    [
        ({"episodes": 0}, "episodes"),
        ({"seed": -1}, "seed"),
        ({"action_noise": -0.1}, "action_noise"),
        ({"action_noise": float("nan")}, "action_noise"),
        ({"dataset_id": "no version"}, "dataset_id"),
    ],
)
def test_bad_arguments_are_named(tmp_path, kwargs, named):
    with pytest.raises(DatasetError, match=named):
        collect_dataset(PLANAR, tmp_path, progress=False, **kwargs)


def test_an_existing_dataset_is_kept_unless_overwritten(tmp_path):
    collect_dataset(PLANAR, tmp_path, episodes=1, progress=False)
    with pytest.raises(DatasetError, match="exists"):
        collect_dataset(PLANAR, tmp_path, episodes=1, progress=False)
    summary = collect_dataset(PLANAR, tmp_path, episodes=2, seed=3, overwrite=True, progress=False)
    assert load_demonstrations(summary.path).metadata["seeds"] == [3, 4]


def test_the_cli_writes_a_dataset_and_says_how_to_load_it(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)  # a relative --out, as the README writes it
    status = main(["collect", PLANAR, "--episodes", "1", "--out", "datasets", "--no-progress"])
    out = capsys.readouterr().out
    assert status == 0 and "redundancy_gym/PlanarReach/clik-v0" in out and "--algo bc --dataset" in out
    assert load_demonstrations("datasets").episodes == 1
    assert main(["collect", PLANAR, "--episodes", "1", "--out", "datasets", "--no-progress"]) == 2
    assert "exists" in capsys.readouterr().err
