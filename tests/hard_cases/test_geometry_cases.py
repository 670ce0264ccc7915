"""Hard cases of the swept-sphere distances against references computed another way.

``tests/geometry/test_distance.py`` checks the named degenerate cases against coal and an exact QP; here each
degenerate volume (zero-length segment, coincident or collinear triangle vertices, zero radius) is checked against a
brute-force minimum over dense samples of the two cores, deep penetrations against the closed forms for spheres
and a point and a segment, and the extremes of the coordinates for finiteness. The SSV convention: the distance
of the cores minus both radii, negative when the volumes overlap.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from redundancy_gym.geometry import LSS, PSS, TSS, GeometryError, PairBatch, distance

GRID = 60  # samples per edge of the brute force


def _samples(volume) -> np.ndarray:
    """Points of the core of ``volume`` (the point, the segment or the triangle), dense enough for the brute force."""
    p = volume.points
    if len(p) == 1:
        return p.copy()
    s = np.linspace(0.0, 1.0, GRID + 1)
    if len(p) == 2:
        return p[0] + s[:, None] * (p[1] - p[0])
    u, v = np.meshgrid(s, s)
    keep = (u + v) <= 1.0 + 1e-12
    u, v = u[keep], v[keep]
    return p[0] + u[:, None] * (p[1] - p[0]) + v[:, None] * (p[2] - p[0])


def _brute_force(a, b) -> tuple[float, float]:
    """``(upper bound, resolution)`` of the SSV distance: the smallest sampled core distance minus the radii, and
    how far the true minimum can lie below it (half the longest sample spacing of both cores)."""
    pa, pb = _samples(a), _samples(b)
    gaps = np.linalg.norm(pa[:, None, :] - pb[None, :, :], axis=2)
    spacing = (
        sum(max((np.linalg.norm(x - y) for x, y in itertools.combinations(v.points, 2)), default=0.0) for v in (a, b))
        / GRID
    )
    return float(gaps.min()) - a.radius - b.radius, float(spacing)


def _check_against_brute_force(a, b) -> None:
    result = distance(a, b)
    upper, resolution = _brute_force(a, b)
    assert upper - resolution - 1e-12 <= result.distance <= upper + 1e-12, (result.distance, upper, resolution)
    # the witness points lie on the cores' surfaces and realize the distance
    assert np.linalg.norm(result.point_b - result.point_a) - a.radius - b.radius == pytest.approx(
        result.distance, abs=1e-12
    )
    assert np.linalg.norm(result.normal) == pytest.approx(1.0, abs=1e-12)
    assert distance(b, a).distance == pytest.approx(result.distance, abs=1e-12)


ZERO_LENGTH_SEGMENT = LSS([0.2, 0.1, 0.3], [0.2, 0.1, 0.3], 0.05)
COINCIDENT_TRIANGLE = TSS([0.3, -0.2, 0.1], [0.3, -0.2, 0.1], [0.3, -0.2, 0.1], 0.04)
COLLINEAR_TRIANGLE = TSS([-0.2, 0.0, 0.0], [0.6, 0.0, 0.0], [0.1, 0.0, 0.0], 0.03)  # a flat "rectangle"'s diagonal
TWO_EQUAL_VERTICES = TSS([0.0, 0.4, 0.0], [0.0, 0.4, 0.0], [0.5, 0.4, 0.3], 0.02)
ZERO_RADIUS = {
    "PSS": PSS([0.1, 0.5, -0.2], 0.0),
    "LSS": LSS([-0.3, 0.2, 0.4], [0.4, 0.3, -0.1], 0.0),
    "TSS": TSS([0.0, -0.5, 0.0], [0.5, -0.4, 0.1], [0.1, -0.3, 0.5], 0.0),
}
PARTNERS = {
    "sphere": PSS([0.4, 0.3, 0.2], 0.1),
    "segment": LSS([-0.5, -0.5, 0.5], [0.5, 0.6, -0.2], 0.05),
    "triangle": TSS([-0.4, 0.2, -0.3], [0.5, 0.1, -0.2], [0.0, 0.5, 0.4], 0.02),
}
DEGENERATE = {
    "zero-length-segment": ZERO_LENGTH_SEGMENT,
    "coincident-triangle": COINCIDENT_TRIANGLE,
    "collinear-triangle": COLLINEAR_TRIANGLE,
    "two-equal-vertices": TWO_EQUAL_VERTICES,
    **{f"zero-radius-{k}": v for k, v in ZERO_RADIUS.items()},
}


@pytest.mark.parametrize("partner", sorted(PARTNERS))
@pytest.mark.parametrize("name", sorted(DEGENERATE))
def test_degenerate_volume_matches_the_brute_force_minimum(name: str, partner: str) -> None:
    _check_against_brute_force(DEGENERATE[name], PARTNERS[partner])


@pytest.mark.parametrize("a, b", list(itertools.combinations(sorted(DEGENERATE), 2)))
def test_two_degenerate_volumes_match_the_brute_force_minimum(a: str, b: str) -> None:
    _check_against_brute_force(DEGENERATE[a], DEGENERATE[b])


def test_collinear_triangle_is_the_segment_of_its_extreme_vertices() -> None:
    segment = LSS([-0.2, 0.0, 0.0], [0.6, 0.0, 0.0], 0.03)
    for partner in PARTNERS.values():
        assert distance(COLLINEAR_TRIANGLE, partner).distance == pytest.approx(
            distance(segment, partner).distance, abs=1e-14
        )


# ------------------------------------------------------------------------------------------- deep penetration
@pytest.mark.parametrize("offset", [0.0, 1e-9, 0.05, 0.29])
def test_deep_sphere_penetration_is_the_closed_form(offset: float) -> None:
    """One sphere's centre inside the other: |c_a - c_b| - r_a - r_b, negative, down to -(r_a + r_b) when
    concentric."""
    a, b = PSS([0.1, 0.2, 0.3], 0.3), PSS([0.1 + offset, 0.2, 0.3], 0.2)
    result = distance(a, b)
    assert result.distance == pytest.approx(offset - 0.5, abs=1e-15)
    assert result.distance < 0.0 and np.linalg.norm(result.normal) == pytest.approx(1.0)


@pytest.mark.parametrize("along", [-0.1, 0.0, 0.37, 1.0, 1.1])  # the centre within 0.12 m of the core
@pytest.mark.parametrize("depth", [0.0, 1e-12, 0.02, 0.1])
def test_sphere_centre_inside_a_capsule_is_the_point_segment_closed_form(along: float, depth: float) -> None:
    a, b = np.array([0.0, 0.0, 0.0]), np.array([1.0, 0.5, -0.2])
    axis = (b - a) / np.linalg.norm(b - a)
    normal = np.cross(axis, [0.0, 0.0, 1.0])
    normal /= np.linalg.norm(normal)
    centre = a + along * (b - a) + depth * normal
    t = np.clip((centre - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    expected = np.linalg.norm(centre - (a + t * (b - a))) - 0.15 - 0.08
    for first, second in ((LSS(a, b, 0.15), PSS(centre, 0.08)), (PSS(centre, 0.08), LSS(a, b, 0.15))):
        result = distance(first, second)
        assert result.distance == pytest.approx(expected, abs=1e-14)
        assert result.distance < 0.0
        assert np.all(np.isfinite(result.normal)) and np.linalg.norm(result.normal) == pytest.approx(1.0)


def test_segment_through_a_triangle_core_is_minus_both_radii() -> None:
    tri = TSS([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0.06)
    for point in ([0.2, 0.2], [0.0, 0.0], [0.5, 0.5], [0.3, 0.0]):  # inside, at a vertex, on the edges
        seg = LSS([*point, -0.4], [*point, 0.7], 0.04)
        assert distance(seg, tri).distance == pytest.approx(-0.1, abs=1e-14)


@pytest.mark.parametrize("gap", [0.5, 0.0, -0.3])
def test_parallel_segments_side_by_side_are_the_closed_form(gap: float) -> None:
    """Parallel cores 0.2 apart whose projections overlap, touch end to end, or miss by ``gap`` along the axis."""
    a = LSS([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.05)
    b = LSS([1.0 + gap, 0.2, 0.0], [2.5 + gap, 0.2, 0.0], 0.05)
    expected = np.hypot(max(gap, 0.0), 0.2) - 0.1
    assert distance(a, b).distance == pytest.approx(expected, abs=1e-14)
    _check_against_brute_force(a, b)


# ----------------------------------------------------------------------------------------- extreme coordinates
@pytest.mark.parametrize("scale", [1e-150, 1e-9, 1e9, 1e150])
@pytest.mark.parametrize("kinds", [("PSS", "PSS"), ("LSS", "LSS"), ("LSS", "TSS"), ("TSS", "TSS")])
def test_huge_and_tiny_coordinates_stay_finite_and_scale(scale: float, kinds: tuple[str, str]) -> None:
    """The same pair scaled by 1e-150 ... 1e150 has its distance scaled (no overflow or underflow to 0 / NaN)."""
    shapes = {
        "PSS": lambda p, r: PSS(p[0], r),
        "LSS": lambda p, r: LSS(p[0], p[1], r),
        "TSS": lambda p, r: TSS(p[0], p[1], p[2], r),
    }
    pa = np.array([[0.0, 0.0, 0.0], [1.0, 0.2, 0.0], [0.2, 1.0, 0.1]])
    pb = np.array([[0.3, 0.4, 1.5], [1.2, 0.1, 1.1], [0.1, 0.9, 2.0]])
    a, b = shapes[kinds[0]](pa, 0.1), shapes[kinds[1]](pb, 0.2)
    a_s, b_s = shapes[kinds[0]](pa * scale, 0.1 * scale), shapes[kinds[1]](pb * scale, 0.2 * scale)
    reference, scaled = distance(a, b), distance(a_s, b_s)
    assert np.isfinite(scaled.distance) and np.all(np.isfinite(scaled.normal))
    assert np.all(np.isfinite(scaled.point_a)) and np.all(np.isfinite(scaled.point_b))
    assert scaled.distance / scale == pytest.approx(reference.distance, rel=1e-9)


def test_far_from_the_origin_a_pair_keeps_its_distance() -> None:
    offset = np.array([3e7, -1e7, 2e7])
    a, b = LSS([0, 0, 0], [1, 0.1, 0], 0.05), TSS([0.2, 0.5, -0.1], [0.8, 0.6, 0.2], [0.5, 0.9, 0.0], 0.05)
    near = distance(a, b).distance
    p0, p1, p2 = b.points + offset
    far = distance(LSS(a.points[0] + offset, a.points[1] + offset, 0.05), TSS(p0, p1, p2, 0.05)).distance
    assert far == pytest.approx(near, abs=1e-8)  # ulp(3e7) ~ 4e-9


# ------------------------------------------------------------------------------------------------- bad inputs
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("kind, vertex", [("PSS", 0), ("LSS", 0), ("LSS", 1), ("TSS", 0), ("TSS", 1), ("TSS", 2)])
def test_non_finite_vertex_is_rejected_with_geometry_error(kind: str, vertex: int, value: float) -> None:
    n = {"PSS": 1, "LSS": 2, "TSS": 3}[kind]
    points = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]][:n]
    points[vertex][2] = value
    cls = {"PSS": PSS, "LSS": LSS, "TSS": TSS}[kind]
    with pytest.raises(GeometryError, match="finite"):
        cls(*points, radius=0.1)


@pytest.mark.parametrize("radius", [np.nan, np.inf, -1e-12, -np.inf])
def test_bad_radius_is_rejected_naming_the_radius(radius: float) -> None:
    for make in (
        lambda r: PSS([0, 0, 0], r),
        lambda r: LSS([0, 0, 0], [1, 0, 0], r),
        lambda r: TSS([0, 0, 0], [1, 0, 0], [0, 1, 0], r),
    ):
        with pytest.raises(GeometryError, match="radius"):
            make(radius)


def test_pair_batch_of_degenerate_volumes_equals_single_queries() -> None:
    volumes = list(DEGENERATE.values()) + list(PARTNERS.values())
    pairs = list(itertools.combinations(range(len(volumes)), 2))
    batch = PairBatch(volumes, [i for i, _ in pairs], [j for _, j in pairs])
    result = batch.compute()
    for k, (i, j) in enumerate(pairs):
        assert result.distance[k] == pytest.approx(distance(volumes[i], volumes[j]).distance, abs=1e-12)


@pytest.mark.parametrize("scale", [1e-150, 1e-100, 1e-40, 1.0, 1e40, 1e100, 1e150])
def test_crossing_segments_and_a_point_over_a_face_keep_their_closed_form_at_every_scale(scale: float) -> None:
    """Was: below ~1e-80 m the squared lengths' products underflowed, every segment pair was taken for parallel
    and every triangle for degenerate, and the distance came from the ends (0.92 instead of 0.82 for a segment
    and a triangle at 1e-150; nightly-style geometry case). The pair is now scaled by a power of two first."""
    s = scale
    crossing = distance(LSS([0, 0, -s], [0, 0, s], 0.0), LSS([-s, 0.5 * s, 0], [s, 0.5 * s, 0], 0.0))
    assert crossing.distance / s == pytest.approx(0.5, rel=1e-12)
    over_face = distance(PSS([0.3 * s, 0.3 * s, 0.7 * s], 0.0), TSS([0, 0, 0], [s, 0, 0], [0, s, 0], 0.0))
    assert over_face.distance / s == pytest.approx(0.7, rel=1e-12)
    np.testing.assert_allclose(over_face.point_b / s, [0.3, 0.3, 0.0], atol=1e-12)
    through = distance(
        LSS([0.2 * s, 0.2 * s, -s], [0.2 * s, 0.2 * s, s], 0.1 * s), TSS([0, 0, 0], [s, 0, 0], [0, s, 0], 0.05 * s)
    )
    assert through.distance / s == pytest.approx(-0.15, rel=1e-12)


@pytest.mark.parametrize("gap", [2.2250738585e-313, 5e-324, 1e-305])
@pytest.mark.parametrize("kinds", [("PSS", "PSS"), ("PSS", "LSS"), ("LSS", "TSS")])
def test_subnormal_separation_is_finite_and_about_zero(gap: float, kinds: tuple[str, str]) -> None:
    """Volumes a subnormal distance apart (nightly fuzz: the power-of-two rescaling of tiny pairs overflowed to inf
    and gave NaN): the distance is finite and within a few subnormals of the gap."""
    make = {
        "PSS": lambda o: PSS(o, 0.0),
        "LSS": lambda o: LSS(o, o + [0.0, 0.0, gap], 0.0),
        "TSS": lambda o: TSS(o, o + [gap, 0.0, 0.0], o + [0.0, gap, 0.0], 0.0),
    }
    a = make[kinds[0]](np.zeros(3))
    b = make[kinds[1]](np.array([0.0, 0.0, 2.0 * gap]))
    result = distance(a, b)
    assert np.isfinite(result.distance) and abs(result.distance) <= 4.0 * gap
    assert np.all(np.isfinite(result.point_a)) and np.all(np.isfinite(result.point_b))
