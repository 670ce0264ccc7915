"""bench soak: short soaks of every env are clean, and a faulty env is counted, not a crash."""

from __future__ import annotations

import json
from typing import cast

import gymnasium as gym
import numpy as np
import pytest
from gymnasium.envs.registration import EnvCreator

from redundancy_gym import ENV_IDS
from redundancy_gym.bench.soak import SOURCES, format_soak_bench, run_soak_bench
from redundancy_gym.cli import main
from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.eval.json_writer import write_json

FAULTY_ID = "soak_test/Faulty-v0"
BROKEN_RESET_ID = "soak_test/BrokenReset-v0"


class _FaultyEnv(gym.Env):
    """Episodes of 8 steps; step 3 returns a NaN observation and an inf info value, step 5 raises."""

    observation_space = gym.spaces.Box(-1.0, 1.0, (3,), np.float64)
    action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.t = 0
        return np.zeros(3), {}

    def step(self, action):
        assert self.action_space.contains(np.asarray(action, dtype=np.float32)), action
        self.t += 1
        if self.t == 5:
            raise RuntimeError("faulty step 5")
        obs = np.full(3, np.nan) if self.t == 3 else np.zeros(3)
        info = {"error": float("inf") if self.t == 3 else 0.0, "label": "x"}
        return obs, 0.0, False, self.t >= 8, info


class _BrokenResetEnv(_FaultyEnv):
    def reset(self, *, seed=None, options=None):
        raise ValueError("reset always fails")


for _id, _cls in ((FAULTY_ID, _FaultyEnv), (BROKEN_RESET_ID, _BrokenResetEnv)):
    if _id not in gym.registry:
        # gym.make calls the entry point with the env kwargs: none here (the stub asks for a **kwargs callable)
        gym.register(_id, entry_point=cast(EnvCreator, _cls))


def test_short_soak_of_every_env_is_clean(tmp_path) -> None:
    report = run_soak_bench(steps=120, envs=ENV_IDS, progress=False)
    assert report["ok"], format_soak_bench(report)
    for env_id in ENV_IDS:
        entry = report["envs"][env_id]
        assert set(entry["sources"]) == set(SOURCES)
        wrapped = env_id.count("-") > 1  # <Env>-<Wrapper>-v0: the wrapper's controller alone
        assert entry["reference_policy"] == ("zero" if wrapped else "walking" if "Biped" in env_id else "clik")
        for source, r in entry["sources"].items():
            assert r["steps"] > 0, (env_id, source)
            assert r["exceptions"]["count"] == 0 and r["non_finite"]["count"] == 0, (env_id, source, r)
            assert r["steps_per_second"] > 0
        assert entry["steps"] == sum(r["steps"] for r in entry["sources"].values())
    assert report["totals"]["steps"] == sum(e["steps"] for e in report["envs"].values())
    written = json.loads(write_json(report, tmp_path / "soak.json").read_text())
    assert written["totals"] == report["totals"] and "processor" in written["machine"]
    assert written["budget"] == {"steps_per_env": 120}
    assert all(e["steps"] == 120 for e in report["envs"].values())


def test_seconds_budget_and_table() -> None:
    report = run_soak_bench(
        seconds=0.1, envs=("redundancy_gym/PlanarReach-v0",), sources=("random", "bang_bang"), progress=False
    )
    r = report["envs"]["redundancy_gym/PlanarReach-v0"]["sources"]
    assert r["random"]["steps"] >= 64 and r["bang_bang"]["steps"] >= 64
    assert report["ok"] and "OK" in format_soak_bench(report)


def test_faulty_env_is_counted_not_a_crash() -> None:
    report = run_soak_bench(steps=60, envs=(FAULTY_ID,), progress=False)
    entry = report["envs"][FAULTY_ID]
    assert entry["reference_policy"] is None
    for source in ("random", "bang_bang"):
        r = entry["sources"][source]
        # 20 attempts per source: steps 1-4 then a raise at 5 (reset), so 4 steps per 5 attempts
        assert r["exceptions"]["count"] == 4 and r["steps"] == 16, r
        assert r["exceptions"]["first"][0]["type"] == "RuntimeError"
        assert r["exceptions"]["first"][0]["message"] == "faulty step 5"
        keys = {k["key"] for k in r["non_finite"]["first"]}
        assert keys == {"observation", "info.error"}
        assert r["non_finite"]["count"] == 8  # 2 keys, once in each of 4 episodes
    assert "stopped" in entry["sources"]["reference"] and entry["sources"]["reference"]["steps"] == 0
    assert not report["ok"]
    assert "faulty step 5" in format_soak_bench(report)


def test_env_whose_reset_always_fails_is_stopped() -> None:
    report = run_soak_bench(steps=10, envs=(BROKEN_RESET_ID,), sources=("random",), progress=False)
    r = report["envs"][BROKEN_RESET_ID]["sources"]["random"]
    assert r["steps"] == 0 and r["exceptions"]["count"] >= 1 and "stopped" in r
    assert r["exceptions"]["first"][0]["type"] == "ValueError"


@pytest.mark.parametrize(
    "kwargs", [{}, {"seconds": 1.0, "steps": 10}, {"seconds": 0.0}, {"steps": 0}, {"steps": 10, "sources": ("nope",)}]
)
def test_bad_arguments(kwargs) -> None:
    with pytest.raises(EvalError):
        run_soak_bench(progress=False, **kwargs)


def test_cli_soak(tmp_path, capsys) -> None:
    path = tmp_path / "soak.json"
    assert main(["bench", "soak", "--steps", "60", "--no-progress", "--json", str(path)]) == 0
    report = json.loads(path.read_text())
    assert set(report["envs"]) == set(ENV_IDS) and report["ok"]
    assert "reference (clik)" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        main(["bench", "envs", "--seconds", "1"])
    with pytest.raises(SystemExit):
        main(["bench", "soak", "--seconds", "1", "--steps", "5"])
