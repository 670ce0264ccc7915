"""Dynamics randomization (issue 36): the ``dynamics`` argument of every env changes the simulated model as its
docstring says, draws from the env's seeded generator, leaves every episode bitwise as it was when off, and names
the item and its valid range when a value is bad."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
import pytest

import redundancy_gym
from redundancy_gym.envs import EnvConfigError
from redundancy_gym.envs.dynamics import (
    ARM_ITEMS,
    BIPED_ITEMS,
    DynamicsRandomization,
    ScaleOrRange,
    parse_dynamics,
)

PLANAR = "redundancy_gym/PlanarReach-v0"
AGRI = "redundancy_gym/AgriReach-v0"
BIPED = "redundancy_gym/BipedWalk-v0"
OBSTACLES = "redundancy_gym/BipedObstacles-v0"
BASE_ENVS = (PLANAR, AGRI, BIPED, OBSTACLES)


def _rollout(env_id: str, steps: int, seed: int = 11, **kwargs: Any) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """Observations and rewards of ``steps`` seeded small random actions (a reset after an episode's end), and the
    first reset's info."""
    env = gym.make(env_id, **kwargs)
    obs, first = env.reset(seed=seed)
    rng = np.random.default_rng(2)
    observations, rewards = [obs], []
    for _ in range(steps):
        obs, reward, terminated, truncated, _ = env.step(rng.uniform(-0.3, 0.3, env.action_space.shape))
        observations.append(obs)
        rewards.append(reward)
        if terminated or truncated:
            obs, _ = env.reset()
            observations.append(obs)
    env.close()
    return np.array(observations), np.array(rewards), first


@pytest.mark.parametrize("env_id", redundancy_gym.ENV_IDS)
@pytest.mark.parametrize("off", [None, 0.0, {}, {"level": 0.0, "latency": 0}])
def test_dynamics_off_is_bitwise_identical_to_the_default(env_id: str, off: Any) -> None:
    # {"level": 0, "latency": 0}: every scale (1, 1), offsets 0 and no latency: a randomization that draws but
    # changes nothing must give the default's episodes too (the model restored and its constants as compiled)
    obs, rewards, info = _rollout(env_id, 40)
    obs_off, rewards_off, info_off = _rollout(env_id, 40, dynamics=off)
    if isinstance(off, dict) and off:
        assert "dynamics" in info_off
        # the draws came from the env's generator: what follows them (reset noise, courses) differs, so compare
        # the model alone (below); the default's episode is that of dynamics None
        return
    assert "dynamics" not in info_off
    assert np.array_equal(obs, obs_off)
    assert np.array_equal(rewards, rewards_off)


@pytest.mark.parametrize("env_id", BASE_ENVS)
def test_identity_draws_restore_the_compiled_model(env_id: str) -> None:
    """After a randomized reset, scales of exactly 1, zero offsets and no payload write the compiled values back,
    the constants that mj_setConst derives included: the randomizer restores its model before each draw."""
    items = ARM_ITEMS if env_id in (PLANAR, AGRI) else BIPED_ITEMS
    env = gym.make(env_id).unwrapped
    env.reset(seed=0)
    model = env.model
    fields = (
        "body_mass",
        "body_inertia",
        "body_ipos",
        "body_iquat",
        "body_pos",
        "body_subtreemass",
        "body_invweight0",
        "dof_invweight0",
        "dof_damping",
        "dof_armature",
        "dof_frictionloss",
        "actuator_gainprm",
        "actuator_biasprm",
        "geom_friction",
    )
    compiled = {f: getattr(model, f).copy() for f in fields}
    spec = parse_dynamics(0.2, items)
    identity = parse_dynamics({"level": 0.0, **({"payload": (0.0, 0.0)} if items == ARM_ITEMS else {})}, items)
    assert spec is not None and identity is not None
    randomizer = DynamicsRandomization(spec, *_roots(env_id))
    randomizer.apply(model, env.data, np.random.default_rng(0))
    assert not np.array_equal(model.body_mass, compiled["body_mass"])
    randomizer.spec = identity
    randomizer.apply(model, env.data, np.random.default_rng(0))
    for f in fields:
        assert np.array_equal(getattr(model, f), compiled[f]), f


def _roots(env_id: str) -> tuple[str, str | None]:
    return {PLANAR: ("link1", "tcp"), AGRI: ("carriage", "tcp")}.get(env_id, ("pelvis", None))


@pytest.mark.parametrize("env_id", BASE_ENVS)
def test_draws_are_reproducible_from_the_seed(env_id: str) -> None:
    env = gym.make(env_id, dynamics=0.1)
    _, a = env.reset(seed=5)
    _, b = env.reset(seed=5)
    _, c = env.reset(seed=6)
    for key, value in a["dynamics"].items():
        assert np.array_equal(value, b["dynamics"][key]), key
    assert not np.array_equal(a["dynamics"]["mass_scale"], c["dynamics"]["mass_scale"])
    env.close()


def test_level_shorthand_sets_every_item_as_documented() -> None:
    arm = parse_dynamics(0.1, ARM_ITEMS)
    assert arm is not None
    assert arm.mass == arm.servo_gain == pytest.approx((0.9, 1.1))
    assert arm.damping == arm.armature == ScaleOrRange("scale", 0.9, 1.1)
    assert arm.com_offset == arm.placement == pytest.approx(0.01)
    assert arm.latency == (1, 1) and arm.payload == pytest.approx((0.0, 1.0))
    assert arm.friction is None and arm.frictionloss is None
    biped = parse_dynamics({"level": 0.2, "latency": (0, 2), "damping": None}, BIPED_ITEMS)
    assert biped is not None
    assert biped.friction == pytest.approx((0.4, 1.6)) and biped.latency == (0, 2) and biped.damping is None
    assert biped.payload is None and biped.placement is None
    assert parse_dynamics(0.05, BIPED_ITEMS).latency == (0, 0)


def test_masses_inertias_and_com_offsets_as_drawn() -> None:
    env = gym.make(BIPED, dynamics={"mass": (0.8, 1.2), "com_offset": 0.02}).unwrapped
    nominal = gym.make(BIPED).unwrapped.model
    _, info = env.reset(seed=1)
    drawn, model = info["dynamics"], env.model
    scale = drawn["mass_scale"]
    assert scale[0] == 1.0 and np.all((scale[1:] >= 0.8) & (scale[1:] <= 1.2)) and np.ptp(scale[1:]) > 0.1
    np.testing.assert_allclose(model.body_mass, nominal.body_mass * scale, rtol=1e-15)
    np.testing.assert_allclose(model.body_inertia, nominal.body_inertia * scale[:, None], rtol=1e-15)
    np.testing.assert_allclose(model.body_ipos - nominal.body_ipos, drawn["com_offset"], atol=1e-15)
    assert np.abs(drawn["com_offset"]).max() <= 0.02 and np.abs(drawn["com_offset"][1:]).max() > 0.01
    # the simulated weight is the drawn one: the subtree mass that mj_setConst derives, and gravity in the RNEA
    assert model.body_subtreemass[1] == pytest.approx(float((nominal.body_mass * scale).sum()), rel=1e-12)


def test_joint_items_scale_or_draw_in_the_range() -> None:
    env = gym.make(
        AGRI, dynamics={"damping": (0.5, 0.6), "armature": {"range": (0.1, 0.2)}, "frictionloss": {"range": (0.3, 0.4)}}
    ).unwrapped
    nominal = gym.make(AGRI).unwrapped.model
    _, info = env.reset(seed=2)
    ratio = env.model.dof_damping / nominal.dof_damping
    assert np.all((ratio >= 0.5) & (ratio <= 0.6))
    np.testing.assert_array_equal(env.model.dof_damping, info["dynamics"]["damping"])
    assert np.all((env.model.dof_armature >= 0.1) & (env.model.dof_armature <= 0.2))
    assert np.all((env.model.dof_frictionloss >= 0.3) & (env.model.dof_frictionloss <= 0.4))


def test_a_floating_base_gets_no_joint_damping_or_armature() -> None:
    env = gym.make(BIPED, dynamics={"damping": {"range": (1.0, 2.0)}, "armature": {"range": (0.1, 0.2)}}).unwrapped
    _, info = env.reset(seed=4)
    m = env.model
    np.testing.assert_array_equal(m.dof_damping[:6], 0.0)  # the free joint's six DoFs
    np.testing.assert_array_equal(m.dof_armature[:6], 0.0)
    assert np.all((m.dof_damping[6:] >= 1.0) & (m.dof_damping[6:] <= 2.0))
    np.testing.assert_array_equal(info["dynamics"]["damping"], m.dof_damping)


def test_servo_gains_scale_stiffness_and_damping_together() -> None:
    env = gym.make(BIPED, dynamics={"servo_gain": (0.7, 0.9)}).unwrapped
    nominal = gym.make(BIPED).unwrapped.model
    _, info = env.reset(seed=3)
    gain = info["dynamics"]["servo_gain"]
    m = env.model
    np.testing.assert_allclose(m.actuator_gainprm[:, 0], nominal.actuator_gainprm[:, 0] * gain, rtol=1e-15)
    np.testing.assert_allclose(m.actuator_biasprm[:, 1:3], nominal.actuator_biasprm[:, 1:3] * gain[:, None], rtol=1e-15)
    # kv / kp is kept (the servo's velocity lead), and the env's nominal stiffness is what the controllers see
    np.testing.assert_allclose(
        m.actuator_biasprm[:, 2] / m.actuator_gainprm[:, 0],
        nominal.actuator_biasprm[:, 2] / nominal.actuator_gainprm[:, 0],
    )
    np.testing.assert_array_equal(env.servo_stiffness, nominal.actuator_gainprm[:22, 0])
    # measured on the data: the servo torque for a 0.01 rad target offset is the drawn stiffness's
    env.data.ctrl[:] = env.data.qpos[7:] + 0.01
    env.data.qvel[:] = 0.0
    mujoco.mj_forward(m, env.data)
    np.testing.assert_allclose(env.data.actuator_force, 0.01 * m.actuator_gainprm[:, 0], rtol=1e-9)


def test_ground_friction_scales_every_geom() -> None:
    env = gym.make(OBSTACLES, course="beam", dynamics={"friction": (0.5, 0.5)}).unwrapped
    nominal = gym.make(OBSTACLES, course="beam").unwrapped.model
    _, info = env.reset(seed=0)
    assert info["dynamics"]["friction"] == 0.5
    np.testing.assert_array_equal(env.model.geom_friction[:, 0], 0.5 * nominal.geom_friction[:, 0])
    np.testing.assert_array_equal(env.model.geom_friction[:, 1:], nominal.geom_friction[:, 1:])


@pytest.mark.parametrize("env_id", [PLANAR, AGRI])
def test_payload_adds_its_weight_at_the_tcp(env_id: str) -> None:
    """The gravity torques of the plant grow by the payload's ``J_tcp^T m g`` (the TCP's translational Jacobian):
    the payload sits at the TCP, with its mass, CoM and inertia combined exactly."""
    env = gym.make(env_id, dynamics={"payload": (2.0, 2.0)}).unwrapped
    plain = gym.make(env_id).unwrapped
    _, info = env.reset(seed=4)
    plain.reset(seed=4)
    assert info["dynamics"]["payload"] == 2.0
    m0, m1 = plain.model, env.model
    site = m1.site("tcp")
    body = int(site.bodyid[0])
    assert m1.body_mass[body] == pytest.approx(m0.body_mass[body] + 2.0)
    q = env.data.qpos.copy()
    torques = []
    for model in (m0, m1):
        data = mujoco.MjData(model)
        data.qpos[:] = q
        mujoco.mj_forward(model, data)
        torques.append(data.qfrc_bias.copy())  # gravity only: zero velocity
        jacobian = np.zeros((3, model.nv))
        mujoco.mj_jacSite(model, data, jacobian, None, site.id)
    np.testing.assert_allclose(torques[1] - torques[0], jacobian.T @ np.array([0.0, 0.0, 2.0 * 9.81]), atol=1e-9)
    # the combined inertia is a rotation of a positive diagonal: the principal axes of a valid body
    assert np.all(m1.body_inertia[body] > 0.0)
    assert np.linalg.norm(m1.body_iquat[body]) == pytest.approx(1.0)


@pytest.mark.parametrize("env_id", [PLANAR, AGRI])
def test_placement_moves_the_base_and_the_tcp_with_it(env_id: str) -> None:
    env = gym.make(env_id, dynamics={"placement": 0.02}).unwrapped
    plain = gym.make(env_id).unwrapped
    _, info = env.reset(seed=7)
    plain.reset(seed=7)
    shift = info["dynamics"]["placement"]
    assert np.abs(shift).max() <= 0.02 and np.abs(shift).max() > 0.005
    root = env.model.body(_roots(env_id)[0]).id
    np.testing.assert_allclose(env.model.body_pos[root] - plain.model.body_pos[root], shift, atol=1e-15)
    # the same joints put the TCP ``shift`` away (a translation of the base moves the whole arm)
    data = mujoco.MjData(env.model)
    data.qpos[:] = plain.data.qpos
    mujoco.mj_kinematics(env.model, data)
    np.testing.assert_allclose(data.site("tcp").xpos - plain.data.site("tcp").xpos, shift, atol=1e-12)


@pytest.mark.parametrize("env_id", BASE_ENVS)
@pytest.mark.parametrize("latency", [1, 2])
def test_latency_applies_the_controls_of_k_periods_before(env_id: str, latency: int) -> None:
    """The controls the physics gets (``data.ctrl`` after a step) are those a latency-free env got ``k`` steps
    before; the first ``k`` steps apply the reset's controls."""
    kwargs: dict[str, Any] = {"course": "beam"} if env_id == OBSTACLES else {}
    delayed = gym.make(env_id, dynamics={"latency": latency}, **kwargs).unwrapped
    plain = gym.make(env_id, **kwargs).unwrapped
    _, info = delayed.reset(seed=0)
    plain.reset(seed=0)
    assert info["dynamics"]["latency"] == latency
    start = plain.data.ctrl.copy()
    rng = np.random.default_rng(0)
    applied, commanded = [], []
    for _ in range(6):
        action = rng.uniform(-0.2, 0.2, plain.action_space.shape)
        plain.step(action)
        delayed.step(action)
        commanded.append(plain.data.ctrl.copy())
        applied.append(delayed.data.ctrl.copy())
    for k in range(latency):
        np.testing.assert_array_equal(applied[k], start)
    for k in range(latency, 6):
        np.testing.assert_array_equal(applied[k], commanded[k - latency])


@pytest.mark.parametrize(
    ("env_id", "value", "match"),
    [
        (BIPED, -0.1, r"dynamics must be a finite real number in \[0, 0.3\]"),
        (BIPED, 0.5, r"dynamics must be .*\[0, 0.3\]"),
        (BIPED, "high", "dynamics must be"),
        (BIPED, {"payload": (0.0, 1.0)}, "dynamics has unknown item.*payload.*valid: level, mass"),
        (PLANAR, {"friction": (0.5, 1.0)}, "unknown item.*friction"),
        (BIPED, {"mass": (0.0, 1.0)}, r"dynamics\['mass'\] must be a \(low, high\) pair .*> 0"),
        (BIPED, {"mass": (1.2, 0.8)}, r"dynamics\['mass'\].*low <= high"),
        (BIPED, {"servo_gain": 1.1}, r"dynamics\['servo_gain'\]"),
        (BIPED, {"damping": {"scale": (1, 2)}}, r"dynamics\['damping'\] must be a scale range"),
        (BIPED, {"armature": {"range": (-1.0, 1.0)}}, r"dynamics\['armature'\]\['range'\].*>= 0"),
        (BIPED, {"com_offset": -0.01}, r"dynamics\['com_offset'\] must be .*\[0, 0.5\] \[m\]"),
        (BIPED, {"latency": 11}, r"dynamics\['latency'\] must be an int in \[0, 10\]"),
        (BIPED, {"latency": 1.0}, r"dynamics\['latency'\] must be a \(low, high\) pair of ints"),
        (BIPED, {"latency": True}, r"dynamics\['latency'\]"),
        (BIPED, {"level": 0.4}, r"dynamics\['level'\] must be .*\[0, 0.3\]"),
        (AGRI, {"payload": (-1.0, 1.0)}, r"dynamics\['payload'\] .*\[0, 100\] \[kg\]"),
        (AGRI, {"placement": float("nan")}, r"dynamics\['placement'\]"),
    ],
)
def test_bad_values_raise_naming_the_item_and_its_range(env_id: str, value: Any, match: str) -> None:
    with pytest.raises(EnvConfigError, match=match):
        gym.make(env_id, dynamics=value)
