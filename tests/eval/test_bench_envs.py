"""bench envs: the report's rates and ratios are consistent and measured for every env asked for."""

from __future__ import annotations

import json

import pytest

from redundancy_gym.eval.bench_envs import format_envs_bench, run_envs_bench, write_envs_bench


def test_envs_bench_report(tmp_path) -> None:
    report = run_envs_bench(seconds=0.05, envs=("redundancy_gym/AgriReach-v0",), peers=("Pusher-v5",),
                            wrapped=("redundancy_gym/AgriReach-Nullspace-v0",), rounds=3, progress=False)
    unpruned = report["envs"]["redundancy_gym/AgriReach-v0 (prune=False)"]
    assert unpruned["steps"] > 0
    assert report["agri_prune_speedup"] == pytest.approx(
        report["envs"]["redundancy_gym/AgriReach-v0"]["steps_per_second"] / unpruned["steps_per_second"])
    agri = report["envs"]["redundancy_gym/AgriReach-v0"]
    pusher = report["envs"]["Pusher-v5"]
    assert agri["steps"] > 0 and pusher["steps"] > 0
    assert agri["steps_per_second"] == pytest.approx(agri["steps"] / agri["seconds"])
    assert report["agri_vs_pusher"] == pytest.approx(agri["steps_per_second"] / pusher["steps_per_second"])
    assert "agri_vs_pusher" in format_envs_bench(report)
    written = json.loads(write_envs_bench(report, tmp_path / "b.json").read_text())
    assert written["agri_vs_pusher"] == report["agri_vs_pusher"]
    wrapped = report["wrapped"]["redundancy_gym/AgriReach-Nullspace-v0"]
    assert wrapped["raw"] == "redundancy_gym/AgriReach-v0" and wrapped["rounds"] == 3
    assert wrapped["ratio_min"] <= wrapped["ratio"] <= wrapped["ratio_max"]
    assert 0.0 < wrapped["ratio"] < 1.5 and wrapped["steps_per_second"] > 0
    assert "AgriReach-Nullspace-v0" in format_envs_bench(report)
