"""TrainingRecord: what a training run cost and what it ran, saved beside its model (``NAME.zip`` ->
``NAME.json``) so that the learned-baselines table (``redundancy-gym bench learned``) can report the training steps
and CPU time of every shipped model without training it again."""

from __future__ import annotations

import json
import os
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from .exceptions import LearningError

__all__ = ["CpuClock", "TrainingRecord", "machine", "read_training_record", "record_path"]


@dataclass(frozen=True)
class TrainingRecord:
    """One training run.

    Attributes:
        learner: ``ppo``, ``sac`` or ``bc``.
        env_id: the env trained on (a wrapped id for a wrapper's action).
        env_steps: environment steps taken while training (for behaviour cloning: the expert's and the learner's
            rollouts of every round).
        wall_s: wall-clock time of the run [s].
        cpu_s: CPU time of the run [s], over all threads of this process and of its finished child processes
            (``SubprocVecEnv`` workers).
        seed: the run's seed.
        settings: the learner's settings (hyperparameters, budget, env kwargs) as text, for the record.
        machine: processor, core count and Python version of the machine it ran on.
        result: the learner's own end-of-training statistics (recent return and success; for behaviour cloning the
            action loss and the learner's success per DAgger round).
    """

    learner: str
    env_id: str
    env_steps: int
    wall_s: float
    cpu_s: float
    seed: int
    settings: dict[str, Any] = field(default_factory=dict)
    machine: dict[str, Any] = field(default_factory=dict)
    result: dict[str, Any] = field(default_factory=dict)

    def write(self, model_path: str | Path) -> Path:
        """Write the record beside ``model_path`` (``record_path``); returns its path."""
        path = record_path(model_path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(asdict(self), indent=2, default=_text) + "\n")
        return path


def _text(value: Any) -> str:
    return repr(value)


def record_path(model_path: str | Path) -> Path:
    """Where the record of ``model_path`` lives: the same name with ``.json`` instead of ``.zip``."""
    path = Path(model_path)
    return path.with_suffix(".json") if path.suffix == ".zip" else path.with_name(path.name + ".json")


def read_training_record(model_path: str | Path) -> TrainingRecord | None:
    """The record beside ``model_path``, or None when there is none.

    Raises:
        LearningError: the record exists but is not a training record.
    """
    path = record_path(model_path)
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text())
        return TrainingRecord(**data)
    except (OSError, ValueError, TypeError) as exc:
        raise LearningError(f"{path} is not a training record: {exc}") from None


def machine() -> dict[str, Any]:
    """Processor model, logical cores and Python version of this machine (from the benches' ``machine_info``)."""
    from ..eval.machine import machine_info

    info = machine_info()
    out = {"processor": info["processor"], "cores": info["cpu_count"], "python": info["python"]}
    if "cpu_model" in info:
        out["cpu_model"] = info["cpu_model"]
    return out


class CpuClock:
    """Wall and CPU time of a block (``with CpuClock() as clock: ...``; then ``clock.wall_s``, ``clock.cpu_s``).

    CPU time counts every thread of this process and the finished child processes (``os.times``), so a
    ``SubprocVecEnv``'s workers count once they have been closed inside the block.
    """

    def __init__(self) -> None:
        self.wall_s = 0.0
        self.cpu_s = 0.0

    @staticmethod
    def _cpu() -> float:
        t = os.times()
        return t.user + t.system + t.children_user + t.children_system

    def __enter__(self) -> CpuClock:
        self._wall0, self._cpu0 = time.perf_counter(), self._cpu()
        return self

    def __exit__(self, *exc: Any) -> None:
        self.wall_s = time.perf_counter() - self._wall0
        self.cpu_s = self._cpu() - self._cpu0
