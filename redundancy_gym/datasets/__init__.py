"""Demonstration datasets of the reference policies in Minari's format (the ``dataset`` extra): :func:`collect_dataset`
records a policy's episodes, :func:`load_demonstrations` reads them back as ``(observation, action)`` pairs for
behaviour cloning."""

from .collector import MINARI_EXTRA_HINT, CollectSummary, collect_dataset, import_minari
from .demonstrations import Demonstrations, find_dataset, load_demonstrations
from .exceptions import DatasetError

__all__ = [
    "MINARI_EXTRA_HINT",
    "CollectSummary",
    "DatasetError",
    "Demonstrations",
    "collect_dataset",
    "find_dataset",
    "import_minari",
    "load_demonstrations",
]
