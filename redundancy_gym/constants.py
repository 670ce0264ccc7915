"""Physical constants shared by the controllers and the envs, defined once."""

from __future__ import annotations

__all__ = ["GRAVITY"]

GRAVITY = 9.81
"""Gravitational acceleration [m/s^2]: the magnitude of MuJoCo's default gravity ``0 0 -9.81``, which every MJCF
keeps."""
