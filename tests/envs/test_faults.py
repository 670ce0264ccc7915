"""Faults as env options (issue 17): ``sensor_noise``, ``push``, ``actuator_torque_scale`` on BipedWalk and
``obs_noise`` on PlanarReach and AgriReach; seeded, off by default and bitwise unchanged when off."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401  (registers the envs)
from redundancy_gym.envs import EnvConfigError
from redundancy_gym.envs.biped_walk import BipedWalkEnv

BIPED = "redundancy_gym/BipedWalk-v0"
PLANAR = "redundancy_gym/PlanarReach-v0"
AGRI = "redundancy_gym/AgriReach-v0"
LAYOUT = BipedWalkEnv.OBSERVATION_LAYOUT


def _run(
    env_id: str, steps: int = 100, seed: int = 3, action: Any = None, **kwargs: Any
) -> tuple[np.ndarray, np.ndarray, list[dict[str, Any]]]:
    """Observations (reset first) and rewards of ``steps`` steps of seeded small random actions."""
    env = gym.make(env_id, **kwargs)
    obs, _ = env.reset(seed=seed)
    rng = np.random.default_rng(1)
    observations, rewards, infos = [obs], [], []
    for _ in range(steps):
        a = rng.uniform(-0.2, 0.2, env.action_space.shape) if action is None else action
        obs, reward, terminated, truncated, info = env.step(a)
        observations.append(obs)
        rewards.append(reward)
        infos.append(info)
        if terminated or truncated:
            obs, _ = env.reset()
            observations.append(obs)
    env.close()
    return np.array(observations), np.array(rewards), infos


@pytest.mark.parametrize(
    ("env_id", "off"),
    [
        (BIPED, {"sensor_noise": 0.0}),
        (BIPED, {"sensor_noise": None, "push": None, "actuator_torque_scale": 1.0}),
        (BIPED, {"sensor_noise": {"q": 0.0}}),
        (BIPED, {"push": []}),
        (PLANAR, {"obs_noise": 0}),
        (PLANAR, {"obs_noise": None}),
        (AGRI, {"obs_noise": 0.0}),
        (AGRI, {"obs_noise": {"q": 0.0, "tcp": 0.0}}),
    ],
)
def test_faults_off_are_bitwise_identical_to_the_defaults(env_id: str, off: dict[str, Any]) -> None:
    obs, rewards, _ = _run(env_id)
    obs_off, rewards_off, _ = _run(env_id, **off)
    assert np.array_equal(obs, obs_off)
    assert np.array_equal(rewards, rewards_off)


@pytest.mark.parametrize(
    ("env_id", "kwarg", "channels"),
    [
        (
            BIPED,
            "sensor_noise",
            [
                LAYOUT[k]
                for k in (
                    "q",
                    "qdot",
                    "right_force",
                    "right_torque",
                    "left_force",
                    "left_torque",
                    "imu_acceleration",
                    "imu_gyro",
                )
            ],
        ),
        (PLANAR, "obs_noise", [slice(0, 4), slice(4, 8), slice(8, 10), slice(18, 20)]),  # tcp_error: from the noisy TCP
        (AGRI, "obs_noise", [slice(0, 9), slice(9, 18), slice(18, 21), slice(47, 50)]),  # tcp_error as PlanarReach's
    ],
)
def test_observation_noise_is_seeded_and_on_the_measured_channels_only(
    env_id: str, kwarg: str, channels: list[slice]
) -> None:
    noise: dict[str, Any] = {kwarg: 0.01}
    clean, rewards, _ = _run(env_id, steps=30)
    noisy, noisy_rewards, _ = _run(env_id, steps=30, **noise)
    again, _, _ = _run(env_id, steps=30, **noise)
    other, _, _ = _run(env_id, steps=30, seed=4, **noise)
    other_clean, _, _ = _run(env_id, steps=30, seed=4)
    assert np.array_equal(noisy, again)  # same seed, same noise
    assert not np.allclose(noisy - clean, other - other_clean)  # another seed, other noise
    assert np.array_equal(rewards, noisy_rewards)  # the rewards see the true state (open-loop actions)
    measured = np.zeros(clean.shape[1], dtype=bool)
    for part in channels:
        measured[part] = True
        assert np.any(noisy[:, part] != clean[:, part])
    # the other channels are exact (BipedWalk: base state, IMU orientation, command, time; the arms: the
    # reference or grasp pose, obstacles, time)
    assert np.array_equal(noisy[:, ~measured], clean[:, ~measured])


@pytest.mark.parametrize(
    ("env_id", "kwarg", "part", "std"),
    [
        (BIPED, "sensor_noise", "q", 0.02),
        (BIPED, "sensor_noise", "force", 5.0),
        (PLANAR, "obs_noise", "q", 0.05),
        (AGRI, "obs_noise", "q", 0.05),
    ],
)
def test_observation_noise_has_the_requested_std(env_id: str, kwarg: str, part: str, std: float) -> None:
    slices = {
        BIPED: {"q": LAYOUT["q"], "force": LAYOUT["right_force"]},
        PLANAR: {"q": slice(0, 4)},
        AGRI: {"q": slice(0, 9)},
    }[env_id]
    value = {part: std} if env_id == BIPED else std
    zero = np.zeros({BIPED: 22, PLANAR: 4, AGRI: 9}[env_id])  # no resets
    clean, _, _ = _run(env_id, steps=200, seed=5, action=zero)
    noisy, _, _ = _run(env_id, steps=200, seed=5, action=zero, **{kwarg: value})
    error = (noisy - clean)[:, slices[part]].ravel()
    assert abs(error.mean()) < 0.15 * std
    assert error.std() == pytest.approx(std, rel=0.15)


def test_biped_sensor_noise_groups_leave_the_others_exact() -> None:
    clean, _, _ = _run(BIPED, steps=20)
    noisy, _, _ = _run(BIPED, steps=20, sensor_noise={"qdot": 0.01})
    diff = noisy != clean
    assert diff[:, LAYOUT["qdot"]].all()
    others = np.ones(clean.shape[1], dtype=bool)
    others[LAYOUT["qdot"]] = False
    assert not diff[:, others].any()


def _stand(steps: int, **kwargs: Any) -> tuple[np.ndarray, list[dict[str, Any]]]:
    obs, _, infos = _run(BIPED, steps=steps, seed=0, action=np.zeros(22), **kwargs)
    return obs, infos


@pytest.mark.parametrize(("force", "axis"), [((0.0, 150.0, 0.0), 1), ((-150.0, 0.0, 0.0), 0)])
def test_scheduled_push_moves_the_base_in_its_direction_during_its_window(force: tuple[float, ...], axis: int) -> None:
    dt = 0.004
    steps = 150  # 0.6 s; the push acts in [0.4, 0.5)
    obs, infos = _stand(steps, push=[{"time": 0.4, "force": force, "duration": 0.1}])
    ref, _ = _stand(steps)
    velocity = LAYOUT["base_linear_velocity"].start + axis
    sign = np.sign(force[axis])
    start, end = int(round(0.4 / dt)), int(round(0.5 / dt))  # obs[k] is after k steps
    assert np.array_equal(obs[: start + 1], ref[: start + 1])  # nothing before the window
    pushed = [np.asarray(i["push_force"]) for i in infos]
    assert all(not p.any() for p in pushed[:start]) and all(not p.any() for p in pushed[end:])
    assert all(np.array_equal(p, force) for p in pushed[start:end])
    gain = sign * (obs[end, velocity] - ref[end, velocity])
    assert gain > 0.05  # 15 N s on 60 kg: about 0.25 m/s at the CoM
    assert sign * (obs[start + 5, velocity] - ref[start + 5, velocity]) > 0.0


def test_push_on_another_body_and_cleared_after_the_window() -> None:
    env = gym.make(BIPED, push=[{"time": 0.0, "force": [0.0, 0.0, -100.0], "duration": 0.02, "body": "pelvis"}])
    env.reset(seed=0)
    base = env.unwrapped
    env.step(np.zeros(22))
    assert base.data.xfrc_applied[base.model.body("pelvis").id, 2] == -100.0
    for _ in range(5):
        _, _, _, _, info = env.step(np.zeros(22))
    assert not base.data.xfrc_applied.any() and not info["push_force"].any()


def test_random_push_process_is_reproducible_by_seed() -> None:
    push = {"rate": 4.0, "force": (50.0, 80.0), "duration": 0.05, "direction": "lateral"}
    obs, infos = _stand(200, push=push)
    again, infos_again = _stand(200, push=push)
    forces = np.array([i["push_force"] for i in infos])
    assert np.array_equal(obs, again)
    assert np.array_equal(forces, np.array([i["push_force"] for i in infos_again]))
    on = np.linalg.norm(forces, axis=1) > 0
    assert on.any() and not on.all()
    assert np.all(forces[on, 0] == 0.0) and np.all(forces[on, 2] == 0.0)
    assert np.all((np.abs(forces[on, 1]) >= 50.0) & (np.abs(forces[on, 1]) <= 80.0))
    _, _, other_infos = _run(BIPED, steps=200, seed=1, action=np.zeros(22), push=push)
    assert not np.array_equal(forces, np.array([i["push_force"] for i in other_infos]))


@pytest.mark.parametrize("direction", ["forward", "any"])
def test_random_push_directions_are_horizontal(direction: str) -> None:
    _, infos = _stand(150, push={"rate": 10.0, "force": (30.0, 30.0), "duration": 0.02, "direction": direction})
    forces = np.array([i["push_force"] for i in infos])
    on = np.linalg.norm(forces, axis=1) > 0
    assert on.any()
    assert np.allclose(np.linalg.norm(forces[on], axis=1), 30.0) and np.all(forces[on, 2] == 0.0)
    if direction == "forward":
        assert np.all(forces[on, 1] == 0.0)


def test_actuator_torque_scale_weakens_the_servos() -> None:
    # a knee-bending command the full servos hold; at 30 % of the torque limits the biped sinks and falls
    action = np.zeros(22)
    action[[3, 10]] = 0.3
    results = {}
    for scale in (1.0, 0.3):
        env = gym.make(BIPED, actuator_torque_scale=scale)
        env.reset(seed=0)
        base = env.unwrapped
        assert np.allclose(base.model.actuator_forcerange[3], [-250.0 * scale, 250.0 * scale])
        peak, fell_at = 0.0, None
        for k in range(250):
            _, _, terminated, _, _ = env.step(action)
            peak = max(peak, float(np.abs(base.data.actuator_force).max()))
            if terminated:
                fell_at = k
                break
        results[scale] = (peak, fell_at)
    assert results[1.0][1] is None
    assert results[0.3][1] is not None
    assert results[0.3][0] <= 0.3 * 250.0 + 1e-6 < results[1.0][0]


@pytest.mark.parametrize(
    ("env_id", "kwargs", "name"),
    [
        (BIPED, {"sensor_noise": -0.1}, "sensor_noise"),
        (BIPED, {"sensor_noise": "0.1"}, "sensor_noise"),
        (BIPED, {"sensor_noise": float("nan")}, "sensor_noise"),
        (BIPED, {"sensor_noise": {"gps": 0.1}}, "sensor_noise"),
        (BIPED, {"sensor_noise": {"q": -1.0}}, "sensor_noise"),
        (BIPED, {"actuator_torque_scale": 0.0}, "actuator_torque_scale"),
        (BIPED, {"actuator_torque_scale": 1.5}, "actuator_torque_scale"),
        (BIPED, {"actuator_torque_scale": True}, "actuator_torque_scale"),
        (BIPED, {"push": "yes"}, "push"),
        (BIPED, {"push": [{"time": -1.0, "force": [0, 1, 0], "duration": 0.1}]}, r"push\[0\]\['time'\]"),
        (BIPED, {"push": [{"time": 1.0, "force": [0, 1], "duration": 0.1}]}, r"push\[0\]\['force'\]"),
        (BIPED, {"push": [{"time": 1.0, "force": [0, 1, 0], "duration": 0.0}]}, r"push\[0\]\['duration'\]"),
        (BIPED, {"push": [{"time": 1.0, "force": [0, 1, 0]}]}, r"push\[0\]"),
        (BIPED, {"push": [{"time": 1.0, "force": [0, 1, 0], "duration": 0.1, "body": "tail"}]}, "push"),
        (BIPED, {"push": [{"time": 1.0, "force": [0, 1, 0], "duration": 0.1, "bdy": "torso"}]}, r"push\[0\]"),
        (BIPED, {"push": {"rate": 0.0, "force": (1, 2), "duration": 0.1}}, r"push\['rate'\]"),
        (BIPED, {"push": {"rate": 1.0, "force": (2, 1), "duration": 0.1}}, r"push\['force'\]"),
        (BIPED, {"push": {"rate": 1.0, "force": (1, 2), "duration": 0.1, "direction": "up"}}, r"push\['direction'\]"),
        (PLANAR, {"obs_noise": -0.1}, "obs_noise"),
        (PLANAR, {"obs_noise": {"target": 0.1}}, "obs_noise"),
        (AGRI, {"obs_noise": float("inf")}, "obs_noise"),
        (AGRI, {"obs_noise": [0.1]}, "obs_noise"),
    ],
)
def test_invalid_fault_arguments_raise_naming_the_argument(env_id: str, kwargs: dict[str, Any], name: str) -> None:
    with pytest.raises(EnvConfigError, match=name):
        gym.make(env_id, **kwargs)
