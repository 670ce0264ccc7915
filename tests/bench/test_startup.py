"""bench startup (seconds): each probe runs in a fresh process, cold with an empty numba cache and warm with the cache
that run filled, so a warm run compiles nothing; unknown probes are named; the report states its targets."""

from __future__ import annotations

import pytest

from redundancy_gym.bench.exceptions import BenchError
from redundancy_gym.bench.startup import STARTUP_TARGETS, format_startup_bench, run_startup_bench, startup_probes


def test_a_warm_process_loads_what_the_cold_one_compiled():
    report = run_startup_bench(names=["import", "PlanarReach-v0"], rounds=3, progress=False)
    probe = report["probes"]["PlanarReach-v0"]
    cold, warm = probe["cold"], probe["warm"]
    assert "error" not in cold and "error" not in warm, probe
    assert report["rounds"] == 3 and len(warm["process_s_runs"]) == 3
    assert warm["process_s"] == sorted(warm["process_s_runs"])[1]  # the median run is the one reported
    assert cold["compile_s"] > 0.0  # the env's first step compiled its kernels into the empty cache
    assert warm["compile_s"] == 0.0 < warm["kernels_s"]  # and the next process loaded them
    for run in (cold, warm):
        assert 0.0 < run["first_step_s"] <= run["total_s"] <= run["process_s"]
    imported = report["probes"]["import"]["cold"]
    assert 0.0 < imported["import_s"] <= imported["process_s"]
    assert set(report["targets"]) == set(STARTUP_TARGETS)
    assert report["targets"]["quick_start_cold"]["met"] is None  # not measured in this run: not claimed
    text = format_startup_bench(report)
    assert "PlanarReach-v0" in text and "quick_start_cold: <= 8 s, not measured" in text


def test_the_warm_result_is_the_median_run_and_a_failed_run_is_not_hidden():
    from redundancy_gym.bench.startup import _median_run

    runs = [{"process_s": 2.0, "x": 2}, {"process_s": 1.0, "x": 1}, {"process_s": 9.0, "x": 9}]
    assert _median_run(runs) == {"process_s": 2.0, "x": 2, "process_s_runs": [2.0, 1.0, 9.0]}
    assert _median_run(runs[:2])["x"] == 1  # an even count: the lower of the two middle runs
    assert _median_run([*runs, {"error": "exit 1: boom"}]) == {"error": "exit 1: boom"}
    with pytest.raises(BenchError, match=r"rounds must be an integer >= 1, got 0"):
        run_startup_bench(names=["import"], rounds=0, progress=False)


def test_probes_cover_every_env_and_reference_and_unknown_ones_are_named():
    from redundancy_gym import ENV_IDS

    names = [p.name for p in startup_probes()]
    assert {"import", "list", "quick_start", "policy:clik", "policy:walking"} <= set(names)
    assert {env_id.split("/")[-1] for env_id in ENV_IDS} <= set(names)
    assert [p.name for p in startup_probes(quick=True)] == ["import", "PlanarReach-v0"]
    with pytest.raises(BenchError, match=r"unknown startup probe nope; valid: import, list, quick_start"):
        startup_probes(["nope"])
