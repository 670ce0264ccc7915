"""``redundancy-gym bench ssv`` writes per-pair times for every pair type and the ratios against coal, as medians
over alternating rounds with their spread."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from redundancy_gym.bench.ssv import PAIR_TYPES, TABLE_5_1, format_ssv_bench, run_ssv_bench
from redundancy_gym.cli import main
from redundancy_gym.eval.exceptions import EvalError


def test_bench_ssv_quick_writes_the_report(tmp_path: Path) -> None:
    path = tmp_path / "ssv.json"
    assert main(["bench", "ssv", "--quick", "--rounds", "3", "--no-progress", "--json", str(path)]) == 0
    report = json.loads(path.read_text())
    assert set(report["per_pair_us"]) == set(PAIR_TYPES)
    assert report["timing"]["rounds"] == 3 and report["timing"]["warmup"] == 1
    for pair_type in PAIR_TYPES:
        rows = report["per_pair_us"][pair_type]
        assert set(rows) == {"1", "10", "100", "1000"}
        assert all(v > 0 for row in rows.values() for v in row.values())
        ratio = report["ratio_vs_coal_batch100"][pair_type]
        stats = report["ratio_vs_coal_batch100_rounds"][pair_type]
        # the median of the per-round ratios against the faster coal variant, bounded by its rounds
        assert stats["median"] == ratio and stats["rounds"] == 3
        assert 0.0 < stats["min"] <= ratio <= stats["max"]
        assert stats["spread"] == pytest.approx((stats["max"] - stats["min"]) / ratio)
        assert report["table_5_1"][pair_type]["monograph_rel"] == TABLE_5_1[pair_type][1]
    assert report["ratio_vs_coal_batch100_max"] == max(report["ratio_vs_coal_batch100"].values())
    machine = report["machine"]
    assert len(machine["load_average_start"]) == 3 and len(machine["load_average_end"]) == 3
    assert "coal" in machine["versions"] and machine["cpu_count"] >= 1
    assert "(" in format_ssv_bench(report)  # the round range beside each ratio


def test_bench_ssv_rejects_bad_options() -> None:
    with pytest.raises(EvalError, match="rounds"):
        run_ssv_bench(rounds=0, progress=False)
    with pytest.raises(EvalError, match="min_time"):
        run_ssv_bench(min_time=0.0, progress=False)
    with pytest.raises(EvalError, match="100"):
        run_ssv_bench(batch_sizes=(1, 10), progress=False)


@pytest.mark.parametrize("argv", [["bench", "soak", "--rounds", "3"], ["bench", "ssv", "--rounds", "0"]])
def test_cli_rounds_option_is_checked(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2 and "--rounds" in capsys.readouterr().err
