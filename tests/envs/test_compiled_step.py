"""The compiled step of every env (``backend="compiled"``, the default) against its readable NumPy reference
(``backend="python"``): two envs stepped in lockstep with the same seed and actions see the same physics, so every
observation entry and every ``info`` key must come out the same, bit for bit, except the few values whose
summation order the kernels change (a dot product, a 3 x 3 product, the pair loop of the self-clearance), which
agree to round-off. The contact kernels are held to ``mj_contactForce`` bit for bit, under both friction cones."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import redundancy_gym  # noqa: F401  (registers the envs)
from redundancy_gym.envs import EnvConfigError
from redundancy_gym.envs.contact_pressure import (
    compiled_contact_pressure,
    compiled_touches_geoms,
    contact_layout,
    contact_pressure,
    foot_of_geom,
    touches_geoms,
)

ROUND_OFF = {
    # qdot^T qdot: NumPy's dot sums in its own order
    "pseudoenergy",
    "reward_energy",
    # R @ -tau per ankle: NumPy's matrix-vector product
    "contact_moments",
    # the self-clearance through the general pair loop of compute_near instead of the grouped one of compute
    "min_self_clearance",
    "min_clearance",
    # AgriReach's distances: the kernel squares by a product, Python's ** through its libm's pow (which differs
    # from the correctly rounded product in about 1 of 1000 cases here)
    "goal_error",
    "tracking_error",
    "reward_position",
    # PlanarReach's tracking error (a 2-norm: NumPy's through BLAS, whose AVX-512 kernels fuse the multiply-adds) and
    # what follows from it
    "reward_tracking",
    "max_tracking_error",
    # arccos of the torso's z-z entry: NumPy's SIMD arccos on AVX-512 machines against the kernel's libm acos
    # (1 ulp apart on AMD EPYC with AVX-512; equal on machines without it)
    "torso_tilt",
}
"""The ``info`` keys that agree to round-off only (all others and every observation: bit for bit)."""

_OBSTACLE_AHEAD = [{"shape": "box", "center": [0.55, 0.0, 0.25], "size": [0.3, 1.2, 0.5]}]

CASES: dict[str, tuple[str, dict[str, Any], float]] = {
    "planar": ("redundancy_gym/PlanarReach-v0", {}, 1.0),
    "planar noisy, no obstacle": ("redundancy_gym/PlanarReach-v0", {"obs_noise": 0.01, "obstacle": False}, 1.0),
    "agri": ("redundancy_gym/AgriReach-v0", {}, 1.0),
    "agri noisy": ("redundancy_gym/AgriReach-v0", {"obs_noise": 0.01, "difficulty": "hard"}, 1.0),
    "biped": ("redundancy_gym/BipedWalk-v0", {}, 0.3),
    "biped noisy, pushed": (
        "redundancy_gym/BipedWalk-v0",
        {"sensor_noise": 0.01, "push": {"rate": 5.0, "force": (50.0, 150.0), "duration": 0.1}},
        0.3,
    ),
    "obstacles random": ("redundancy_gym/BipedObstacles-v0", {"course": "random"}, 0.3),
    "obstacle ahead": (
        "redundancy_gym/BipedObstacles-v0",
        {"obstacles": _OBSTACLE_AHEAD, "push": [{"time": 0.0, "force": (300.0, 0.0, 0.0), "duration": 0.3}]},
        0.05,
    ),
}
"""name -> (env id, kwargs, action amplitude): the bipeds' random actions are small enough to stand a while, then
fall; in the last case a push topples the robot onto the obstacle ahead (its contacts, clearances and counters are
compared too)."""


def _same(key: str, old: Any, new: Any) -> None:
    assert type(old) is type(new), (key, type(old), type(new))
    if key in ROUND_OFF:
        np.testing.assert_allclose(new, old, rtol=1e-12, atol=1e-12, err_msg=key)
    elif isinstance(old, np.ndarray):
        assert old.dtype == new.dtype and old.shape == new.shape, key
        np.testing.assert_array_equal(new, old, err_msg=key)
    else:
        assert new == old or (old != old and new != new), (key, old, new)  # NaN == NaN here


@pytest.mark.parametrize("case", CASES)
def test_compiled_step_equals_the_python_reference(case: str) -> None:
    env_id, kwargs, amplitude = CASES[case]
    reference = gym.make(env_id, backend="python", **kwargs)
    compiled = gym.make(env_id, **kwargs)
    assert compiled.unwrapped._backend == "compiled"  # the default
    rng = np.random.default_rng(7)
    seen: set[str] = set()
    datas = []  # a random course's reset makes a new model and data: the kernels' bound arguments must follow
    try:
        for episode in range(2):
            old, old_info = reference.reset(seed=episode)
            new, new_info = compiled.reset(seed=episode)
            datas.append(compiled.unwrapped.data)
            np.testing.assert_array_equal(new, old)
            for step in range(300):
                action = amplitude * rng.uniform(-1.0, 1.0, reference.action_space.shape)
                old, old_reward, old_end, old_cut, old_info = reference.step(action)
                new, new_reward, new_end, new_cut, new_info = compiled.step(action)
                np.testing.assert_array_equal(new, old, err_msg=f"{case}: observation at step {step}")
                assert set(new_info) == set(old_info)
                for key, value in old_info.items():
                    _same(key, value, new_info[key])
                assert new_reward == pytest.approx(old_reward, rel=1e-12, abs=1e-12)
                assert (new_end, new_cut) == (old_end, old_cut)
                seen.update(k for k in ("obstacle_contact", "fell", "collision") if old_info.get(k))
                if old_end or old_cut:
                    break
    finally:
        reference.close()
        compiled.close()
    if case == "obstacles random":
        assert datas[0] is not datas[1], "the second course must be another model, to exercise the rebinding"
    if case == "obstacle ahead":
        assert "obstacle_contact" in seen, "the episode must exercise the obstacle contacts it compares"


def test_backend_is_checked() -> None:
    with pytest.raises(EnvConfigError, match="backend must be one of compiled, python"):
        gym.make("redundancy_gym/PlanarReach-v0", backend="gpu")


def _contacts_of_falling_biped(cone: int, condim: int) -> tuple[Any, list[tuple[Any, Any]]]:
    """A biped falling with random actions under the friction cone ``cone``, every geom of contact dimension
    ``condim``: its env and (model, data) states copied at each step with contacts."""
    env = gym.make("redundancy_gym/BipedWalk-v0")
    base = env.unwrapped
    base.model.opt.cone = cone
    base.model.geom_condim[:] = condim
    env.reset(seed=1)
    rng = np.random.default_rng(3)
    states = []
    for _ in range(200):
        _, _, end, cut, _ = env.step(0.4 * rng.uniform(-1.0, 1.0, 22))
        if base.data.ncon:
            copy = mujoco.MjData(base.model)
            mujoco.mj_copyData(copy, base.model, base.data)
            states.append((base.model, copy))
        if end or cut:
            break
    return env, states


@pytest.mark.parametrize(
    ("cone", "condim"),
    [
        (int(mujoco.mjtCone.mjCONE_PYRAMIDAL), 3),
        (int(mujoco.mjtCone.mjCONE_ELLIPTIC), 3),
        (int(mujoco.mjtCone.mjCONE_PYRAMIDAL), 1),
        (int(mujoco.mjtCone.mjCONE_PYRAMIDAL), 4),
        (int(mujoco.mjtCone.mjCONE_ELLIPTIC), 6),
    ],
)
def test_contact_kernels_equal_mj_contact_force(cone: int, condim: int) -> None:
    env, states = _contacts_of_falling_biped(cone, condim)
    base = env.unwrapped
    ground, foot = base._ground, base._foot_of_geom
    loaded = 0
    try:
        for model, data in states:
            layout = contact_layout(data)
            old = contact_pressure(model, data, ground, foot)
            new = compiled_contact_pressure(data, ground, foot, layout)
            for name, a, b in zip(old._fields, old, new, strict=True):
                assert type(a) is type(b), name
                np.testing.assert_array_equal(b, a, err_msg=name)
            loaded += int(old.zmp_valid)
            for low, high in ((0, 1), (1, model.ngeom), (2, 5), (3, 3)):
                assert compiled_touches_geoms(data, low, high, layout) == touches_geoms(data, low, high)
    finally:
        env.close()
    assert loaded > 10, "the states must hold loaded feet"


def test_foot_of_geom_checks_its_map() -> None:
    np.testing.assert_array_equal(foot_of_geom(4, {1: 0, 3: 1}), [-1, 0, -1, 1])
    with pytest.raises(EnvConfigError, match="sole geom 5"):
        foot_of_geom(4, {5: 0})
    with pytest.raises(EnvConfigError, match="foot 2"):
        foot_of_geom(4, {1: 2})
