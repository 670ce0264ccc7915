"""Obstacle figures: the trace of a short beam walk and what the swing and top-view plots show."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from redundancy_gym.assets.obstacle_course import beam_course
from redundancy_gym.studies.obstacle_plots import (
    ObstacleTrace,
    obstacle_windows,
    plot_footholds_top_view,
    plot_swing_trajectories,
    record_obstacle_walk,
)

_DURATION = 4.2  # [s]: the left foot crosses the beam at about 3.1 s, the right one at about 3.9 s
_DT = 0.004  # [s] BipedObstacles' control period


@pytest.fixture(scope="module")
def beam() -> ObstacleTrace:
    return record_obstacle_walk("beam", seed=0, duration=_DURATION)


def test_trace_shapes_and_values(beam: ObstacleTrace) -> None:
    n = int(round(_DURATION / _DT))
    assert beam.course == "beam"
    assert beam.time.shape == (n,)
    np.testing.assert_allclose(np.diff(beam.time), _DT, atol=1e-9)
    assert beam.time[0] == pytest.approx(0.0)
    for name in ("nominal", "planned", "reference", "measured"):
        feet = getattr(beam, name)
        assert feet.shape == (n, 2, 3), name
        assert np.all(np.isfinite(feet)), name
    assert beam.planned_contact.shape == (n, 2) and beam.planned_contact.dtype == np.bool_
    assert beam.obstacle_contact.shape == (n,) and beam.obstacle_contact.dtype == np.bool_
    assert beam.obstacle_contacts == int(beam.obstacle_contact.sum())
    assert beam.footholds.shape == beam.nominal_footholds.shape
    assert beam.footholds.shape[1] == 3 and beam.footholds.shape[0] >= 7  # h_0 ... the landing of step >= 4
    assert np.all(np.isfinite(beam.footholds)) and np.all(np.isfinite(beam.nominal_footholds))
    lower, upper = beam_course()[0].bounding_box()
    np.testing.assert_allclose(beam.obstacle_boxes, [[lower, upper]])
    assert beam.plan_boxes.ndim == 3 and beam.plan_boxes.shape[1:] == (2, 3)
    assert not beam.fell
    assert not beam.success  # stopped before the course's end
    # right foot on the right; both start standing on the ground at the origin
    assert np.all(beam.planned[:, 0, 1] < beam.planned[:, 1, 1])
    np.testing.assert_allclose(beam.planned[0], beam.nominal[0])
    np.testing.assert_allclose(beam.measured[0, :, 2], 0.0, atol=5e-3)


def test_ssta_swing_rises_over_the_beam(beam: ObstacleTrace) -> None:
    """Each foot crosses the beam once, planned above its top, where the nominal swing would pass through it; the
    reference with RCA is above the top too; SSTA moved a foothold off the beam."""
    windows = obstacle_windows(beam)
    assert [foot for foot, _, _ in windows] == [1, 0]  # the left foot first (the 5th foothold is a left one)
    top = float(beam.obstacle_boxes[0, 1, 2])
    for foot, start, end in windows:
        over = (beam.time >= start) & (beam.time <= end)
        assert over.sum() >= 10
        planned = beam.planned[over, foot, 2]
        nominal = beam.nominal[over, foot, 2]
        assert planned.min() > top  # the sole point clears the 16.1 cm beam
        assert nominal.max() < top  # the nominal swing (10 cm apex) would hit it
        assert np.all(planned > nominal + 0.05)
        assert beam.reference[over, foot, 2].min() > top
    assert [kind for _, kind, _, _ in beam.modifications] == ["over", "over"]
    # no planned foothold's sole overlaps the beam along x, while a nominal one did
    lower, upper = beam.obstacle_boxes[0, 0, 0], beam.obstacle_boxes[0, 1, 0]

    def on_beam(h: np.ndarray) -> np.ndarray:
        return (h[:, 0] + 0.165 >= lower) & (h[:, 0] - 0.095 <= upper)

    assert not on_beam(beam.footholds).any()
    assert on_beam(beam.nominal_footholds).any()


def _check_png(path: Path) -> None:
    assert path.stat().st_size > 10_000
    with Image.open(path) as image:
        assert image.format == "PNG"
        assert image.size[0] > 800 and image.size[1] > 300


def test_plots_write_pngs(beam: ObstacleTrace, tmp_path: Path) -> None:
    swing = plot_swing_trajectories(beam, tmp_path / "sub" / "swing.png", "beam: swing feet")
    top = plot_footholds_top_view(beam, tmp_path / "top.png", "beam: footholds")
    assert swing == tmp_path / "sub" / "swing.png" and top == tmp_path / "top.png"
    _check_png(swing)
    _check_png(top)
