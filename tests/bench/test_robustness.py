"""bench robustness: every reference under the dynamics randomization's level and latency; the table says where each
reference breaks, a matched-latency row runs only where there is a latency, and the figure is written."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from redundancy_gym.bench.exceptions import BenchError
from redundancy_gym.bench.robustness import (
    CONDITIONS,
    ROBUSTNESS_SETTINGS,
    _breaks,
    plot_robustness_bench,
    robustness_markdown,
    run_robustness_bench,
)
from redundancy_gym.cli import main


def _conditions(*labels: str) -> list:
    return [c for c in CONDITIONS if c.label in labels]


def test_the_latency_breaks_the_clik_only_without_its_compensation(tmp_path: Path) -> None:
    """PlanarReach's 1 mm tolerance: two periods of latency fail the CLIK without latency compensation (its tracking
    error about doubles); measuring the latency from rest, its Smith predictor keeps it within the tolerance."""
    table = run_robustness_bench(
        episodes=1,
        envs=["planar_reach"],
        conditions=_conditions("nominal", "latency 2"),
        progress=False,
        log=None,
        seed=761000,
    )
    rows = table["envs"]["planar_reach"]["rows"]
    plain, measured = rows["clik, latency=0 (no latency compensation)"], rows["clik"]
    assert plain["nominal"]["success_rate"] == 1.0 and plain["latency 2"]["success_rate"] == 0.0
    assert plain["latency 2"]["tracking_max"] > 1.0 > measured["latency 2"]["tracking_max"]  # [mm]
    assert measured["latency 2"]["success_rate"] == 1.0
    assert plain["nominal"]["tracking_max"] == measured["nominal"]["tracking_max"]  # nothing to compensate
    assert plain["latency 2"]["failed_seeds"] == [761000]
    text = robustness_markdown(table)
    assert "**clik**: model error: holds through nominal; latency: holds through latency 2" in text
    assert "compensation)**: model error: holds through nominal; latency: breaks at latency 2 (success 0.00" in text
    (written,) = plot_robustness_bench(table, tmp_path)
    assert written.name == "robustness_planar_reach.png" and written.stat().st_size > 10_000


def test_breaks_names_the_first_failing_condition_along_each_axis() -> None:
    conditions = [c.__dict__ for c in CONDITIONS]
    cells = {c["label"]: {"success_rate": 1.0, "fall_rate": 0.0} for c in conditions}
    cells["level 0.1"] = {"success_rate": 0.9, "fall_rate": 0.0}
    cells["level 0.2"] = {"success_rate": 1.0, "fall_rate": 0.1}  # after the first break: not named
    cells["dynamics=0.2"] = {"success_rate": 1.0, "fall_rate": 0.05}
    env = {"rows": {"walking": cells}, "rate": "fall_rate"}
    text = _breaks(env, "walking", conditions)
    assert "model error: breaks at level 0.1 (success 0.90, fall rate 0.00)" in text
    assert "latency: holds through latency 2" in text
    assert "the level shorthand: breaks at dynamics=0.2 (success 1.00, fall rate 0.05)" in text
    # below the threshold on the nominal plant: judged against its own nominal figures
    cells = {c["label"]: {"success_rate": 0.9, "fall_rate": 0.0} for c in conditions}
    cells["latency 2"] = {"success_rate": 0.8, "fall_rate": 0.0}
    env = {"rows": {"walking": cells}, "rate": "fall_rate"}
    text = _breaks(env, "walking", conditions)
    assert "below the threshold on the nominal plant already (success 0.90, fall rate 0.00" in text
    assert "model error: holds through level 0.2; latency: breaks at latency 2 (success 0.80" in text


def test_every_setting_has_references_and_known_errors() -> None:
    assert [s.key for s in ROBUSTNESS_SETTINGS] == ["planar_reach", "agri_reach", "biped_walk", "biped_obstacles"]
    walkers = {label for s in ROBUSTNESS_SETTINGS if s.rate == "fall_rate" for label in s.references}
    assert walkers == {"walking", "walking (IKD)"}
    levels = [c.x for c in CONDITIONS if c.axis == "level"]
    latencies = [c.x for c in CONDITIONS if c.axis == "latency"]
    assert levels == [0.0, 0.05, 0.1, 0.2] and latencies == [1.0, 2.0]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [({"episodes": 0}, "episodes must be an int >= 1"), ({"envs": ["moon"]}, "unknown env 'moon'.*planar_reach")],
)
def test_bad_arguments_are_named(kwargs: dict, match: str) -> None:
    with pytest.raises(BenchError, match=match):
        run_robustness_bench(progress=False, log=None, **kwargs)


def test_cli_writes_json_markdown_and_figure(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "bench_robustness.json"
    code = main(
        ["bench", "robustness", "--episodes", "1", "--envs", "planar_reach", "--json", str(path), "--no-progress"]
    )
    assert code == 0
    table = json.loads(path.read_text())
    assert [c["label"] for c in table["conditions"]] == [c.label for c in CONDITIONS]
    assert set(table["envs"]) == {"planar_reach"}
    assert path.with_suffix(".md").read_text().startswith("# The references on plants that differ from their model")
    assert (tmp_path / "bench_robustness_planar_reach.png").is_file()
    assert "clik, latency=0 (no latency compensation)" in capsys.readouterr().out
