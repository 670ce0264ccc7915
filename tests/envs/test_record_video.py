"""Gymnasium's own RecordVideo on our env with only the documented extras (``video``: MoviePy): a real episode
written as an MP4 whose frames decode."""

from __future__ import annotations

import gymnasium as gym
import imageio.v3 as iio
from gymnasium.wrappers import RecordVideo

import redundancy_gym  # noqa: F401 - registers the envs


def test_record_video_writes_an_episode(tmp_path):
    env = gym.make("redundancy_gym/PlanarReach-v0", render_mode="rgb_array", width=96, height=64, max_episode_steps=12)
    env = RecordVideo(env, str(tmp_path), episode_trigger=lambda episode: True, disable_logger=True)
    env.reset(seed=0)
    done = False
    while not done:
        _, _, terminated, truncated, _ = env.step(env.action_space.sample() * 0.0)
        done = terminated or truncated
    env.close()
    (video,) = tmp_path.glob("*.mp4")
    frames = iio.imread(video)
    assert frames.shape[0] >= 12 and frames.shape[1:3] == (64, 96)  # the reset's frame and each step's
    assert frames.std() > 0.0  # a rendered scene, not a blank frame
