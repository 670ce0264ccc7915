import json

import pytest

from redundancy_gym.bench.scale import amdahl_serial_fraction, amdahl_speedup, run_scale_bench
from redundancy_gym.cli import main
from redundancy_gym.eval.exceptions import EvalError


def test_amdahl_round_trip_and_bounds() -> None:
    f = amdahl_serial_fraction(1.8, 2)
    assert f == pytest.approx(1.0 / 9.0)
    assert amdahl_speedup(f, 2) == pytest.approx(1.8)
    assert amdahl_speedup(f, 64) == pytest.approx(1.0 / (f + (1.0 - f) / 64))
    assert amdahl_serial_fraction(2.5, 2) == 0.0 and amdahl_serial_fraction(0.5, 2) == 1.0  # clipped
    with pytest.raises(EvalError, match="n >= 2"):
        amdahl_serial_fraction(1.0, 1)


def test_a_quick_run_measures_every_part() -> None:
    report = run_scale_bench(
        workers=(2,), episodes=2, rounds=1, cases=("agri_reach",), num_envs=(1, 2), vec_steps=5, progress=False
    )
    row = report["eval"]["agri_reach"]
    assert row["workers"]["2"]["episodes_per_second"] > 0 and row["workers"]["2"]["serial_episodes_per_second"] > 0
    assert 0.0 <= row["serial_fraction"] <= 1.0 and row["predicted_speedup_64"] >= 1.0
    assert set(report["make_vec"]["sync"]) == {"1", "2"} and min(report["make_vec"]["async"].values()) > 0
    assert report["machine"]["cores"] >= 1 and len(report["machine"]["load_average"]) == 3
    with pytest.raises(EvalError, match="workers must each be >= 2"):
        run_scale_bench(workers=(1,), progress=False)


def test_cli_quick(tmp_path) -> None:
    path = tmp_path / "scale.json"
    assert main(["bench", "scale", "--quick", "--episodes", "2", "--json", str(path), "--no-progress"]) == 0
    assert set(json.loads(path.read_text())["eval"]) == {"agri_reach", "biped_walk"}
