"""Ground contact by force (foot force difference control): the foot carrying more than its planned share rises,
the other is pressed down, both return to the plan when the forces agree, and the controller moves the soles'
references by half the difference each."""

from __future__ import annotations

import math

import numpy as np
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.controllers import ControllerError
from redundancy_gym.controllers.walking import FootForceControl, FootForceGains
from redundancy_gym.model import RobotModel

from .biped_helpers import standing, walking_controller

DT = 0.004


def test_the_foot_with_more_than_its_share_rises_and_the_other_is_pressed_down() -> None:
    control = FootForceControl(FootForceGains(gain=1e-4, time_constant=0.1, force_filter=0.0))
    # the plan puts the weight on the right foot (an early touchdown of the left): the left rises (delta > 0)
    delta, rate = control.update(DT, 400.0, 200.0, right_load=1.0)
    error = (200.0 - 400.0) - (1.0 - 2.0) * 600.0
    assert rate == pytest.approx(1e-4 * error) and delta == pytest.approx(1e-4 * error * DT) and delta > 0.0
    control.reset()
    # the plan moves the weight onto the left foot, which carries nothing yet (a late touchdown): it goes down
    delta, _ = control.update(DT, 600.0, 0.0, right_load=0.3)
    assert delta < 0.0


def test_agreeing_forces_let_the_feet_return_to_the_plan_at_the_time_constant() -> None:
    control = FootForceControl(FootForceGains(gain=1e-4, time_constant=0.1, force_filter=0.0))
    for _ in range(25):
        control.update(DT, 0.0, 600.0, right_load=1.0)  # the left overloaded for 0.1 s
    held = control.offset
    for _ in range(250):  # 1 s of forces as planned: exp(-1 / 0.1) of the offset left, to Euler's round-off
        control.update(DT, 600.0, 0.0, right_load=1.0)
    assert held > 0.0 and 0.0 < control.offset < held * 1.5 * math.exp(-10.0)


def test_the_height_difference_stays_within_max_offset_and_its_rate_says_so() -> None:
    control = FootForceControl(FootForceGains(gain=1e-2, time_constant=0.1, max_offset=0.01, force_filter=0.0))
    previous = 0.0
    for _ in range(50):
        delta, rate = control.update(DT, 0.0, 600.0, right_load=1.0)
        assert delta <= 0.01 and rate == pytest.approx((delta - previous) / DT)
        previous = delta
    assert delta == 0.01


def test_the_force_filter_smooths_a_ringing_force() -> None:
    # a force that flips between the feet every period (the touchdown's ringing) moves the filtered control less
    raw = FootForceControl(FootForceGains(gain=1e-4, force_filter=0.0))
    filtered = FootForceControl(FootForceGains(gain=1e-4, force_filter=0.03))
    for k in range(40):
        left = 600.0 if k % 2 else 0.0
        raw.update(DT, 600.0 - left, left, right_load=0.5)
        filtered.update(DT, 600.0 - left, left, right_load=0.5)
    assert abs(filtered.rate) < 0.2 * abs(raw.rate)


@pytest.mark.parametrize(
    ("name", "value", "bound"),
    [
        ("gain", -1e-4, ">= 0"),
        ("time_constant", 0.0, "> 0"),
        ("max_offset", math.nan, ">= 0"),
        ("force_filter", -1.0, ">= 0"),
    ],
)
def test_bad_gains_raise_naming_the_gain_and_its_range(name: str, value: float, bound: str) -> None:
    with pytest.raises(ControllerError, match=f"foot force {name} must be a finite number {bound}"):
        FootForceGains(**{name: value})


def test_the_controller_moves_the_soles_by_half_the_difference_each_and_off_changes_nothing() -> None:
    model = RobotModel.from_mjcf(BIPED_XML)
    q = standing(model)
    v = np.zeros(model.nv)
    torques = np.zeros((2, 3))
    forces = np.array([[0.0, 0.0, -600.0], [0.0, 0.0, 0.0]])  # all the weight on the right foot (sensor: -reaction)
    soles, deltas = [], []
    for gains in (None, FootForceGains(gain=1e-4, force_filter=0.0), FootForceGains()):
        controller = walking_controller(model)
        controller.foot_force_gains = gains or FootForceGains()
        controller.foot_force = FootForceControl(gains) if gains is not None and gains.active else None
        controller.start(q, 0.5)
        controller.step(q, v, forces, torques)
        assert controller.q_ref is not None
        model.update(controller.q_ref)
        soles.append([model.frame_position(f)[2] for f in ("r_sole", "l_sole")])
        if controller.foot_force is not None:
            deltas.append(controller.foot_force.offset)
    (delta,) = deltas
    assert delta < 0.0  # the right foot carries more than the weight shift's share: it rises, the left goes down
    (right, left), (right_ff, left_ff), (right_off, left_off) = soles
    assert right_ff - right == pytest.approx(-0.5 * delta, abs=2e-6)
    assert left_ff - left == pytest.approx(0.5 * delta, abs=2e-6)
    assert (right_off, left_off) == (right, left)  # gain 0: the control is not built, the step is the same
