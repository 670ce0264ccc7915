"""CompiledBipedIkd against BipedIkd: the same accelerations from the compiled model terms, the same integration,
and the same IKD walk."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.ikd import BipedIkd, CompiledBipedIkd
from redundancy_gym.controllers.objectives import ObjectiveValue
from redundancy_gym.model import RobotModel
from tests.controllers.ikd.test_biped_ikd import _assert_same_result, _walk_states
from tests.controllers.walking.biped_helpers import standing


@pytest.fixture(scope="module")
def biped() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def test_the_compiled_terms_give_the_reference_step_along_a_walk(biped):
    # the states of a stabilized IKD walk: the same accelerations, moments and diagnostics as the pinocchio terms,
    # with and without the posture term, and the terms themselves to round-off
    states = _walk_states(biped, 0.6)
    posture = standing(biped)
    pairs = [
        (cls(biped, posture=posture, moment_gain=1e-3), kind)
        for kind in ("posture", "free")
        for cls in (BipedIkd, CompiledBipedIkd)
    ]
    for q, qdot, reference in states:
        for k in range(0, len(pairs), 2):
            slow, fast = pairs[k][0], pairs[k + 1][0]
            _assert_same_result(fast.step(q, qdot, reference), slow.step(q, qdot, reference))
            for name, a, b in zip(slow.terms._fields, slow.terms, fast.terms, strict=True):
                np.testing.assert_allclose(b, a, atol=1e-10, rtol=1e-10, err_msg=name)


class _CentreOfMassHeight:
    """``H = c_z``: an objective that reads the model's kinematic cache (its CoM and CoM Jacobian)."""

    def evaluate(self, model: RobotModel, q: np.ndarray) -> ObjectiveValue:
        return ObjectiveValue(float(model.com()[2]), model.com_jacobian()[2].copy())


def test_other_objectives_see_the_model_at_the_step_state(biped):
    # an objective other than the walking controller's joint limits is evaluated on the model; the compiled terms
    # leave pinocchio's cache alone, so the twin must update the model at q first (else the gradient is stale)
    states = _walk_states(biped, 0.4)
    posture = standing(biped)
    objectives = (_CentreOfMassHeight(),)
    slow = BipedIkd(biped, posture=posture, moment_gain=1e-3, objectives=objectives)
    fast = CompiledBipedIkd(biped, posture=posture, moment_gain=1e-3, objectives=objectives)
    for q, qdot, reference in states[::4]:
        biped.update(posture)  # a stale cache
        expected = slow.step(q, qdot, reference)
        biped.update(posture)
        _assert_same_result(fast.step(q, qdot, reference), expected)


def test_integrate_equals_the_models_and_refuses_bad_input(biped, rng):
    ikd = CompiledBipedIkd(biped)
    q = standing(biped)
    for _ in range(5):
        qdot = rng.normal(size=biped.nv)
        np.testing.assert_allclose(ikd.integrate(q, qdot, 0.004), biped.integrate(q, qdot, 0.004), atol=1e-14)
    with pytest.raises(ControllerError, match="shapes"):
        ikd.integrate(q[:-1], np.zeros(biped.nv), 0.004)
    with pytest.raises(ControllerError, match="non-finite"):
        ikd.integrate(q, np.full(biped.nv, np.inf), 0.004)
