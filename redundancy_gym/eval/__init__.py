"""The evaluation harness: evaluate and run episodes (serial, parallel, on Ray), the eval metrics, videos, plots,
the speed-vs-error report, the machine record and the one JSON writer (imports gymnasium and the envs).

Training, behaviour cloning and the baselines runner live in :mod:`redundancy_gym.learning`; the monograph-figure
studies in :mod:`redundancy_gym.studies`; the benchmarks in :mod:`redundancy_gym.bench`.
"""

from .._moved import forward_attributes
from .evaluate import EpisodeTrace, EvalReport, evaluate, format_report, make_env, reseed_policy, run_episode
from .exceptions import EvalError
from .json_writer import write_json
from .machine import finish_machine_info, machine_info
from .parallel import EpisodeFailure, ParallelEvalError

__all__ = [
    "EpisodeFailure",
    "EpisodeTrace",
    "EvalError",
    "EvalReport",
    "ParallelEvalError",
    "evaluate",
    "finish_machine_info",
    "format_report",
    "machine_info",
    "make_env",
    "reseed_policy",
    "run_episode",
    "write_json",
]

# moved to redundancy_gym.learning in 0.2 (the old names warn and go in 0.3)
__getattr__ = forward_attributes(
    __name__,
    {
        "TrainingRecord": "redundancy_gym.learning.training_record",
        "read_training_record": "redundancy_gym.learning.training_record",
    },
)
