"""Recording an episode as MP4 (ffmpeg through imageio) or GIF."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

os.environ.setdefault("MUJOCO_GL", "osmesa")  # headless by default; an explicit choice wins

import imageio.v2 as imageio  # noqa: E402
import numpy as np  # noqa: E402

from .. import make_policy  # noqa: E402
from .evaluate import EpisodeSummary, make_env, run_episode  # noqa: E402

__all__ = ["record_episode"]


def record_episode(env_id: str, policy: str, path: str | Path, *, seed: int = 0,
                   env_kwargs: dict[str, Any] | None = None, policy_kwargs: dict[str, Any] | None = None,
                   width: int = 480, height: int = 480) -> tuple[Path, EpisodeSummary]:
    """Render one episode to ``path`` (``.mp4`` or ``.gif``) at the env's control rate (real time)."""
    path = Path(path)
    if path.suffix not in (".mp4", ".gif"):
        raise ValueError(f"video path must end in .mp4 or .gif, got {path}")
    env = make_env(env_id, env_kwargs, render_mode="rgb_array", width=width, height=height)
    try:
        agent = make_policy(policy, env, **(policy_kwargs or {}))
        frames: list[np.ndarray] = []
        summary, _ = run_episode(env, agent, seed, frames=frames)
        fps = int(env.metadata.get("render_fps", 30))
    finally:
        env.close()
    path.parent.mkdir(parents=True, exist_ok=True)
    if path.suffix == ".mp4":
        imageio.mimsave(path, frames, fps=fps, macro_block_size=16)
    else:
        imageio.mimsave(path, frames[::4], duration=4.0 / fps, loop=0)
    return path, summary
