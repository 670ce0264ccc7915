"""The BipedTerrain side view: a recorded walk over a low platform and its figure."""

from __future__ import annotations

import numpy as np

from redundancy_gym.studies.terrain_plots import plot_terrain_walk, record_terrain_walk


def test_a_recorded_platform_walk_and_its_side_view(tmp_path) -> None:
    kwargs = {"segments": [{"kind": "platform", "height": 0.08, "length": 1.0}], "first_segment_distance": 1.0}
    trace = record_terrain_walk(kwargs, seed=4100)
    assert trace.success and not trace.fell
    n = trace.time.size
    assert trace.planned_feet.shape == trace.measured_feet.shape == (n, 2, 3)
    # the measured soles stood on the platform's top, and the plan put them there too (in the world frame)
    on_top = (trace.measured_feet[:, :, 0] > 1.2) & (trace.measured_feet[:, :, 0] < 1.8)
    assert np.any(np.abs(trace.measured_feet[:, :, 2][on_top] - 0.08 - 0.0) < 0.02)
    assert np.max(trace.planned_feet[:, :, 2]) > 0.08
    assert trace.profile.max() == 0.08 and trace.description[0].startswith("platform at x 1.00-2.00 m")
    path = plot_terrain_walk(trace, tmp_path / "side.png", "platform")
    assert path.is_file() and path.stat().st_size > 20_000
