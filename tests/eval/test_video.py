"""record_episode: real-time playback at a reduced frame rate, MP4 and GIF."""

from __future__ import annotations

import imageio.v2 as imageio
import pytest
from PIL import Image

from redundancy_gym.eval.video import record_episode, video_stride

_PLANAR = "redundancy_gym/PlanarReach-v0"


@pytest.mark.parametrize(
    ("control_fps", "max_fps", "stride"),
    [(250.0, 50.0, 5), (100.0, 50.0, 2), (100.0, 25.0, 4), (250.0, 25.0, 10), (30.0, 50.0, 1), (60.0, 50.0, 2)],
)
def test_video_stride(control_fps: float, max_fps: float, stride: int) -> None:
    assert video_stride(control_fps, max_fps) == stride
    assert max_fps / 2.0 < control_fps / stride <= max_fps or stride == 1


def test_mp4_plays_in_real_time_at_the_reduced_rate(tmp_path) -> None:
    path, summary = record_episode(
        _PLANAR, "clik", tmp_path / "planar.mp4", env_kwargs={"obstacle": False}, width=64, height=64, progress=False
    )
    reader = imageio.get_reader(path)
    try:
        fps = reader.get_meta_data()["fps"]
        frames = reader.count_frames()
    finally:
        reader.close()
    assert fps == pytest.approx(50.0)  # the 100 Hz env rendered every 2nd step
    assert frames == summary.length // 2 + 1  # the reset frame, then every 2nd step
    assert (frames - 1) / fps == pytest.approx(summary.length * 0.01)  # frame k shows time 2 k * 10 ms


def test_gif_frame_time(tmp_path) -> None:
    path, summary = record_episode(
        _PLANAR, "clik", tmp_path / "planar.gif", env_kwargs={"obstacle": False}, width=48, height=48, progress=True
    )
    with Image.open(path) as image:
        durations = []
        for k in range(image.n_frames):  # pillow merges identical frames, adding up their times
            image.seek(k)
            durations.append(image.info["duration"])
    assert min(durations) == 40  # 25 fps: every 4th step of 10 ms
    assert sum(durations) == 40 * (summary.length // 4 + 1)


def test_bad_suffix(tmp_path) -> None:
    with pytest.raises(ValueError, match="mp4 or .gif"):
        record_episode(_PLANAR, "clik", tmp_path / "planar.avi")
