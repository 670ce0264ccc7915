import argparse
import json

import gymnasium as gym
import pytest

import redundancy_gym
from redundancy_gym.cli import _parser, main
from redundancy_gym.policies import PolicyError

PLANAR = "redundancy_gym/PlanarReach-v0"
BIPED = "redundancy_gym/BipedWalk-v0"
OBSTACLES = "redundancy_gym/BipedObstacles-v0"
TERRAIN = "redundancy_gym/BipedTerrain-v0"


def test_version(capsys) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(["--version"])
    assert exit_info.value.code == 0
    assert capsys.readouterr().out.strip() == f"redundancy-gym {redundancy_gym.__version__}"


def test_list_shows_every_env_with_its_shapes_and_policies(capsys, monkeypatch) -> None:
    def no_env(*args, **kwargs):
        raise AssertionError("list builds an env")

    with monkeypatch.context() as patch:  # a table of facts builds nothing (seconds, and compiled kernels, saved)
        patch.setattr(gym, "make", no_env)
        assert main(["list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    for env_id in redundancy_gym.ENV_IDS:
        env = gym.make(env_id)
        line = next(line for line in lines if line.startswith(env_id + " "))
        assert str(env.observation_space.shape) in line and str(env.action_space.shape) in line
        assert f" {gym.spec(env_id).max_episode_steps} (" in line and f"{env.unwrapped.dt * 1e3:g} ms" in line
        env.close()
    planar = next(line for line in lines if line.startswith(PLANAR))
    biped = next(line for line in lines if line.startswith(BIPED))
    assert "clik, predictive, global, zero, random, SB3 .zip" in planar and "walking" not in planar
    assert "walking, zero, random, SB3 .zip" in biped and "clik" not in biped


def test_list_json(capsys) -> None:
    assert main(["list", "--json"]) == 0
    rows = {row["id"]: row for row in json.loads(capsys.readouterr().out)}
    assert tuple(rows) == redundancy_gym.ENV_IDS
    assert rows[PLANAR]["observation_shape"] == [20] and rows[PLANAR]["action_shape"] == [4]
    assert rows[PLANAR]["control_period_s"] == pytest.approx(0.01) and rows[PLANAR]["max_episode_steps"] == 250
    assert rows[BIPED]["policies"] == ["walking", "zero", "random", "SB3 .zip"]


def test_policy_on_the_wrong_env_names_the_envs_it_supports(capsys) -> None:
    with pytest.raises(PolicyError, match=f"policy 'walking' supports {BIPED}, {OBSTACLES}, {TERRAIN}; got {PLANAR}"):
        redundancy_gym.make_policy("walking", gym.make(PLANAR))
    with pytest.raises(PolicyError, match=f"policy 'clik' supports {PLANAR}, redundancy_gym/AgriReach-v0; got {BIPED}"):
        redundancy_gym.make_policy("clik", gym.make(BIPED))
    assert main(["eval", PLANAR, "--policy", "walking", "--episodes", "1", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert f"policy 'walking' supports {BIPED}, {OBSTACLES}, {TERRAIN}; got {PLANAR}" in err


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = _parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {"": parser, **action.choices}


@pytest.mark.parametrize("command", list(_subparsers()))
def test_help_shows_defaults_in_plain_text(command: str, capsys) -> None:
    parser = _subparsers()[command]
    with pytest.raises(SystemExit):
        main([*([command] if command else []), "--help"])
    text = capsys.readouterr().out
    assert "``" not in text and ":class:" not in text
    for action in parser._actions:
        if isinstance(action, (argparse._HelpAction, argparse._VersionAction, argparse._SubParsersAction)):
            continue
        assert action.help, f"{command} {action.dest} has no help"
        if action.default not in (None, False):
            assert f"(default: {action.default})" in " ".join(text.split()), f"{command} {action.dest}"


def test_eval_help_shows_episodes_and_seed_defaults(capsys) -> None:
    with pytest.raises(SystemExit):
        main(["eval", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "number of episodes (default: 10)" in text and "(default: 0)" in text


def test_list_shows_the_registry_and_each_envs_wrappers(capsys) -> None:
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    for name in ("clik", "walking", "task_space", "nullspace", "residual"):
        assert any(line.startswith(name + " ") for line in out.splitlines()), name
    assert main(["list", "--json"]) == 0
    rows = {row["id"]: row for row in json.loads(capsys.readouterr().out)}
    assert rows[PLANAR]["wrappers"] == ["task_space", "nullspace", "residual"]
    assert rows[BIPED]["wrappers"] == ["residual", "walking_command"]
    assert rows["redundancy_gym/PlanarReach-Nullspace-v0"]["policies"] == ["zero", "random", "SB3 .zip"]


def test_eval_with_a_wrapper_is_the_wrapped_id(tmp_path, capsys) -> None:
    by_flag, by_id = tmp_path / "flag.json", tmp_path / "id.json"
    assert (
        main(
            [
                "eval",
                PLANAR,
                "--wrapper",
                "nullspace",
                "--wrapper-kwargs",
                '{"objectives": true}',
                "--policy",
                "zero",
                "--episodes",
                "1",
                "--no-progress",
                "--json",
                str(by_flag),
            ]
        )
        == 0
    )
    assert (
        main(
            [
                "eval",
                "redundancy_gym/PlanarReach-Nullspace-v0",
                "--env-kwargs",
                '{"wrapper_kwargs": {"objectives": true}}',
                "--policy",
                "zero",
                "--episodes",
                "1",
                "--no-progress",
                "--json",
                str(by_id),
            ]
        )
        == 0
    )
    flag, direct = json.loads(by_flag.read_text()), json.loads(by_id.read_text())
    assert flag["env"] == "redundancy_gym/PlanarReach-Nullspace-v0" and flag["success_rate"] == 1.0
    assert flag["episode_return"] == direct["episode_return"]
    assert main(["eval", BIPED, "--wrapper", "nullspace", "--policy", "zero", "--no-progress"]) == 2
    assert (
        "no registered 'nullspace' wrapper for redundancy_gym/BipedWalk-v0; its wrappers: residual, "
        "walking_command" in capsys.readouterr().err
    )
    assert main(["eval", PLANAR, "--wrapper", "nulspace", "--policy", "zero", "--no-progress"]) == 2
    assert (
        "unknown wrapper 'nulspace'; valid: task_space, nullspace, residual, walking_command" in capsys.readouterr().err
    )
    assert main(["eval", PLANAR, "--wrapper-kwargs", "{}", "--policy", "zero", "--no-progress"]) == 0
    assert main(["eval", PLANAR, "--wrapper-kwargs", '{"objectives": true}', "--policy", "zero", "--no-progress"]) == 2
    assert "--wrapper-kwargs needs --wrapper" in capsys.readouterr().err
