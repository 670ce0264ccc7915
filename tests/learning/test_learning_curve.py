"""A learning curve trained in segments (seconds): budgets met in order, a run extended from its last point keeps the
points it had, an interrupted segment resumes from its checkpoint (whole, even when killed while saving), other
settings or a lost agent are refused (the number of torch threads is not a setting), an uninterrupted run repeats
bitwise, sb3-contrib's TQC trains and evaluates through the harness; the budget ladder is logarithmic."""

from __future__ import annotations

import json
import tempfile

import pytest

from redundancy_gym.learning.exceptions import LearningError
from redundancy_gym.learning.learning_curve import CurveRun, budgets_between, train_learning_curve

PLANAR = "redundancy_gym/PlanarReach-v0"
TINY_PPO = {"n_steps": 32, "batch_size": 16, "n_epochs": 1}
SMALL_OFF_POLICY = {"learning_starts": 20, "batch_size": 16, "buffer_size": 1000}  # a 1M buffer pickles to GBs


def _run(budgets, **changes):
    fields = dict(
        name="pr-ppo-s0",
        env_id=PLANAR,
        env_kwargs={"obstacle": False},
        algo="ppo",
        seed=0,
        budgets=budgets,
        hyperparameters=TINY_PPO,
        eval_episodes=1,
    )
    fields.update(changes)
    return CurveRun(**fields)


def test_a_curve_is_extended_from_its_last_point(tmp_path, monkeypatch):
    temporary = tmp_path / "tmp"  # SB3's default logger made a folder here per learn() call
    temporary.mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(temporary))
    monkeypatch.delenv("SB3_LOGDIR", raising=False)  # the session sets it (conftest); SB3 would write there instead
    first = train_learning_curve(_run((32, 64)), tmp_path, log=None)
    assert [p["steps"] for p in first["points"]] == [32, 64]
    assert all(0.0 <= p["success_rate"] <= 1.0 and "tracking_error_max" in p for p in first["points"])
    assert first["points"][1]["cpu_s"] >= first["points"][0]["cpu_s"] > 0.0
    extended = train_learning_curve(_run((32, 64, 128)), tmp_path, log=None)
    assert extended["points"][:2] == first["points"]  # the old points as they were
    assert [p["steps"] for p in extended["points"]] == [32, 64, 128]
    saved = json.loads((tmp_path / "pr-ppo-s0.json").read_text())
    assert saved["points"] == extended["points"]
    again = train_learning_curve(_run((32, 64, 128)), tmp_path, log=None)  # nothing left to train
    assert again["points"] == extended["points"]
    assert not list(temporary.glob("SB3-*"))


def test_an_interrupted_segment_resumes_from_its_last_checkpoint(tmp_path, monkeypatch):
    from redundancy_gym.learning import learning_curve

    evaluate = learning_curve.evaluate

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(learning_curve, "evaluate", interrupted)
    with pytest.raises(KeyboardInterrupt):
        train_learning_curve(_run((96,)), tmp_path, checkpoint_every=32, log=None)
    saved = json.loads((tmp_path / "pr-ppo-s0.json").read_text())
    assert saved["points"] == [] and saved["checkpoint_steps"] == 96 and saved["cpu_s"] > 0.0
    monkeypatch.setattr(learning_curve, "evaluate", evaluate)
    resumed = train_learning_curve(_run((96,)), tmp_path, checkpoint_every=32, log=None)
    assert [p["steps"] for p in resumed["points"]] == [96]  # the saved agent, not trained again
    assert resumed["points"][0]["cpu_s"] == pytest.approx(saved["cpu_s"], abs=0.01)
    assert "checkpoint_steps" not in json.loads((tmp_path / "pr-ppo-s0.json").read_text())
    with pytest.raises(LearningError, match="checkpoint_every"):
        train_learning_curve(_run((128,)), tmp_path, checkpoint_every=0, log=None)


def test_other_settings_or_a_lost_agent_are_refused(tmp_path):
    train_learning_curve(_run((32,)), tmp_path, log=None)
    with pytest.raises(LearningError, match="other settings"):
        train_learning_curve(_run((32, 64), seed=1), tmp_path, log=None)
    (tmp_path / "pr-ppo-s0.zip").unlink()
    with pytest.raises(LearningError, match="agent .* is missing"):
        train_learning_curve(_run((32, 64)), tmp_path, log=None)
    assert len(json.loads((tmp_path / "pr-ppo-s0.json").read_text())["points"]) == 1  # kept


def test_a_run_resumes_on_another_number_of_threads_and_records_them(tmp_path):
    first = train_learning_curve(_run((32,)), tmp_path, log=None)
    assert first["points"][0]["torch_threads"] == 1
    saved = json.loads((tmp_path / "pr-ppo-s0.json").read_text())
    saved["settings"]["torch_threads"] = 1  # as states written before threads left the settings
    (tmp_path / "pr-ppo-s0.json").write_text(json.dumps(saved))
    resumed = train_learning_curve(_run((32, 64), torch_threads=2), tmp_path, log=None)
    assert [p["torch_threads"] for p in resumed["points"]] == [1, 2]
    assert resumed["points"][0] == first["points"][0]


def test_an_off_policy_contrib_learner_keeps_its_replay_buffer(tmp_path):
    pytest.importorskip("sb3_contrib")
    run = _run((40, 80), name="pr-tqc-s0", algo="tqc", hyperparameters=SMALL_OFF_POLICY)
    state = train_learning_curve(run, tmp_path, agents=tmp_path / "agents", log=None)
    assert [p["steps"] for p in state["points"]] == [40, 80]
    assert (tmp_path / "agents" / "pr-tqc-s0.zip").is_file()
    assert (tmp_path / "agents" / "pr-tqc-s0_replay.pkl").is_file()


def test_an_uninterrupted_run_repeats_bitwise(tmp_path):
    # every draw (init, exploration, replay sampling, env resets) comes from the run's seed: the same run in another
    # folder gives the same points after gradient updates; only a resumed segment starts from other draws
    run = _run((40, 80), name="pr-sac-s0", algo="sac", hyperparameters=SMALL_OFF_POLICY)
    first = train_learning_curve(run, tmp_path / "a", agents=tmp_path / "a" / "agents", log=None)
    second = train_learning_curve(run, tmp_path / "b", agents=tmp_path / "b" / "agents", log=None)

    def measured(state):
        return [{k: v for k, v in p.items() if k not in ("cpu_s", "wall_s")} for p in state["points"]]

    assert [p["steps"] for p in first["points"]] == [40, 80]
    assert measured(first) == measured(second)
    other = train_learning_curve(
        _run((40, 80), name="pr-sac-s1", algo="sac", seed=1, hyperparameters=SMALL_OFF_POLICY),
        tmp_path / "c",
        agents=tmp_path / "c" / "agents",
        log=None,
    )
    assert measured(other) != measured(first)  # the comparison can tell runs apart


def test_a_run_killed_while_saving_keeps_its_last_checkpoint_whole(tmp_path, monkeypatch):
    from stable_baselines3.common.off_policy_algorithm import OffPolicyAlgorithm

    save_buffer, calls = OffPolicyAlgorithm.save_replay_buffer, []

    def killed_at_the_second(self, path):
        calls.append(path)
        if len(calls) == 2:  # half a pickle written, as when the process is killed mid-write
            with open(path, "wb") as handle:
                handle.write(b"\x80\x04\x95")
            raise KeyboardInterrupt
        save_buffer(self, path)

    monkeypatch.setattr(OffPolicyAlgorithm, "save_replay_buffer", killed_at_the_second)
    run = _run((60,), name="pr-sac-s0", algo="sac", hyperparameters={**SMALL_OFF_POLICY, "learning_starts": 10})
    with pytest.raises(KeyboardInterrupt):
        train_learning_curve(run, tmp_path, checkpoint_every=20, log=None)
    assert json.loads((tmp_path / "pr-sac-s0.json").read_text())["checkpoint_steps"] == 20  # the first checkpoint
    monkeypatch.setattr(OffPolicyAlgorithm, "save_replay_buffer", save_buffer)
    resumed = train_learning_curve(run, tmp_path, checkpoint_every=20, log=None)  # its agent at 20, its buffer whole
    assert [p["steps"] for p in resumed["points"]] == [60]
    assert not list(tmp_path.glob("*.partial"))


def test_a_reward_variant_trains_on_its_kwargs_and_is_evaluated_on_the_envs(tmp_path, monkeypatch):
    import torch
    from stable_baselines3 import PPO

    from redundancy_gym.learning import learning_curve

    made, evaluated = [], []
    make_env, evaluate = learning_curve.make_env, learning_curve.evaluate

    def recording_make(env_id, env_kwargs=None, **rest):
        made.append(dict(env_kwargs or {}))
        return make_env(env_id, env_kwargs, **rest)

    def recording_evaluate(*args, **kwargs):
        evaluated.append(dict(kwargs["env_kwargs"]))
        return evaluate(*args, **kwargs)

    monkeypatch.setattr(learning_curve, "make_env", recording_make)
    monkeypatch.setattr(learning_curve, "evaluate", recording_evaluate)
    variant = train_learning_curve(
        _run((32,), name="variant", train_env_kwargs={"energy_weight": 4000.0}), tmp_path, log=None
    )
    assert made == [{"obstacle": False, "energy_weight": 4000.0}]  # trained on the variant's reward
    assert evaluated == [{"obstacle": False}]  # evaluated on the env as defined
    assert variant["settings"]["train_env_kwargs"] == {"energy_weight": 4000.0}
    train_learning_curve(_run((32,)), tmp_path, log=None)
    assert made[-1] == {"obstacle": False}
    # the same seed and steps on another reward: another agent
    weights = [PPO.load(str(tmp_path / f"{n}.zip"), device="cpu").policy.state_dict() for n in ("variant", "pr-ppo-s0")]
    assert any(not torch.equal(weights[0][k], weights[1][k]) for k in weights[0])
    assert "train_env_kwargs" not in _run((32,)).settings()  # states written before the option stay valid


def test_a_normalized_run_saves_its_statistics_and_its_policy_reads_them(tmp_path):
    import numpy as np
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from redundancy_gym.eval.evaluate import make_env
    from redundancy_gym.policies import make_policy

    state = train_learning_curve(_run((32,), normalize=True), tmp_path, log=None)
    stats = tmp_path / "pr-ppo-s0_vecnormalize.pkl"
    assert stats.is_file() and state["settings"]["normalize"] is True
    extended = train_learning_curve(_run((32, 64), normalize=True), tmp_path, log=None)  # resumed with its stats
    assert [p["steps"] for p in extended["points"]] == [32, 64]
    env = make_env(PLANAR, {"obstacle": False})
    saved = VecNormalize.load(str(stats), DummyVecEnv([lambda: make_env(PLANAR, {"obstacle": False})]))
    assert saved.obs_rms.count > 64  # updated while training on, not restarted
    policy = make_policy(str(tmp_path / "pr-ppo-s0.zip"), env)
    assert policy.normalization is not None
    obs, _ = env.reset(seed=3)
    normalized = saved.normalize_obs(obs)
    assert np.array_equal(policy.normalization(obs), normalized)
    expected, _ = PPO.load(str(tmp_path / "pr-ppo-s0.zip"), device="cpu").predict(normalized, deterministic=True)
    np.testing.assert_allclose(policy.predict(obs)[0], expected, atol=1e-5)  # the fast path on normalized input
    np.testing.assert_allclose(policy.sb3_predict(obs)[0], expected, atol=0)
    raw, _ = PPO.load(str(tmp_path / "pr-ppo-s0.zip"), device="cpu").predict(obs, deterministic=True)
    assert not np.allclose(raw, expected)  # the statistics change what the agent does
    # a plain run keeps its old settings (states written before the option existed stay valid)
    assert "normalize" not in _run((32,)).settings()


def test_statistics_of_another_shape_or_no_statistics_are_refused(tmp_path):
    import numpy as np
    from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize

    from redundancy_gym.eval.evaluate import make_env
    from redundancy_gym.policies import make_policy
    from redundancy_gym.policies.exceptions import PolicyError

    train_learning_curve(_run((32,), normalize=True), tmp_path, log=None)
    stats = tmp_path / "pr-ppo-s0_vecnormalize.pkl"
    env = make_env(PLANAR, {"obstacle": False})
    saved = VecNormalize.load(str(stats), DummyVecEnv([lambda: make_env(PLANAR, {"obstacle": False})]))
    saved.obs_rms.mean = np.zeros(3)
    saved.save(str(stats))
    with pytest.raises(PolicyError, match=r"statistics of shape \(3,\)"):
        make_policy(str(tmp_path / "pr-ppo-s0.zip"), env)
    stats.write_bytes(b"not a pickle")
    with pytest.raises(PolicyError, match="not a VecNormalize file"):
        make_policy(str(tmp_path / "pr-ppo-s0.zip"), env)


@pytest.mark.parametrize(
    ("changes", "named"),
    [
        ({"algo": "dqn"}, "algo"),
        ({"budgets": ()}, "budgets"),
        ({"budgets": (64, 32)}, "budgets"),
        ({"eval_episodes": 0}, "eval_episodes"),
    ],
)
def test_bad_runs_are_named(changes, named):
    with pytest.raises(LearningError, match=named):
        _run(changes.pop("budgets", (32,)), **changes)


def test_budgets_are_logarithmic_round_numbers():
    assert budgets_between(10_000, 3_000_000) == (10_000, 30_000, 100_000, 300_000, 1_000_000, 3_000_000)
    assert budgets_between(10_000, 300_000) == (10_000, 30_000, 100_000, 300_000)
    assert budgets_between(1000, 5000) == (1000, 3000, 5000)  # the last budget kept
    with pytest.raises(LearningError):
        budgets_between(100, 10)


def test_another_state_folders_agent_is_neither_overwritten_nor_resumed(tmp_path):
    """One agents folder serves every state folder (every --json of the bench): a same-named run elsewhere must not
    start afresh over this one's agent, nor resume from an agent that trained other steps than its state says."""
    agents = tmp_path / "agents"
    train_learning_curve(_run((32, 64)), tmp_path / "study", agents=agents, log=None)
    agent = (agents / "pr-ppo-s0.zip").read_bytes()
    with pytest.raises(LearningError, match="has no points, but .*pr-ppo-s0.zip exists"):
        train_learning_curve(_run((32,)), tmp_path / "elsewhere", agents=agents, log=None)
    assert (agents / "pr-ppo-s0.zip").read_bytes() == agent  # untouched
    assert not (tmp_path / "elsewhere" / "pr-ppo-s0.json").exists()
    train_learning_curve(_run((32,)), tmp_path / "other", agents=tmp_path / "other_agents", log=None)
    (tmp_path / "other_agents" / "pr-ppo-s0.zip").replace(agents / "pr-ppo-s0.zip")  # a 32-step agent
    with pytest.raises(LearningError, match="has trained 32 steps, but .* says 64"):
        train_learning_curve(_run((32, 64, 128)), tmp_path / "study", agents=agents, log=None)
