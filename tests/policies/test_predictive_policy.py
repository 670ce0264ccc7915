"""The ``predictive`` and ``global`` policies on PlanarReach and AgriReach: whole episodes, the receding
horizon's warm start and continuity, bad options."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401  (registers the env ids)
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.predictive.receding_horizon import RecedingHorizon
from redundancy_gym.eval.evaluate import evaluate
from redundancy_gym.policies import PolicyError, make_policy
from redundancy_gym.policies.predictive_policy import TASK_DEFAULTS, PredictivePolicyConfig

PLANAR = "redundancy_gym/PlanarReach-v0"
AGRI = "redundancy_gym/AgriReach-v0"


def test_planar_predictive_and_global_succeed_with_less_pseudoenergy_than_local_clik() -> None:
    """Fig. 5.31 on the default obstacle scene, two episodes: global <= predictive(1 s) < local CLIK."""
    reports = {
        name: evaluate(PLANAR, name, episodes=2, seed=0, progress=False).to_json()
        for name in ("clik", "predictive", "global")
    }
    for report in reports.values():
        assert report["success_rate"] == 1.0 and report["collision_rate"] == 0.0
    energy = {name: r["pseudoenergy"] for name, r in reports.items()}
    assert energy["global"] <= energy["predictive"] * 1.01
    assert energy["predictive"] < 0.9 * energy["clik"]


def test_agri_predictive_runs_a_grasp_episode() -> None:
    report = evaluate(
        AGRI,
        "predictive",
        episodes=1,
        seed=0,
        env_kwargs={"difficulty": "medium"},
        policy_kwargs={"horizon": 0.15},
        progress=False,
    ).to_json()
    assert report["success_rate"] == 1.0 and report["collision_rate"] == 0.0


def test_augmented_horizon_applies_the_input_it_planned_one_step_earlier() -> None:
    """(5.127): the input applied now is the one the previous update planned for now, so the nullspace
    velocity does not jump when the horizon moves; the velocity-level horizon re-plans it freely."""
    env = gym.make(PLANAR)
    obs, _ = env.reset(seed=0)
    for augmented in (True, False):
        policy = make_policy("predictive", env, augmented=augmented)
        obs, _ = env.reset(seed=0)
        planned, gaps = None, []
        for k in range(60):
            action, _ = policy.predict(obs, episode_start=np.array([k == 0]))
            update = policy.last_update
            assert update is not None
            if planned is not None:
                gaps.append(float(np.max(np.abs(update.u - planned))))
            planned = update.result.rollout.u[1].copy()
            obs, *_ = env.step(action)
        if augmented:
            assert max(gaps) < 1e-12
        else:
            assert max(gaps) > 1e-6
    env.close()


def test_predictive_options_are_checked() -> None:
    env = gym.make(PLANAR)
    with pytest.raises(PolicyError, match="descent"):
        make_policy("predictive", env, descent="newton")
    with pytest.raises(PolicyError, match="horizon"):
        make_policy("predictive", env, horizon=0.0)
    with pytest.raises(PolicyError, match="valid"):
        make_policy("global", env, horizon_steps=3)
    with pytest.raises(PolicyError, match="reference"):
        make_policy("predictive", gym.make("redundancy_gym/BipedWalk-v0"))
    policy = make_policy("predictive", env)
    with pytest.raises(ControllerError, match="steps"):
        RecedingHorizon(policy.pik if policy.pik is not None else policy.problem(), 0, 0.01)
    obs, _ = env.reset(seed=0)
    policy.start(obs)
    assert policy.horizon is not None
    with pytest.raises(ControllerError, match="update"):
        policy.horizon.input_at(0.0)
    policy.predict(obs)
    with pytest.raises(ControllerError, match="elapsed"):
        policy.horizon.input_at(2.0 * policy.dt)
    env.close()


def test_a_sample_time_of_several_control_periods_replans_once_per_sample() -> None:
    """``sample_time`` = 5 control periods: one update per 5 steps; between updates the velocity-level input is
    held (a staircase) and the augmented input moves linearly onto the next update's start (continuous)."""
    env = gym.make(PLANAR)
    for augmented in (False, True):
        policy = make_policy("predictive", env, augmented=augmented, sample_time=0.05)
        assert policy.substeps == 5 and policy.dt == pytest.approx(0.05)
        obs, _ = env.reset(seed=0)
        updates, inputs = [], []
        for k in range(30):
            action, _ = policy.predict(obs, episode_start=np.array([k == 0]))
            assert policy.horizon is not None and policy.horizon.last is not None
            updates.append(policy.horizon.last)
            inputs.append(policy.horizon.input_at((k % 5) * policy.control_dt))
            obs, *_ = env.step(action)
        assert len({id(u) for u in updates}) == 6
        for first in range(0, 30, 5):
            within = np.array(inputs[first : first + 5])
            if augmented:
                rate = updates[first].result.params[0]
                assert np.allclose(np.diff(within, axis=0), policy.control_dt * rate, atol=1e-12)
                if first + 5 < 30:  # the sample's end is the next update's start
                    end = policy.horizon.pik.inputs(updates[first].result.params, policy.dt, within[0])[1]
                    assert np.allclose(inputs[first + 5], end, atol=1e-12)
            else:
                assert np.all(within == within[0])
    with pytest.raises(PolicyError, match="multiple"):
        make_policy("predictive", env, sample_time=0.015)
    env.close()


def test_task_defaults_fill_only_what_is_unset() -> None:
    config = PredictivePolicyConfig(collision_weight=7.0)
    grasp = config.for_task("grasp")
    assert grasp.collision_weight == 7.0
    assert grasp.collision_activation == TASK_DEFAULTS["grasp"]["collision_activation"]
    assert config.for_task("planar").collision_activation is None  # the clik reference's shape
    with pytest.raises(PolicyError, match="planar"):
        config.for_task("biped")
    env = gym.make(AGRI)
    policy = make_policy("predictive", env)
    assert policy.config.collision_slope == TASK_DEFAULTS["grasp"]["collision_slope"]
    obs, _ = env.reset(seed=0)
    policy.start(obs)  # the collision model comes with the episode's plants
    assert policy.pik is not None and policy.pik.collision is not None
    assert policy.pik.collision.weight == TASK_DEFAULTS["grasp"]["collision_weight"]
    assert policy.pik.collision.potential.activation_distance == TASK_DEFAULTS["grasp"]["collision_activation"]
    env.close()
