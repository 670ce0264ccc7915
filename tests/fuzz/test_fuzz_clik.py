"""Fuzz Clik.step and CompiledClik.step on random q and targets: both agree, or both raise ControllerError;
never a NaN command."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from redundancy_gym.assets import PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.controllers import (
    Clik,
    CollisionObjective,
    CompiledClik,
    ControllerError,
    FramePositionTask,
    JointLimitObjective,
    Objective,
    PostureObjective,
)
from redundancy_gym.geometry import PSS, Segment
from redundancy_gym.model import ModelError, RobotModel, collision_model_from_mjcf

from ..controllers.clik.test_compiled_clik import agri_clik
from .strategies import hostile_vectors, vectors


def _planar(method: str) -> Clik:
    model = RobotModel.from_mjcf(PLANAR_ARM_XML)
    ball = Segment("ball", (PSS([0.7, 0.0, -0.12], 0.1),))
    objectives: list[Objective] = [
        JointLimitObjective.from_model(model, activation_distance=0.3),
        PostureObjective(np.zeros(4), [1.0, 0.5, 0.2, 0.1]),
        CollisionObjective(collision_model_from_mjcf(model, [ball]), activation_distance=0.15, slope=2.0, weight=3.0),
    ]
    return Clik(model, FramePositionTask(PLANAR_ARM_TCP, "xz"), method=method, objectives=objectives, period=0.01)


def _agri(method: str) -> Clik:
    return agri_clik(method)[0]


CASES = [(robot, method) for robot in ("planar", "agri") for method in ("dls", "pseudoinverse", "transpose")]


@pytest.fixture(scope="module", params=CASES, ids=[f"{r}-{m}" for r, m in CASES])
def cliks(request) -> tuple[Clik, CompiledClik, int]:
    robot, method = request.param
    clik = (_planar if robot == "planar" else _agri)(method)
    return clik, CompiledClik(clik), (2 if robot == "planar" else 6)


# a wrong-shaped q raises the model's ModelError (documented, in both backends); everything else ControllerError
PACKAGE_ERRORS = (ControllerError, ModelError)


def _outcome(fn, *args):
    try:
        return fn(*args)
    except PACKAGE_ERRORS as exc:
        return exc


@given(data=st.data())
def test_clik_backends_agree_or_both_raise(cliks, data) -> None:
    clik, compiled, dim = cliks
    model = clik.model
    lo, hi = model.lower_limits, model.upper_limits
    inside = st.lists(st.floats(-0.1, 1.1), min_size=model.nq, max_size=model.nq).map(
        lambda u: lo + np.array(u) * (hi - lo)
    )
    q = data.draw(st.one_of(inside, vectors(model.nq), hostile_vectors(model.nq)), label="q")
    target = data.draw(st.one_of(vectors(dim), hostile_vectors(dim)), label="target")
    velocity = data.draw(st.one_of(st.none(), vectors(dim), hostile_vectors(dim)), label="target_velocity")
    reference = _outcome(clik.step, q, target, velocity)
    result = _outcome(compiled.step, q, target, velocity)
    if isinstance(reference, PACKAGE_ERRORS) or isinstance(result, PACKAGE_ERRORS):
        assert isinstance(reference, PACKAGE_ERRORS) and isinstance(result, PACKAGE_ERRORS), (reference, result)
        return
    for r in (reference, result):
        assert r.qdot.shape == (model.nv,)
        assert np.all(np.isfinite(r.qdot)) and np.all(np.isfinite(r.error))
        assert np.all(np.abs(r.qdot) <= clik.max_joint_velocity * (1 + 1e-9))
    scale = max(1.0, float(np.abs(reference.qdot).max()))
    np.testing.assert_allclose(result.qdot, reference.qdot, atol=1e-6 * scale)
    assert (result.status, result.limited) == (reference.status, reference.limited)
