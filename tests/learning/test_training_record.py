import json
import time

import pytest

from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.learning.training_record import CpuClock, TrainingRecord, read_training_record, record_path


def test_cpu_clock_counts_busy_time_not_sleep() -> None:
    # the busy loop runs until the process has used 0.2 s of CPU (not of wall time), so a loaded machine that
    # preempts it stretches its wall time but not what the clock must count
    with CpuClock() as busy:
        end = time.process_time() + 0.2
        while time.process_time() < end:
            pass
    with CpuClock() as idle:
        time.sleep(0.2)
    assert idle.wall_s >= 0.2 and busy.wall_s >= busy.cpu_s - 0.02
    # os.times ticks in 10 ms steps; a sleep uses next to no CPU
    assert busy.cpu_s >= 0.18 and idle.cpu_s < 0.05


def test_record_round_trip_beside_the_model(tmp_path) -> None:
    model = tmp_path / "ppo-joint-x.zip"
    record = TrainingRecord(
        learner="ppo",
        env_id="redundancy_gym/PlanarReach-v0",
        env_steps=1000,
        wall_s=2.0,
        cpu_s=1.5,
        seed=3,
        settings={"schedule": object()},
        result={"recent_success": 1.0},
    )
    assert record.write(model) == tmp_path / "ppo-joint-x.json" == record_path(model)
    back = read_training_record(model)
    assert back is not None and back.env_steps == 1000 and back.cpu_s == 1.5 and back.seed == 3
    assert back.settings["schedule"].startswith("<object")  # what JSON cannot hold is kept as its repr
    assert read_training_record(tmp_path / "other.zip") is None


def test_a_file_that_is_not_a_record_is_named(tmp_path) -> None:
    (tmp_path / "m.json").write_text(json.dumps({"learner": "ppo"}))
    with pytest.raises(EvalError, match="m.json is not a training record"):
        read_training_record(tmp_path / "m.zip")
