"""The grasp CLIK policy's one-call step (observation -> path sample -> CompiledClik kernel -> action) gives what
the separate calls give, bit for bit, and keeps the controller's diagnostics and errors."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import redundancy_gym  # noqa: F401 - registers the envs
from redundancy_gym.controllers import ClikResult, CompiledClik, ControllerError
from redundancy_gym.policies.grasp_clik_policy import GraspClikPolicy

ENV_ID = "redundancy_gym/AgriReach-v0"


def _separate_calls(policy: GraspClikPolicy, obs: np.ndarray) -> tuple[np.ndarray, ClikResult]:
    """The action and result of ``obs`` by the public calls: path sample, ``CompiledClik.step``, clip."""
    q, target, velocity = policy.task_reference(obs, False)
    assert policy.controller is not None
    result = policy.controller.step(q, target, velocity)
    return np.clip(result.qdot / policy.max_joint_speeds, -1.0, 1.0).astype(np.float32), result


def _same_result(a: ClikResult, b: ClikResult) -> None:
    assert np.array_equal(a.qdot, b.qdot) and np.array_equal(a.error, b.error)
    assert (a.error_norm, a.sigma_min, a.damping, a.objective, a.success, a.status, a.limited) == (
        b.error_norm,
        b.sigma_min,
        b.damping,
        b.objective,
        b.success,
        b.status,
        b.limited,
    )


@pytest.mark.parametrize("difficulty", ["medium", "hard"])
def test_fused_step_equals_the_separate_calls_along_an_episode(difficulty: str) -> None:
    """Two policies on the same states: one steps by the fused kernel (the default), the other by the separate
    public calls; actions, results and the smallest collision distance agree to the last bit."""
    env = gym.make(ENV_ID, difficulty=difficulty)
    fused, separate = GraspClikPolicy(env), GraspClikPolicy(env)
    obs, _ = env.reset(seed=3)
    steps = 0
    while True:
        action = fused.predict(obs)[0]
        assert fused._fused is not None  # noqa: SLF001 - the one-call step ran
        expected, result = _separate_calls(separate, obs)
        assert action.dtype == np.float32 and np.array_equal(action, expected)
        assert fused.last_result is not None
        _same_result(fused.last_result, result)
        assert isinstance(fused.controller, CompiledClik) and isinstance(separate.controller, CompiledClik)
        assert fused.controller.last_min_distance == separate.controller.last_min_distance
        obs, _, terminated, truncated, _ = env.step(action)
        steps += 1
        if terminated or truncated:
            break
    assert steps > 50


def test_last_result_is_the_step_that_made_it_across_a_new_episode() -> None:
    """last_result is built when read, from a copy of that step's outputs: a later step of the controller does
    not change it, and a new episode (a new controller) gives that episode's first result."""
    env = gym.make(ENV_ID)
    policy, separate = GraspClikPolicy(env), GraspClikPolicy(env)
    obs, _ = env.reset(seed=0)
    for _ in range(5):
        separate.predict(obs)  # the same episode (path and obstacles) for the separate calls
        obs = env.step(policy.predict(obs)[0])[0]
    policy.predict(obs)
    expected = _separate_calls(separate, obs)[1]
    assert policy.path is not None
    policy.controller.step(obs[policy._layout["q"]], *policy.path(0.0))  # noqa: SLF001 - another step between
    assert policy.last_result is not None
    _same_result(policy.last_result, expected)
    policy.predict(obs)  # left unread: the next episode's controller replaces this one
    first, _ = env.reset(seed=1)
    policy.predict(first)
    assert policy.last_result is not None
    _same_result(policy.last_result, _separate_calls(GraspClikPolicy(env), first)[1])


def test_batch_rows_in_any_memory_layout() -> None:
    """A Fortran-ordered batch (strided rows) gives the actions of the same observations one by one."""
    env = gym.make(ENV_ID)
    obs, _ = env.reset(seed=4)
    observations = [obs]
    for _ in range(3):
        observations.append(env.step(env.action_space.sample() * 0.0)[0])
    batch = np.asfortranarray(np.stack([observations[-1]] * 2))
    assert not batch[0].flags.c_contiguous
    one = GraspClikPolicy(env)
    reference = [one.predict(o)[0] for o in observations[-1:]]
    policy = GraspClikPolicy(env)
    policy.predict(np.stack([observations[-1]] * 2))  # the same time for both: plan at the first call
    actions = policy.predict(batch)[0]
    assert np.array_equal(actions[0], reference[0]) and np.array_equal(actions[1], reference[0])


def test_close_pairs_after_a_fused_step_and_none_after_a_failed_one() -> None:
    """The controller's close pairs read the kinematics that the fused step left; a rejected observation leaves
    none (as a failed CompiledClik.step does)."""
    env = gym.make(ENV_ID, difficulty="hard")
    policy, separate = GraspClikPolicy(env), GraspClikPolicy(env)
    obs, _ = env.reset(seed=0)
    for _ in range(3):  # past the episode start, so that the bad observation below plans no new controller
        separate.predict(obs)
        obs = env.step(policy.predict(obs)[0])[0]
    policy.predict(obs)
    controller = policy.controller
    assert isinstance(controller, CompiledClik)
    limit = 0.1
    distances, rows = controller.close_pairs(limit)
    _separate_calls(separate, obs)
    expected, expected_rows = separate.controller.close_pairs(limit)
    assert distances.size > 0 and np.array_equal(distances, expected) and np.array_equal(rows, expected_rows)
    bad = obs.copy()
    bad[policy._layout["q"].start] = np.nan  # noqa: SLF001
    with pytest.raises(ControllerError, match="q must be finite") as fused_error:
        policy.predict(bad)
    with pytest.raises(ControllerError) as separate_error:
        separate.predict(bad)
    assert str(fused_error.value) == str(separate_error.value)
    assert policy.controller is controller and controller.close_pairs(limit)[0].size == 0


def test_compiled_step_reads_strided_vectors() -> None:
    """CompiledClik.step passes q, target and velocity to the kernel as they are: strided views give the result
    of contiguous copies."""
    env = gym.make(ENV_ID)
    policy = GraspClikPolicy(env)
    obs, _ = env.reset(seed=2)
    policy.predict(obs)
    controller = policy.controller
    q, target, velocity = policy.task_reference(obs, False)
    wide = np.zeros((3, q.size + target.size + velocity.size))
    wide[1] = np.concatenate([q, target, velocity])
    column = np.asfortranarray(wide)[1]
    assert not column.flags.c_contiguous
    strided = controller.step(column[: q.size], column[q.size : q.size + 6], column[q.size + 6 :])
    _same_result(strided, controller.step(q.copy(), target.copy(), velocity.copy()))
