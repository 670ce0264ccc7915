"""Fuzz the swept-sphere constructors, `distance` and `PairBatch`: a valid volume/result or GeometryError."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from redundancy_gym.geometry import LSS, PSS, TSS, GeometryError, PairBatch, distance

from .strategies import points3, radii, vectors

SANE_POINT = vectors(3)
SANE_RADIUS = st.floats(0.0, 2.0)


def build(kind: str, pts: list, radius) -> object:
    """Construct one volume; a GeometryError is the only accepted failure."""
    cls = {"PSS": PSS, "LSS": LSS, "TSS": TSS}[kind]
    n = {"PSS": 1, "LSS": 2, "TSS": 3}[kind]
    volume = cls(*pts[:n], radius=radius)
    assert np.all(np.isfinite(volume.vertices)) and volume.vertices.shape == (3, 3)
    assert np.isfinite(volume.radius) and volume.radius >= 0.0
    return volume


@given(kind=st.sampled_from(["PSS", "LSS", "TSS"]), pts=st.lists(points3(), min_size=3, max_size=3), radius=radii())
def test_ssv_constructors_validate_or_raise(kind: str, pts: list, radius) -> None:
    try:
        build(kind, pts, radius)
    except GeometryError:
        pass


volumes = st.builds(
    lambda kind, pts, r: {"PSS": PSS, "LSS": LSS, "TSS": TSS}[kind](
        *pts[: {"PSS": 1, "LSS": 2, "TSS": 3}[kind]], radius=r
    ),
    st.sampled_from(["PSS", "LSS", "TSS"]),
    st.lists(SANE_POINT, min_size=3, max_size=3),
    SANE_RADIUS,
)


@given(a=volumes, b=volumes)
def test_distance_is_finite_and_consistent(a, b) -> None:
    d = distance(a, b)
    assert np.isfinite(d.distance)
    assert np.all(np.isfinite(d.point_a)) and np.all(np.isfinite(d.point_b)) and np.all(np.isfinite(d.normal))
    assert d.distance >= -(a.radius + b.radius) - 1e-9
    gap = float(np.linalg.norm(d.point_b - d.point_a))
    assert gap - a.radius - b.radius == pytest.approx(d.distance, abs=1e-7 * max(1.0, gap))
    assert float(np.linalg.norm(d.normal)) == pytest.approx(1.0, abs=1e-9)
    # symmetric
    assert distance(b, a).distance == pytest.approx(d.distance, abs=1e-7 * max(1.0, gap))


@given(
    a=st.one_of(volumes, st.none(), st.integers(), st.text(max_size=2)),
    b=st.one_of(volumes, st.none(), st.just([0.0, 0.0, 0.0])),
)
def test_distance_rejects_non_volumes(a, b) -> None:
    try:
        d = distance(a, b)
    except GeometryError:
        return
    assert np.isfinite(d.distance)


@given(
    vols=st.lists(volumes, min_size=1, max_size=8),
    pairs=st.lists(st.tuples(st.integers(-2, 9), st.integers(-2, 9)), max_size=12),
    moving=st.one_of(st.none(), st.integers(-2, 10), st.floats(allow_nan=True), st.text(max_size=1)),
    moves=st.lists(vectors(3), min_size=1, max_size=3),
)
def test_pair_batch_matches_distance_or_raises(vols, pairs, moving, moves) -> None:
    ia = [p[0] for p in pairs]
    ib = [p[1] for p in pairs]
    try:
        batch = PairBatch(vols, ia, ib, moving=moving)
    except GeometryError:
        return
    assert len(batch) == len(pairs)
    for shift in moves:  # move every volume in place, then recompute
        batch.vertices += shift
        moved = [type(v)(*(v.points + shift), radius=v.radius) for v in vols]
        batch.set_active(np.ones(len(batch), dtype=bool))  # compute_near below leaves far pairs masked (+inf)
        result = batch.compute()
        assert np.all(np.isfinite(result.distance))
        for k, (i, j) in enumerate(pairs):
            expected = distance(moved[i], moved[j]).distance
            assert result.distance[k] == pytest.approx(expected, abs=1e-9 * max(1.0, abs(expected)))
        nearest = batch.compute_near(0.5)
        assert not np.isnan(nearest)
