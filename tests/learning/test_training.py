import json
import math
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
import yaml

from redundancy_gym.cli import main
from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.learning.training import LinearSchedule, load_config, load_hyperparameters, train
from redundancy_gym.learning.training_record import read_training_record

ENV_ID = "redundancy_gym/PlanarReach-v0"
ROOT = Path(__file__).resolve().parents[2]
# the SB3 learners' configs (rl-zoo3 reads them); bc_*.yaml hold behaviour cloning's options (test below)
CONFIGS = sorted(p for p in (ROOT / "configs").glob("*_*.yaml") if p.name.split("_")[0] in ("ppo", "sac"))


def _smoke_config(tmp_path: Path, **overrides) -> Path:
    """configs/ppo_planar_reach.yaml, shortened to a smoke run (a few hundred steps: a test, not a result)."""
    data = yaml.safe_load((ROOT / "configs" / "ppo_planar_reach.yaml").read_text())
    data[ENV_ID].update(overrides)
    path = tmp_path / "ppo.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


def test_ppo_smoke_training_on_two_envs_prints_statistics_then_eval_loads_zip(tmp_path, capsys) -> None:
    """--steps and --n-envs default to the config's n_timesteps and n_envs; the run prints episode statistics."""
    zip_path = tmp_path / "ppo_planar.zip"
    config = _smoke_config(tmp_path, n_timesteps=512, n_envs=2, n_steps=128, batch_size=64, n_epochs=2)
    assert (
        main(
            [
                "train",
                ENV_ID,
                "--algo",
                "ppo",
                "--out",
                str(zip_path),
                "--config",
                str(config),
                "--no-progress",
                "--print-every",
                "256",
                "--tensorboard",
                str(tmp_path / "tb"),
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "512 steps, 2 env(s)" in out
    lines = out.splitlines()
    assert any(line.startswith("step 256/512") and "no episode finished yet" in line for line in lines)
    # PlanarReach episodes last 250 steps: each of the two envs has finished one by step 512
    assert any(
        line.startswith("step 512/512")
        and "episodes     2" in line
        and "success 0%" in line
        and "length 250" in line
        and "return -" in line
        for line in lines
    )
    summary = next(line for line in lines if line.startswith("trained 512 steps"))
    assert "2 episodes; last 2: return" in summary and "success" in summary and "length 250" in summary
    assert zip_path.is_file() and any((tmp_path / "tb").iterdir())
    report = tmp_path / "ppo_eval.json"
    assert (
        main(["eval", ENV_ID, "--policy", str(zip_path), "--episodes", "1", "--no-progress", "--json", str(report)])
        == 0
    )
    data = json.loads(report.read_text())
    assert data["policy"] == str(zip_path) and data["episodes"] == 1 and data["step_time_us"]["median"] > 0


def test_train_needs_steps_without_n_timesteps(tmp_path, capsys) -> None:
    assert main(["train", ENV_ID, "--out", str(tmp_path / "x.zip"), "--no-progress"]) == 2
    assert "--steps" in capsys.readouterr().err


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.name)
def test_configs_load_as_rl_zoo3_reads_them(path: Path) -> None:
    """rl-zoo3 (ExperimentManager.read_hyperparameters): yaml.safe_load, then the env id's section; its own keys
    (policy, n_timesteps, n_envs, normalize) are popped and the rest goes to the SB3 constructor."""
    import stable_baselines3 as sb3
    from stable_baselines3.common.env_util import make_vec_env

    import redundancy_gym

    data = yaml.safe_load(path.read_text())
    assert set(data) <= set(redundancy_gym.ENV_IDS), "sections are keyed by registered env ids"
    algo = path.name.split("_")[0].upper()
    for env_id, section in data.items():
        assert section["policy"] == "MlpPolicy" and float(section["n_timesteps"]) >= 1 and section["n_envs"] >= 1
        config = load_config(path, env_id)
        assert config.n_timesteps == int(float(section["n_timesteps"])) and config.n_envs == section["n_envs"]
        hyper = load_hyperparameters(path, env_id)
        assert not {"policy", "n_timesteps", "n_envs", "normalize"} & set(hyper)
        env = make_vec_env(env_id, n_envs=1)
        try:
            getattr(sb3, algo)(config.policy, env, device="cpu", **hyper)  # every key is a constructor argument
        finally:
            env.close()


def test_load_config_reads_rl_zoo3_conventions(tmp_path) -> None:
    path = tmp_path / "c.yaml"
    path.write_text(
        "default:\n  policy: MlpPolicy\n  n_timesteps: !!float 2e4\n  learning_rate: lin_1e-3\n"
        '  train_freq: [1, episode]\n  policy_kwargs: "dict(net_arch=[64, 64], activation_fn=nn.Tanh)"\n'
        "  env_kwargs: {obstacle: false}\n"
    )
    config = load_config(path, ENV_ID)  # no section for the env: 'default', as rl-zoo3
    assert config.n_timesteps == 20000 and config.n_envs is None and config.env_kwargs == {"obstacle": False}
    lr = config.hyperparameters["learning_rate"]
    assert isinstance(lr, LinearSchedule) and lr(1.0) == pytest.approx(1e-3) and lr(0.5) == pytest.approx(5e-4)
    assert config.hyperparameters["train_freq"] == (1, "episode")
    assert config.hyperparameters["policy_kwargs"]["net_arch"] == [64, 64]


@pytest.mark.parametrize(
    "text, match",
    [
        ("other/Env-v0:\n  n_timesteps: 1\n", "no section for redundancy_gym/PlanarReach-v0"),
        (f"{ENV_ID}:\n  normalize: true\n", "normalize not supported"),
        (f"{ENV_ID}:\n  env_wrapper: x.Y\n", "env_wrapper not supported"),
        (f"{ENV_ID}:\n  learning_rate: exp_1e-3\n", "lin_"),
        ("n_steps: 64\n", "put its keys under .redundancy_gym/PlanarReach-v0:"),
    ],
)
def test_load_config_errors(tmp_path, text: str, match: str) -> None:
    path = tmp_path / "c.yaml"
    path.write_text(text)
    with pytest.raises(EvalError, match=match):
        load_config(path, ENV_ID)


def test_rl_zoo3_trains_on_our_config(tmp_path) -> None:
    """python -m rl_zoo3.train reads configs/ppo_planar_reach.yaml (n_steps cut to 256 with -params: one short
    rollout and update), and the model it saves is evaluated by redundancy-gym eval."""
    pytest.importorskip("rl_zoo3")
    env = {**os.environ, "MUJOCO_GL": "osmesa", "OMP_NUM_THREADS": "1"}
    command = [
        sys.executable,
        "-m",
        "rl_zoo3.train",
        "--algo",
        "ppo",
        "--env",
        ENV_ID,
        "--gym-packages",
        "redundancy_gym",
        "-conf",
        str(ROOT / "configs" / "ppo_planar_reach.yaml"),
        "-n",
        "256",
        "--seed",
        "0",
        "--device",
        "cpu",
        "-f",
        str(tmp_path / "logs"),
        "-params",
        "n_steps:256",
    ]
    result = subprocess.run(command, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-3000:]
    models = list((tmp_path / "logs" / "ppo").glob("*/redundancy_gym-PlanarReach-v0.zip"))
    assert len(models) == 1
    assert main(["eval", ENV_ID, "--policy", str(models[0]), "--episodes", "1", "--no-progress"]) == 0


def test_eval_callback_checkpoints_keep_best_and_the_training_record(tmp_path, capsys, monkeypatch) -> None:
    """--eval-freq evaluates on seeds apart from training, --checkpoint-freq saves along the way, --keep best ships
    the evaluation's best agent (the last goes beside it), and the record beside the .zip states steps and cost;
    without --tensorboard-log no SB3-<date> folder is left in the temporary folder (SB3's default logger)."""
    temporary = tmp_path / "tmp"
    temporary.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    monkeypatch.delenv("SB3_LOGDIR", raising=False)  # the session sets it (conftest); SB3 would write there instead
    zip_path = tmp_path / "m.zip"
    config = _smoke_config(tmp_path, n_timesteps=1024, n_envs=2, n_steps=128, batch_size=64, n_epochs=1)
    assert (
        main(
            [
                "train",
                ENV_ID,
                "--out",
                str(zip_path),
                "--config",
                str(config),
                "--no-progress",
                "--eval-freq",
                "512",
                "--eval-episodes",
                "1",
                "--checkpoint-freq",
                "512",
                "--keep",
                "best",
            ]
        )
        == 0
    )
    assert zip_path.is_file() and (tmp_path / "m_last.zip").is_file()
    assert sorted(p.name for p in (tmp_path / "m_checkpoints").iterdir()) == ["ppo_1024_steps.zip", "ppo_512_steps.zip"]
    record = read_training_record(zip_path)
    assert record is not None and record.learner == "ppo" and record.env_id == ENV_ID
    assert record.env_steps == 1024 and record.seed == 0
    assert 0.0 < record.cpu_s and 0.0 < record.wall_s
    assert record.result["kept"] == "best" and record.result["eval_seed"] == 30000
    # one PlanarReach episode of 250 steps; a return is a finite sum of per-step rewards
    assert math.isfinite(record.result["best_eval_return"])
    assert record.settings["hyperparameters"]["n_steps"] == 128 and record.machine["cores"] >= 1
    assert not list(temporary.glob("SB3-*"))


def test_keep_best_needs_the_eval_callback(tmp_path, capsys) -> None:
    config = _smoke_config(tmp_path, n_timesteps=256, n_envs=1, n_steps=128)
    assert (
        main(
            [
                "train",
                ENV_ID,
                "--out",
                str(tmp_path / "x.zip"),
                "--config",
                str(config),
                "--no-progress",
                "--keep",
                "best",
            ]
        )
        == 2
    )
    assert "eval_freq" in capsys.readouterr().err
    with pytest.raises(EvalError, match="eval_freq must be an int >= 1"):
        train(ENV_ID, "ppo", 128, tmp_path / "y.zip", eval_freq=0)


def test_train_on_async_envs_gives_the_sync_agent(tmp_path) -> None:
    """--vec async (SB3's SubprocVecEnv, one process per env) trains the agent --vec sync does: same seeds, same
    rollouts, same network."""
    import numpy as np
    from stable_baselines3 import PPO

    hyper = {"n_steps": 64, "batch_size": 64, "n_epochs": 1}
    paths = []
    for vec in ("sync", "async"):
        paths.append(
            train(
                ENV_ID,
                "ppo",
                128,
                tmp_path / f"{vec}.zip",
                n_envs=2,
                vec_env=vec,
                hyperparameters=hyper,
                progress_bar=False,
                log=None,
            )
        )
    a, b = (PPO.load(p, device="cpu") for p in paths)
    for x, y in zip(a.policy.parameters(), b.policy.parameters(), strict=True):
        np.testing.assert_array_equal(x.detach().numpy(), y.detach().numpy())


def test_behaviour_cloning_configs_hold_its_options() -> None:
    import inspect

    from redundancy_gym.learning.behaviour_cloning import train_behaviour_cloning

    options = set(inspect.signature(train_behaviour_cloning).parameters)
    paths = sorted((ROOT / "configs").glob("bc_*.yaml"))
    assert paths
    for path in paths:
        for env_id, section in yaml.safe_load(path.read_text()).items():
            assert set(section) <= options, (path.name, env_id)
            assert load_config(path, env_id).hyperparameters == section
