"""Speed-vs-error report: the markdown rows and the plot of the chosen error."""

from __future__ import annotations

import pytest

from redundancy_gym.eval.speed_error import plot_speed_error, speed_error_markdown


def _report(median: float, rms: float, peak: float) -> dict:
    return {"success_rate": 1.0, "collision_rate": 0.0, "task_error_rms": rms, "task_error_max": peak,
            "pseudoenergy": 0.5, "step_time_us": {"median": median, "p99": 2 * median}}


def test_markdown_has_one_row_per_policy_in_the_given_unit() -> None:
    text = speed_error_markdown({"a": _report(10.0, 0.1, 0.3), "b": _report(20.0, 0.2, 0.4)}, "T", "m/s")
    assert "task error rms [m/s]" in text
    assert "| a | 1.00 | 0.00 | 1.00e-01 | 3.00e-01 | 0.500 | 10.0 | 20.0 |" in text
    assert text.count("\n| b |") == 1


def test_plot_writes_a_png_and_rejects_an_unknown_error(tmp_path) -> None:
    path = plot_speed_error({"a": _report(10.0, 0.1, 0.3)}, tmp_path / "s.png", "T", "m/s", error="rms")
    assert path.stat().st_size > 1000
    with pytest.raises(ValueError, match="rms"):
        plot_speed_error({"a": _report(10.0, 0.1, 0.3)}, tmp_path / "t.png", "T", error="mean")
    path = plot_speed_error({"a": _report(10.0, 0.1, 0.3)}, tmp_path / "p.png", "T", error="pseudoenergy")
    assert path.stat().st_size > 1000
