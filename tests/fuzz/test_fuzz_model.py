"""Fuzz RobotModel queries on random configurations: finite results or ModelError, never another exception."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from redundancy_gym.assets import AGRI_ARM_TCP, AGRI_ARM_XML, BIPED_XML, PLANAR_ARM_TCP, PLANAR_ARM_XML
from redundancy_gym.model import ModelError, RobotModel

from .strategies import JUNK, hostile_vectors, vectors

MODELS = {"planar": (PLANAR_ARM_XML, PLANAR_ARM_TCP), "agri": (AGRI_ARM_XML, AGRI_ARM_TCP), "biped": (BIPED_XML, None)}


@pytest.fixture(scope="module", params=sorted(MODELS))
def model_and_frame(request) -> tuple[RobotModel, str]:
    path, frame = MODELS[request.param]
    model = RobotModel.from_mjcf(path)
    return model, frame or model.frame_names[-1]


def configurations(model: RobotModel) -> st.SearchStrategy:
    """Configurations inside the limits (the useful ones), beyond them, and hostile ones."""
    lo = np.where(np.isfinite(model.lower_limits), model.lower_limits, -10.0)
    hi = np.where(np.isfinite(model.upper_limits), model.upper_limits, 10.0)
    inside = st.lists(st.floats(0.0, 1.0), min_size=model.nq, max_size=model.nq).map(
        lambda u: lo + np.array(u) * (hi - lo)
    )
    return st.one_of(inside, vectors(model.nq), hostile_vectors(model.nq))


def _finite(*arrays) -> None:
    for a in arrays:
        assert np.all(np.isfinite(a)), a


@given(data=st.data())
def test_model_queries_are_finite_or_raise(model_and_frame, data) -> None:
    model, frame = model_and_frame
    q = data.draw(configurations(model), label="q")
    try:
        checked = model.update(q)
    except ModelError:
        return
    _finite(checked)
    _finite(
        model.frame_position(frame),
        model.frame_rotation(frame),
        model.frame_jacobian(frame),
        model.frame_jacobian(frame, "translational"),
        model.com(),
        model.com_jacobian(),
        model.mass_matrix(),
        model.clamp(checked),
        model.to_mujoco_qpos(checked),
    )
    assert model.frame_jacobian(frame).shape == (6, model.nv)
    qdot = data.draw(st.one_of(vectors(model.nv), hostile_vectors(model.nv)), label="qdot")
    dt = data.draw(st.one_of(st.floats(0.0, 0.1), st.floats(allow_nan=True, allow_infinity=True), JUNK), label="dt")
    try:
        _finite(model.integrate(checked, qdot, dt))
    except ModelError:
        pass
    kind = data.draw(st.one_of(st.sampled_from(["full", "translational", "rotational"]), st.text(max_size=4)))
    try:
        assert model.frame_jacobian(frame, kind).shape[1] == model.nv
    except ModelError:
        pass
