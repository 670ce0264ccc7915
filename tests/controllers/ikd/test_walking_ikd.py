"""The IKD as the walking controller's trajectory generator: along the walking pattern its motion needs exactly the
realized contact moment (RNEA), whose ZMP stays in the support box; the hybrid stabilization keeps the CoM on the
plan; the balance feedback moves the soles against the CoM."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.ikd import WalkingIkd, WalkingIkdConfig
from redundancy_gym.controllers.walking import GaitConfig, WalkingController, WalkingPattern
from redundancy_gym.model import RobotModel
from tests.controllers.walking.biped_helpers import standing

FEET = ("r_sole", "l_sole")
DT = 0.004


@pytest.fixture(scope="module")
def biped() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def _contact_moment(model: RobotModel, q: np.ndarray, qdot: np.ndarray, qddot: np.ndarray) -> np.ndarray:
    """The ground's moment about the world origin [N m] for the motion (RNEA's floating-base rows)."""
    data = model.pinocchio_model.createData()
    tau = pin.rnea(model.pinocchio_model, data, q, qdot, qddot)
    base = pin.XYZQUATToSE3(q[:7])
    force = base.rotation @ tau[:3]
    return base.rotation @ tau[3:6] + np.cross(base.translation, force)


def _walk(biped: RobotModel, config: WalkingIkdConfig, duration: float, shift: np.ndarray | None = None) -> dict:
    """A kinematic walk of the IKD along a plain LIPM pattern at 0.4 m/s (4 ms periods, as in BipedWalk)."""
    q = standing(biped)
    biped.update(q)
    feet = [biped.frame_position(f).copy() for f in FEET]
    com = biped.com().copy()
    gait = GaitConfig()
    pattern = WalkingPattern(gait, feet[0], feet[1], com[:2], 0.4)
    ikd = WalkingIkd(biped, DT, config, omega=np.sqrt(9.81 / gait.com_height), posture=q)
    ikd.start(q)
    out = {"moment_error": [], "inside": [], "distance": [], "shift_outside_ds": [], "relative": [], "limited": False}
    offset = np.zeros(2) if shift is None else shift
    for n in range(int(round(duration / DT))):
        t = n * DT
        start, end = pattern.sample(t), pattern.sample(t + DT)
        start_ref = WalkingController._reference_array(start, np.zeros(2), np.zeros(2))
        end_ref = WalkingController._reference_array(end, np.zeros(2), np.zeros(2))
        k = start.step
        window = (pattern.step_start(k) + pattern.step_single(k), pattern.step_start(k + 1)) if k >= 0 else None
        q0, qdot0 = ikd.q.copy(), ikd.qdot.copy()
        step = ikd.step(start, start_ref, end_ref, window, offset)
        assert step.success
        if step.limited:  # run off so far that the legs stretch: the velocity bound acts, the moment is not exact
            out["limited"] = True
            break
        moment = _contact_moment(biped, q0, qdot0, step.qddot)
        out["moment_error"].append(float(np.abs(moment[:2] - step.moment).max() / np.abs(step.moment).max()))
        out["inside"].append(bool(np.all(step.zmp >= step.support[0] - 1e-9) and np.all(step.zmp <= step.support[1] + 1e-9)))
        out["distance"].append(float(np.linalg.norm(step.com[:2] - start.com[:2])))
        in_double = window is not None and window[0] - DT <= t <= window[1]
        out["shift_outside_ds"].append(bool(step.planning_shift.any()) and not in_double)
        biped.update(q0)
        out["relative"].append(step.com[:2] - np.mean([biped.frame_position(f)[:2] for f in FEET], axis=0))
    return out


def test_along_the_pattern_the_motion_needs_exactly_the_realized_moment_and_its_zmp_stays_in_the_support(biped):
    out = _walk(biped, WalkingIkdConfig(), 2.6)  # the start and three steps
    assert not out["limited"] and len(out["distance"]) == 650
    assert max(out["moment_error"]) < 1e-6
    assert all(out["inside"])
    assert max(out["distance"]) < 0.01  # hybrid stabilization: on the plan to a centimetre
    assert not any(out["shift_outside_ds"])  # the planning modifies the ZMP in double support only


def test_without_stabilization_the_ikd_runs_off_the_plan(biped):
    out = _walk(biped, WalkingIkdConfig(moment_gain=0.0, planning=False), 2.6)
    assert max(out["distance"]) > 0.03


def test_the_balance_offset_moves_the_soles_and_leaves_the_com_on_the_plan(biped):
    base = _walk(biped, WalkingIkdConfig(), 0.3)
    moved = _walk(biped, WalkingIkdConfig(), 0.3, shift=np.array([0.02, -0.01]))
    # the CoM relative to the soles moves by the offset (the soles by minus it), the CoM itself stays on the plan
    np.testing.assert_allclose(moved["relative"][-1] - base["relative"][-1], [0.02, -0.01], atol=2e-3)
    assert max(moved["distance"]) < 0.01


def test_bad_settings_are_refused_by_name():
    with pytest.raises(ControllerError, match="moment_gain"):
        WalkingIkdConfig(moment_gain=-1.0)
    with pytest.raises(ControllerError, match="planning_ramp"):
        WalkingIkdConfig(planning_ramp=0.0)
    with pytest.raises(ControllerError, match="max_velocity"):
        WalkingIkdConfig(max_velocity=0.0)
    with pytest.raises(ControllerError, match="support_margin"):
        WalkingIkdConfig(support_margin=0.2)
