"""baselines/*.yaml: every file names a model, its learner, action and env consistently; a baseline trains into a
models directory with its record (a smoke budget: the shipped models use the files' budgets)."""

import gymnasium as gym
import pytest

from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.learning.baselines import BASELINES_DIR, baselines, train_baseline
from redundancy_gym.learning.training_record import read_training_record
from redundancy_gym.policies.shipped_models import env_slug
from redundancy_gym.registration import BASE_ENV_IDS, WRAPPED_ENV_IDS, wrapped_env_id

ALL = baselines()


def test_every_file_is_a_baseline_and_the_table_has_its_rows() -> None:
    names = {b.name for b in ALL}
    for env in ("planar_reach", "agri_reach"):  # the arms: raw joints, both arm wrappers, residual, cloning
        assert {
            f"ppo-joint-{env}",
            f"ppo-nullspace-{env}",
            f"ppo-task_space-{env}",
            f"ppo-residual-{env}",
            f"bc-joint-{env}",
        } <= names
    assert {
        "ppo-joint-biped_walk",
        "ppo-walking_command-biped_walk",
        "ppo-residual-biped_walk",
        "bc-joint-biped_walk",
        "ppo-joint-biped_obstacles",
        "bc-joint-biped_obstacles",
    } <= names


@pytest.mark.parametrize("baseline", ALL, ids=lambda b: b.name)
def test_name_action_and_env_agree(baseline) -> None:
    slug = baseline.slug
    if baseline.action == "joint":
        assert baseline.env_id in BASE_ENV_IDS
        base = baseline.env_id
    else:
        assert baseline.env_id in WRAPPED_ENV_IDS
        base = next(b for b in BASE_ENV_IDS if wrapped_env_id(b, baseline.action) == baseline.env_id)
    env = gym.make(base)
    try:
        assert env_slug(env) == slug
    finally:
        env.close()
    variant = "" if baseline.variant is None else f"-{baseline.variant}"
    assert baseline.name == f"{baseline.learner}-{baseline.action}-{slug}{variant}"
    assert baseline.short_name == f"{baseline.learner}-{baseline.action}{variant}"
    assert baseline.model.parent.parent == BASELINES_DIR
    # a model trained under dynamics randomization says so in its name, and its nominal twin is shipped too
    assert ("dynamics" in baseline.env_kwargs) == (baseline.variant == "dynamics")
    if baseline.variant is not None:
        assert f"{baseline.learner}-{baseline.action}-{slug}" in {b.name for b in ALL}


def test_unknown_names_and_bad_files_are_named(tmp_path) -> None:
    with pytest.raises(EvalError, match="no baseline ppo-nope-x .*ppo-joint-planar_reach"):
        baselines(["ppo-nope-x"])
    (tmp_path / "ppo-fly-planar_reach.yaml").write_text("redundancy_gym/PlanarReach-v0: {}\n")
    with pytest.raises(EvalError, match="learner in ppo, sac, bc, action in joint.* and variant in dynamics"):
        baselines(directory=tmp_path)
    (tmp_path / "ppo-fly-planar_reach.yaml").unlink()
    (tmp_path / "ppo-joint-planar_reach-windy.yaml").write_text("redundancy_gym/PlanarReach-v0: {}\n")
    with pytest.raises(EvalError, match="variant in dynamics"):
        baselines(directory=tmp_path)
    (tmp_path / "ppo-joint-planar_reach-windy.yaml").unlink()
    (tmp_path / "ppo-joint-planar_reach.yaml").write_text("redundancy_gym/Nope-v0: {}\n")
    with pytest.raises(EvalError, match="keyed by a registered env id"):
        baselines(directory=tmp_path)


def test_a_baseline_trains_into_a_models_directory_with_its_record(tmp_path) -> None:
    (baseline,) = baselines(["ppo-residual-planar_reach"])
    path = train_baseline(
        baseline, work_dir=tmp_path / "work", tensorboard_log=None, models_dir=tmp_path / "models", steps=1, log=None
    )
    assert path == tmp_path / "models" / "ppo-residual-planar_reach.zip" and path.is_file()
    record = read_training_record(path)
    # one whole rollout of n_steps x n_envs (2048 x 4): PPO never stops inside one
    assert record is not None and record.env_steps == 8192 and record.env_id == baseline.env_id
    assert record.result["kept"] == "best"
    assert (tmp_path / "work" / "ppo-residual-planar_reach_last.zip").is_file()


@pytest.mark.parametrize("folder", ["empty", "missing"])
def test_listing_no_baselines_names_the_folder_and_fails(tmp_path, monkeypatch, capsys, folder) -> None:
    from redundancy_gym.cli import main

    where = tmp_path / folder
    if folder == "empty":
        where.mkdir()
    monkeypatch.setattr("redundancy_gym.learning.baselines.BASELINES_DIR", where)
    assert main(["baselines", "--list"]) == 2
    err = capsys.readouterr().err
    assert f"no baselines found: {where}" in err
    assert ("does not exist" if folder == "missing" else "holds no baseline file") in err


def test_listing_says_where_it_looked(capsys) -> None:
    from redundancy_gym.cli import main

    assert main(["baselines", "--list"]) == 0
    assert f"baseline(s) in {BASELINES_DIR}:" in capsys.readouterr().out.splitlines()[0]
    assert main(["list"]) == 0
    assert capsys.readouterr().out.rstrip().endswith(f"shipped model(s) in {BASELINES_DIR / 'models'}")
