import json
from pathlib import Path

from redundancy_gym.cli import main
from redundancy_gym.eval.training import load_hyperparameters

ENV_ID = "redundancy_gym/PlanarReach-v0"
CONFIGS = Path(__file__).resolve().parents[2] / "configs"


def test_ppo_smoke_training_then_eval_loads_zip(tmp_path) -> None:
    zip_path = tmp_path / "ppo_planar.zip"
    config = tmp_path / "ppo.yaml"
    hyper = load_hyperparameters(CONFIGS / "ppo_planar_reach.yaml")
    hyper.update(n_steps=128, batch_size=64)  # a few hundred steps: a smoke test, not a result
    config.write_text("\n".join(f"{k}: {v}" for k, v in hyper.items()))
    assert main(["train", ENV_ID, "--algo", "ppo", "--steps", "256", "--out", str(zip_path), "--config",
                 str(config), "--no-progress"]) == 0
    assert zip_path.is_file()
    report = tmp_path / "ppo_eval.json"
    assert main(["eval", ENV_ID, "--policy", str(zip_path), "--episodes", "1", "--no-progress", "--json",
                 str(report)]) == 0
    data = json.loads(report.read_text())
    assert data["policy"] == str(zip_path) and data["episodes"] == 1 and data["step_time_us"]["median"] > 0
