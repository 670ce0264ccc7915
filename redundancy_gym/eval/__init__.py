"""Evaluation harness, training, plots, videos and the demo (imports gymnasium and the envs)."""

from .evaluate import EpisodeTrace, EvalReport, evaluate, format_report, make_env, run_episode
from .exceptions import EvalError

__all__ = ["EpisodeTrace", "EvalError", "EvalReport", "evaluate", "format_report", "make_env", "run_episode"]
