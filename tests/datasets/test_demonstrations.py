"""Demonstrations read back from a dataset, and behaviour cloning from one: the pairs are the recorded ones, a
folder is found at any level, and a clone learns the dataset's actions without rolling out an expert."""

from __future__ import annotations

import numpy as np
import pytest

import redundancy_gym
from redundancy_gym.cli import main
from redundancy_gym.datasets import DatasetError, collect_dataset, find_dataset, load_demonstrations
from redundancy_gym.learning.behaviour_cloning import train_behaviour_cloning
from redundancy_gym.learning.exceptions import LearningError

minari = pytest.importorskip("minari", reason="the dataset extra")

PLANAR = "redundancy_gym/PlanarReach-v0"


@pytest.fixture(scope="module")
def planar_dataset(tmp_path_factory):
    return collect_dataset(PLANAR, tmp_path_factory.mktemp("ds"), episodes=2, seed=11, progress=False)


def test_the_pairs_are_the_recorded_observations_and_actions(planar_dataset):
    demos = load_demonstrations(planar_dataset.path)
    dataset = minari.MinariDataset(find_dataset(planar_dataset.path))
    episodes = list(dataset.iterate_episodes())
    assert demos.episodes == 2 and len(demos.observations) == len(demos.actions) == planar_dataset.steps
    # every observation an action was taken at (not the final one), in order
    expected = np.concatenate([e.observations[:-1] for e in episodes]).astype(np.float32)
    assert np.array_equal(demos.observations, expected)
    assert np.array_equal(demos.actions, np.concatenate([e.actions for e in episodes]))


def test_a_dataset_is_found_from_its_root_its_folder_or_its_data(planar_dataset, tmp_path):
    data = find_dataset(planar_dataset.path)
    assert data.name == "data" and (data / "metadata.json").is_file()
    assert find_dataset(data) == data == find_dataset(planar_dataset.path.parents[2])  # the root of one dataset
    with pytest.raises(DatasetError, match="does not exist"):
        find_dataset(tmp_path / "missing")
    with pytest.raises(DatasetError, match="no Minari dataset"):
        find_dataset(tmp_path)
    collect_dataset(PLANAR, tmp_path, episodes=1, progress=False)
    collect_dataset(PLANAR, tmp_path, episodes=1, dataset_id="redundancy_gym/PlanarReach/other-v0", progress=False)
    with pytest.raises(DatasetError, match="2 datasets"):
        find_dataset(tmp_path)


def test_a_clone_learns_from_the_dataset_alone(planar_dataset, tmp_path, monkeypatch):
    # no expert may run: the dataset is the only source
    monkeypatch.setattr(
        "redundancy_gym.learning.behaviour_cloning.make_policy",
        lambda *a, **k: (_ for _ in ()).throw(AssertionError("an expert was built")),
    )
    summary = train_behaviour_cloning(
        PLANAR, tmp_path / "bc.zip", dataset=planar_dataset.path, epochs=40, progress=False, log=None
    )
    assert summary.rounds == 1 and summary.samples == summary.env_steps == planar_dataset.steps
    demos = load_demonstrations(planar_dataset.path)
    import gymnasium as gym

    env = gym.make(PLANAR)
    monkeypatch.undo()
    clone = redundancy_gym.make_policy(str(summary.path), env)
    predicted, _ = clone.predict(demos.observations, deterministic=True)
    spread = float(np.mean(demos.actions**2))
    # the fit explains most of the actions' variation on the dataset's states
    assert float(np.mean((predicted - demos.actions) ** 2)) < 0.05 * spread


def test_a_dataset_of_another_env_is_refused(planar_dataset, tmp_path):
    with pytest.raises(LearningError, match="collected on redundancy_gym/PlanarReach-v0"):
        train_behaviour_cloning(
            "redundancy_gym/AgriReach-v0", tmp_path / "bc.zip", dataset=planar_dataset.path, progress=False, log=None
        )


def test_the_cli_clones_a_dataset_and_refuses_it_for_ppo(planar_dataset, tmp_path, capsys):
    out = tmp_path / "bc.zip"
    args = ["train", PLANAR, "--algo", "bc", "--dataset", str(planar_dataset.path), "--out", str(out)]
    assert main([*args, "--no-progress"]) == 0 and out.is_file()
    assert "from the dataset" in capsys.readouterr().out
    assert main(["train", PLANAR, "--algo", "ppo", "--steps", "10", "--dataset", str(planar_dataset.path)]) == 2
    assert "--dataset apply to --algo bc only" in capsys.readouterr().err


def test_a_clone_of_a_dataset_fits_on_the_threads_asked_and_records_the_dataset_not_an_expert(
    planar_dataset, tmp_path, monkeypatch
) -> None:
    """torch's default of one thread per core made fitting 12 times slower on a busy 2-core machine; the record of a
    dataset-only clone named an expert and expert episodes it never had."""
    import torch

    from redundancy_gym.learning.training_record import read_training_record

    before = torch.get_num_threads()
    calls: list[int] = []
    real = torch.set_num_threads

    def recording(n: int) -> None:
        calls.append(n)
        real(n)

    monkeypatch.setattr(torch, "set_num_threads", recording)
    summary = train_behaviour_cloning(
        PLANAR, tmp_path / "bc.zip", dataset=planar_dataset.path, epochs=1, progress=False, log=None
    )
    assert calls == [1, before] and torch.get_num_threads() == before  # one thread while fitting, then restored
    record = read_training_record(summary.path)
    assert record is not None
    settings = record.settings
    assert settings["expert"] is None and settings["dagger_episodes"] is None
    assert settings["episodes"] == 2 and settings["torch_threads"] == 1  # the dataset's episodes
    with pytest.raises(LearningError, match="torch_threads must be an int >= 1 or None, got 0"):
        train_behaviour_cloning(PLANAR, tmp_path / "x.zip", dataset=planar_dataset.path, torch_threads=0, log=None)
