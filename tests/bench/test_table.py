"""The table of benchmarks (redundancy_gym.bench.table) that the CLI reads: one row per benchmark file, option
checks that name the benches that take an option, and the CLI's choices and help built from it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import redundancy_gym.bench as bench_package
from redundancy_gym.bench.exceptions import BenchError
from redundancy_gym.bench.table import BENCHES, OPTIONS, BenchArgs, check_bench_args
from redundancy_gym.cli import _parser

NOT_BENCHES = {"__init__", "table", "timing", "exceptions", "coal_shapes"}
"""The files of bench/ that are shared pieces, not benchmarks."""


def test_every_benchmark_file_has_a_row() -> None:
    files = {p.stem for p in Path(bench_package.__file__).parent.glob("*.py")} - NOT_BENCHES
    # ikd is the kinematic IKD study of studies/, run by the bench command
    assert files == set(BENCHES) - {"ikd"}


def test_rows_take_known_options_only() -> None:
    for entry in BENCHES.values():
        assert entry.options <= set(OPTIONS), entry.name
        assert entry.summary


def test_an_option_the_bench_does_not_take_names_the_benches_that_do() -> None:
    with pytest.raises(BenchError, match=r"--trials applies to bench push, curves only"):
        check_bench_args("ssv", BenchArgs(json_path="x.json", trials=3))
    with pytest.raises(BenchError, match=r"--rounds must be >= 1"):
        check_bench_args("ssv", BenchArgs(json_path="x.json", rounds=0))
    with pytest.raises(BenchError, match=r"unknown bench 'moon'; valid: ssv, envs"):
        check_bench_args("moon", BenchArgs(json_path="x.json"))
    assert check_bench_args("soak", BenchArgs(json_path="x.json", steps=5)).name == "soak"


def test_the_cli_offers_every_row(capsys: pytest.CaptureFixture[str]) -> None:
    parser = _parser()
    with pytest.raises(SystemExit):
        parser.parse_args(["bench", "--help"])
    out = capsys.readouterr().out
    for name in BENCHES:
        assert name in out


def test_a_table_of_some_envs_keeps_the_other_sections_of_the_same_seed_and_episodes(tmp_path) -> None:
    from redundancy_gym.bench.table import _merged

    path = tmp_path / "learned.json"
    old = {"seed": 1, "episodes": 2, "envs": {"a": {"rows": "old a"}, "b": {"rows": "old b"}}}
    path.write_text(json.dumps(old))
    new = {"seed": 1, "episodes": 2, "envs": {"b": {"rows": "new b"}, "c": {"rows": "new c"}}}
    merged = _merged(new, str(path))
    # a's section kept, b's replaced in its place, c's appended
    assert list(merged["envs"]) == ["a", "b", "c"]
    assert [s["rows"] for s in merged["envs"].values()] == ["old a", "new b", "new c"]
    # another seed or episode count: the old sections are of other episodes and are not mixed in
    assert _merged({**new, "seed": 2}, str(path))["envs"] == new["envs"]
    assert _merged({**new, "episodes": 3}, str(path))["envs"] == new["envs"]
    assert _merged(new, str(tmp_path / "missing.json")) is new
