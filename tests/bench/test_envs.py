"""bench envs: the report's rates and ratios are medians over alternating rounds, with their spread, and measured
for every env asked for."""

from __future__ import annotations

import json

import numpy as np
import pytest

from redundancy_gym.bench.envs import format_envs_bench, run_envs_bench
from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.eval.json_writer import write_json


def test_envs_bench_report(tmp_path) -> None:
    report = run_envs_bench(
        seconds=0.15,
        envs=("redundancy_gym/AgriReach-v0",),
        peers=("Pusher-v5",),
        wrapped=("redundancy_gym/AgriReach-Nullspace-v0",),
        rounds=3,
        progress=False,
    )
    timing = report["timing"]
    assert timing["rounds"] == 3 and timing["warmup"] == 1 and timing["window_s"] == pytest.approx(0.05)
    envs = ["redundancy_gym/AgriReach-v0", "Pusher-v5", "redundancy_gym/AgriReach-v0 (prune=False)"]
    labels = [name for env in envs for name in (env, f"{env} physics")]  # each env beside its bare physics
    assert timing["orders"] == [labels, labels[::-1], labels]  # ABC CBA ABC: no env always first
    unpruned = report["envs"]["redundancy_gym/AgriReach-v0 (prune=False)"]
    agri = report["envs"]["redundancy_gym/AgriReach-v0"]
    pusher = report["envs"]["Pusher-v5"]
    for r in (agri, pusher, unpruned):
        assert r["steps"] > 0 and r["seconds"] > 0.0  # the three recorded windows, not the warm-up
        assert r["sim_seconds_per_second"] == pytest.approx(r["steps_per_second"] * r["control_period"])
    for name in ("agri_vs_pusher", "agri_prune_speedup"):
        stats = report["ratio_rounds"][name]
        assert report[name] == report["ratios"][name] == stats["median"]
        assert 0.0 < stats["min"] <= stats["median"] <= stats["max"] and stats["rounds"] == 3
        assert stats["spread"] == pytest.approx((stats["max"] - stats["min"]) / stats["median"])
    # the median of per-round ratios lies near the ratio of the median rates (equal when the rounds agree)
    assert report["agri_vs_pusher"] == pytest.approx(agri["steps_per_second"] / pusher["steps_per_second"], rel=0.5)
    assert "agri_vs_pusher" in format_envs_bench(report) and "rounds" in format_envs_bench(report)
    written = json.loads(write_json(report, tmp_path / "b.json").read_text())
    assert written["agri_vs_pusher"] == report["agri_vs_pusher"]
    assert len(written["machine"]["load_average_end"]) == 3 and "gymnasium" in written["machine"]["versions"]
    wrapped = report["wrapped"]["redundancy_gym/AgriReach-Nullspace-v0"]
    assert wrapped["raw"] == "redundancy_gym/AgriReach-v0" and wrapped["rounds"] == 3
    assert wrapped["ratio_min"] <= wrapped["ratio"] <= wrapped["ratio_max"] and wrapped["ratio_spread"] >= 0.0
    assert 0.0 < wrapped["ratio"] < 1.5 and wrapped["steps_per_second"] > 0
    assert "AgriReach-Nullspace-v0" in format_envs_bench(report)
    # the wrapper's glue: its step less the raw step less its controller, all three measured
    assert wrapped["controller_time_us"] > 0.0 and wrapped["step_us"] > wrapped["raw_step_us"] > 0.0
    assert len(wrapped["glue_us_rounds"]) == 3 and wrapped["glue_us"] == pytest.approx(
        float(np.median(wrapped["glue_us_rounds"]))
    )
    assert wrapped["glue_us_min"] <= wrapped["glue_us"] <= wrapped["glue_us_max"]
    # each env against its own bare physics (mj_step with nstep=frame_skip on its model and data)
    physics = report["physics"]
    assert set(physics) == set(envs)
    for name, row in physics.items():
        assert row["substeps"] == {"Pusher-v5": 5}.get(name, 1)
        assert 0.0 < row["physics_us"] < row["env_step_us"]  # a step is its physics and more
        stats = row["env_vs_physics_rounds"]
        assert stats["min"] <= row["env_vs_physics"] == stats["median"] <= stats["max"] and stats["rounds"] == 3
    agri_row = physics["redundancy_gym/AgriReach-v0"]
    pusher_overhead = physics["Pusher-v5"]["overhead_us"]
    assert agri_row["bound_us"] == max(1.5 * agri_row["physics_us"], agri_row["physics_us"] + pusher_overhead)
    assert agri_row["within_bound"] == (agri_row["env_step_us"] <= agri_row["bound_us"])
    assert "bound_us" not in physics["Pusher-v5"] and "env / physics" in format_envs_bench(report)


def test_envs_bench_rejects_bad_options() -> None:
    with pytest.raises(EvalError, match="rounds"):
        run_envs_bench(rounds=0, progress=False)
    with pytest.raises(EvalError, match="seconds"):
        run_envs_bench(seconds=0.0, progress=False)
