"""``bench push``: trials, the level bookkeeping, the report's figures and its plot."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

from redundancy_gym.bench.push import (
    DIRECTIONS,
    RECOVERY_TARGET,
    format_push_bench,
    plot_push_bench,
    push_trial,
    run_push_bench,
)
from redundancy_gym.eval.exceptions import EvalError


def test_a_tiny_push_is_recovered_and_a_huge_one_is_not() -> None:
    assert push_trial(2.0, (0.0, 1.0), 2.0, 0)[0]
    recovered, when = push_trial(60.0, (0.0, 1.0), 2.0, 0)
    assert not recovered and 2.0 < when < 5.0  # it falls after the push, before the trial's end


def test_report_levels_and_figures_are_consistent(tmp_path) -> None:
    report = run_push_bench(trials=2, impulses=(5.0, 60.0), progress=False)
    assert report["trials_per_level"] == 2 and report["impulses"] == [5.0, 60.0]
    for name in ("step_adjustment", "baseline"):
        for direction in DIRECTIONS:
            result = report["results"][name][direction]
            rows = result["levels"]
            held = [row["impulse"] for row in rows if row["holds"]]
            assert result["impulse_recovered"] == (held[-1] if held else 0.0)
            for row in rows:  # a level holds when >= 90 % of its trials recover; it stops at the first fall too many
                assert row["holds"] == (row["recovered"] >= RECOVERY_TARGET * report["trials_per_level"])
                assert len(row["falls"]) == row["trials_run"] - row["recovered"]
            assert rows[0]["holds"] and not rows[-1]["holds"]  # 5 N s is nothing, 60 N s throws it over
    assert report["lateral_impulse_recovered"] == report["results"]["step_adjustment"]["lateral"]["impulse_recovered"]
    assert report["baseline_forward_impulse_recovered"] == report["results"]["baseline"]["forward"]["impulse_recovered"]
    json.dumps(report)
    assert "recovered up to 5 N s" in format_push_bench(report)
    path = plot_push_bench(report, str(tmp_path / "push.png"))
    assert (tmp_path / "push.png").stat().st_size > 10_000 and path.endswith("push.png")


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"trials": 0}, "trials"),
        ({"trials": True}, "trials"),
        ({"impulses": (10.0, 5.0)}, "impulses"),
        ({"impulses": ()}, "impulses"),
        ({"impulses": (float("nan"),)}, "impulses"),
    ],
)
def test_bad_arguments_raise(kwargs: dict, match: str) -> None:
    with pytest.raises(EvalError, match=match):
        run_push_bench(progress=False, **kwargs)


def test_cli_rejects_trials_for_other_benches() -> None:
    result = subprocess.run(
        [sys.executable, "-m", "redundancy_gym.cli", "bench", "ssv", "--trials", "3"], capture_output=True, text=True
    )
    assert result.returncode == 2 and "--trials applies to bench push, curves only" in result.stderr
