"""SSV distances (5.2.3) against coal and an exact QP oracle, on random and named degenerate pairs."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.bench.coal_shapes import coal_distance
from redundancy_gym.geometry import LSS, PSS, SSV, TSS, GeometryError, distance, distances

from .qp_oracle import point_to_primitive, ssv_distance

TOL = 1e-9  # the acceptance asks for 1e-7
KINDS = ("PSS", "LSS", "TSS")
PAIR_TYPES = [(a, b) for i, a in enumerate(KINDS) for b in KINDS[i:]]


def random_volume(rng: np.random.Generator, kind: str, spread: float = 1.0, size: float = 0.5) -> SSV:
    c = rng.uniform(-spread, spread, 3)
    r = rng.uniform(0.0, 0.2)
    p = [c + rng.uniform(-size, size, 3) for _ in range(3)]
    return {"PSS": PSS(c, r), "LSS": LSS(p[0], p[1], r), "TSS": TSS(p[0], p[1], p[2], r)}[kind]


def check_pair(a: SSV, b: SSV, tol: float = TOL) -> None:
    """Oracle distance, witness consistency, witnesses on the primitives, symmetry, unit normal."""
    res = distance(a, b)
    assert np.isfinite(res.distance) and np.all(np.isfinite(res.point_a)) and np.all(np.isfinite(res.normal))
    assert res.distance == pytest.approx(ssv_distance(a, b), abs=tol)
    gap = np.linalg.norm(res.point_b - res.point_a)
    assert gap - a.radius - b.radius == pytest.approx(res.distance, abs=tol)
    assert point_to_primitive(res.point_a, a) < tol
    assert point_to_primitive(res.point_b, b) < tol
    assert np.linalg.norm(res.normal) == pytest.approx(1.0, abs=1e-12)
    if gap > 1e-9:
        np.testing.assert_allclose(res.normal * gap, res.point_b - res.point_a, atol=tol)
    swapped = distance(b, a)
    assert swapped.distance == pytest.approx(res.distance, abs=1e-12)


@pytest.mark.parametrize(("kind_a", "kind_b"), PAIR_TYPES)
def test_random_separated_pairs_match_coal(kind_a: str, kind_b: str) -> None:
    rng = np.random.default_rng(7)
    checked = 0
    while checked < 60:
        a, b = random_volume(rng, kind_a), random_volume(rng, kind_b)
        res = distance(a, b)
        if res.distance < 1e-3:
            continue
        ref, near_a, near_b = coal_distance(a, b)
        assert res.distance == pytest.approx(ref, abs=1e-9)
        # coal's nearest points lie on the swept surfaces: our witnesses moved out by the radii
        np.testing.assert_allclose(res.point_a + a.radius * res.normal, near_a, atol=1e-6)
        np.testing.assert_allclose(res.point_b - b.radius * res.normal, near_b, atol=1e-6)
        checked += 1


@pytest.mark.parametrize(("kind_a", "kind_b"), PAIR_TYPES)
def test_random_pairs_match_qp_oracle(kind_a: str, kind_b: str) -> None:
    """Dense random pairs, most overlapping or intersecting, against the exact QP."""
    rng = np.random.default_rng(11)
    for _ in range(80):
        check_pair(random_volume(rng, kind_a, spread=0.3), random_volume(rng, kind_b, spread=0.3))


def test_batched_equals_single(rng: np.random.Generator) -> None:
    a = [random_volume(rng, KINDS[i % 3]) for i in range(30)]
    b = [random_volume(rng, KINDS[(i // 3) % 3]) for i in range(30)]
    batch = distances(a, b)
    for k in range(30):
        single = distance(a[k], b[k])
        assert batch.distance[k] == single.distance
        np.testing.assert_array_equal(batch.point_a[k], single.point_a)
        np.testing.assert_array_equal(batch.normal[k], single.normal)


# --- named degenerate cases ------------------------------------------------------------------------------


def test_zero_length_segments() -> None:
    point_like = LSS([0.2, 0.1, 0.3], [0.2, 0.1, 0.3], 0.05)
    check_pair(point_like, LSS([0, 0, 0], [1, 0, 0], 0.1))
    check_pair(point_like, LSS([0.5, 0.5, 0.5], [0.5, 0.5, 0.5], 0.1))
    check_pair(point_like, TSS([0, 0, 0], [1, 0, 0], [0, 1, 0], 0.01))
    check_pair(point_like, PSS([0.2, 0.1, 0.3], 0.02))
    assert distance(point_like, PSS([0.2, 0.1, 0.3], 0.02)).distance == pytest.approx(-0.07, abs=1e-15)


def test_parallel_segments_apart() -> None:
    a = LSS([0, 0, 0], [1, 0, 0], 0.1)
    b = LSS([2, 0.5, 0], [3, 0.5, 0], 0.1)
    check_pair(a, b)
    assert distance(a, b).distance == pytest.approx(np.hypot(1.0, 0.5) - 0.2, abs=1e-14)


def test_parallel_overlapping_segments_return_the_middle_of_the_overlap() -> None:
    """(5.48) and the text below it: the minimizing region is a range; its middle is returned."""
    a = LSS([0, 0, 0], [1, 0, 0], 0.1)
    b = LSS([0.6, 0.5, 0], [1.6, 0.5, 0], 0.1)
    check_pair(a, b)
    res = distance(a, b)
    assert res.distance == pytest.approx(0.3, abs=1e-14)
    np.testing.assert_allclose(res.point_a, [0.8, 0, 0], atol=1e-14)
    np.testing.assert_allclose(res.point_b, [0.8, 0.5, 0], atol=1e-14)


def test_antiparallel_and_nearly_parallel_segments() -> None:
    check_pair(LSS([0, 0, 0], [1, 0, 0], 0.1), LSS([1.4, 0.3, 0.1], [0.2, 0.3, 0.1], 0.1))
    for angle in (1e-4, 1e-6, 1e-8, 1e-11):
        b = LSS([0.3, 0.2, 0.0], [0.3 + np.cos(angle), 0.2 + np.sin(angle), 0.0], 0.0)
        check_pair(LSS([0, 0, 0], [1, 0, 0], 0.0), b)


def test_collinear_segments() -> None:
    overlapping = distance(LSS([0, 0, 0], [1, 0, 0], 0.1), LSS([0.5, 0, 0], [2, 0, 0], 0.2))
    assert overlapping.distance == pytest.approx(-0.3, abs=1e-15)
    check_pair(LSS([0, 0, 0], [1, 0, 0], 0.1), LSS([0.5, 0, 0], [2, 0, 0], 0.2))
    apart = distance(LSS([0, 0, 0], [1, 0, 0], 0.1), LSS([1.5, 0, 0], [2, 0, 0], 0.2))
    assert apart.distance == pytest.approx(0.2, abs=1e-15)
    np.testing.assert_allclose(apart.normal, [1, 0, 0])


def test_degenerate_triangles() -> None:
    collinear = TSS([0, 0, 0], [1, 0, 0], [0.4, 0, 0], 0.05)
    coincident = TSS([0.3, 0.3, 0.3], [0.3, 0.3, 0.3], [0.3, 0.3, 0.3], 0.05)
    two_equal = TSS([0, 0, 0], [0, 0, 0], [0, 1, 0], 0.05)
    others = [
        PSS([0.5, 0.5, 0.2], 0.1),
        LSS([0.2, -1, 0.3], [0.2, 1, 0.3], 0.1),
        TSS([0, 0, 0.5], [1, 1, 0.5], [0, 1, 0.5], 0.1),
        TSS([0.2, -1, -1], [0.2, 1, -1], [0.2, 0, 1], 0.0),
        collinear,
        coincident,
        two_equal,
    ]
    for tri in (collinear, coincident, two_equal):
        for other in others:
            check_pair(tri, other)
    assert distance(coincident, PSS([0.3, 0.3, 1.3], 0.1)).distance == pytest.approx(0.85, abs=1e-14)


def test_coplanar_triangles() -> None:
    base = TSS([0, 0, 0], [1, 0, 0], [0, 1, 0], 0.05)
    overlapping = TSS([0.2, 0.2, 0], [1.2, 0.2, 0], [0.2, 1.2, 0], 0.05)
    contained = TSS([0.1, 0.1, 0], [0.3, 0.1, 0], [0.1, 0.3, 0], 0.05)
    apart = TSS([1, 1, 0], [2, 1, 0], [1, 2, 0], 0.05)
    assert distance(base, overlapping).distance == pytest.approx(-0.1, abs=1e-15)
    assert distance(base, contained).distance == pytest.approx(-0.1, abs=1e-15)
    assert distance(base, apart).distance == pytest.approx(np.sqrt(0.5) - 0.1, abs=1e-14)
    for other in (overlapping, contained, apart):
        check_pair(base, other)


def test_segment_piercing_triangle() -> None:
    tri = TSS([0, 0, 0], [1, 0, 0], [0, 1, 0], 0.02)
    seg = LSS([0.25, 0.25, -1], [0.25, 0.25, 1], 0.03)
    res = distance(seg, tri)
    assert res.distance == pytest.approx(-0.05, abs=1e-15)
    np.testing.assert_allclose(res.point_a, [0.25, 0.25, 0], atol=1e-15)
    check_pair(seg, tri)
    check_pair(tri, TSS([0.25, 0.25, -1], [0.25, 0.25, 1], [0.3, 0.1, 1], 0.0))  # triangle through triangle
    check_pair(LSS([0.25, 0.25, 0], [3, 3, 0], 0.0), tri)  # in-plane segment leaving the triangle


def test_concentric_and_touching_spheres() -> None:
    concentric = distance(PSS([1, 2, 3], 0.2), PSS([1, 2, 3], 0.3))
    assert concentric.distance == pytest.approx(-0.5, abs=1e-15)
    assert np.linalg.norm(concentric.normal) == pytest.approx(1.0)
    touching = distance(PSS([0, 0, 0], 0.2), PSS([0.5, 0, 0], 0.3))
    assert touching.distance == pytest.approx(0.0, abs=1e-15)
    np.testing.assert_allclose(touching.normal, [1, 0, 0])
    concentric_triangle = distance(TSS([0, 0, 0], [1, 0, 0], [0, 1, 0], 0.1), TSS([0, 0, 0], [1, 0, 0], [0, 1, 0], 0.1))
    assert concentric_triangle.distance == pytest.approx(-0.2, abs=1e-15)
    assert np.all(np.isfinite(concentric_triangle.normal))


@pytest.mark.parametrize(("kind_a", "kind_b"), PAIR_TYPES)
def test_large_coordinates(kind_a: str, kind_b: str) -> None:
    """A pair 1e6 m from the origin has the distance it has at the origin."""
    rng = np.random.default_rng(3)
    offset = np.array([1e6, -2e6, 3e6])
    for _ in range(20):
        a, b = random_volume(rng, kind_a), random_volume(rng, kind_b)
        near = distance(a, b).distance
        far = distance(a.transformed(np.eye(3), offset), b.transformed(np.eye(3), offset)).distance
        assert far == pytest.approx(near, abs=1e-8)


@pytest.mark.parametrize(("kind_a", "kind_b"), PAIR_TYPES)
def test_tiny_features(kind_a: str, kind_b: str) -> None:
    """Micrometre-sized primitives a micrometre apart keep their relative accuracy."""
    rng = np.random.default_rng(5)
    for _ in range(20):
        a = random_volume(rng, kind_a, spread=1e-6, size=1e-6)
        b = random_volume(rng, kind_b, spread=1e-6, size=1e-6)
        a = SSV.from_kind(a.kind, a.points, 1e-7)
        b = SSV.from_kind(b.kind, b.points, 1e-7)
        check_pair(a, b, tol=1e-15)


def test_invalid_input_raises() -> None:
    with pytest.raises(GeometryError, match="radius"):
        PSS([0, 0, 0], -1.0)
    with pytest.raises(GeometryError, match="finite"):
        LSS([0, 0, np.nan], [1, 0, 0], 0.1)
    with pytest.raises(GeometryError, match="3-vector"):
        TSS([0, 0], [1, 0, 0], [0, 1, 0], 0.1)
    with pytest.raises(GeometryError, match="PSS, LSS or TSS"):
        distance(PSS([0, 0, 0], 1.0), [0, 0, 0])  # type: ignore[arg-type]


def test_pair_batch_matches_single_queries_in_the_original_order(rng: np.random.Generator) -> None:
    from redundancy_gym.geometry import PairBatch

    volumes = [random_volume(rng, KINDS[i % 3], spread=0.4) for i in range(24)]
    volumes.append(PSS(volumes[0].points[0], 0.1))  # touching primitives: the centroid normal
    ia = rng.integers(0, len(volumes), 60)
    ib = rng.integers(0, len(volumes), 60)
    ia[-1], ib[-1] = len(volumes) - 1, 0
    batch = PairBatch(volumes, ia, ib)
    result = batch.compute()
    for k in range(60):
        single = distance(volumes[ia[k]], volumes[ib[k]])
        assert result.distance[k] == pytest.approx(single.distance, abs=1e-12)
        np.testing.assert_allclose(result.point_a[k], single.point_a, atol=1e-12)
        np.testing.assert_allclose(result.point_b[k], single.point_b, atol=1e-12)
        np.testing.assert_allclose(result.normal[k], single.normal, atol=1e-12)
    batch.vertices[:] += np.array([0.5, -0.2, 0.1])  # moving every volume leaves the distances unchanged
    np.testing.assert_allclose(batch.compute().distance, result.distance.copy(), atol=1e-12)


def test_flat_sphere_and_capsule_loops_hand_hard_cases_to_the_general_path(rng: np.random.Generator) -> None:
    """The branch-free PSS-PSS, PSS-LSS and LSS-LSS loops must agree with the general closest-point code on every
    pair, with hard cases (parallel, nearly parallel, collapsed, intersecting, concentric, touching, tiny, huge,
    inactive) mixed in."""
    from redundancy_gym.geometry import PairBatch
    from redundancy_gym.geometry.ssv_kernels import point_segment, segment_segment

    def lss(p0: list[float], p1: list[float]) -> LSS:
        return LSS(p0, p1, 0.05)

    hard = [
        (lss([0, 0, 0], [1, 0, 0]), lss([0.2, 0.3, 0], [1.4, 0.3, 0])),  # parallel, overlapping projections
        (lss([0, 0, 0], [1, 0, 0]), lss([1.4, 0.3, 0], [0.2, 0.3, 0])),  # antiparallel
        (lss([0, 0, 0], [1, 0, 0]), lss([0, 0.2, 0], [1, 0.2 + 1e-9, 0])),  # nearly parallel
        (lss([0.3, 0.3, 0.3], [0.3, 0.3, 0.3]), lss([0, 0, 0], [1, 0, 0])),  # collapsed segment
        (lss([0, 0, 0], [1, 0, 0]), lss([0.5, -1, 0], [0.5, 1, 0])),  # crossing: intersecting primitives
        (lss([0, 0, 0], [1, 0, 0]), lss([1, 0, 0], [2, 1, 0])),  # sharing an end point
    ]
    pairs = [(random_volume(rng, "LSS"), random_volume(rng, "LSS")) for _ in range(40)] + hard
    pairs += [(random_volume(rng, "PSS"), random_volume(rng, "PSS")) for _ in range(20)]
    pairs += [(PSS([0.1, 0.2, 0.3], 0.1), PSS([0.1, 0.2, 0.3], 0.2))]  # concentric
    # sphere/capsule pairs in both orders (the kernel swaps the capsule-first ones), with their hard cases
    pairs += [(random_volume(rng, "PSS"), random_volume(rng, "LSS")) for _ in range(20)]
    pairs += [(random_volume(rng, "LSS"), random_volume(rng, "PSS")) for _ in range(20)]
    pairs += [
        (PSS([0.5, 0.0, 0.0], 0.1), lss([0, 0, 0], [1, 0, 0])),  # centre on the segment: touching primitives
        (lss([0, 0, 0], [1, 0, 0]), PSS([1.0, 0.0, 0.0], 0.1)),  # centre on an end point, capsule first
        (PSS([0.3, 0.4, 0.0], 0.1), lss([0.2, 0.2, 0.2], [0.2, 0.2, 0.2])),  # collapsed segment
        (PSS([-1.0, 0.5, 0.0], 0.1), lss([0, 0, 0], [1, 0, 0])),  # beyond the first end: s clamped to 0
        (PSS([1e-40, 0.0, 0.0], 1e-41), lss([0, 1e-40, 0], [1e-40, 1e-40, 0])),  # tiny: rescaled general path
        (PSS([1e40, 0.0, 0.0], 1.0), lss([1e40, 1e39, 0], [2e40, 1e39, 0])),  # huge
    ]
    order = rng.permutation(len(pairs))
    volumes = [v for k in order for v in pairs[k]]
    ia = np.arange(0, len(volumes), 2)
    ib = ia + 1
    batch = PairBatch(volumes, ia, ib)
    active = np.ones(len(ia), dtype=bool)
    active[::7] = False
    batch.set_active(active)
    res = batch.compute()
    for k, (a, b) in enumerate(zip(volumes[::2], volumes[1::2], strict=False)):
        if not active[k]:
            assert res.distance[k] == np.inf
            continue
        assert np.all(np.isfinite(res.normal[k])) and np.linalg.norm(res.normal[k]) == pytest.approx(1.0)
        assert res.distance[k] == pytest.approx(ssv_distance(a, b), abs=TOL)
        if isinstance(a, PSS) != isinstance(b, PSS):  # the flat sphere/capsule loop against point_segment
            sphere, capsule = (a, b) if isinstance(a, PSS) else (b, a)
            c = tuple(sphere.points[0])
            d2, q = point_segment(c, *[tuple(x) for x in capsule.points])
            scale = max(1.0, float(np.abs(c).max()))
            assert res.distance[k] == pytest.approx(np.sqrt(d2) - a.radius - b.radius, abs=1e-12 * scale)
            np.testing.assert_allclose(res.point_a[k], c if a is sphere else q, atol=1e-12 * scale)
            np.testing.assert_allclose(res.point_b[k], q if a is sphere else c, atol=1e-12 * scale)
        if isinstance(a, LSS) and isinstance(b, LSS):
            p = [tuple(x) for x in (*a.points, *b.points)]
            d2, pa, pb = segment_segment(*p)
            assert res.distance[k] == pytest.approx(np.sqrt(d2) - a.radius - b.radius, abs=1e-12)
            np.testing.assert_allclose(res.point_a[k], pa, atol=1e-12)
            np.testing.assert_allclose(res.point_b[k], pb, atol=1e-12)


def test_cull_keeps_every_pair_within_the_margin_and_only_lower_bounded_ones_out(rng: np.random.Generator) -> None:
    """The broad phase is conservative: a culled pair is farther than the margin, and compute() gives +inf there."""
    from redundancy_gym.geometry import PairBatch

    volumes = [random_volume(rng, KINDS[i % 3], spread=1.5, size=0.3) for i in range(40)]
    ia = rng.integers(0, 40, 300)
    ib = rng.integers(0, 40, 300)
    batch = PairBatch(volumes, ia, ib)
    exact = batch.compute().distance.copy()
    assert np.all(np.isfinite(exact))
    margin = 0.3
    count = batch.cull(margin)
    culled = batch.compute().distance
    active = np.isfinite(culled)
    assert count == int(active.sum()) and 0 < count < 300  # the test scene has both kinds
    assert np.all(exact[~active] > margin)
    np.testing.assert_allclose(culled[active], exact[active], atol=1e-12)
    batch.set_active(np.ones(300, dtype=bool))
    np.testing.assert_allclose(batch.compute().distance, exact, atol=1e-12)


def test_compute_near_equals_cull_then_compute_and_returns_the_minimum(rng: np.random.Generator) -> None:
    """One-pass broad and narrow phase: the same pairs as cull + compute, the same distances, +inf elsewhere,
    and after moving only the first ``moving`` volumes it still agrees with a fresh full evaluation."""
    from redundancy_gym.geometry import PairBatch

    volumes = [random_volume(rng, KINDS[i % 3], spread=1.5, size=0.3) for i in range(40)]
    ia = rng.integers(0, 6, 300)  # the first 6 volumes move
    ib = rng.integers(6, 40, 300)
    batch = PairBatch(volumes, ia, ib, moving=6)
    reference = PairBatch(volumes, ia, ib)
    margin = 0.3
    for _step in range(3):
        smallest = batch.compute_near(margin)
        near = batch.result.distance.copy()
        count = reference.cull(margin)
        expected = reference.compute().distance
        assert 0 < count < 300 and int(np.isfinite(near).sum()) == count
        np.testing.assert_allclose(near, expected, atol=1e-12)  # inf where culled, exact elsewhere
        assert smallest == pytest.approx(np.min(expected[np.isfinite(expected)]), abs=1e-12)
        shift = rng.normal(0.0, 0.3, (6, 1, 3))
        batch.vertices[:6] += shift
        reference.vertices[:6] += shift
    assert batch.compute_near(-10.0) == np.inf and np.all(batch.result.distance == np.inf)  # negative reach


def test_attached_frames_place_segments_and_points(rng: np.random.Generator) -> None:
    """compute_near reads attached frames in place: volume i becomes p_i -/+ h_i z_i (z: third rotation column)."""
    from scipy.spatial.transform import Rotation

    from redundancy_gym.geometry import PairBatch

    volumes = [
        LSS([0, 0, 0], [0, 0, 1], 0.05),
        PSS([0, 0, 0], 0.04),
        LSS([1, 0, 0], [1, 1, 0], 0.03),
        TSS([0, 1, 0], [1, 1, 1], [0, 1, 1], 0.01),
    ]
    batch = PairBatch(volumes, [0, 0, 1, 1], [2, 3, 2, 3], moving=2)
    positions = np.zeros((2, 3))
    rotations = np.zeros((2, 9))
    batch.attach_frames(positions, rotations, [0.2, 0.0])
    for _ in range(3):
        positions[:] = rng.uniform(-0.5, 0.5, (2, 3))  # written in place, after attaching
        rotations[:] = Rotation.random(2, random_state=rng.integers(1 << 30)).as_matrix().reshape(2, 9)
        batch.compute_near(np.inf)
        z = rotations[0].reshape(3, 3)[:, 2]
        moved = [LSS(positions[0] - 0.2 * z, positions[0] + 0.2 * z, 0.05), PSS(positions[1], 0.04)]
        for k, (a, b) in enumerate([(0, 2), (0, 3), (1, 2), (1, 3)]):
            assert batch.result.distance[k] == pytest.approx(distance(moved[a], volumes[b]).distance, abs=1e-12)
    with pytest.raises(GeometryError, match="C-contiguous float64"):
        batch.attach_frames(positions[:, :2], rotations, [0.2, 0.0])
    with pytest.raises(GeometryError, match="LSS"):
        batch.attach_frames(positions, rotations, [0.0, 0.0])  # volume 0 is an LSS
    with pytest.raises(GeometryError, match="moving"):
        PairBatch(volumes, [0], [2], moving=5)


@pytest.mark.parametrize(("kind_a", "kind_b"), [*PAIR_TYPES, ("TSS", "PSS"), ("LSS", "PSS"), ("TSS", "LSS")])
def test_in_kernel_pair_distance_matches_distance(kind_a: str, kind_b: str) -> None:
    """``volume_pair_distance`` (used inside the fused CLIK kernel) gives ``distance``'s result, either order."""
    from redundancy_gym.geometry import PackedVolumes
    from redundancy_gym.geometry.ssv_kernels import volume_pair_distance

    rng = np.random.default_rng(7)
    for _ in range(100):
        a, b = random_volume(rng, kind_a, spread=0.5), random_volume(rng, kind_b, spread=0.5)
        packed = PackedVolumes.from_volumes((a, b))
        d, pa, pb, n = volume_pair_distance(packed.vertices, packed.radii, packed.kinds, 0, 1)
        ref = distance(a, b)
        assert d == pytest.approx(ref.distance, abs=TOL)
        np.testing.assert_allclose(pa, ref.point_a, atol=1e-9)
        np.testing.assert_allclose(pb, ref.point_b, atol=1e-9)
        np.testing.assert_allclose(n, ref.normal, atol=1e-9)


def test_in_kernel_pair_distance_of_touching_volumes_has_a_unit_normal() -> None:
    from redundancy_gym.geometry import PackedVolumes
    from redundancy_gym.geometry.ssv_kernels import volume_pair_distance

    a, b = LSS([-1, 0, 0], [1, 0, 0], 0.1), LSS([0, -1, 0], [0, 1, 0], 0.1)  # crossing axes: witnesses coincide
    packed = PackedVolumes.from_volumes((a, b))
    d, _, _, n = volume_pair_distance(packed.vertices, packed.radii, packed.kinds, 0, 1)
    assert d == pytest.approx(-0.2)
    assert np.linalg.norm(n) == pytest.approx(1.0)
    np.testing.assert_allclose(n, distance(a, b).normal)


def test_crossing_segments_off_the_grid_get_the_centroid_normal() -> None:
    """Two capsule axes crossing at a point that is not exactly representable: the witnesses differ by
    round-off only, so the normal must be the centroid direction, not normalized noise (batch and in-kernel)."""
    from redundancy_gym.geometry import PackedVolumes, PairBatch
    from redundancy_gym.geometry.ssv_kernels import volume_pair_distance

    rng = np.random.default_rng(11)
    for _ in range(50):
        a0, a1 = rng.normal(size=3), rng.normal(size=3)
        p = a0 + rng.uniform(0.2, 0.8) * (a1 - a0)
        d = rng.normal(size=3)
        s = rng.uniform(0.2, 0.8)
        a, b = LSS(a0, a1, 0.05), LSS(p - s * d, p + (1.0 - s) * d, 0.05)
        centroid = 0.5 * (b.points[0] + b.points[1]) - 0.5 * (a.points[0] + a.points[1])
        expected = centroid / np.linalg.norm(centroid)
        ref = distance(a, b)
        assert ref.distance == pytest.approx(-0.1, abs=1e-9)
        np.testing.assert_allclose(ref.normal, expected, atol=1e-9)
        packed = PackedVolumes.from_volumes((a, b))
        np.testing.assert_allclose(
            volume_pair_distance(packed.vertices, packed.radii, packed.kinds, 0, 1)[3], expected, atol=1e-9
        )
        np.testing.assert_allclose(PairBatch((a, b), [0], [1]).compute().normal[0], expected, atol=1e-9)
