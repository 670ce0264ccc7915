"""Evaluation harness, training, plots, videos and the demo (imports gymnasium and the envs)."""

from .evaluate import EpisodeTrace, EvalReport, evaluate, format_report, make_env, reseed_policy, run_episode
from .exceptions import EvalError
from .parallel import EpisodeFailure, ParallelEvalError
from .training_record import TrainingRecord, read_training_record

__all__ = ["EpisodeFailure", "EpisodeTrace", "EvalError", "EvalReport", "ParallelEvalError", "TrainingRecord",
           "evaluate", "format_report", "make_env", "read_training_record", "reseed_policy", "run_episode"]
