"""Recording an episode as MP4 (ffmpeg through imageio) or GIF."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import gymnasium as gym
import imageio.v2 as imageio
import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from .. import make_policy
from .evaluate import EpisodeSummary, make_env, run_episode

__all__ = ["GIF_FPS", "MP4_MAX_FPS", "record_episode", "video_stride"]

MP4_MAX_FPS = 50.0
"""Highest frame rate of an MP4 [1/s]: faster envs (BipedWalk's 250 Hz) are rendered every n-th step."""
GIF_FPS = 25.0
"""Frame rate a GIF aims at [1/s] (GIF frame times are whole centiseconds)."""


def video_stride(control_fps: float, max_fps: float) -> int:
    """The smallest ``n`` such that rendering every ``n``-th control step gives at most ``max_fps`` frames/s.

    The video's frame rate is then ``control_fps / n`` (above ``max_fps / 2`` when ``n > 1``): playback stays
    real time.
    """
    if control_fps <= 0.0 or max_fps <= 0.0:
        raise ValueError(f"frame rates must be positive, got {control_fps} and {max_fps}")
    return max(1, int(np.ceil(control_fps / max_fps - 1e-9)))


class _EveryNthRender(gym.Wrapper):
    """Renders only every ``stride``-th ``render()`` call (the first one included); the others return ``None``."""

    def __init__(self, env: gym.Env, stride: int) -> None:
        super().__init__(env)
        self._stride = stride
        self._calls = 0

    def render(self) -> Any:
        render = self._calls % self._stride == 0
        self._calls += 1
        return self.env.render() if render else None


class _FrameSink(list):
    """Stands in for ``run_episode``'s frame list: writes each rendered frame to the video as it comes (a 10 s
    walk at 640 x 480 would hold 2.3 GB of frames) and advances the progress bar once per control step."""

    def __init__(self, writer: Any, bar: Any) -> None:
        super().__init__()
        self._writer = writer
        self._bar = bar
        self.written = 0

    def append(self, frame: NDArray[np.uint8] | None) -> None:
        if frame is not None:
            self._writer.append_data(frame)
            self.written += 1
        self._bar.update(1)


def record_episode(
    env_id: str,
    policy: str,
    path: str | Path,
    *,
    seed: int = 0,
    env_kwargs: dict[str, Any] | None = None,
    policy_kwargs: dict[str, Any] | None = None,
    width: int | None = None,
    height: int | None = None,
    max_fps: float | None = None,
    progress: bool = True,
) -> tuple[Path, EpisodeSummary]:
    """Render one episode to ``path`` (``.mp4`` or ``.gif``), played back in real time.

    Frames are taken every ``n``-th control step, ``n`` the smallest stride that keeps the video at or below
    ``max_fps`` (default :data:`MP4_MAX_FPS` for MP4, :data:`GIF_FPS` for GIF); the file's frame rate is the
    control rate divided by ``n``. Frames are encoded while the episode runs.

    Args:
        env_id, policy, seed, env_kwargs, policy_kwargs: as for :func:`redundancy_gym.eval.evaluate.evaluate`.
        path: the video file; its suffix picks the format.
        width, height: frame size [px] (MP4 wants multiples of 16); default: the env's (480 x 480 for the arms,
            640 x 480 for the biped).
        max_fps: highest video frame rate [1/s].
        progress: show a progress bar over the episode's control steps while rendering.
    """
    path = Path(path)
    if path.suffix not in (".mp4", ".gif"):
        raise ValueError(f"video path must end in .mp4 or .gif, got {path}")
    if max_fps is None:
        max_fps = MP4_MAX_FPS if path.suffix == ".mp4" else GIF_FPS
    size = {key: value for key, value in (("width", width), ("height", height)) if value is not None}
    env = make_env(env_id, env_kwargs, render_mode="rgb_array", **size)
    try:
        agent = make_policy(policy, env, **(policy_kwargs or {}))
        control_fps = float(env.metadata.get("render_fps", 30))
        stride = video_stride(control_fps, max_fps)
        fps = control_fps / stride
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix == ".mp4":
            writer = imageio.get_writer(path, fps=fps, macro_block_size=16)
        else:  # pillow takes the frame time in ms and stores it in centiseconds
            writer = imageio.get_writer(path, mode="I", duration=1000.0 / fps, loop=0)
        steps = env.spec.max_episode_steps if env.spec is not None else None
        bar = tqdm(
            total=None if steps is None else steps + 1,
            desc=f"render {path.name} ({fps:g} fps)",
            unit="step",
            disable=not progress,
            leave=False,
        )
        try:
            sink = _FrameSink(writer, bar)
            summary, _ = run_episode(_EveryNthRender(env, stride), agent, seed, frames=sink)
            bar.set_description(f"encode {path.name}")
        finally:
            writer.close()
            bar.close()
    finally:
        env.close()
    return path, summary
