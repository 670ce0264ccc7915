"""Learning: training stable-baselines3 agents (:mod:`.training`) with their training records
(:mod:`.training_record`), behaviour cloning with DAgger (:mod:`.behaviour_cloning`), the learned baselines runner
(:mod:`.baselines`) and seed sweeps (:mod:`.sweep`). Imported lazily: torch loads only when a learner is built."""

from .exceptions import LearningError
from .training_record import CpuClock, TrainingRecord, read_training_record, record_path

__all__ = ["CpuClock", "LearningError", "TrainingRecord", "read_training_record", "record_path"]
