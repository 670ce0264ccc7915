import json

import pytest

from redundancy_gym.cli import main
from redundancy_gym.eval import EvalError, evaluate, format_report

ENV_ID = "redundancy_gym/PlanarReach-v0"
CONTRACT = {"env", "policy", "episodes", "success_rate", "collision_rate", "task_error_rms", "task_error_max",
            "pseudoenergy", "peak_joint_speed", "min_clearance", "step_time_us", "episode_return"}


def test_json_contract_and_clik_success() -> None:
    report = evaluate(ENV_ID, "clik", episodes=3, seed=0, env_kwargs={"obstacle": False}, progress=False)
    data = report.to_json()
    assert CONTRACT <= set(data)
    assert set(data["step_time_us"]) >= {"median", "p99"}
    assert data["step_time_us"]["median"] > 0 and data["step_time_us"]["p99"] >= data["step_time_us"]["median"]
    assert data["success_rate"] == 1.0 and data["collision_rate"] == 0.0
    assert data["task_error_max"] <= 1e-3 and data["task_error_rms"] <= data["task_error_max"]
    assert data["min_clearance"] is None  # no obstacle: null, never inf in JSON
    assert data["pseudoenergy"] > 0 and data["peak_joint_speed"] > 0
    assert [e["seed"] for e in data["per_episode"]] == [0, 1, 2]
    json.dumps(data, allow_nan=False)
    assert "success rate" in format_report(data)


def test_zero_policy_fails_and_collision_is_counted() -> None:
    data = evaluate(ENV_ID, "zero", episodes=2, seed=0, progress=False).to_json()
    assert data["success_rate"] == 0.0 and data["task_error_max"] > 0.1
    blocked = evaluate(ENV_ID, "clik", episodes=2, seed=0, progress=False,
                       env_kwargs={"obstacle_center": (0.9, 0.2), "obstacle_radius": 0.05}).to_json()
    assert blocked["collision_rate"] == 1.0 and blocked["min_clearance"] <= 0.0


def test_cli_eval_writes_json(tmp_path, capsys) -> None:
    out = tmp_path / "report.json"
    code = main(["eval", ENV_ID, "--policy", "clik", "--episodes", "2", "--seed", "5", "--no-progress",
                 "--env-kwargs", '{"obstacle": false}', "--json", str(out)])
    assert code == 0
    data = json.loads(out.read_text())
    assert CONTRACT <= set(data) and data["episodes"] == 2 and data["env_kwargs"] == {"obstacle": False}
    assert "success rate" in capsys.readouterr().out


def test_cli_errors_are_clear(capsys) -> None:
    assert main(["eval", "redundancy_gym/Nope-v0", "--policy", "clik", "--no-progress"]) == 2
    assert "PlanarReach-v0" in capsys.readouterr().err
    assert main(["eval", ENV_ID, "--policy", "nope", "--no-progress"]) == 2
    assert "clik, walking, predictive, global, zero, random" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["eval", ENV_ID, "--policy", "clik", "--env-kwargs", "[1, 2]"])


def test_episode_count_validated() -> None:
    with pytest.raises(EvalError):
        evaluate(ENV_ID, "zero", episodes=0)
