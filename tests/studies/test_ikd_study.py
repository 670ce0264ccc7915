"""The kinematic IKD study (figs. 5.21, 5.23, 5.24, 5.27 analogues) on a two-step walk: properties that the
monograph's comparison rests on, and the inverse dynamics it measures with."""

from __future__ import annotations

import json

import numpy as np
import pytest

from redundancy_gym.controllers.ikd.biped_ikd import GRAVITY, BipedIkd, BipedIkdReference
from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.studies import ikd_study
from redundancy_gym.studies.ikd_study import (
    IkdStudyConfig,
    contact_wrench,
    format_ikd_study,
    plot_ikd_study,
    run_ikd_study,
    write_ikd_study,
)

CONFIG = IkdStudyConfig(steps=2, gains=(0.0, 1e-3, 1e-2))


@pytest.fixture(scope="module")
def study() -> ikd_study.IkdStudy:
    return run_ikd_study(CONFIG, progress=False)


@pytest.fixture(scope="module")
def report(study) -> dict:
    return study.to_json()


def test_the_ikd_hybrid_needs_the_smallest_moment_error_of_the_three(report):
    # fig. 5.27: the moment by inverse dynamics against the ideal, LIPM + CLIK, + error compensation, IKD hybrid
    methods = report["fig_5_27_comparison"]
    rms = {name: row["moment_error_rms_nm"]["norm"] for name, row in methods.items()}
    assert rms["ikd_hybrid"] < rms["plan_clik"] and rms["ikd_hybrid"] < rms["plan_error_compensation"]
    assert all(row["completed"] for row in methods.values())
    # the CLIK's motion is not the plan's dynamics: a moment error of tens of N m (the swinging leg)
    assert methods["plan_clik"]["moment_error_max_nm"]["norm"] > 20.0


def test_the_ikd_realizes_its_moment_exactly_and_its_cop_stays_in_the_support_box(study, report):
    # the IKD's realized moment is the inverse dynamics' to 1e-6 (relative) on every run; where (5.97) saturates to
    # the support box, the inverse dynamics' CoP never leaves it
    for walk in (study.unstabilized, *study.moment_feedback, *study.hybrid, study.comparison):
        scale = np.abs(walk.moment).max(axis=1)
        assert np.all(np.abs(walk.inverse_dynamics_moment - walk.moment).max(axis=1) <= 1e-6 * scale), walk.label
    for walk in (*study.moment_feedback[1:], *study.hybrid[1:], study.comparison):
        inside = np.all((walk.cop >= walk.support[:, 0] - 1e-6) & (walk.cop <= walk.support[:, 1] + 1e-6), axis=1)
        assert walk.completed and np.all(inside), walk.label
        realized = np.column_stack([-walk.moment[:, 1], walk.moment[:, 0]]) / (60.0 * GRAVITY)
        assert np.all((realized >= walk.support[:, 0] - 1e-9) & (realized <= walk.support[:, 1] + 1e-9))
    for row in report["k_sweep"]:
        assert row["inverse_dynamics_relative_error_max"] < 1e-6


def test_unstabilized_the_ikd_drifts_off_the_plan_and_the_gain_keeps_it_on(study, report):
    # fig. 5.21: k = 0 runs off (it stops at the divergence limit before the walk ends); figs. 5.23: k = 1e-3 and
    # 1e-2 (K_p = 40, 400 > g / z_c) stay within a centimetre and the larger gain stays closer, at the price of a
    # larger moment modification
    unstabilized = report["fig_5_21_unstabilized"]
    assert not unstabilized["completed"] and unstabilized["com_distance_max_m"] > 0.1
    assert unstabilized["com_distance_after_step_m"][0] > 0.02
    assert unstabilized["moment_error_max_nm"]["norm"] < 1e-9  # the moment is the ideal one: tracked exactly
    rows = {(row["k"], row["stabilization"]): row for row in report["k_sweep"]}
    small, large = rows[(1e-3, "moment")], rows[(1e-2, "moment")]
    assert small["completed"] and large["completed"]
    assert large["com_distance_max_m"] < small["com_distance_max_m"] < 0.01
    assert small["moment_error_rms_nm"]["norm"] < large["moment_error_rms_nm"]["norm"]
    assert rows[(1e-3, "moment")]["kp_per_s2"] == pytest.approx(40.0)
    assert report["pendulum_bound_kp_per_s2"] == pytest.approx(GRAVITY / 0.91)


def test_the_error_compensation_moves_the_com_and_changes_the_moment(study):
    # the compensated CLIK tracks the plan plus the pendulum's offset: its CoM leaves the plan by millimetres and its
    # moment differs from the plain CLIK's
    plain, compensated = study.clik, study.error_compensation
    offset = np.linalg.norm(compensated.com - compensated.plan_com, axis=1)
    assert 1e-3 < offset.max() < 0.05
    assert np.linalg.norm(plain.com - plain.plan_com, axis=1).max() < 1e-3
    assert np.abs(compensated.moment - plain.moment).max() > 1.0


def test_the_contact_wrench_of_a_standing_robot_is_its_weight_under_its_com():
    walk = ikd_study._Walk(IkdStudyConfig(steps=1))
    model, q = walk.model, walk.start
    force, moment = contact_wrench(model, q, np.zeros(model.nv), np.zeros(model.nv))
    model.update(q)
    com = model.com()
    np.testing.assert_allclose(force, [0.0, 0.0, model.total_mass * GRAVITY], atol=1e-9)
    np.testing.assert_allclose(ikd_study._cop(force, moment, walk.ground), com[:2], atol=1e-9)


def test_central_differences_of_the_configurations_give_the_ikd_moment():
    # the CLIK runs' moment comes from the central differences of their configurations; on the IKD's own motion
    # (semi-implicit Euler: the second difference is its qddot exactly, the central velocity off by h qddot / 2) they
    # give its realized moment to a fraction of a N m
    walk = ikd_study._Walk(IkdStudyConfig(steps=1))
    model, h = walk.model, walk.period
    ikd = BipedIkd(model, posture=walk.start, moment_gain=1e-3, period=h)
    q, qdot = walk.start.copy(), np.zeros(model.nv)
    configurations, realized = [q.copy(), q.copy()], []
    for n in range(800):
        sample, ahead = walk.samples[n], walk.samples[n + 1]
        twist = ikd_study._feet_twist(sample)
        reference = BipedIkdReference(
            sample.feet.copy(),
            np.array([ikd_study._pitch(a) for a in sample.feet_pitch]),
            twist,
            (ikd_study._feet_twist(ahead) - twist) / h,
            np.eye(3),
            np.zeros(3),
            np.zeros(3),
            np.array([sample.com[2], 0.0, 0.0]),
            walk.ideal[n],
            np.concatenate([sample.com[:2], sample.com_velocity[:2]]),
            walk.support[n],
        )
        result = ikd.step(q, qdot, reference)
        realized.append(result.moment)
        qdot = qdot + h * result.qddot
        q = model.integrate(q, qdot, h)
        configurations.append(q.copy())
    errors = [
        np.abs(ikd_study._differenced_wrench(model, configurations[n : n + 3], h)[1][:2] - realized[n]).max()
        for n in range(1, 800)
    ]
    assert max(errors) < 0.5


def test_the_report_is_json_and_the_figures_are_written(study, report, tmp_path):
    text = json.dumps(report)
    assert "NaN" not in text and "Infinity" not in text
    path = write_ikd_study(study, tmp_path / "ikd.json")
    assert json.loads(path.read_text())["walk"]["periods"] == 2000
    written = plot_ikd_study(study, tmp_path)
    assert [p.name for p in written] == ["ikd_fig_5_21.png", "ikd_fig_5_23.png", "ikd_fig_5_24.png", "ikd_fig_5_27.png"]
    assert all(p.stat().st_size > 10_000 for p in written)
    table = format_ikd_study(report)
    assert "fig. 5.27" in table and "ikd_hybrid" in table


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"speed": 0.0}, "speed"),
        ({"steps": 0}, "steps"),
        ({"period": float("nan")}, "period"),
        ({"gains": (-1.0,)}, "gains"),
    ],
)
def test_bad_settings_are_refused_by_name(kwargs, name):
    with pytest.raises(EvalError, match=name):
        IkdStudyConfig(**kwargs)


def test_on_the_corrected_plan_the_hybrid_holds_a_small_gain_and_moves_the_modification_into_double_support():
    # fig. 5.24 on the walking controller's plan (multi-body ZMP correction, the first steps with their own tables):
    # with k = 2e-4 (K_p = 8 < g / z_c) the contact-moment feedback alone lets the CoM drift off the plan, farther
    # with every step (its largest distance is its last, eight times the hybrid's), the hybrid keeps it within a few
    # millimetres, with a larger share of its moment modification in double support
    study = run_ikd_study(IkdStudyConfig(gains=(2e-4,), comparison_gain=2e-4, correction=True), progress=False)
    sweep = {row["stabilization"]: row for row in study.to_json()["k_sweep"]}
    feedback, hybrid = sweep["moment"], sweep["hybrid"]
    assert hybrid["completed"] and hybrid["com_distance_max_m"] < 0.01
    assert feedback["com_distance_final_m"] == feedback["com_distance_max_m"] > 5.0 * hybrid["com_distance_max_m"]
    assert hybrid["modification_share_in_double_support"] > feedback["modification_share_in_double_support"] + 0.1
    # the ideal is the reference ZMP, not the corrected plan's own
    assert study.config.plan_name == "LIPM plan + ZMP correction"
    assert "ZMP correction" in study.clik.label
