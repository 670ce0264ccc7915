"""Exceptions of :mod:`redundancy_gym.geometry`."""

from __future__ import annotations

__all__ = ["GeometryError"]


class GeometryError(ValueError):
    """Invalid geometric input or parameters (e.g. a non-positive activation distance)."""
