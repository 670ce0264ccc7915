"""The learned baselines shipped in baselines/models/: each loads by its short name on its env and reproduces the
first episodes of its recorded evaluation (baselines/results/, held-out seeds 20000-20019) exactly."""

from __future__ import annotations

import json

import gymnasium as gym
import pytest

import redundancy_gym
from redundancy_gym.eval.evaluate import evaluate
from redundancy_gym.policies import PolicyError
from redundancy_gym.policies.shipped_models import (
    SHIPPED_MODELS_DIR,
    env_slug,
    is_shipped_name,
    shipped_models,
)

RESULTS = SHIPPED_MODELS_DIR.parent / "results"
_WRAPPERS = {"nullspace": "Nullspace", "task_space": "TaskSpace", "residual": "Residual",
             "walking_command": "WalkingCommand"}


def _env_id(stem: str) -> tuple[str, str]:
    """``(env id, short name)`` of a model file stem ``<learner>-<action>-<env>``."""
    learner, action, slug = stem.split("-", 2)
    for env_id in redundancy_gym.ENV_IDS:
        env = gym.make(env_id)
        matches = env_slug(env) == slug
        env.close()
        if matches:
            base = env_id.removesuffix("-v0")
            return (env_id if action == "joint" else f"{base}-{_WRAPPERS[action]}-v0"), f"{learner}-{action}"
    raise AssertionError(f"no env for {stem}")


def test_every_env_the_baselines_cover_has_its_shipped_models():
    # the rows so far: PlanarReach (with the obstacle) by PPO on the nullspace and the raw action, and
    # behaviour cloning from the clik reference
    assert {"ppo-nullspace-planar_reach", "ppo-joint-planar_reach", "bc-joint-planar_reach"} <= set(shipped_models())


@pytest.mark.parametrize("stem", shipped_models())
def test_a_shipped_model_reproduces_its_recorded_evaluation(stem):
    env_id, short = _env_id(stem)
    recorded = json.loads((RESULTS / f"{stem}.json").read_text())
    assert recorded["env"] == env_id and recorded["seed"] == 20000
    report = evaluate(env_id, short, episodes=3, seed=20000, progress=False).to_json()
    for got, want in zip(report["per_episode"], recorded["per_episode"][:3], strict=True):
        assert got["seed"] == want["seed"]
        assert got["success"] == want["success"] and got["collision"] == want["collision"]
        # deterministic on one machine; another CPU may round the network differently in the last digits
        assert got["return"] == pytest.approx(want["return"], rel=1e-3, abs=1e-3)


def test_short_names_resolve_per_env_and_name_what_is_shipped():
    assert is_shipped_name("ppo-nullspace") and is_shipped_name("bc-joint") and not is_shipped_name("ppo-nope")
    env = gym.make("redundancy_gym/AgriReach-v0")
    assert env_slug(env) == "agri_reach"
    with pytest.raises(PolicyError, match="shipped: .*bc-joint-planar_reach"):
        redundancy_gym.make_policy("sac-joint", env)
    env.close()
