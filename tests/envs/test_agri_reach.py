"""AgriReach-v0: scene generation, pruning, target geometry, contact judging against direct SSV queries, and the
clik reference solving episodes."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401 - registers the ids
from redundancy_gym import make_policy
from redundancy_gym.assets import AGRI_ARM_GEOMS
from redundancy_gym.assets.crop_row import crop_row_defaults, generate_crop_row
from redundancy_gym.envs import EnvConfigError
from redundancy_gym.geometry import LSS, PSS, TSS, distance

ENV_ID = "redundancy_gym/AgriReach-v0"


def _arm_volumes(env: gym.Env) -> list:
    u = env.unwrapped
    out: list[LSS | PSS] = []
    for k, name in enumerate(AGRI_ARM_GEOMS):
        g = u.model.geom(name).id
        pos = u.data.geom_xpos[g]
        r = float(u.model.geom_size[g, 0])
        if u._half_length[k] > 0.0:
            axis = u.data.geom_xmat[g].reshape(3, 3)[:, 2] * u._half_length[k]
            out.append(LSS(pos - axis, pos + axis, r))
        else:
            out.append(PSS(pos, r))
    return out


def _part(row, k: int):
    v, r = row.vertices[k], float(row.radius[k])
    return (PSS(v[0], r), LSS(v[0], v[1], r), TSS(v[0], v[1], v[2], r))[int(row.kind[k])]


def test_difficulty_presets_change_the_crop() -> None:
    counts = {}
    for level in ("easy", "hard"):
        row = generate_crop_row(np.random.default_rng(0), **crop_row_defaults(level))
        counts[level] = {c: int(np.sum(row.category == c)) for c in ("leaf", "fruit", "shoot")}
    assert counts["hard"]["leaf"] > 2 * counts["easy"]["leaf"]
    assert counts["hard"]["shoot"] > counts["easy"]["shoot"] == 0
    with pytest.raises(ValueError, match="easy, medium, hard"):
        crop_row_defaults("extreme")
    with pytest.raises(EnvConfigError, match="easy, medium, hard"):
        gym.make(ENV_ID, difficulty="extreme")


def test_prune_keeps_exactly_the_parts_within_reach_with_whole_leaf_blades() -> None:
    pruned = gym.make(ENV_ID)
    full = gym.make(ENV_ID, prune=False)
    pruned.reset(seed=1)
    full.reset(seed=1)  # pruning draws nothing: the same row and target
    p_row, f_row = pruned.unwrapped.crop_row, full.unwrapped.crop_row
    assert len(p_row) < 0.6 * len(f_row)
    assert pruned.unwrapped.model.ngeom < full.unwrapped.model.ngeom
    reach = LSS([0, 0, 0.55], [0, 0, 1.35], 1.29 + 0.075)
    inside = [k for k in range(len(f_row)) if distance(_part(f_row, k), reach).distance <= 0.0]
    assert len(inside) < len(f_row)  # the unpruned row reaches beyond the arm
    expected = f_row.subset(np.array(inside))
    np.testing.assert_array_equal(p_row.vertices, expected.vertices)
    np.testing.assert_array_equal(p_row.category, expected.category)
    # every part kept is within reach, or the other triangle of a blade that is
    kept_in = {int(f_row.blade[k]) for k in inside if f_row.blade[k] >= 0}
    for k in range(len(p_row)):
        assert distance(_part(p_row, k), reach).distance <= 0.0 or int(p_row.blade[k]) in kept_in
    target = pruned.unwrapped.target_index
    np.testing.assert_array_equal(p_row.vertices[target], f_row.vertices[full.unwrapped.target_index])


def test_leaf_blades_are_two_adjacent_triangles_of_one_kite() -> None:
    row = generate_crop_row(np.random.default_rng(3), **crop_row_defaults("medium"))
    leaves = np.flatnonzero(row.category == "leaf")
    assert leaves.size % 2 == 0 and np.all(np.diff(leaves) == 1)
    a, b = leaves[0::2], leaves[1::2]
    np.testing.assert_array_equal(row.blade[a], row.blade[b])
    np.testing.assert_array_equal(row.vertices[a, 0], row.vertices[b, 0])  # shared end (petiole tip)
    np.testing.assert_array_equal(row.vertices[a, 2], row.vertices[b, 1])  # shared tip
    assert np.all(row.blade[row.category != "leaf"] == -1)


def test_target_pose_geometry() -> None:
    env = gym.make(ENV_ID, approach_elevation=(10.0, 20.0), pregrasp_distance=0.2)
    for seed in range(3):
        obs, _ = env.reset(seed=seed)
        u = env.unwrapped
        lay = u.observation_layout
        grasp, approach = obs[lay["grasp_position"]], obs[lay["approach"]]
        assert np.linalg.norm(approach) == pytest.approx(1.0)
        assert 10.0 - 1e-9 <= np.degrees(np.arcsin(approach[2])) <= 20.0 + 1e-9
        np.testing.assert_allclose(obs[lay["pregrasp_position"]], grasp - 0.2 * approach)
        row = u.crop_row
        assert row.category[u.target_index] == "fruit"
        np.testing.assert_allclose(row.vertices[u.target_index, 0], grasp)
        block = obs[lay["obstacles"]].reshape(-1, 15)
        valid = block[block[:, 0] > 0.5]
        assert len(valid) == min(32, len(row) - 1)
        np.testing.assert_allclose(valid[:, 1:4].sum(axis=1), 1.0)


def test_contacts_match_direct_ssv_queries() -> None:
    """min_clearance (hard parts and non-adjacent links, capped at the horizon) and leaf contacts equal a brute
    force over every pair with :func:`distance`, along a random motion."""
    env = gym.make(ENV_ID, difficulty="hard", max_joint_speed=3.0)
    rng = np.random.default_rng(0)
    obs, info = env.reset(seed=4)
    u = env.unwrapped
    row = u.crop_row
    others = [k for k in range(len(row)) if k != u.target_index]
    self_pairs = u._self_pairs
    checked = 0
    for _ in range(40):
        obs, _, terminated, truncated, info = env.step(rng.uniform(-1, 1, 9).astype(np.float32))
        arm = _arm_volumes(env)
        hard = [distance(a, _part(row, k)).distance for a in arm[1:] for k in others if row.hard[k]]
        hard += [distance(arm[i], arm[j]).distance for i, j in self_pairs]
        assert info["min_clearance"] == pytest.approx(min(min(hard), u._horizon), abs=1e-9)
        leaves = {k for a in arm[1:] for k in others if not row.hard[k] and distance(a, _part(row, k)).distance <= 0}
        assert info["leaf_contacts"] == len(leaves)
        checked += 1
        if terminated or truncated:
            break
    assert checked >= 5


def test_clik_reference_reaches_the_grasp_pose() -> None:
    env = gym.make(ENV_ID, difficulty="medium")
    policy = make_policy("clik", env)
    for seed in (0, 1):
        obs, _ = env.reset(seed=seed)
        for _ in range(500):
            action, _ = policy.predict(obs)
            obs, _, terminated, truncated, info = env.step(action)
            if terminated or truncated:
                break
        assert info["is_success"] and not info["collision"]
        assert info["goal_error"] <= 0.01 and np.degrees(info["orientation_error"]) <= 10.0 and info["goal_reached"]
        # the clik reference follows the env's own reference path to within the servo lag
        assert info["tracking_error"] < 0.01 and np.linalg.norm(info["tcp"] - info["tcp_ref"]) == pytest.approx(
            info["tracking_error"]
        )


def test_invalid_arguments_name_the_valid_choices() -> None:
    with pytest.raises(EnvConfigError, match="side, front"):
        gym.make(ENV_ID, camera_name="top")
    with pytest.raises(EnvConfigError, match="low, high"):
        gym.make(ENV_ID, harvest_band=(1.3, 0.9))
    with pytest.raises(EnvConfigError, match="unknown keyword"):
        gym.make(ENV_ID, leafs=3)
