"""The backdrop every scene shares: sky box and a checkered, non-colliding floor."""

from __future__ import annotations

from collections.abc import Sequence

from dm_control import mjcf

__all__ = ["add_backdrop"]


def add_backdrop(root: mjcf.RootElement, *, floor_size: float, floor_position: Sequence[float] = (0.0, 0.0, 0.0),
                 floor_colors: tuple[Sequence[float], Sequence[float]], floor_repeat: int) -> None:
    """Add the sky box and a floor plane of half size ``floor_size`` [m] (visual only) to ``root``."""
    root.asset.add("texture", name="sky", type="skybox", builtin="gradient", rgb1=[0.92, 0.94, 0.97],
                   rgb2=[0.62, 0.68, 0.78], width=256, height=256)
    grid = root.asset.add("texture", name="grid", type="2d", builtin="checker", rgb1=list(floor_colors[0]),
                          rgb2=list(floor_colors[1]), width=256, height=256)
    material = root.asset.add("material", name="floor", texture=grid, texrepeat=[floor_repeat, floor_repeat])
    root.worldbody.add("geom", name="floor", type="plane", size=[floor_size, floor_size, 0.05],
                       pos=list(floor_position), material=material, contype=0, conaffinity=0)
