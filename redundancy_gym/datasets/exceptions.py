"""The datasets subpackage's exceptions."""

from __future__ import annotations

__all__ = ["DatasetError"]


class DatasetError(ValueError):
    """A bad dataset argument (the message names it, its value and the valid choices), or a dataset that cannot be
    written or read (a missing Minari, an existing dataset, a folder without one)."""
