"""The fast path of SB3 policies (redundancy_gym.policies.mlp_inference, built by sb3_policy's
mlp_inference_from_sb3): every shipped model acts as SB3's
deterministic predict on 1000 observations of its own seeded rollout, to 1e-6 or, where torch's float32 arithmetic is
further than that from the network's exact value, to within torch's own error (the fast path is within 1e-7 of the
exact value); PPO, A2C, SAC and TD3 with other bounds and activations too; what is no plain MLP keeps SB3's predict
and says why; an evaluation reports both times."""

from __future__ import annotations

import copy
import logging
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import pytest
from gymnasium import spaces
from numpy.typing import NDArray

import redundancy_gym  # noqa: F401  (registers the ids)
from redundancy_gym.eval.evaluate import evaluate, format_report
from redundancy_gym.eval.speed_error import speed_error_markdown
from redundancy_gym.learning.baselines import Baseline, baselines
from redundancy_gym.policies import PolicyError, make_policy
from redundancy_gym.policies.mlp_inference import MlpInference, tanh64
from redundancy_gym.policies.sb3_policy import Sb3Policy, mlp_inference_from_sb3

sb3 = pytest.importorskip("stable_baselines3")
torch = pytest.importorskip("torch")

OBSERVATIONS = 1000
SHIPPED = [b for b in baselines() if b.model.is_file()]


def _rollout(env: gym.Env, policy: Sb3Policy, steps: int) -> tuple[NDArray[np.float64], NDArray[np.floating]]:
    """``steps`` observations of episodes from seeds 0, 1, ... driven by SB3's deterministic predict, with its
    actions."""
    observations: list[NDArray[np.float64]] = []
    actions: list[NDArray[np.floating]] = []
    episode = 0
    obs, _ = env.reset(seed=episode)
    while len(observations) < steps:
        action, _ = policy.sb3_predict(obs, deterministic=True)
        observations.append(obs)
        actions.append(action)
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            episode += 1
            obs, _ = env.reset(seed=episode)
    return np.asarray(observations), np.asarray(actions)


def _exact(model: Any, observations: NDArray[np.floating]) -> NDArray[np.float64]:
    """SB3's deterministic actions with its own modules in float64 on the float32-rounded observations: the
    network's value without torch's float32 rounding (SB3's preprocessing would cast back to float32)."""
    policy = copy.deepcopy(model.policy).double()
    obs = torch.as_tensor(np.asarray(observations, dtype=np.float32).astype(np.float64))
    with torch.no_grad():
        if hasattr(policy, "mlp_extractor"):  # PPO, A2C
            raw = policy.action_net(policy.mlp_extractor.forward_actor(policy.pi_features_extractor(obs)))
        elif hasattr(policy.actor, "latent_pi"):  # SAC: the squashed Gaussian's mode
            actor = policy.actor
            raw = torch.tanh(actor.mu(actor.latent_pi(actor.features_extractor(obs))))
        else:  # TD3
            raw = policy.actor.mu(policy.actor.features_extractor(obs))
    actions = raw.numpy().reshape((-1, *model.action_space.shape))
    if policy.squash_output:
        return np.asarray(policy.unscale_action(actions), dtype=np.float64)
    return np.clip(actions, model.action_space.low, model.action_space.high)


@pytest.mark.parametrize("baseline", SHIPPED, ids=lambda b: b.name)
def test_a_shipped_model_on_the_fast_path_acts_as_sb3_predict(baseline: Baseline) -> None:
    env = gym.make(baseline.env_id, **baseline.env_kwargs)
    try:
        policy = Sb3Policy(baseline.model, env)
        assert policy.fast_path, policy.fast_path_reason
        assert "MLP" in policy.fast_path_reason
        observations, sb3_actions = _rollout(env, policy, OBSERVATIONS)
    finally:
        env.close()
    fast = np.stack([policy.predict(obs, deterministic=True)[0] for obs in observations])
    assert fast.dtype == sb3_actions.dtype and fast.shape == sb3_actions.shape
    exact = _exact(policy.model, observations)
    off_exact = float(np.abs(fast - exact).max())
    torch_error = float(np.abs(sb3_actions - exact).max())
    difference = float(np.abs(fast - sb3_actions).max())
    assert off_exact <= 1e-7, f"the fast path is {off_exact:.2e} from the network's exact value"
    # torch rounds each partial sum to float32: where that puts SB3 further than 1e-6 from the exact value (up to
    # 1.4e-5 on BipedObstacles, whose observations reach 2000), the difference is torch's own
    assert difference <= max(1e-6, torch_error + 1e-7), (difference, torch_error)
    # a batch is the same computation, row by row
    batch, state = policy.predict(observations, state=None, deterministic=True)
    assert state is None and np.array_equal(batch, fast)


class _DictEnv(gym.Env[dict[str, Any], NDArray[np.float32]]):
    """Two Box observations in a Dict: SB3's MultiInputPolicy, no plain MLP input."""

    observation_space = spaces.Dict(
        {"a": spaces.Box(-1.0, 1.0, (2,), np.float32), "b": spaces.Box(-1.0, 1.0, (3,), np.float32)}
    )
    action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[Any, dict[str, Any]]:
        super().reset(seed=seed)
        return self.observation_space.sample(), {}

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        return self.observation_space.sample(), 0.0, False, False, {}


def _pendulum_observations(n: int) -> NDArray[np.float32]:
    return np.random.default_rng(1).normal(scale=3.0, size=(n, 3)).astype(np.float32)


@pytest.mark.parametrize(
    "algo, kwargs",
    [
        ("PPO", {"policy_kwargs": {"net_arch": [16, 16], "activation_fn": "ReLU"}}),
        ("A2C", {"policy_kwargs": {"net_arch": [8]}}),
        ("PPO", {"policy_kwargs": {"net_arch": []}}),  # action_net alone
        ("SAC", {"buffer_size": 10, "policy_kwargs": {"net_arch": [16, 16]}}),
        ("TD3", {"buffer_size": 10, "policy_kwargs": {"net_arch": [16, 8]}}),
    ],
)
def test_other_algorithms_and_bounds_act_as_sb3_predict(algo: str, kwargs: dict[str, Any]) -> None:
    """Pendulum's torque bounds are +-2: PPO and A2C clip to them, SAC and TD3 unscale from [-1, 1]."""
    policy_kwargs = dict(kwargs.pop("policy_kwargs"))
    if isinstance(policy_kwargs.get("activation_fn"), str):
        policy_kwargs["activation_fn"] = getattr(torch.nn, policy_kwargs["activation_fn"])
    env = gym.make("Pendulum-v1")
    model = getattr(sb3, algo)("MlpPolicy", env, policy_kwargs=policy_kwargs, device="cpu", seed=0, **kwargs)
    env.close()
    torch.manual_seed(0)
    with torch.no_grad():  # weights of order 1 (SB3 initializes the action layer at 0.01), so that the bounds act
        for p in model.policy.parameters():
            p.copy_(0.7 * torch.randn_like(p))
    inference, reason = mlp_inference_from_sb3(model)
    assert inference is not None, reason
    assert reason.startswith(algo)
    observations = _pendulum_observations(300)
    want = np.stack([model.predict(obs, deterministic=True)[0] for obs in observations])
    got = np.stack([inference(obs) for obs in observations])
    assert got.dtype == want.dtype and got.shape == want.shape == (300, 1)
    exact = _exact(model, observations)
    # float32 near 2 is spaced 2.4e-7, and the unscaling rounds three times in float32 as SB3's NumPy does
    assert np.abs(got - exact).max() <= 5e-7
    torch_error = float(np.abs(want - exact).max())  # weights of order 1: torch's float32 sums err by 1e-6 and more
    assert np.abs(got - want).max() <= max(1e-6, torch_error + 5e-7)
    assert np.abs(got).max() > 1.0  # the bounds are +-2, not +-1
    if algo in ("PPO", "A2C"):
        assert np.any(np.abs(got) == 2.0)  # clipped
    assert np.array_equal(inference(observations), got)


@pytest.mark.parametrize(
    "make, reason",
    [
        (lambda: sb3.PPO("MlpPolicy", "Pendulum-v1", policy_kwargs={"activation_fn": torch.nn.ELU}), "ELU"),
        (lambda: sb3.PPO("MultiInputPolicy", _DictEnv()), "observation space Dict"),
        (lambda: sb3.PPO("MlpPolicy", "Pendulum-v1", use_sde=True), "StateDependentNoiseDistribution"),
        (lambda: sb3.SAC("MlpPolicy", "Pendulum-v1", use_sde=True, buffer_size=10), "gSDE"),
        (lambda: sb3.PPO("MlpPolicy", "CartPole-v1"), "action space Discrete"),
    ],
    ids=["elu", "dict", "ppo-gsde", "sac-gsde", "discrete"],
)
def test_what_is_no_plain_mlp_has_no_fast_path_and_says_why(make: Any, reason: str) -> None:
    inference, why = mlp_inference_from_sb3(make())
    assert inference is None and reason in why


def test_a_fallback_policy_runs_sb3_predict_and_logs_why(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    model = sb3.PPO("MlpPolicy", "Pendulum-v1", policy_kwargs={"activation_fn": torch.nn.ELU}, device="cpu")
    model.save(tmp_path / "elu.zip")
    with caplog.at_level(logging.INFO, logger="redundancy_gym.policies.sb3_policy"):
        policy = Sb3Policy(tmp_path / "elu.zip")
    assert not policy.fast_path and policy.inference is None and "ELU" in policy.fast_path_reason
    assert any("no fast path" in r.getMessage() and "ELU" in r.getMessage() for r in caplog.records)
    obs = _pendulum_observations(5)
    assert np.array_equal(policy.predict(obs, deterministic=True)[0], policy.model.predict(obs, deterministic=True)[0])


def test_the_fast_path_can_be_turned_off_for_torchs_actions_to_the_last_bit() -> None:
    env = gym.make("redundancy_gym/PlanarReach-v0")
    try:
        policy = make_policy("ppo-joint", env, fast_path=False)
        obs, _ = env.reset(seed=0)
        with pytest.raises(PolicyError, match="fast_path='yes'; valid: True, False"):
            make_policy("ppo-joint", env, fast_path="yes")
        with pytest.raises(PolicyError, match="valid: algo, fast_path"):
            make_policy("ppo-joint", env, fast=False)
    finally:
        env.close()
    assert isinstance(policy, Sb3Policy) and not policy.fast_path and "fast_path=False" in policy.fast_path_reason
    assert np.array_equal(policy.predict(obs)[0], policy.model.predict(obs, deterministic=True)[0])


def test_a_stochastic_predict_is_sb3s(monkeypatch: pytest.MonkeyPatch) -> None:
    policy = Sb3Policy(SHIPPED[0].model)
    calls: list[bool] = []

    def recorded(observation: Any, state: Any = None, episode_start: Any = None, deterministic: bool = False) -> Any:
        calls.append(deterministic)
        return np.zeros(policy.model.action_space.shape, np.float32), state

    monkeypatch.setattr(policy.model, "predict", recorded)
    obs = np.zeros(policy.model.observation_space.shape)
    policy.predict(obs, deterministic=False)
    policy.predict(obs, deterministic=True)  # the fast path: SB3 is not called
    policy.sb3_predict(obs)
    assert calls == [False, True]


def test_tanh64_is_tanh_to_1e_14_and_exactly_one_beyond_its_clamp() -> None:
    x = np.concatenate([np.linspace(-20.0, 20.0, 8001), [0.0, 1e-300, 1e-12, -3e-5, 0.07, -0.2, 19.99]])
    got = np.array([tanh64(v) for v in x])
    assert np.all(np.abs(got - np.tanh(x)) <= 1e-14 * np.abs(np.tanh(x)))
    far = np.array([20.0, 21.0, 50.0, 1e300, np.inf])
    far = np.concatenate([far, -far])
    assert np.array_equal(np.array([tanh64(v) for v in far]), np.tanh(far))  # +-1
    assert np.isnan(tanh64(np.nan))


def test_an_observation_of_another_shape_is_named() -> None:
    inference = MlpInference([(np.ones((2, 3)), np.zeros(2), "tanh")], (3,), -np.ones(2), np.ones(2))
    assert inference(np.zeros(3)).shape == (2,) and inference(np.zeros((4, 3))).shape == (4, 2)
    with pytest.raises(PolicyError, match=r"observation of shape \(4,\) is neither the model's \(3,\) nor a batch"):
        inference(np.zeros(4))
    with pytest.raises(PolicyError, match="activation='elu'; valid: identity, tanh, relu"):
        MlpInference([(np.ones((2, 3)), np.zeros(2), "elu")], (3,), -np.ones(2), np.ones(2))
    with pytest.raises(PolicyError, match="do not take 4 inputs"):
        MlpInference([(np.ones((2, 3)), np.zeros(2), "tanh")], (4,), -np.ones(2), np.ones(2))


def test_an_evaluation_reports_sb3_predict_beside_the_fast_step_time() -> None:
    learned = evaluate("redundancy_gym/PlanarReach-v0", "ppo-joint", episodes=1, seed=20000, progress=False)
    report = learned.to_json()
    fast, sb3_times = report["step_time_us"], report["sb3_predict_us"]
    assert list(report).index("sb3_predict_us") == list(report).index("step_time_us") + 1
    assert set(sb3_times) == set(fast) and sb3_times["steps"] == fast["steps"] == report["episode_length"]
    summary = learned.summaries[0]
    assert summary.sb3_predict_us is not None and summary.sb3_predict_us.shape == (summary.length,)
    assert sb3_times["median"] > fast["median"]  # SB3's per-call overhead is what the fast path removes
    analytic = evaluate("redundancy_gym/PlanarReach-v0", "zero", episodes=1, seed=20000, progress=False).to_json()
    assert "sb3_predict_us" not in analytic
    assert "with SB3's predict instead [us]" in format_report(report)
    assert "SB3" not in format_report(analytic)
    text = speed_error_markdown({"ppo-joint": report, "zero": analytic}, "PlanarReach")
    rows = [line for line in text.splitlines() if line.startswith("|")]
    assert "SB3 predict median / p99 [us]" in rows[0] and rows[3].split("|")[8].strip() == "-"
    assert "SB3 predict" not in speed_error_markdown({"zero": analytic}, "PlanarReach")
