"""bench ik: ours and mink are timed on the same states with the same collision geoms, in alternating rounds; the
report is consistent."""

from __future__ import annotations

import json

import pytest

from redundancy_gym.eval.json_writer import write_json

pytest.importorskip("mink")

from redundancy_gym.bench.ik import format_ik_bench, run_ik_bench  # noqa: E402
from redundancy_gym.eval.exceptions import EvalError  # noqa: E402


def test_ik_bench_report(tmp_path) -> None:
    report = run_ik_bench(repeats=1, rounds=3, scaling=(10, 30), progress=False)
    ours, mink = report["ours"], report["mink"]
    assert report["states"] > 50  # one clik episode of the medium scene
    assert 0.0 < ours["step_us_median"] <= ours["step_us_p90"]
    assert 0.0 < mink["step_us_median"] <= mink["step_us_p90"]
    stats = report["ratio_vs_mink_rounds"]
    assert report["ratio_vs_mink"] == stats["median"] and stats["rounds"] == report["timing"]["rounds"] == 3
    assert 0.0 < stats["min"] <= stats["median"] <= stats["max"] and stats["spread"] >= 0.0
    # the median of per-round ratios lies near the ratio of the medians
    assert report["ratio_vs_mink"] == pytest.approx(ours["step_us_median"] / mink["step_us_median"], rel=0.5)
    # the same arm against the same observed hard obstacles: the pair counts differ only by mink's own
    # adjacency rule (it also skips the column against the carriage's child, etc.)
    assert abs(ours["volume_pairs"] - mink["geom_pairs"]) <= 10 and mink["geom_pairs"] > 20
    assert [s["primitives"] for s in report["scaling"]] == [10, 30]
    assert "ratio_vs_mink" in format_ik_bench(report) and "spread" in format_ik_bench(report)
    written = json.loads(write_json(report, tmp_path / "ik.json").read_text())
    assert written["ratio_vs_mink"] == report["ratio_vs_mink"]
    assert "mink" in written["machine"]["versions"] and len(written["machine"]["load_average_start"]) == 3


def test_ik_bench_rejects_bad_options() -> None:
    with pytest.raises(EvalError, match="rounds"):
        run_ik_bench(rounds=0, progress=False)
    with pytest.raises(EvalError, match="repeats"):
        run_ik_bench(repeats=0, progress=False)
