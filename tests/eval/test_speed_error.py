"""Speed-vs-error report: table columns and units, the generated paragraph, the axis choice and the plot."""

from __future__ import annotations

from typing import Any

import matplotlib.pyplot as plt
import pytest

import redundancy_gym.eval.speed_error as speed_error
from redundancy_gym.eval.evaluate import evaluate
from redundancy_gym.eval.speed_error import (
    axis_scale,
    plot_speed_error,
    plot_speed_error_panels,
    speed_error_markdown,
    speed_error_paragraph,
)


def _report(
    mean_us: float,
    tracking_max: float,
    *,
    success: float = 1.0,
    median_us: float | None = None,
    first_us: float = 20.0,
    pseudoenergy: float = 0.5,
    **extra: Any,
) -> dict[str, Any]:
    """A synthetic evaluation-contract object (SI units, as ``EvalReport.to_json`` writes them)."""
    median = mean_us if median_us is None else median_us
    return {
        "env": "redundancy_gym/PlanarReach-v0",
        "env_kwargs": {"obstacle": False},
        "episodes": 5,
        "seed": 3,
        "success_rate": success,
        "collision_rate": 0.0,
        "tracking_error_rms": 0.6 * tracking_max,
        "tracking_error_max": tracking_max,
        "goal_error": 0.002,
        "time_to_goal": 1.5,
        "pseudoenergy": pseudoenergy,
        "step_time_us": {"median": median, "p99": 2.0 * median, "mean": mean_us, "first_step_mean": first_us},
        **extra,
    }


def _biped(mean_us: float, speed: float) -> dict[str, Any]:
    return {
        **_report(mean_us, 0.0),
        "env": "redundancy_gym/BipedWalk-v0",
        "env_kwargs": {"target_speed": 0.7},
        "episodes": 2,
        "seed": 0,
        "tracking_error_rms": None,
        "tracking_error_max": None,
        "goal_error": None,
        "time_to_goal": None,
        "speed_error": speed,
        "speed_error_rms": 4.0 * speed,
    }


def _table(text: str) -> list[list[str]]:
    return [[cell.strip() for cell in line.strip("|").split("|")] for line in text.splitlines() if line.startswith("|")]


def test_markdown_columns_units_and_header() -> None:
    text = speed_error_markdown(
        {"a": _report(10.0, 0.0005, first_us=12500.0), "b": _report(20.0, 0.0004)},
        "T",
        columns=("tracking_rms", "tracking_max", "goal", "time_to_goal"),
    )
    rows = _table(text)
    assert rows[0] == [
        "policy",
        "success",
        "collision",
        "tracking error rms [mm]",
        "tracking error max [mm]",
        "goal error at the end [mm]",
        "time to goal [s]",
        "pseudoenergy [rad^2/s]",
        "step time median / p99 [us]",
        "step time amortized (mean) [us]",
        "first step (plan) [ms]",
    ]
    assert rows[2] == ["a", "1.00", "0.00", "0.3", "0.5", "2.00", "1.50", "0.5", "10.0 / 20.0", "10.0", "12.5"]
    assert len(rows) == 4
    assert text.startswith("## T\n")
    assert '`redundancy_gym/PlanarReach-v0`, env kwargs `{"obstacle": false}`' in text
    assert "5 episodes per policy, seeds 3-7" in text


def test_markdown_biped_columns_in_metres_per_second() -> None:
    text = speed_error_markdown({"w": _biped(200.0, 0.05)}, "B", columns=("speed", "speed_rms"))
    head = _table(text)[0]
    assert "speed error (mean speed vs command) [m/s]" in head
    assert "speed error rms (instantaneous) [m/s]" in head
    assert "tracking error rms [mm]" not in head
    assert _table(text)[2][3:5] == ["0.05", "0.2"]
    assert "2 episodes per policy, seeds 0-1" in text


def test_paragraph_names_fastest_and_most_accurate_and_leaves_out_the_failed() -> None:
    reports = {
        "zero": _report(0.4, 0.0001, success=0.0),  # fastest and "most accurate", but failed
        "local": _report(10.0, 0.0008),
        "predictive": _report(2000.0, 0.0002),
        "global": _report(100.0, 0.0004, median_us=20.0, first_us=12000.0),
    }
    text = speed_error_paragraph(reports, ["tracking_max"])
    assert "Fastest (amortized step time, first-step plan included): **local**, 10.0 us" in text
    assert "Most accurate by tracking error max: **predictive**, 0.2 mm" in text
    assert "**predictive** takes 200.0x the amortized step time of **local**" in text
    assert "Left out as failed (success rate 0): zero." in text
    assert "**zero**" not in text
    table = speed_error_markdown(reports, "T", columns=("tracking_max",))
    assert "| zero (failed) | 0.00 |" in table
    assert "| global | 1.00 | 0.00 | 0.4 | 0.5 | 20.0 / 40.0 | 100 | 12.0 |" in table


def test_paragraph_reports_ties_within_the_tolerance() -> None:
    reports = {"a": _report(10.0, 0.000500), "b": _report(11.0, 0.000510), "c": _report(50.0, 0.000800)}
    text = speed_error_paragraph(reports, ["tracking_max", "pseudoenergy"], tolerance=0.05, time_tolerance=0.2)
    assert "**b** (11.0 us)" in text  # within 20 % of the fastest
    assert "Most accurate by tracking error max: **a** and **b** tie (0.5-0.51 mm, within 5%" in text
    assert "**a** and **b** are among the fastest as well" in text
    assert "Lowest pseudoenergy: **a**, **b** and **c** tie" in text
    assert "this metric does not separate them" in text
    assert "failed" not in text


def test_paragraph_when_every_policy_failed() -> None:
    text = speed_error_paragraph({"x": _report(1.0, 1.0, success=0.0)}, ["tracking_max"])
    assert "Every policy failed" in text and "**x**" in text


def test_axis_scale_is_log_only_for_a_wide_positive_spread() -> None:
    assert axis_scale([0.0503, 0.0506, 0.0503]) == "linear"
    assert axis_scale([1.0, 19.0]) == "linear"
    assert axis_scale([1.0, 21.0]) == "log"
    assert axis_scale([0.0, 100.0]) == "linear"  # not all positive
    assert axis_scale([]) == "linear"


def _captured_figure(monkeypatch: pytest.MonkeyPatch) -> list[Any]:
    figures: list[Any] = []
    original = speed_error.save_figure

    def capture(fig: Any, path: Any) -> Any:
        fig.tight_layout()  # as save_figure lays it out
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        fig.label_boxes = [[plt.Text.get_window_extent(t, renderer) for t in ax.texts] for ax in fig.axes]
        figures.append(fig)
        return original(fig, path)

    monkeypatch.setattr(speed_error, "save_figure", capture)
    return figures


def test_plot_small_spread_is_linear_from_zero_and_marks_failed(tmp_path, monkeypatch) -> None:
    figures = _captured_figure(monkeypatch)
    reports = {
        "compiled": _biped(220.0, 0.0503),
        "python": _biped(830.0, 0.0504),
        "broken": {**_biped(225.0, 0.0505), "success_rate": 0.0},
    }
    path = plot_speed_error(reports, tmp_path / "biped.png", "Biped", error="speed")
    assert path.is_file() and path.stat().st_size > 1000
    ax = figures[0].axes[0]
    assert ax.get_yscale() == "linear" and ax.get_ylim()[0] == 0.0
    assert ax.get_xscale() == "linear" and ax.get_xlim()[0] == 0.0
    assert "2 episodes per policy, seeds 0-1" in ax.get_title()
    assert "amortized" in ax.get_xlabel() and "[m/s]" in ax.get_ylabel()
    labels = {t.get_text() for t in ax.texts}
    assert labels == {"compiled", "python", "broken (failed)"}
    hollow = [c for c in ax.collections if c.get_label() == "broken (failed)"]
    assert len(hollow) == 1 and hollow[0].get_facecolors().size == 0
    plt.close("all")


def test_plot_wide_spread_is_log_and_labels_do_not_overlap(tmp_path, monkeypatch) -> None:
    figures = _captured_figure(monkeypatch)
    reports = {
        "zero": _report(0.3, 0.9, success=0.0),
        "dls": _report(7.0, 0.0005),
        "pinv": _report(7.1, 0.0005),
        "no limits": _report(7.2, 0.0005),
        "transpose": _report(7.0, 0.055, success=0.0),
    }
    plot_speed_error(reports, tmp_path / "free.png", "Free", error="tracking_max")
    fig = figures[0]
    ax = fig.axes[0]
    assert ax.get_xscale() == "log" and ax.get_yscale() == "log"
    boxes = fig.label_boxes[0]
    assert len(boxes) == 5
    assert not any(a.overlaps(b) for i, a in enumerate(boxes) for b in boxes[i + 1 :])
    plt.close("all")


def test_panels_and_unknown_error(tmp_path) -> None:
    reports = {"a": _report(10.0, 0.0005), "b": _report(100.0, 0.0004, pseudoenergy=0.4)}
    path = plot_speed_error_panels(
        [(reports, "P", "pseudoenergy"), (reports, "Q", "tracking_rms")], tmp_path / "p.png", "both"
    )
    assert path.stat().st_size > 1000
    with pytest.raises(ValueError, match="unknown error 'rms'.*tracking_max"):
        plot_speed_error(reports, tmp_path / "t.png", "T", error="rms")
    with pytest.raises(ValueError, match="unknown error"):
        speed_error_markdown(reports, "T", columns=("task_error_max",))
    with pytest.raises(ValueError, match="speed error"):
        plot_speed_error(reports, tmp_path / "s.png", "T", error="speed")  # no report defines it


def test_warm_evaluation_times_the_requested_seeds() -> None:
    report = evaluate(
        "redundancy_gym/PlanarReach-v0",
        "zero",
        episodes=2,
        seed=4,
        env_kwargs={"obstacle": False},
        progress=False,
        warmup=1,
    ).to_json()
    assert report["episodes"] == 2 and report["seed"] == 4
    assert [row["seed"] for row in report["per_episode"]] == [4, 5]
    assert report["step_time_us"]["steps"] == sum(row["length"] for row in report["per_episode"])
