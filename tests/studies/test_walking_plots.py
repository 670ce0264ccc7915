"""The walking figures' traces: the CLIK walker's planned ZMP is the plan's whole-body ZMP (near the reference,
inside the soles), the IKD walker has none of its own (it realizes the reference), and the figure is written."""

from __future__ import annotations

import numpy as np

from redundancy_gym.studies.walking_plots import plot_com_zmp, record_walk


def test_the_planned_zmp_is_the_whole_body_plans_and_the_figure_draws_it(tmp_path) -> None:
    trace = record_walk(0.7, 2.0, 0)
    walking = np.isfinite(trace.zmp_plan[:, 0])
    # from the first step (after the 0.4 s weight shift) to the last step the trace covers
    assert not walking[trace.time < 0.4].any() and walking[(trace.time > 0.45) & (trace.time < 1.6)].all()
    distance = np.linalg.norm(trace.zmp_plan[walking] - trace.zmp_target[walking], axis=1)
    assert np.sqrt(np.mean(distance**2)) < 0.03  # the whole body follows the reference, the LIPM's ZMP does not
    lipm = np.linalg.norm(trace.zmp_ref[walking] - trace.zmp_target[walking], axis=1)
    assert lipm.max() > 2.0 * distance.max()
    ikd = record_walk(0.7, 0.6, 0, ik="ikd")
    assert np.isnan(ikd.zmp_plan).all()
    path = plot_com_zmp(trace, tmp_path / "com_zmp.png", "test")
    assert path.stat().st_size > 20_000
