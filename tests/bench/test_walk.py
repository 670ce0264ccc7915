"""bench walk: the compiled and the pinocchio whole-body IK are timed on the same recorded states and agree."""

from __future__ import annotations

import json

import pytest

from redundancy_gym.bench.walk import LOLA_CYCLE_US, format_walk_bench, run_walk_bench
from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.eval.json_writer import write_json


def test_walk_bench_report(tmp_path) -> None:
    report = run_walk_bench(duration=0.6, repeats=1, rounds=2, progress=False)
    # the IKD controller is timed in the same run: a ratio to the CLIK controller, and both ZMPs measured
    assert report["ikd"]["step_us_median"] > 0.0 and report["ikd_vs_clik"] > 0.0 and not report["ikd"]["fell"]
    assert all(0.0 < v < 200.0 for v in report["zmp_rms_mm"].values())
    for ik, phases in report["zmp_rms_by_phase_mm"].items():  # the phases split the periods and the squared error
        assert set(phases) == {"single", "double", "touchdown", "liftoff"}
        assert sum(p["period_share"] for p in phases.values()) == pytest.approx(1.0)
        assert sum(p["error_share"] or 0.0 for p in phases.values()) == pytest.approx(1.0)
        # the rms over all periods is the share-weighted rms of the phases
        assert sum(p["period_share"] * (p["rms_mm"] or 0.0) ** 2 for p in phases.values()) == pytest.approx(
            report["zmp_rms_mm"][ik] ** 2
        )
        # the reference ZMP lies inside the planned support polygon by construction (heel to toe, foot to foot)
        assert report["zmp_reference_margin_mm"][ik] > 0.0
    # the planned ZMP (the plan's whole-body motion) keeps 20 mm inside the soles in every step, the first included
    plan = report["zmp_whole_body_plan"]
    assert report["zmp_plan_margin_mm"] == plan["margin_mm"] == min(row["margin_mm"] for row in plan["by_step"])
    assert report["zmp_plan_margin_mm"] >= 20.0
    assert report["states"] == 149 and not report["fell"]  # every period after the first records one IK call
    assert report["ik_max_difference"] < 1e-9  # the same inputs give the same configuration in both backends
    assert report["self_collision_pairs"] > 100
    k, p = report["ik_compiled"], report["ik_python"]
    # ratios are medians of per-round ratios (compiled, python / python, compiled), near the ratio of the medians
    stats = report["ik_compiled_vs_python_rounds"]
    assert report["ik_compiled_vs_python"] == stats["median"] and stats["rounds"] == 2
    assert 0.0 < stats["min"] <= stats["median"] <= stats["max"]
    assert report["ik_compiled_vs_python"] == pytest.approx(k["step_us_median"] / p["step_us_median"], rel=0.5)
    assert report["timing"]["ik_orders"] == [["compiled", "python"], ["python", "compiled"]]
    assert report["timing"]["walk_orders"] == [["clik", "ikd"], ["ikd", "clik"]]
    ikd = report["ikd_vs_clik_rounds"]
    assert report["ikd_vs_clik"] == ikd["median"] and report["ikd_vs_clik_spread"] == [ikd["min"], ikd["max"]]
    assert report["controller_vs_lola"] == pytest.approx(report["controller"]["step_us_median"] / LOLA_CYCLE_US)
    lola = report["controller_vs_lola_rounds"]
    assert lola["min"] <= report["controller_vs_lola"] <= lola["max"]
    # the terrain walks are walked to their end: the stairs and the platform passed, every step timed
    terrain = report["terrain"]
    assert set(terrain["courses"]) == {"stairs", "platform"}
    assert all(r["success"] and r["steps"] > 1000 for r in terrain["courses"].values())
    assert terrain["within_target"] == (terrain["step_us_median"] <= 150.0)
    assert report["terrain_vs_flat"] == pytest.approx(
        terrain["step_us_median"] / report["controller"]["step_us_median"]
    )
    assert "on terrain (stairs)" in format_walk_bench(report)
    assert len(report["machine"]["load_average_end"]) == 3
    assert "ik_compiled_vs_python" in format_walk_bench(report)
    written = json.loads(write_json(report, tmp_path / "walk.json").read_text())
    assert written["ik_compiled_vs_python"] == report["ik_compiled_vs_python"]


def test_walk_bench_rejects_bad_options() -> None:
    with pytest.raises(EvalError, match="repeats"):
        run_walk_bench(repeats=0, progress=False)
    with pytest.raises(EvalError, match="duration"):
        run_walk_bench(duration=-1.0, progress=False)
    with pytest.raises(EvalError, match="rounds"):
        run_walk_bench(rounds=0, progress=False)
