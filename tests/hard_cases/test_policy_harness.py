"""Hard cases of issue 17, "What was seen" 1 and 2: the reference policies in stable-baselines3's harness.

1. ``evaluate_policy(policy, vec_env)`` passes a batch ``(n_envs, obs_dim)`` and ``episode_start``; every reference
   policy on every env it supports runs there with 1 and 4 envs and gives the success (and, for the deterministic
   policies, the episode) of ``redundancy-gym eval`` on the same seeds; batches give batched actions, and each env
   index keeps its own controller state.
2. A policy reused for another episode without ``episode_start`` acts as a fresh one (it notices the new episode
   from the observation's time).
"""

from __future__ import annotations

from functools import cache
from typing import Any, cast

import gymnasium as gym
import numpy as np
import pytest
from numpy.typing import NDArray

import redundancy_gym
from redundancy_gym.eval.evaluate import EpisodeSummary, evaluate
from redundancy_gym.policies import PolicyError

pytest.importorskip("stable_baselines3")
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402
from stable_baselines3.common.evaluation import evaluate_policy  # noqa: E402

PLANAR = "redundancy_gym/PlanarReach-v0"
AGRI = "redundancy_gym/AgriReach-v0"
BIPED = "redundancy_gym/BipedWalk-v0"
SEED = 3
N_ENVS = 4
PAIRS = (
    [(PLANAR, name) for name in ("zero", "random", "clik", "predictive", "global")]
    + [(AGRI, name) for name in ("zero", "random", "clik", "predictive", "global")]
    + [(BIPED, name) for name in ("zero", "random", "walking")]
)


def _make_policy(name: str, env: Any) -> Any:
    """As ``redundancy-gym eval`` builds it (the random policy seeded with the first episode's seed)."""
    return redundancy_gym.make_policy(name, env, **({"seed": SEED} if name == "random" else {}))


@cache
def _eval_episodes(env_id: str, name: str) -> tuple[EpisodeSummary, ...]:
    """``redundancy-gym eval ENV --policy NAME --episodes 4 --seed SEED``: seeds SEED ... SEED + 3."""
    return tuple(evaluate(env_id, name, episodes=N_ENVS, seed=SEED, progress=False).summaries)


def _short_id(pair: tuple[str, str]) -> str:
    return f"{pair[0].split('/')[1].split('-')[0]}-{pair[1]}"


@pytest.mark.parametrize("n_envs", [1, N_ENVS])
@pytest.mark.parametrize("env_id, name", PAIRS, ids=[_short_id(p) for p in PAIRS])
def test_evaluate_policy_runs_every_reference_policy_like_eval(env_id: str, name: str, n_envs: int) -> None:
    """Was: IndexError (clik), ModelError (walking), InvalidActionError (zero, random) on the batch SB3 passes.

    ``make_vec_env(..., seed=S)`` resets env i with seed S + i, so env i's first episode is eval's episode i.
    """
    venv = make_vec_env(env_id, n_envs=n_envs, seed=SEED)
    try:
        policy = _make_policy(name, venv.envs[0])
        first: dict[int, tuple[bool, int, float]] = {}  # env index -> (is_success, length, return) of its episode

        def record(local: dict[str, Any], _: dict[str, Any]) -> None:
            i, info = local["i"], local["info"]
            if local["done"] and i not in first:
                first[i] = (bool(info["is_success"]), int(info["episode"]["l"]), float(info["episode"]["r"]))

        # per-episode lists with return_episode_rewards (the stub's return type also covers the means)
        rewards, lengths = cast(
            tuple[list[float], list[int]],
            evaluate_policy(
                policy, venv, n_eval_episodes=n_envs, deterministic=True, return_episode_rewards=True, callback=record
            ),
        )
    finally:
        venv.close()
    assert len(rewards) == len(lengths) == n_envs and sorted(first) == list(range(n_envs))
    expected = _eval_episodes(env_id, name)[:n_envs]
    assert [first[i][0] for i in range(n_envs)] == [e.success for e in expected]
    if name == "random":  # eval continues one random stream over its episodes; env i > 0 has its own stream here
        return
    assert [first[i][1] for i in range(n_envs)] == [e.length for e in expected]
    # Monitor rounds the return to 6 decimals; the walking reference re-estimates its ZMP correction per env
    # index here, where eval reuses the first episode's (the starts differ by the reset noise)
    tolerance = 1e-3 if name == "walking" else 1e-5
    np.testing.assert_allclose(
        [first[i][2] for i in range(n_envs)], [e.episode_return for e in expected], rtol=tolerance, atol=tolerance
    )


def test_make_policy_takes_the_dummy_vec_env_that_evaluate_policy_gets() -> None:
    from stable_baselines3.common.vec_env import VecNormalize

    venv = make_vec_env(PLANAR, n_envs=2, seed=SEED)
    try:
        policy = redundancy_gym.make_policy("clik", venv)
        successes: list[bool] = []
        evaluate_policy(
            policy,
            venv,
            n_eval_episodes=2,
            callback=lambda local, _: successes.append(bool(local["info"]["is_success"])) if local["done"] else None,
        )
        assert successes == [True, True]
        with pytest.raises(PolicyError, match="VecEnv VecNormalize"):  # normalized observations are not the env's
            redundancy_gym.make_policy("clik", VecNormalize(venv))
    finally:
        venv.close()


def _rollout(
    env: gym.Env, policy: Any, seed: int, steps: int | None = None
) -> tuple[NDArray[np.float32], dict[str, Any]]:
    """The actions of an episode from ``reset(seed)`` driven by ``predict(obs)`` alone (no ``episode_start``), and
    the last info; ``steps`` ends it early (as a user's ``reset`` mid-episode would)."""
    obs, info = env.reset(seed=seed)
    actions: list[NDArray[np.float32]] = []
    while steps is None or len(actions) < steps:
        action, _ = policy.predict(obs)
        actions.append(action)
        obs, _, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
    return np.asarray(actions), info


@pytest.mark.parametrize(
    "env_id, name, max_steps",
    [
        (PLANAR, "predictive", None),  # was: collides at 0.24 s (kept counting steps of the old episode)
        (PLANAR, "global", None),  # was: misses the line by 0.87 m (followed the old plan's end)
        (BIPED, "walking", 300),  # was: falls at 0.46 s (kept the old walking pattern); 1.2 s show it
    ],
    ids=["planar-predictive", "planar-global", "biped-walking"],
)
def test_a_policy_reused_without_episode_start_acts_as_a_fresh_one(
    env_id: str, name: str, max_steps: int | None
) -> None:
    env = gym.make(env_id, max_episode_steps=max_steps)  # None: the registered limit
    try:
        reused = redundancy_gym.make_policy(name, env)
        _, first = _rollout(env, reused, SEED)
        again, second = _rollout(env, reused, SEED)
        fresh, reference = _rollout(env, redundancy_gym.make_policy(name, env), SEED)
    finally:
        env.close()
    assert again.shape == fresh.shape
    np.testing.assert_array_equal(again, fresh)
    if env_id == BIPED:
        assert not (first["fell"] or second["fell"] or reference["fell"])
    else:
        assert first["is_success"] and second["is_success"] and reference["is_success"]


def test_a_reset_mid_episode_starts_the_policy_afresh() -> None:
    """A user's ``reset`` after 60 steps of another seed: the observation's time goes back to 0."""
    env = gym.make(PLANAR)
    try:
        reused = redundancy_gym.make_policy("predictive", env)
        _rollout(env, reused, SEED + 1, steps=60)
        again, info = _rollout(env, reused, SEED)
        fresh, _ = _rollout(env, redundancy_gym.make_policy("predictive", env), SEED)
    finally:
        env.close()
    np.testing.assert_array_equal(again, fresh)
    assert info["is_success"]


@pytest.mark.parametrize("env_id, name", PAIRS, ids=[_short_id(p) for p in PAIRS])
def test_a_batch_of_observations_gives_a_batch_of_actions(env_id: str, name: str) -> None:
    env = gym.make(env_id)
    try:
        policy = _make_policy(name, env)
        obs = np.stack([env.reset(seed=SEED + k)[0] for k in range(3)])
        action, state = policy.predict(obs[0])
        assert state is None and action.shape == env.action_space.shape and env.action_space.contains(action)
        for batch in (obs, obs[:1], obs.astype(np.float32)):
            actions, state = policy.predict(batch, episode_start=np.ones(len(batch), dtype=bool))
            assert state is None and actions.shape[0] == len(batch) and actions.shape[1:] == env.action_space.shape
            assert all(env.action_space.contains(a) for a in actions)
    finally:
        env.close()


def test_bad_batch_shapes_are_a_clear_error() -> None:
    env = gym.make(PLANAR)
    obs, _ = env.reset(seed=SEED)
    policy = redundancy_gym.make_policy("clik", env)
    for bad in (obs[:-1], np.stack([obs, obs])[:, :-1], obs.reshape(1, 1, -1)):
        with pytest.raises(PolicyError, match=r"\(20,\)"):
            policy.predict(bad)
    with pytest.raises(PolicyError, match="episode_start"):
        policy.predict(np.stack([obs, obs]), episode_start=np.array([True, False, True]))
    env.close()


def _step(env: gym.Env, action: NDArray[np.float32], seed: int) -> tuple[NDArray[np.float64], bool]:
    """A VecEnv's step: the next observation, or after the episode's end the next episode's first one."""
    obs, _, terminated, truncated, _ = env.step(action)
    if terminated or truncated:
        return env.reset(seed=seed)[0], True
    return obs, False


@pytest.mark.parametrize(
    "env_id, name, steps",
    [
        (AGRI, "clik", 120),  # plans a path and a collision model per episode, per scene
        (PLANAR, "predictive", 120),  # receding horizon, warm-started
        (BIPED, "walking", 150),  # walking pattern, stabilizer, IK
    ],
    ids=["agri-clik", "planar-predictive", "biped-walking"],
)
def test_each_env_index_keeps_its_own_controller_state(env_id: str, name: str, steps: int) -> None:
    """Two envs on different seeds in one batch, env 1 reset mid-way on a third seed: the batch policy acts as
    two single policies do."""
    envs = [gym.make(env_id) for _ in range(2)]
    try:
        batched = redundancy_gym.make_policy(name, envs[0])
        singles = [redundancy_gym.make_policy(name, envs[0]) for _ in envs]
        obs = np.stack([env.reset(seed=SEED + 7 * k)[0] for k, env in enumerate(envs)])
        starts = np.ones(2, dtype=bool)
        for t in range(steps):
            actions, _ = batched.predict(obs, episode_start=starts)
            for k, single in enumerate(singles):
                np.testing.assert_array_equal(actions[k], single.predict(obs[k], episode_start=starts[k : k + 1])[0])
            stepped = [_step(env, actions[k], SEED + 20 + k) for k, env in enumerate(envs)]
            obs = np.stack([o for o, _ in stepped])
            starts = np.array([done for _, done in stepped])
            if t == steps // 2:  # env 1 starts a new episode while env 0 goes on
                obs[1] = envs[1].reset(seed=SEED + 30)[0]
                starts[1] = True
    finally:
        for env in envs:
            env.close()
