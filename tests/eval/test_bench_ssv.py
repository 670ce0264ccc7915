"""``redundancy-gym bench ssv`` writes per-pair times for every pair type and the ratios against coal."""

from __future__ import annotations

import json
from pathlib import Path

from redundancy_gym.cli import main
from redundancy_gym.eval.bench_ssv import PAIR_TYPES, TABLE_5_1


def test_bench_ssv_quick_writes_the_report(tmp_path: Path) -> None:
    path = tmp_path / "ssv.json"
    assert main(["bench", "ssv", "--quick", "--no-progress", "--json", str(path)]) == 0
    report = json.loads(path.read_text())
    assert set(report["per_pair_us"]) == set(PAIR_TYPES)
    for pair_type in PAIR_TYPES:
        rows = report["per_pair_us"][pair_type]
        assert set(rows) == {"1", "10", "100", "1000"}
        assert all(v > 0 for row in rows.values() for v in row.values())
        ratio = report["ratio_vs_coal_batch100"][pair_type]
        row = rows["100"]
        assert ratio == row["ours_us_per_pair"] / min(row["coal_us_per_pair"], row["coal_pinocchio_us_per_pair"])
        assert report["table_5_1"][pair_type]["monograph_rel"] == TABLE_5_1[pair_type][1]
    assert report["ratio_vs_coal_batch100_max"] == max(report["ratio_vs_coal_batch100"].values())
