"""The backdrop every scene shares: sky box and a checkered, non-colliding floor; a look-at helper for cameras."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from dm_control import mjcf

__all__ = ["add_backdrop", "look_at_xyaxes"]


def add_backdrop(
    root: mjcf.RootElement,
    *,
    floor_size: float,
    floor_position: Sequence[float] = (0.0, 0.0, 0.0),
    floor_colors: tuple[Sequence[float], Sequence[float]],
    floor_repeat: int,
    floor_lines: Sequence[float] | None = None,
) -> None:
    """Add the sky box and a floor plane of half size ``floor_size`` [m] (visual only) to ``root``.

    The floor texture is a 2 x 2 checker of ``floor_colors``, repeated ``floor_repeat`` times along each side
    (MuJoCo's ``texrepeat``); ``floor_lines``, an RGB colour, marks the texture's edges (``mark="edge"``).
    """
    root.asset.add(
        "texture",
        name="sky",
        type="skybox",
        builtin="gradient",
        rgb1=[0.92, 0.94, 0.97],
        rgb2=[0.62, 0.68, 0.78],
        width=256,
        height=256,
    )
    marks = {} if floor_lines is None else {"mark": "edge", "markrgb": list(floor_lines)}
    grid = root.asset.add(
        "texture",
        name="grid",
        type="2d",
        builtin="checker",
        rgb1=list(floor_colors[0]),
        rgb2=list(floor_colors[1]),
        width=256,
        height=256,
        **marks,
    )
    material = root.asset.add("material", name="floor", texture=grid, texrepeat=[floor_repeat, floor_repeat])
    root.worldbody.add(
        "geom",
        name="floor",
        type="plane",
        size=[floor_size, floor_size, 0.05],
        pos=list(floor_position),
        material=material,
        contype=0,
        conaffinity=0,
    )


def look_at_xyaxes(position: Sequence[float], target: Sequence[float]) -> list[float]:
    """MJCF ``xyaxes`` of a camera at ``position`` looking at ``target`` with the image's up pointing up (+z).

    MuJoCo cameras look along their -z axis; x is the image's right, y its up.
    """
    forward = np.asarray(target, dtype=float) - np.asarray(position, dtype=float)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    if np.linalg.norm(right) < 1e-9:
        raise ValueError("look_at_xyaxes: the view direction must not be vertical")
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return [round(float(v), 6) for v in (*right, *up)]
