"""Fuzz the predictive IK: the constructor's weights, and rollout / optimize / command on generated states and
references (sane, perturbed, hostile): a finite result with its status and diagnostics, or ControllerError."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from redundancy_gym.assets import PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.controllers import ControllerError, FramePositionTask, JointLimitObjective, PredictiveIk
from redundancy_gym.model import RobotModel

from .strategies import ANY_FLOATS, JUNK, hostile_vectors, vectors

DT = 0.01


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(PLANAR_ARM_XML)


@pytest.fixture(scope="module")
def pik(model) -> PredictiveIk:
    limits = JointLimitObjective.from_model(model, activation_distance=0.35, weight=0.6)
    return PredictiveIk(
        model, FramePositionTask(PLANAR_ARM_TCP, "xz"), joint_limits=limits, augmented=True, input_weight=1e-3
    )


WEIGHTS = st.one_of(st.floats(0.0, 10.0), ANY_FLOATS, JUNK)


@given(velocity_weight=WEIGHTS, input_weight=WEIGHTS, damping=WEIGHTS, augmented=st.booleans())
def test_constructor_validates_or_raises(model, velocity_weight, input_weight, damping, augmented) -> None:
    try:
        pik = PredictiveIk(
            model,
            FramePositionTask(PLANAR_ARM_TCP, "xz"),
            velocity_weight=velocity_weight,
            input_weight=input_weight,
            damping=damping,
            augmented=augmented,
        )
    except ControllerError:
        return
    assert pik.velocity_weight >= 0.0 and pik.damping >= 0.0 and np.isfinite(pik.input_weight)


def _arrays(shape: tuple[int, int], scale: float) -> st.SearchStrategy:
    n = shape[0] * shape[1]
    sane = st.lists(st.floats(-scale, scale), min_size=n, max_size=n).map(lambda v: np.array(v).reshape(shape))
    return st.one_of(
        sane,
        sane.map(lambda a: a * 1e3),
        st.tuples(sane, st.integers(0, n - 1), ANY_FLOATS).map(lambda t: _put(*t)),
        st.just(np.zeros((shape[0] + 1, shape[1]))),
        st.just(np.zeros(shape[1])),
    )


def _put(a: np.ndarray, i: int, value: float) -> np.ndarray:
    out = a.copy()
    out.flat[i] = value
    return out


@given(data=st.data())
def test_optimize_is_finite_or_raises(pik, data) -> None:
    steps = data.draw(st.integers(1, 12), label="steps")
    lo, hi = pik.model.lower_limits, pik.model.upper_limits
    q0 = data.draw(
        st.one_of(
            st.lists(st.floats(-0.1, 1.1), min_size=4, max_size=4).map(lambda u: lo + np.array(u) * (hi - lo)),
            hostile_vectors(4),
        ),
        label="q0",
    )
    wdot = data.draw(_arrays((steps, 6), 1.0), label="wdot")
    initial = data.draw(_arrays((steps, 4), 1.0), label="initial")
    u_b = data.draw(st.one_of(st.none(), vectors(4), hostile_vectors(4)), label="u_b")
    dt = data.draw(st.one_of(st.just(DT), st.floats(1e-4, 0.1), ANY_FLOATS), label="dt")
    iterations = data.draw(st.integers(0, 4), label="max_iterations")
    try:
        result = pik.optimize(q0, wdot, dt, initial, u_b=u_b, max_iterations=iterations)
    except ControllerError:
        return
    roll = result.rollout
    steps = np.shape(initial)[0]  # the wrong-shaped draws of wdot and initial may agree with each other
    assert result.params.shape == (steps, 4) and roll.q.shape == (steps + 1, 4)
    assert np.all(np.isfinite(roll.q)) and np.all(np.isfinite(roll.qdot)) and np.all(np.isfinite(roll.u))
    assert np.isfinite(roll.cost) and roll.cost >= 0.0 and all(np.isfinite(v) for v in roll.terms.values())
    assert result.status in ("converged", "max_iterations", "no_decrease") and result.success
    assert len(result.costs) == result.iterations + 1 <= iterations + 1
    assert all(b <= a * (1 + 1e-12) + 1e-300 for a, b in zip(result.costs, result.costs[1:], strict=False))


@given(
    q=st.one_of(vectors(4), hostile_vectors(4)),
    u=st.one_of(vectors(4), hostile_vectors(4)),
    target=st.one_of(vectors(2), hostile_vectors(2)),
    velocity=st.one_of(vectors(2), hostile_vectors(2)),
    gain=st.one_of(st.floats(0.0, 50.0), ANY_FLOATS),
)
def test_command_is_finite_or_raises(pik, q, u, target, velocity, gain) -> None:
    try:
        qdot, error = pik.command(q, u, target, velocity, gain)
    except ControllerError:
        return
    assert qdot.shape == (4,) and error.shape == (2,)
    assert np.all(np.isfinite(error))
    # with a finite gain and finite inputs, a finite command; an overflowing product may give inf, never NaN
    assert not np.any(np.isnan(qdot)), (qdot, gain)
