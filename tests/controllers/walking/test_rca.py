"""RCA (monograph 5.4.2): the task-space modification (5.80) against finite differences of the potential, the
attractor, and the C2, overshoot-free return to the nominal before touchdown."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_SOFT_LIMIT_MARGIN, BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import Rca, RcaConfig, return_quintic_no_overshoot_time
from redundancy_gym.geometry import LSS, TSS
from redundancy_gym.model import RobotModel

from .biped_helpers import standing

DT = 0.004


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def make_rca(model: RobotModel, **config: float) -> Rca:
    lower, upper = model.lower_limits[7:], model.upper_limits[7:]
    return Rca(model, lower + BIPED_SOFT_LIMIT_MARGIN, upper - BIPED_SOFT_LIMIT_MARGIN, RcaConfig(**config))


def lifted_right_leg(model: RobotModel) -> np.ndarray:
    """The right leg lifted (hip and knee flexed) as in a swing, the left on the ground."""
    return standing(model, r_hip_pitch=-0.9, r_knee=1.5, r_ankle_pitch=-0.5)


def post_in_front_of_the_right_shin(model: RobotModel, q: np.ndarray, gap: float = 0.03) -> LSS:
    """A horizontal bar across the path at mid-shin height, ``gap`` [m] (swept-sphere distance) in front of the
    right leg."""
    model.update(q)
    mid = 0.5 * (model.frame_position("r_knee") + model.frame_position("r_ankle_roll"))
    probe = make_rca(model, joint_limit_weight=0.0)
    x = float(mid[0]) + 0.2
    for _ in range(3):  # the distance is linear in x while the same witness points are closest
        bar = LSS([x, mid[1] - 0.1, mid[2]], [x, mid[1] + 0.1, mid[2]], 0.02)
        probe.set_obstacles([bar])
        model.update(q)
        _, distance = probe.modification_rate(q, 0)
        x += gap - distance
    return LSS([x, mid[1] - 0.1, mid[2]], [x, mid[1] + 0.1, mid[2]], 0.02)


def rca_at_the_bar(model: RobotModel, gap: float) -> tuple[np.ndarray, Rca, np.ndarray]:
    """The lifted right leg, an RCA with the bar ``gap`` [m] in front of its shin, and its sole position [m]."""
    q = lifted_right_leg(model)
    rca = make_rca(model)
    rca.set_obstacles([post_in_front_of_the_right_shin(model, q, gap=gap)])
    model.update(q)
    return q, rca, model.frame_position("r_sole")


def test_the_modification_is_the_steepest_descent_of_the_potential_through_the_least_squares_map(model):
    """(5.80): ``wdot = -[(J_F)^#]^T dH/dq^T``; each component is minus the derivative of ``H`` along the joint
    motion ``J_F^# e_i`` that moves the swing foot along axis ``i`` (finite differences of the potential)."""
    q = lifted_right_leg(model)
    rca = make_rca(model, joint_limit_weight=0.0)
    rca.set_obstacles([post_in_front_of_the_right_shin(model, q)])
    model.update(q)
    rate, distance = rca.modification_rate(q, 0)
    assert 0.0 < distance < RcaConfig().activation_distance
    assert np.linalg.norm(rate) > 1e-3
    model.update(q)
    jacobian = model.frame_jacobian("r_sole", "translational")
    least_squares = jacobian.T @ np.linalg.inv(jacobian @ jacobian.T)
    objective = rca._models[0]  # noqa: SLF001 (the collision potential of the right leg)

    def potential(x: np.ndarray) -> float:
        model.update(x)
        return objective.evaluate(model, x).value

    eps = 1e-6
    numeric = np.array(
        [
            (
                potential(model.integrate(q, least_squares[:, i], eps))
                - potential(model.integrate(q, least_squares[:, i], -eps))
            )
            / (2 * eps)
            for i in range(3)
        ]
    )
    np.testing.assert_allclose(rate, -numeric, rtol=1e-4, atol=1e-7)
    # the post stands in front: the foot is sent backwards, away from it
    assert rate[0] < 0.0


def test_the_swing_leg_is_pushed_off_the_obstacle_and_the_attractor_pulls_back_to_the_nominal(model):
    q, rca, foot = rca_at_the_bar(model, gap=0.01)
    offsets = [rca.update(q, 0, 3, 0.6 - i * DT, DT, foot, 0.0).offset for i in range(50)]
    assert offsets[-1][0] < -0.01  # pushed backwards while the obstacle is near
    # obstacles gone: the attractor (5.82) alone pulls the modification back, without overshoot
    rca.set_obstacles([])
    trace = np.array([rca.update(q, 0, 3, 0.4 - i * DT, DT, foot, 0.0).offset[0] for i in range(50)])
    assert abs(trace[-1]) < 0.5 * abs(offsets[-1][0])
    assert np.all(trace <= 1e-12)


def test_the_return_before_touchdown_is_c2_overshoot_free_and_ends_exactly_on_the_nominal(model):
    q, rca, foot = rca_at_the_bar(model, gap=0.0)
    single = 0.64
    states = []
    for i in range(int(round(single / DT)) + 1):
        remaining = single - (i + 1) * DT
        states.append(rca.update(q, 0, 5, remaining, DT, foot, 0.0))
    w = np.array([s.offset for s in states])
    v = np.array([s.velocity for s in states])
    a = np.array([s.acceleration for s in states])
    returning = np.array([s.returning for s in states])
    assert returning.any() and not returning[0]
    assert np.abs(w).max() > 0.01  # it did move the foot
    # at touchdown (and from the end of the return on) the reference is the nominal foothold, to 1e-12
    np.testing.assert_allclose(w[-1], 0.0, atol=1e-12)
    np.testing.assert_allclose(v[-1], 0.0, atol=1e-12)
    # continuity: consecutive velocities are the differences of positions; no acceleration jump at the switch
    # beyond the filter's own per-period change
    np.testing.assert_allclose(np.diff(w, axis=0)[1:], 0.5 * (v[1:] + v[:-1])[1:] * DT, atol=2e-4)
    switch = int(np.argmax(returning))
    jumps = np.abs(np.diff(a, axis=0)).max(axis=1)
    assert jumps[switch - 1] <= 3.0 * max(jumps[: switch - 1].max(), 1.0)
    # overshoot-free: no component of the return crosses zero
    w0 = w[switch - 1]
    for i in range(3):
        if abs(w0[i]) > 1e-9:
            assert np.all(np.sign(w[switch:, i]) * np.sign(w0[i]) >= 0.0) or np.all(np.abs(w[switch:, i]) < 1e-12)


@pytest.mark.parametrize("seed", range(20))
def test_the_return_time_bound_keeps_the_quintic_from_crossing_zero(seed):
    rng = np.random.default_rng(seed)
    w0, v0, a0 = rng.uniform(0.01, 0.1), rng.uniform(-1.0, 1.0), rng.uniform(-20.0, 20.0)
    limit = return_quintic_no_overshoot_time(w0, v0, a0)
    duration = min(limit, 1.0)
    tau = np.linspace(0.0, 1.0, 2001)
    sigma = 1 - tau**3 * (10 - 15 * tau + 6 * tau**2)
    psi = tau * (1 - tau) ** 3 * (1 + 3 * tau)
    chi = 0.5 * tau**2 * (1 - tau) ** 3
    path = w0 * sigma + v0 * duration * psi + a0 * duration**2 * chi
    assert np.all(path >= -1e-12)
    # the bound is sharp at the end for a pure velocity towards zero: 10 % longer does cross
    if a0 >= 0.0 and v0 < 0.0 and np.isfinite(limit):
        assert limit == pytest.approx(w0 / (0.4 * -v0))


def test_a_velocity_towards_zero_would_overshoot_without_the_bound():
    w0, v0 = 0.02, -1.0
    limit = return_quintic_no_overshoot_time(w0, v0, 0.0)
    tau = np.linspace(0.0, 1.0, 2001)
    sigma = 1 - tau**3 * (10 - 15 * tau + 6 * tau**2)
    psi = tau * (1 - tau) ** 3 * (1 + 3 * tau)
    assert np.min(w0 * sigma + v0 * 3.0 * limit * psi) < 0.0


def test_the_tss_obstacle_and_config_errors(model):
    q = lifted_right_leg(model)
    rca = make_rca(model)
    rca.set_obstacles([TSS([5.0, -1.0, 0.0], [5.0, 1.0, 0.0], [5.0, 0.0, 1.0], 0.05)])
    model.update(q)
    foot = model.frame_position("r_sole")
    state = rca.update(q, 0, 1, 0.5, DT, foot, 0.0)
    assert not state.active  # gated: the obstacle is 5 m away, no distance computed
    np.testing.assert_array_equal(state.offset, 0.0)
    with pytest.raises(ControllerError, match="attractor"):
        RcaConfig(attractor=-1.0)
    with pytest.raises(ControllerError, match="min_return_time"):
        RcaConfig(return_time=0.05, min_return_time=0.1)
    with pytest.raises(ControllerError, match="unknown segments"):
        Rca(model, model.lower_limits[7:], model.upper_limits[7:], legs=(("r_thigh",), ("nope",)))


def test_the_soles_covers_bring_an_obstacle_beside_the_sole_into_view(model):
    # a post 60 mm beside the right sole's outer edge: the foot's own capsule (r 45 mm on the foot's axis) sees it
    # 80 mm away, the sole's TSS cover (its mid-plane rectangle, r 15 mm) 35 mm away, inside the activation distance
    q = standing(model)
    model.update(q)
    sole = model.frame_position("r_sole")
    x, y = float(sole[0]), float(sole[1]) - 0.075 - 0.06
    post = LSS([x, y, float(sole[2])], [x, y, float(sole[2]) + 0.1], 0.01)
    distances = {}
    for covers in (True, False):
        lower, upper = model.lower_limits[7:], model.upper_limits[7:]
        rca = Rca(model, lower, upper, RcaConfig(), **({} if covers else {"sole_geoms": ()}))
        rca.set_obstacles([post])
        model.update(q)
        distances[covers] = rca.modification_rate(q, 0)[1]
    assert distances[True] == pytest.approx(0.06 - 0.015 - 0.01, abs=1e-9)
    assert distances[False] == pytest.approx(0.075 + 0.06 - 0.045 - 0.01, abs=1e-9)
    with pytest.raises(ControllerError, match=r"sole_geoms move with segments \['r_foot'\]"):
        Rca(
            model,
            model.lower_limits[7:],
            model.upper_limits[7:],
            legs=(("r_thigh",), ("l_thigh",)),
            sole_geoms=("r_sole_geom",),
        )
