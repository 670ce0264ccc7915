"""Behaviour cloning with DAgger (tiny budgets, seconds): the saved PPO agent imitates the expert on its states,
loads through make_policy and the CLI; bad options are refused by name."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym
from redundancy_gym.cli import main
from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.learning.behaviour_cloning import train_behaviour_cloning

ENV = "redundancy_gym/PlanarReach-v0"


def _expert_states(n: int = 150) -> tuple[np.ndarray, np.ndarray]:
    env = gym.make(ENV)
    expert = redundancy_gym.make_policy("clik", env)
    obs, _ = env.reset(seed=999)
    observations, actions = [], []
    for k in range(n):
        action, _ = expert.predict(obs, episode_start=np.array([k == 0]))
        observations.append(obs)
        actions.append(action)
        obs, *_ = env.step(action)
    env.close()
    return np.array(observations), np.array(actions)


def test_the_clone_acts_as_the_expert_on_states_it_did_not_see(tmp_path):
    summary = train_behaviour_cloning(
        ENV, tmp_path / "bc.zip", episodes=3, dagger_rounds=1, dagger_episodes=2, epochs=20, progress=False, log=None
    )
    assert summary.path.is_file() and summary.rounds == 2 and len(summary.learner_success) == 1
    assert summary.samples == summary.env_steps  # every state visited is labelled
    env = gym.make(ENV)
    clone = redundancy_gym.make_policy(str(summary.path), env)
    observations, actions = _expert_states()  # a reset seed none of the training episodes used
    cloned = np.array([clone.predict(o)[0] for o in observations])
    error = float(np.mean((cloned - actions) ** 2))
    # an untrained network of the same shape is far off; the clone is close
    untrained = train_behaviour_cloning(
        ENV,
        tmp_path / "untrained.zip",
        episodes=1,
        dagger_rounds=0,
        epochs=1,
        learning_rate=1e-9,
        progress=False,
        log=None,
    )
    raw = redundancy_gym.make_policy(str(untrained.path), env)
    baseline = float(np.mean((np.array([raw.predict(o)[0] for o in observations]) - actions) ** 2))
    assert error < 0.05 * baseline
    env.close()


def test_cli_trains_a_clone_from_a_config(tmp_path, capsys):
    config = tmp_path / "bc.yaml"
    config.write_text(f"{ENV}:\n  episodes: 2\n  dagger_rounds: 0\n  epochs: 2\n  net_arch: [16, 16]\n")
    out = tmp_path / "bc_cli.zip"
    assert main(["train", ENV, "--algo", "bc", "--config", str(config), "--out", str(out), "--no-progress"]) == 0
    assert out.is_file() and "behaviour cloning" in capsys.readouterr().out
    config.write_text(f"{ENV}:\n  episodes: 2\n  depth: 3\n")
    assert main(["train", ENV, "--algo", "bc", "--config", str(config), "--out", str(out), "--no-progress"]) != 0
    assert "depth" in capsys.readouterr().err


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"episodes": 0}, "episodes"),
        ({"dagger_rounds": -1}, "dagger_rounds"),
        ({"learning_rate": 0.0}, "learning_rate"),
    ],
)
def test_bad_options_are_refused_by_name(tmp_path, kwargs, name):
    with pytest.raises(EvalError, match=name):
        train_behaviour_cloning(ENV, tmp_path / "x.zip", progress=False, log=None, **kwargs)
