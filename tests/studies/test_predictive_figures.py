"""Predictive IK's figures (redundancy_gym.studies.predictive_figures): the kinematic rollouts and their plots."""

from __future__ import annotations

import numpy as np

from redundancy_gym.studies.predictive_figures import planar_kinematic_traces, plot_pseudoenergy


def test_kinematic_traces_track_the_line_and_plot(tmp_path) -> None:
    traces = planar_kinematic_traces(global_iterations=30, augmented=(True,))
    for trace in traces.values():
        assert np.max(trace.task_error) < 2e-3 and np.min(trace.clearance) > 0.0
    assert traces["MPC 1 s (augmented)"].pseudoenergy() < traces["local CLIK"].pseudoenergy()
    path = plot_pseudoenergy(traces, tmp_path / "p.png", "fig. 5.31")
    assert path.stat().st_size > 1000
