import json

import pytest

from redundancy_gym.bench import scale
from redundancy_gym.bench.scale import amdahl_serial_fraction, amdahl_speedup, run_scale_bench, without_timings
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
    assert row["workers"]["2"]["json_equal"] is True and row["json_equal"] is True and report["json_equal"] is True
    others = row["workers"]["2"]["others_cores"]
    assert others is None or 0.0 <= others <= report["machine"]["cores"]
    assert set(report["make_vec"]["sync"]) == {"1", "2"} and min(report["make_vec"]["async"].values()) > 0
    assert report["machine"]["cores"] >= 1 and len(report["machine"]["load_average"]) == 3
    with pytest.raises(EvalError, match="workers must each be >= 2"):
        run_scale_bench(workers=(1,), progress=False)


def test_cli_quick(tmp_path) -> None:
    path = tmp_path / "scale.json"
    assert main(["bench", "scale", "--quick", "--episodes", "2", "--json", str(path), "--no-progress"]) == 0
    report = json.loads(path.read_text())
    assert set(report["eval"]) == {"agri_reach", "agri_reach_1000", "biped_walk"} and report["json_equal"] is True


def _contract(success: float, step_us: float, first_us: float, length: int = 10) -> dict:
    return {
        "success_rate": success,
        "step_time_us": {"median": step_us},
        "sb3_predict_us": {"median": 2 * step_us},
        "compute_time_per_episode_ms": step_us * 1e-3,
        "per_episode": [{"seed": 0, "length": length, "first_step_us": first_us}],
    }


def test_the_json_check_ignores_timings_only() -> None:
    assert without_timings(_contract(1.0, 5.0, 9.0)) == without_timings(_contract(1.0, 6.0, 8.0))
    assert without_timings(_contract(1.0, 5.0, 9.0)) != without_timings(_contract(0.5, 5.0, 9.0))
    assert without_timings(_contract(1.0, 5.0, 9.0)) != without_timings(_contract(1.0, 5.0, 9.0, length=11))
    assert without_timings(_contract(1.0, 5.0, 9.0)) == {
        "success_rate": 1.0,
        "per_episode": [{"seed": 0, "length": 10}],
    }


class _NoBar:
    def update(self, n: int) -> None:
        pass


def test_a_parallel_json_that_differs_in_one_round_is_reported() -> None:
    calls = []

    def run(workers: int, ray_address: str | None) -> tuple[float, dict, float | None]:
        calls.append(workers)
        odd = workers == 2 and len(calls) == 4  # the second round's parallel run
        return (2.0 if workers == 2 else 1.0), _contract(0.5 if odd else 1.0, float(len(calls)), 1.0), None

    row = scale._speedup_rounds(run, 2, None, 3, _NoBar())
    assert calls == [1, 2, 1, 2, 1, 2] and row["json_equal"] is False and row["speedup"] == 2.0
    assert row["others_cores"] is None
    same = scale._speedup_rounds(lambda w, a: (1.0, _contract(1.0, 1.0, 1.0), 0.25), 2, None, 2, _NoBar())
    assert same["json_equal"] is True and same["others_cores"] == 0.25
