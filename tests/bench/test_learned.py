"""bench learned: every analytic reference and every shipped model of an env on the same held-out episodes; the
markdown names what to pick only among policies that succeed, and the plot tells learned from analytic."""

import json

import pytest

from redundancy_gym.bench.learned import LEARNED_SETTINGS, _picks, _setting, learned_markdown, run_learned_bench
from redundancy_gym.cli import main
from redundancy_gym.learning.baselines import baselines


def _report(success: float, collision: float, median_us: float, tracking_m: float) -> dict:
    return {
        "success_rate": success,
        "collision_rate": collision,
        "tracking_error_rms": tracking_m,
        "step_time_us": {"median": median_us, "p99": 2 * median_us, "mean": median_us},
        "pseudoenergy": 1.0,
    }


def test_picks_only_among_policies_that_succeed_and_break_accuracy_ties_by_speed() -> None:
    setting = _setting("planar_reach")
    rows = {
        "fast but failing": {"kind": "learned", "report": _report(0.5, 0.5, 1.0, 1e-4)},
        "slow exact": {"kind": "analytic", "report": _report(1.0, 0.0, 500.0, 1.00e-3)},
        "quick exact": {"kind": "analytic", "report": _report(1.0, 0.0, 50.0, 1.03e-3)},  # within 5 %: a tie
        "fastest good": {"kind": "learned", "report": _report(0.97, 0.0, 10.0, 5e-3)},
    }
    text = _picks(setting, rows)
    assert "For speed pick **fastest good**" in text
    assert "For accuracy pick **quick exact**" in text and "slow exact is as accurate" in text
    assert "fast but failing (success 0.50, collision 0.50)" in text
    assert "match the references' success: fastest good" in text


def test_planar_reach_table_holds_every_reference_and_shipped_model(tmp_path) -> None:
    table = run_learned_bench(episodes=1, envs=["planar_reach"], progress=False, log=None)
    env = table["envs"]["planar_reach"]
    setting = LEARNED_SETTINGS[0]
    shipped = [b for b in baselines() if b.name.endswith("-planar_reach") and b.model.is_file()]
    assert list(env["rows"]) == list(setting.references) + [b.short_name for b in shipped]
    for b in shipped:
        row = env["rows"][b.short_name]
        assert row["kind"] == "learned" and row["report"]["env"] == b.env_id
        assert row["report"]["seed"] == 20000 and row["report"]["env_kwargs"] == {"obstacle": True}
        assert row["training"]["env_steps"] > 0 and row["training"]["cpu_s"] > 0
    for label in setting.references:
        assert env["rows"][label]["kind"] == "analytic" and "training" not in env["rows"][label]
    text = learned_markdown(table)
    for label in env["rows"]:
        assert f"| {label} |" in text
    assert "For speed pick" in text and "For accuracy pick" in text


def test_cli_writes_json_markdown_and_one_plot_per_env(tmp_path, capsys) -> None:
    path = tmp_path / "learned.json"
    assert (
        main(
            [
                "bench",
                "learned",
                "--envs",
                "planar_reach",
                "--episodes",
                "2",
                "--seed",
                "21000",
                "--json",
                str(path),
                "--no-progress",
                "--workers",
                "2",
            ]
        )
        == 0
    )
    data = json.loads(path.read_text())
    assert data["seed"] == 21000 and data["episodes"] == 2 and set(data["envs"]) == {"planar_reach"}
    assert (tmp_path / "learned.md").read_text().startswith("# Learned baselines")
    assert (tmp_path / "learned_planar_reach.png").stat().st_size > 10_000
    capsys.readouterr()
    with pytest.raises(SystemExit):
        main(["bench", "ssv", "--episodes", "3"])
    assert "--episodes applies to bench learned, robustness, curves, scale only" in capsys.readouterr().err


def test_unknown_env_is_named() -> None:
    with pytest.raises(Exception, match="unknown env 'moon' for bench learned; valid: planar_reach"):
        run_learned_bench(episodes=1, envs=["moon"], progress=False, log=None)
