"""The default render cameras show the work: the biped lit on a textured floor and in frame wherever it walks,
AgriReach's target pepper, arm and plants in frame (projected with MuJoCo's camera pose and field of view)."""

from __future__ import annotations

import gymnasium as gym
import mujoco
import numpy as np
import pytest
from numpy.typing import NDArray

import redundancy_gym  # noqa: F401 - registers the ids

WIDTH, HEIGHT = 320, 240


def _project(
    model: mujoco.MjModel, data: mujoco.MjData, camera: str, points: NDArray[np.float64], width: int, height: int
) -> NDArray[np.float64]:
    """Pixel (column, row) of world ``points`` (N, 3) in ``camera``'s image; NaN behind the camera."""
    cam = model.camera(camera).id
    rotation = data.cam_xmat[cam].reshape(3, 3)  # columns: image right, image up, backwards
    local = (np.atleast_2d(points) - data.cam_xpos[cam]) @ rotation
    depth = -local[:, 2]
    focal = 0.5 * height / np.tan(np.deg2rad(model.cam_fovy[cam]) / 2.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        pixels = np.column_stack(
            [0.5 * width + focal * local[:, 0] / depth, 0.5 * height - focal * local[:, 1] / depth]
        )
    pixels[depth <= 0.0] = np.nan
    return pixels


def _inside(pixels: NDArray[np.float64], width: int, height: int, margin: float = 0.0) -> NDArray[np.bool_]:
    col, row = pixels[:, 0], pixels[:, 1]
    return (
        (col >= margin * width)
        & (col <= (1 - margin) * width)
        & (row >= margin * height)
        & (row <= (1 - margin) * height)
    )


def test_projection_matches_the_renderer() -> None:
    """The helper's pixel of the biped's head is where the renderer draws it (segmentation image)."""
    env = gym.make("redundancy_gym/BipedWalk-v0", render_mode="rgb_array", width=WIDTH, height=HEIGHT)
    env.reset(seed=0)
    u = env.unwrapped
    geom = u.model.geom("head_geom").id
    segmenter = mujoco.Renderer(u.model, HEIGHT, WIDTH)
    try:
        segmenter.enable_segmentation_rendering()
        segmenter.update_scene(u.data, camera="track")
        seg = segmenter.render()
    finally:
        segmenter.close()
    rows, cols = np.nonzero((seg[..., 0] == geom) & (seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM)))
    assert rows.size > 20
    col, row = _project(u.model, u.data, "track", u.data.geom_xpos[geom], WIDTH, HEIGHT)[0]
    assert abs(col - cols.mean()) < 4.0 and abs(row - rows.mean()) < 4.0
    env.close()


@pytest.mark.parametrize("forward", [0.0, 5.0, 30.0])
def test_biped_camera_tracks_a_lit_textured_floor(forward: float) -> None:
    """Wherever the robot stands along its walk, the tracking camera frames its whole body near the image centre,
    and the floor under it is lit and textured (the walk used to turn the floor black after a few metres)."""
    env = gym.make("redundancy_gym/BipedWalk-v0", render_mode="rgb_array", width=WIDTH, height=HEIGHT)
    env.reset(seed=0)
    u = env.unwrapped
    u.data.qpos[0] += forward
    mujoco.mj_forward(u.model, u.data)
    frame = env.render().astype(np.float64)
    body = u.data.geom_xpos[u.model.geom_bodyid > 0]  # every robot geom
    pixels = _project(u.model, u.data, "track", body, WIDTH, HEIGHT)
    assert _inside(pixels, WIDTH, HEIGHT, margin=0.05).all()
    com = _project(u.model, u.data, "track", u.data.subtree_com[u.model.body("pelvis").id], WIDTH, HEIGHT)[0]
    assert abs(com[0] - 0.5 * WIDTH) < 0.15 * WIDTH and abs(com[1] - 0.5 * HEIGHT) < 0.2 * HEIGHT
    floor = frame[3 * HEIGHT // 4 :]  # the bottom quarter shows floor only
    assert floor.mean() > 90.0  # lit (the old scene: about 22 after 4.6 m)
    assert floor.mean(axis=2).std() > 15.0  # the checker contrasts (old scene: about 3)
    env.close()


def test_biped_camera_follows_the_walk() -> None:
    """After 4 s of the walking reference, the robot is still framed and the floor still lit."""
    env = gym.make("redundancy_gym/BipedWalk-v0", render_mode="rgb_array", width=WIDTH, height=HEIGHT)
    obs, _ = env.reset(seed=0)
    policy = redundancy_gym.make_policy("walking", env)
    for _ in range(1000):
        action, _ = policy.predict(obs, deterministic=True)
        obs, _, terminated, truncated, info = env.step(action)
        assert not (terminated or truncated)
    assert info["distance"] > 1.0
    u = env.unwrapped
    frame = env.render().astype(np.float64)
    pixels = _project(u.model, u.data, "track", u.data.geom_xpos[u.model.geom_bodyid > 0], WIDTH, HEIGHT)
    assert _inside(pixels, WIDTH, HEIGHT, margin=0.05).all()
    assert frame[3 * HEIGHT // 4 :].mean() > 90.0
    env.close()


@pytest.mark.parametrize("camera", ["side", "front"])
def test_agri_cameras_frame_the_target_arm_and_plants(camera: str) -> None:
    """For several seeds: the target pepper, the TCP and the shoulder project well inside the frame, as do most
    placed plant parts near the target; the pepper itself is seen (not hidden by leaves) for most seeds."""
    env = gym.make(
        "redundancy_gym/AgriReach-v0", render_mode="rgb_array", camera_name=camera, width=WIDTH, height=WIDTH
    )
    u = env.unwrapped
    segmenter = mujoco.Renderer(u.model, WIDTH, WIDTH)
    segmenter.enable_segmentation_rendering()
    seen = []
    try:
        for seed in range(8):
            env.reset(seed=seed)
            grasp, _ = u.grasp_pose
            work = np.array([grasp, u.data.site_xpos[u.model.site("tcp").id], u.data.xpos[u.model.body("shoulder").id]])
            assert _inside(_project(u.model, u.data, camera, work, WIDTH, WIDTH), WIDTH, WIDTH, margin=0.1).all()
            row = u.crop_row
            centres = row.vertices.mean(axis=1)
            near = centres[np.linalg.norm(centres - grasp, axis=1) < 0.3]
            assert near.shape[0] >= 5
            assert _inside(_project(u.model, u.data, camera, near, WIDTH, WIDTH), WIDTH, WIDTH).mean() > 0.9
            target_geom = u.part_geoms[u.target_index]
            segmenter.update_scene(u.data, camera=camera)
            seg = segmenter.render()
            seen.append(int(np.sum((seg[..., 0] == target_geom) & (seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM)))))
    finally:
        segmenter.close()
        env.close()
    # a pepper of 8-9 cm spans about 13 px here; leaves may hide it in a few rows
    assert sum(n >= 50 for n in seen) >= 6, seen
