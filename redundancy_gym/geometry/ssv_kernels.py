"""Compiled closest-point kernels for swept-sphere volumes (monograph 5.2.3, (5.35)-(5.48)).

Every SSV is stored as three vertices and a radius, with a kind code: ``PSS`` (0) uses ``v0``, ``LSS`` (1)
uses ``v0, v1`` and ``TSS`` (2) all three. The distance between two SSVs is the distance between their
generating primitives minus both radii (5.36). Each pair type follows the monograph's recipe: the
unconstrained minimum of the quadratic (5.35) when it lies in the admissible region, otherwise the minimum
over the edge/vertex sub-problems ((5.43), (5.47), (5.48); for triangles the 6 vertex/plane and 9 edge/edge
queries of the text). Every candidate is a pair of feasible points whose distance is measured directly, so
rounding can only make a candidate slightly worse, never infeasible, and no branch divides by a quantity
that can vanish.

The kernels are plain numba functions on tuples of floats (no heap allocation in the inner loop); the
public entry points are :func:`ssv_pairs_grouped` (pairs given as indices into one array of volumes, pre-sorted
by pair type) and :func:`ssv_pairs_at` (the same on buffer addresses, for repeated calls).
"""

from __future__ import annotations

import math

import numpy as np
from numba import carray, njit, types
from numba.extending import intrinsic

from ..kernel_options import BORROW, JIT

__all__ = [
    "BORROW",
    "GROUPS",
    "GROUP_OF",
    "KIND_LSS",
    "KIND_PSS",
    "KIND_TSS",
    "cull_pairs_at",
    "near_pairs_at",
    "pointer_intrinsic",
    "smallest_pair_at",
    "ssv_pairs_at",
    "ssv_pairs_grouped",
    "volume_pair_distance",
]

KIND_PSS = 0
KIND_LSS = 1
KIND_TSS = 2

# A 2x2 normal-equation system is solved only when det > _SINGULAR * (product of the diagonal), i.e. when the
# two directions are not parallel to within ~1e-5 rad; below that the edge candidates alone are exact.
_SINGULAR = 1e-10
# Above _WELL_CONDITIONED the unconstrained minimum is trusted alone; between the two thresholds it is one
# candidate among the edge candidates (its rounding error can then exceed the distance tolerance).
_WELL_CONDITIONED = 1e-6

_INF = np.inf
# Witness points closer than 1e-12 m [squared: m^2] count as touching: their difference is round-off, so its
# direction would be noise; touching volumes get the centroid normal of _fallback_normal instead.
_CONTACT_GAP2 = 1e-24

# Relative coordinates of a pair whose extent lies outside [2^-100, 2^100] m are scaled by a power of two (exact)
# before the closest-point routines: their squared lengths and 2x2 determinants (fourth powers) would underflow
# to zero below ~1e-80 m (every triangle and segment pair taken for degenerate) or overflow above ~1e77 m.
_SCALE_LOW = 2.0**-100
_SUBNORMAL = 2.0**-1000  # below, the scale 2^-exponent itself overflows: such a pair is left as it is (distance ~0)
_SCALE_HIGH = 2.0**100

# every division here is guarded or measured afterwards and the guards rely on IEEE NaN/inf: the package's numba
# options (JIT), and BORROW (no reference counting) for the kernels that only borrow their arrays


@njit(**JIT)
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(**JIT)
def _add_scaled(a, s, d):
    return (a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2])


@njit(**JIT)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(**JIT)
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(**JIT)
def _dist2(a, b):
    dx = a[0] - b[0]
    dy = a[1] - b[1]
    dz = a[2] - b[2]
    return dx * dx + dy * dy + dz * dz


@njit(**JIT)
def point_segment(p, a, b):
    """Closest point on segment ``[a, b]`` to ``p`` (5.38)-(5.43): ``(squared distance, point)``."""
    d = _sub(b, a)
    dd = _dot(d, d)
    s = 0.0
    if dd > 0.0:  # a zero-length segment is the point a
        s = _dot(_sub(p, a), d) / dd
        if s < 0.0:
            s = 0.0
        elif s > 1.0:
            s = 1.0
    q = _add_scaled(a, s, d)
    return _dist2(p, q), q


@njit(**JIT)
def segment_segment(a0, a1, b0, b1):
    """Closest points of segments ``[a0, a1]`` and ``[b0, b1]`` (5.44)-(5.48): ``(d2, point_a, point_b)``.

    The unconstrained minimum (5.46) is clamped to ``Omega_L x Omega_L`` edge by edge (for a convex
    quadratic on a box, clamping one parameter and re-solving the other is exact); near-parallel segments
    also compare the four vertex/segment candidates of (5.47), and parallel ones use those alone (5.48).
    """
    d1 = _sub(a1, a0)
    d2 = _sub(b1, b0)
    r = _sub(a0, b0)
    aa = _dot(d1, d1)
    ee = _dot(d2, d2)
    ff = _dot(d2, r)
    if aa <= 0.0 or ee <= 0.0:  # a segment collapsed to a point
        if aa <= 0.0:
            e, q = point_segment(a0, b0, b1)
            return e, a0, q
        e, q = point_segment(b0, a0, a1)
        return e, q, b0
    bb = _dot(d1, d2)
    cc = _dot(d1, r)
    det = aa * ee - bb * bb
    best = _INF
    pa = a0
    pb = b0
    if det > _SINGULAR * aa * ee:
        # clamp s, solve t for it and clamp, then solve s for that t and clamp: each step minimizes exactly
        # over one parameter, so the objective never rises, and the three steps reach the box optimum
        # (the t < 0 and t > 1 cases of the usual branching form, without unpredictable branches)
        # the three reciprocals are independent, so they overlap instead of forming a chain of divisions
        inv_det = 1.0 / det
        inv_aa = 1.0 / aa
        inv_ee = 1.0 / ee
        s = min(max((bb * ff - cc * ee) * inv_det, 0.0), 1.0)
        t = min(max((bb * s + ff) * inv_ee, 0.0), 1.0)
        s = min(max((bb * t - cc) * inv_aa, 0.0), 1.0)
        pa = _add_scaled(a0, s, d1)
        pb = _add_scaled(b0, t, d2)
        best = _dist2(pa, pb)
        if det > _WELL_CONDITIONED * aa * ee:
            return best, pa, pb
    # vertex/segment candidates (5.47); for parallel segments these alone are exact (5.48)
    e, q = point_segment(a0, b0, b1)
    if e < best:
        best, pa, pb = e, a0, q
    e, q = point_segment(a1, b0, b1)
    if e < best:
        best, pa, pb = e, a1, q
    e, q = point_segment(b0, a0, a1)
    if e < best:
        best, pa, pb = e, q, b0
    e, q = point_segment(b1, a0, a1)
    if e < best:
        best, pa, pb = e, q, b1
    if det <= _SINGULAR * aa * ee:
        # parallel: when the projections overlap, return the middle of the minimizing region (5.48)
        tb0 = _dot(_sub(b0, a0), d1) / aa
        tb1 = _dot(_sub(b1, a0), d1) / aa
        lo = max(0.0, min(tb0, tb1))
        hi = min(1.0, max(tb0, tb1))
        if lo <= hi:
            ma = _add_scaled(a0, 0.5 * (lo + hi), d1)
            e, mb = point_segment(ma, b0, b1)
            if e <= best * (1.0 + 1e-9) + 1e-300 * min(aa, 1.0):  # the tie slack shrinks with tiny segments
                best, pa, pb = e, ma, mb
    return best, pa, pb


@njit(**JIT)
def _triangle(v0, v1, v2):
    """Per-triangle quantities reused by every query: ``(v0, e0, e1, aa, bb, cc, det, n, regular)``."""
    e0 = _sub(v1, v0)
    e1 = _sub(v2, v0)
    aa = _dot(e0, e0)
    bb = _dot(e0, e1)
    cc = _dot(e1, e1)
    det = aa * cc - bb * bb
    return v0, e0, e1, aa, bb, cc, det, _cross(e0, e1), det > _SINGULAR * aa * cc


@njit(**JIT)
def _project(x, tri):
    """Projection of ``x`` onto the plane of a regular triangle: ``(inside, point)``."""
    v0, e0, e1, aa, bb, cc, det = tri[0], tri[1], tri[2], tri[3], tri[4], tri[5], tri[6]
    w = _sub(x, v0)
    r0 = _dot(e0, w)
    r1 = _dot(e1, w)
    s = (cc * r0 - bb * r1) / det
    t = (aa * r1 - bb * r0) / det
    q = (v0[0] + s * e0[0] + t * e1[0], v0[1] + s * e0[1] + t * e1[1], v0[2] + s * e0[2] + t * e1[2])
    return (s >= 0.0 and t >= 0.0 and s + t <= 1.0), q


@njit(**JIT)
def _vertex_plane(p, tri):
    """Vertex/plane query: squared distance to the projection when it falls inside the triangle, else inf."""
    if not tri[8]:
        return _INF, p
    inside, q = _project(p, tri)
    if inside:
        return _dist2(p, q), q
    return _INF, p


@njit(**JIT)
def point_triangle(p, v0, v1, v2):
    """Closest point of triangle ``(v0, v1, v2)`` to ``p``: ``(squared distance, point)``.

    Unconstrained minimum in the plane when it lies inside (5.28), otherwise the best of the three edges; a
    degenerate (collinear or coincident) triangle is the union of its edges, so the edges alone are exact.
    """
    tri = _triangle(v0, v1, v2)
    best, q = _vertex_plane(p, tri)
    if best < _INF and tri[6] > _WELL_CONDITIONED * tri[3] * tri[5]:
        return best, q
    e, c = point_segment(p, v0, v1)
    if e < best:
        best, q = e, c
    e, c = point_segment(p, v1, v2)
    if e < best:
        best, q = e, c
    e, c = point_segment(p, v2, v0)
    if e < best:
        best, q = e, c
    return best, q


@njit(**JIT)
def _pierce(p0, p1, h0, h1, tri):
    """Where the segment ``[p0, p1]`` with plane heights ``h0, h1`` crosses a regular triangle."""
    if h0 * h1 > 0.0 or h0 == h1:  # same side, or parallel to the plane (in-plane cases are edge/edge cases)
        return False, p0
    x = _add_scaled(p0, h0 / (h0 - h1), _sub(p1, p0))
    return _project(x, tri)


@njit(**JIT)
def _heights(p, tri):
    return _dot(tri[7], _sub(p, tri[0]))


@njit(**JIT)
def segment_triangle(p0, p1, v0, v1, v2):
    """Closest points of a segment and a triangle: ``(d2, point_on_segment, point_on_triangle)``.

    The unconstrained minimum of the line/plane problem is the piercing point (distance 0); otherwise the
    minimum is one of the 2 end/plane and 3 segment/edge queries (end/edge cases are part of the latter).
    """
    tri = _triangle(v0, v1, v2)
    best = _INF
    pa = p0
    pb = p0
    if tri[8]:
        hit, x = _pierce(p0, p1, _heights(p0, tri), _heights(p1, tri), tri)
        if hit:
            return 0.0, x, x
        best, pb = _vertex_plane(p0, tri)
        e, q = _vertex_plane(p1, tri)
        if e < best:
            best, pa, pb = e, p1, q
    e, qa, qb = segment_segment(p0, p1, v0, v1)
    if e < best:
        best, pa, pb = e, qa, qb
    e, qa, qb = segment_segment(p0, p1, v1, v2)
    if e < best:
        best, pa, pb = e, qa, qb
    e, qa, qb = segment_segment(p0, p1, v2, v0)
    if e < best:
        best, pa, pb = e, qa, qb
    return best, pa, pb


@njit(**JIT)
def _edges_pierce(a0, a1, a2, tri):
    """Whether an edge of triangle ``a`` crosses the regular triangle ``tri``: ``(hit, point)``."""
    h0 = _heights(a0, tri)
    h1 = _heights(a1, tri)
    h2 = _heights(a2, tri)
    if (h0 > 0.0 and h1 > 0.0 and h2 > 0.0) or (h0 < 0.0 and h1 < 0.0 and h2 < 0.0):
        return False, a0
    hit, x = _pierce(a0, a1, h0, h1, tri)
    if not hit:
        hit, x = _pierce(a1, a2, h1, h2, tri)
    if not hit:
        hit, x = _pierce(a2, a0, h2, h0, tri)
    return hit, x


@njit(**JIT)
def _edge_pair(best, pa, pb, dist, u0, u1, pu0, pu1, w0, w1, pw0, pw1):
    """Edge/edge candidate, skipped when the projections on the current normal are ``dist`` or more apart:
    for unit ``n``, ``|y - x| >= min(n.y) - max(n.x)`` bounds every pair of points of the two edges."""
    if min(pw0, pw1) - max(pu0, pu1) >= dist:
        return best, pa, pb
    e, qa, qb = segment_segment(u0, u1, w0, w1)
    if e < best:
        return e, qa, qb
    return best, pa, pb


@njit(**JIT)
def triangle_triangle(a0, a1, a2, b0, b1, b2):
    """Closest points of two triangles: ``(d2, point_a, point_b)``.

    Intersecting triangles are found by an edge piercing the other triangle; otherwise the minimum is one of
    the 6 vertex/plane and 9 edge/edge queries of 5.2.3 (vertex/edge cases are part of edge/edge). Edge
    pairs that a projection bound proves no better than the best candidate so far are skipped.
    """
    ta = _triangle(a0, a1, a2)
    tb = _triangle(b0, b1, b2)
    if tb[8]:
        hit, x = _edges_pierce(a0, a1, a2, tb)
        if hit:
            return 0.0, x, x
    if ta[8]:
        hit, x = _edges_pierce(b0, b1, b2, ta)
        if hit:
            return 0.0, x, x
    # seed with the closest vertex pair, then the vertex/plane queries
    best = _INF
    pa = a0
    pb = b0
    for i in range(3):
        u = a0 if i == 0 else (a1 if i == 1 else a2)
        e = _dist2(u, b0)
        if e < best:
            best, pa, pb = e, u, b0
        e = _dist2(u, b1)
        if e < best:
            best, pa, pb = e, u, b1
        e = _dist2(u, b2)
        if e < best:
            best, pa, pb = e, u, b2
    if tb[8]:
        for i in range(3):
            u = a0 if i == 0 else (a1 if i == 1 else a2)
            e, q = _vertex_plane(u, tb)
            if e < best:
                best, pa, pb = e, u, q
    if ta[8]:
        for i in range(3):
            w = b0 if i == 0 else (b1 if i == 1 else b2)
            e, q = _vertex_plane(w, ta)
            if e < best:
                best, pa, pb = e, q, w
    dist = np.sqrt(best)
    if dist <= 0.0:
        return best, pa, pb
    n = ((pb[0] - pa[0]) / dist, (pb[1] - pa[1]) / dist, (pb[2] - pa[2]) / dist)
    ha0, ha1, ha2 = _dot(n, a0), _dot(n, a1), _dot(n, a2)
    hb0, hb1, hb2 = _dot(n, b0), _dot(n, b1), _dot(n, b2)
    for i in range(3):
        if i == 0:
            u0, u1, pu0, pu1 = a0, a1, ha0, ha1
        elif i == 1:
            u0, u1, pu0, pu1 = a1, a2, ha1, ha2
        else:
            u0, u1, pu0, pu1 = a2, a0, ha2, ha0
        best, pa, pb = _edge_pair(best, pa, pb, dist, u0, u1, pu0, pu1, b0, b1, hb0, hb1)
        best, pa, pb = _edge_pair(best, pa, pb, dist, u0, u1, pu0, pu1, b1, b2, hb1, hb2)
        best, pa, pb = _edge_pair(best, pa, pb, dist, u0, u1, pu0, pu1, b2, b0, hb2, hb0)
    return best, pa, pb


@njit(**JIT)
def _centroid(p0, p1, p2, kind):
    if kind == KIND_PSS:
        return p0
    if kind == KIND_LSS:
        return (0.5 * (p0[0] + p1[0]), 0.5 * (p0[1] + p1[1]), 0.5 * (p0[2] + p1[2]))
    return ((p0[0] + p1[0] + p2[0]) / 3.0, (p0[1] + p1[1] + p2[1]) / 3.0, (p0[2] + p1[2] + p2[2]) / 3.0)


@njit(**JIT)
def _fallback_normal(a0, a1, a2, ka, b0, b1, b2, kb):
    """Normal for touching or intersecting primitives (coinciding witnesses): the centroid direction."""
    c = _sub(_centroid(b0, b1, b2, kb), _centroid(a0, a1, a2, ka))
    cn = np.sqrt(_dot(c, c))
    if cn > 0.0:
        return (c[0] / cn, c[1] / cn, c[2] / cn)
    return (0.0, 0.0, 1.0)


def pointer_intrinsic(dtype: types.Type):  # noqa: ANN202 - returns a numba intrinsic
    """An intrinsic reinterpreting an integer address as ``dtype*`` (the caller owns and validated the buffer)."""

    @intrinsic
    def as_pointer(typingctx, address):
        if not isinstance(address, types.Integer):
            return None
        sig = types.CPointer(dtype)(address)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(signature.return_type))

        return sig, codegen

    return as_pointer


_float64_pointer = pointer_intrinsic(types.float64)
_int64_pointer = pointer_intrinsic(types.int64)


GROUPS = (
    (KIND_PSS, KIND_PSS),
    (KIND_PSS, KIND_LSS),
    (KIND_PSS, KIND_TSS),
    (KIND_LSS, KIND_LSS),
    (KIND_LSS, KIND_TSS),
    (KIND_TSS, KIND_TSS),
)
# GROUP_OF[lower kind, higher kind] -> index into GROUPS
GROUP_OF = np.full((3, 3), -1, dtype=np.int64)
for _g, (_ka, _kb) in enumerate(GROUPS):
    GROUP_OF[_ka, _kb] = _g


# both inlined: every pair loop calls them, and a call passing the arrays is what made the loops slow (see
# _closest_relative)
@njit(inline="always", **BORROW)
def _vertex(v, i, c):
    return (v[i, c, 0], v[i, c, 1], v[i, c, 2])


@njit(inline="always", **BORROW)
def _volume_pair_result(v, kinds, radii, i, j, g):
    """:func:`_pair_result` of volumes ``i`` and ``j`` (group ``g``, the lower kind first), their vertices read
    from ``v`` (inlined into the pair loops, which thus read them themselves)."""
    return _pair_result(
        _vertex(v, i, 0),
        _vertex(v, i, 1),
        _vertex(v, i, 2),
        kinds[i],
        radii[i],
        _vertex(v, j, 0),
        _vertex(v, j, 1),
        _vertex(v, j, 2),
        kinds[j],
        radii[j],
        g,
    )


@njit(inline="always", **BORROW)
def _write(r, swap, dist, pa, pb, n, out):
    """Row ``r`` of the outputs ``out`` (``(out_d, out_pa, out_pb, out_n)``), with the witnesses swapped and the
    normal reversed where ``swap``."""
    out_d, out_pa, out_pb, out_n = out
    if swap:
        pa, pb = pb, pa
        n = (-n[0], -n[1], -n[2])
    out_d[r] = dist
    out_pa[r, 0] = pa[0]
    out_pa[r, 1] = pa[1]
    out_pa[r, 2] = pa[2]
    out_pb[r, 0] = pb[0]
    out_pb[r, 1] = pb[1]
    out_pb[r, 2] = pb[2]
    out_n[r, 0] = n[0]
    out_n[r, 1] = n[1]
    out_n[r, 2] = n[2]


@njit(inline="always", **BORROW)
def _sphere_pairs_fast(v, radii, index_a, index_b, slot, active, lo, hi, out_d, out_pa, out_pb, out_n, todo):
    """Sphere/sphere pairs ``lo..hi`` as one flat loop; concentric and inactive pairs are left in ``todo``."""
    nt = 0
    for k in range(lo, hi):
        i = index_a[k]
        j = index_b[k]
        a = _vertex(v, i, 0)
        b = _vertex(v, j, 0)
        d = _sub(b, a)
        q = _dot(d, d)
        apart = q > _CONTACT_GAP2
        dist = np.sqrt(q)
        inv = 1.0 / (dist if apart else 1.0)  # square roots and divisions bound these loops: one of each
        _write(slot[k], False, dist - radii[i] - radii[j], a, b, _times(d, inv), (out_d, out_pa, out_pb, out_n))
        todo[nt] = k
        nt += 0 if (apart and active[k] != 0) else 1
    return nt


@njit(inline="always", **BORROW)
def _point_segment_pairs_fast(
    v, radii, index_a, index_b, slot, swap, active, lo, hi, out_d, out_pa, out_pb, out_n, todo
):
    """Sphere/capsule pairs ``lo..hi`` as one flat loop (the arithmetic of :func:`point_segment` relative to the
    sphere's centre, as the general path does); returns how many pairs it left in ``todo``.

    The clamped parameter (5.43) needs no branch: a collapsed segment (``dd == 0``) takes ``s = 0``, the point
    itself. Left for the general path: touching primitives (their normal is the centroid direction), inactive
    pairs, and coordinates outside ``[2^-100, 2^100]`` m of the centre, which the general path rescales.
    """
    nt = 0
    for k in range(lo, hi):
        i = index_a[k]
        j = index_b[k]
        o = _vertex(v, i, 0)
        a = _sub(_vertex(v, j, 0), o)
        b = _sub(_vertex(v, j, 1), o)
        extent = _extent(a, b, b)
        e = _sub(b, a)
        dd = _dot(e, e)
        s = min(max(_dot(_sub((0.0, 0.0, 0.0), a), e) / (dd if dd > 0.0 else 1.0), 0.0), 1.0)
        s = s if dd > 0.0 else 0.0
        p = _add_scaled(a, s, e)  # the closest point on the segment, relative to the centre
        q = _dot(p, p)
        apart = q > _CONTACT_GAP2
        dist = np.sqrt(q)
        inv = 1.0 / (dist if apart else 1.0)
        # witnesses: the centre and the point on the segment, exchanged where the pair was given capsule first
        _write(
            slot[k],
            swap[k] != 0,
            dist - radii[i] - radii[j],
            o,
            _add_scaled(o, 1.0, p),
            _times(p, inv),
            (out_d, out_pa, out_pb, out_n),
        )
        todo[nt] = k
        nt += 0 if (apart and active[k] != 0 and _SCALE_LOW <= extent <= _SCALE_HIGH) else 1
    return nt


@njit(inline="always", **BORROW)
def _segment_pairs_fast(v, radii, index_a, index_b, slot, active, lo, hi, out_d, out_pa, out_pb, out_n, todo):
    """Segment/segment pairs ``lo..hi`` in the common case; returns how many pairs it left in ``todo``.

    The capsule pair is the most frequent and the cheapest nontrivial one, so its loop body is kept flat and
    free of unpredictable branches: the unconstrained minimum (5.46) is clamped as in :func:`segment_segment`,
    with the denominators replaced by 1 where they are not well conditioned so nothing overflows. Pairs whose
    result that would not be exact (near-parallel or collapsed segments, touching segments, inactive pairs)
    are listed in ``todo`` for the general path. Both volumes are of one kind, so pairs are never swapped.
    """
    nt = 0
    for k in range(lo, hi):
        i = index_a[k]
        j = index_b[k]
        o = _vertex(v, i, 0)
        d1 = _sub(_vertex(v, i, 1), o)
        b0 = _sub(_vertex(v, j, 0), o)
        d2 = _sub(_vertex(v, j, 1), _vertex(v, j, 0))
        aa = _dot(d1, d1)
        ee = _dot(d2, d2)
        bb = _dot(d1, d2)
        cc = -_dot(d1, b0)
        ff = -_dot(d2, b0)
        det = aa * ee - bb * bb
        regular = det > _WELL_CONDITIONED * aa * ee  # false for collapsed segments too (0 > 0)
        inv_det = 1.0 / (det if regular else 1.0)
        inv_aa = 1.0 / (aa if regular else 1.0)
        inv_ee = 1.0 / (ee if regular else 1.0)
        s = min(max((bb * ff - cc * ee) * inv_det, 0.0), 1.0)
        t = min(max((bb * s + ff) * inv_ee, 0.0), 1.0)
        s = min(max((bb * t - cc) * inv_aa, 0.0), 1.0)
        pa = _times(d1, s)
        d = _sub(_add_scaled(b0, t, d2), pa)
        q = _dot(d, d)
        apart = q > _CONTACT_GAP2
        dist = np.sqrt(q)
        inv = 1.0 / (dist if apart else 1.0)
        _write(
            slot[k],
            False,
            dist - radii[i] - radii[j],
            _add_scaled(o, 1.0, pa),
            _add_scaled(o, 1.0, _add_scaled(pa, 1.0, d)),
            _times(d, inv),
            (out_d, out_pa, out_pb, out_n),
        )
        todo[nt] = k
        nt += 0 if (regular and apart and active[k] != 0) else 1
    return nt


@njit(**BORROW)
def ssv_pairs_grouped(
    vertices, radii, kinds, index_a, index_b, slot, swap, starts, active, out_d, out_pa, out_pb, out_n, todo
):
    """SSV distances of pairs of one volume array, pre-sorted into the six :data:`GROUPS`.

    ``index_a[k]`` holds the lower kind; pair ``k`` is written to row ``slot[k]``, with witnesses swapped back
    where ``swap[k]``; pairs with ``active[k] == 0`` are skipped (distance +inf). One tight loop per pair type,
    with no kind dispatch inside (about twice as fast as dispatching per pair for the cheap types); sphere and
    capsule pairs take flat loops that hand the rare hard cases to the general path. Large coordinates are shifted to
    a vertex of ``index_a`` first so they do not eat the digits of small distances. Touching primitives get
    the direction between the primitives' centroids as normal.

    Args:
        vertices: (M, 3, 3) generating vertices [m]; radii: (M,) [m]; kinds: (M,) codes (0 PSS, 1 LSS, 2 TSS).
        index_a, index_b, slot, swap: (K,) pair layout; starts: (7,) first pair of each group.
        active: (K,) nonzero to compute the pair.
        out_d: (K,) SSV distances [m]; out_pa, out_pb, out_n: (K, 3) witnesses and unit normals (written).
        todo: (K,) int64 scratch.
    """
    v = vertices
    for g in range(6):
        lo = starts[g]
        hi = starts[g + 1]
        # the flat sphere, sphere/capsule and capsule loops leave their hard cases in todo[:n] for the general path
        if g == 0:
            hi = lo + _sphere_pairs_fast(
                v, radii, index_a, index_b, slot, active, lo, hi, out_d, out_pa, out_pb, out_n, todo
            )
        elif g == 1:
            hi = lo + _point_segment_pairs_fast(
                v, radii, index_a, index_b, slot, swap, active, lo, hi, out_d, out_pa, out_pb, out_n, todo
            )
        elif g == 3:
            hi = lo + _segment_pairs_fast(
                v, radii, index_a, index_b, slot, active, lo, hi, out_d, out_pa, out_pb, out_n, todo
            )
        # the pair's vertices are read here, not in a callee that takes the arrays (see _closest_relative)
        for kk in range(lo, hi):
            k = todo[kk - lo] if g <= 1 or g == 3 else kk
            if active[k] == 0:
                out_d[slot[k]] = np.inf
                continue
            i = index_a[k]
            j = index_b[k]
            dist, pa, pb, n = _volume_pair_result(v, kinds, radii, i, j, g)
            _write(slot[k], swap[k] != 0, dist, pa, pb, n, (out_d, out_pa, out_pb, out_n))


@njit(**JIT)
def _times(p, f):
    return (p[0] * f, p[1] * f, p[2] * f)


@njit(**JIT)
def _extent(p0, p1, p2):
    return max(
        abs(p0[0]), abs(p0[1]), abs(p0[2]), abs(p1[0]), abs(p1[1]), abs(p1[2]), abs(p2[0]), abs(p2[1]), abs(p2[2])
    )


@njit(**JIT)
def _closest_relative(a1, a2, b0, b1, b2, g):
    """Closest points of the generating primitives of a pair of group ``g``, given relative to the first vertex
    of the lower-kind volume (its ``a0`` is the origin): ``(squared distance, point on a, point on b)``.

    Only tuples go in and out. A kernel loop that called a function taking the volume arrays paid numba's
    reference counting of every array argument per pair (two calls to ``NRT_incref``/``NRT_decref`` per array),
    and passed each array as a struct of 7-11 machine words on the stack: about 90 ns per pair on AMD Zen 5,
    five times the closest-point arithmetic.
    """
    a0 = (0.0, 0.0, 0.0)
    extent = max(_extent(a0, a1, a2), _extent(b0, b1, b2))
    scale = 1.0
    if extent > _SUBNORMAL and (extent < _SCALE_LOW or extent > _SCALE_HIGH):
        scale = math.ldexp(1.0, -math.frexp(extent)[1])
        a1, a2, b0, b1, b2 = (
            _times(a1, scale),
            _times(a2, scale),
            _times(b0, scale),
            _times(b1, scale),
            _times(b2, scale),
        )
    if g == 0:
        d2 = _dist2(a0, b0)
        pa = a0
        pb = b0
    elif g == 1:
        d2, pb = point_segment(a0, b0, b1)
        pa = a0
    elif g == 2:
        d2, pb = point_triangle(a0, b0, b1, b2)
        pa = a0
    elif g == 3:
        d2, pa, pb = segment_segment(a0, a1, b0, b1)
    elif g == 4:
        d2, pa, pb = segment_triangle(a0, a1, b0, b1, b2)
    else:
        d2, pa, pb = triangle_triangle(a0, a1, a2, b0, b1, b2)
    if scale != 1.0:
        d2 = d2 / scale / scale
        pa, pb = _times(pa, 1.0 / scale), _times(pb, 1.0 / scale)
    return d2, pa, pb


@njit(**JIT)
def _pair_result(a0, a1, a2, ka, ra, b0, b1, b2, kb, rb, g):
    """SSV distance of two volumes given by world vertices, kinds and radii (``ka <= kb``, group ``g``):
    ``(distance, point on a, point on b, unit normal from a to b)`` [m], the normal of touching primitives being
    the centroid direction of :func:`_fallback_normal`. Large coordinates are taken relative to ``a0`` first so
    they do not eat the digits of small distances."""
    o = a0
    r1, r2 = _sub(a1, o), _sub(a2, o)
    s0, s1, s2 = _sub(b0, o), _sub(b1, o), _sub(b2, o)
    d2, pa, pb = _closest_relative(r1, r2, s0, s1, s2, g)
    dist = np.sqrt(d2)
    if d2 > _CONTACT_GAP2:
        inv = 1.0 / dist
        n = ((pb[0] - pa[0]) * inv, (pb[1] - pa[1]) * inv, (pb[2] - pa[2]) * inv)
    else:
        n = _fallback_normal((0.0, 0.0, 0.0), r1, r2, ka, s0, s1, s2, kb)
    return dist - ra - rb, _add_scaled(o, 1.0, pa), _add_scaled(o, 1.0, pb), n


@njit(**BORROW)
def volume_pair_distance(v, radii, kinds, i, j):
    """SSV distance of volumes ``i`` and ``j`` of ``(v, radii, kinds)``, for use inside other kernels:
    ``(distance, point on i, point on j, unit normal from i to j)`` as float and 3-tuples (world) [m].

    Same results as :func:`ssv_pairs_grouped` (the general path), including the normal of touching volumes.
    """
    swap = kinds[i] > kinds[j]
    lo = j if swap else i
    hi = i if swap else j
    ka = kinds[lo]
    kb = kinds[hi]
    # the radii in the caller's order: dist - r_i - r_j rounds the same whichever volume has the lower kind
    dist, pa, pb, n = _pair_result(
        _vertex(v, lo, 0),
        _vertex(v, lo, 1),
        _vertex(v, lo, 2),
        ka,
        radii[i],
        _vertex(v, hi, 0),
        _vertex(v, hi, 1),
        _vertex(v, hi, 2),
        kb,
        radii[j],
        GROUP_OF[ka, kb],
    )
    if swap:
        return dist, pb, pa, (-n[0], -n[1], -n[2])
    return dist, pa, pb, n


@njit(**JIT)
def ssv_pairs_at(header):
    """:func:`ssv_pairs_grouped` on buffers described by the int64 array at address ``header``.

    ``header`` holds: addresses of vertices, radii, kinds, index_a, index_b, slot, swap, starts, active, out_d,
    out_pa, out_pb, out_n, todo, then the number of volumes and of pairs. Boxing one NumPy array into a numba call costs
    about 0.4 us, as much as 50 sphere pairs take; one integer costs a few nanoseconds. Only
    :class:`~redundancy_gym.geometry.PairBatch` calls this, with C-contiguous buffers it owns and checked once.
    """
    v, r, k, ia, ib, sl, sw, st, ac, d, pa, pb, nn, td = _header_buffers(carray(_int64_pointer(header), (16,)))
    ssv_pairs_grouped(v, r, k, ia, ib, sl, sw, st, ac, d, pa, pb, nn, td)


@njit(**JIT)
def _header_buffers(h):
    """The 14 pair-batch buffers named by the addresses in a header (see :func:`ssv_pairs_at`)."""
    m = h[14]
    n = h[15]
    return (
        carray(_float64_pointer(h[0]), (m, 3, 3)),
        carray(_float64_pointer(h[1]), (m,)),
        carray(_int64_pointer(h[2]), (m,)),
        carray(_int64_pointer(h[3]), (n,)),
        carray(_int64_pointer(h[4]), (n,)),
        carray(_int64_pointer(h[5]), (n,)),
        carray(_int64_pointer(h[6]), (n,)),
        carray(_int64_pointer(h[7]), (7,)),
        carray(_int64_pointer(h[8]), (n,)),
        carray(_float64_pointer(h[9]), (n,)),
        carray(_float64_pointer(h[10]), (n, 3)),
        carray(_float64_pointer(h[11]), (n, 3)),
        carray(_float64_pointer(h[12]), (n, 3)),
        carray(_int64_pointer(h[13]), (n,)),
    )


@njit(**BORROW)
def _bounding_spheres(vertices, radii, kinds, lo, hi, centers, bounds):
    """Bounding spheres of volumes ``lo..hi``: centred on the mean vertex, radius the farthest vertex plus the
    SSV radius (so a sphere distance is a lower bound of the SSV distance)."""
    for i in range(lo, hi):
        nv = kinds[i] + 1
        cx = 0.0
        cy = 0.0
        cz = 0.0
        for r in range(nv):
            cx += vertices[i, r, 0]
            cy += vertices[i, r, 1]
            cz += vertices[i, r, 2]
        cx /= nv
        cy /= nv
        cz /= nv
        far = 0.0
        for r in range(nv):
            dx = vertices[i, r, 0] - cx
            dy = vertices[i, r, 1] - cy
            dz = vertices[i, r, 2] - cz
            far = max(far, dx * dx + dy * dy + dz * dz)
        centers[i, 0] = cx
        centers[i, 1] = cy
        centers[i, 2] = cz
        bounds[i] = np.sqrt(far) + radii[i]


@njit(**BORROW)
def _near(centers, bounds, i, j, margin):
    dx = centers[i, 0] - centers[j, 0]
    dy = centers[i, 1] - centers[j, 1]
    dz = centers[i, 2] - centers[j, 2]
    reach = bounds[i] + bounds[j] + margin
    return reach >= 0.0 and dx * dx + dy * dy + dz * dz <= reach * reach


@njit(**BORROW)
def cull_pairs(vertices, radii, kinds, index_a, index_b, margin, active, centers, bounds):
    """Activate exactly the pairs whose bounding spheres are at most ``margin`` apart; returns how many.

    A culled pair is farther than ``margin``. ``centers`` (M, 3) and ``bounds`` (M,) are scratch (left holding
    every volume's bounding sphere).
    """
    _bounding_spheres(vertices, radii, kinds, 0, radii.shape[0], centers, bounds)
    count = 0
    for k in range(index_a.shape[0]):
        near = _near(centers, bounds, index_a[k], index_b[k], margin)
        active[k] = 1 if near else 0
        count += 1 if near else 0
    return count


@njit(**BORROW)
def near_pairs(
    vertices,
    radii,
    kinds,
    index_a,
    index_b,
    slot,
    swap,
    starts,
    active,
    out_d,
    out_pa,
    out_pb,
    out_n,
    todo,
    centers,
    bounds,
    margin,
    moving,
):
    """Broad and narrow phase in one pass: the pairs whose bounding spheres are at most ``margin`` apart get
    their exact SSV distance (general path), the others +inf; returns the smallest distance (+inf if none).

    Only the bounding spheres of volumes ``0..moving`` are refreshed: the others must hold from an earlier
    :func:`cull_pairs` on unchanged vertices. ``active`` is left marking the computed pairs.
    """
    _bounding_spheres(vertices, radii, kinds, 0, moving, centers, bounds)
    out_d[:] = np.inf
    smallest = np.inf
    for g in range(6):
        nt = 0
        for k in range(starts[g], starts[g + 1]):
            near = _near(centers, bounds, index_a[k], index_b[k], margin)
            active[k] = 1 if near else 0
            todo[nt] = k
            nt += 1 if near else 0
        for kk in range(nt):
            k = todo[kk]
            i = index_a[k]
            j = index_b[k]
            v = vertices
            dist, pa, pb, n = _volume_pair_result(v, kinds, radii, i, j, g)
            _write(slot[k], swap[k] != 0, dist, pa, pb, n, (out_d, out_pa, out_pb, out_n))
            smallest = min(smallest, dist)
    return smallest


@njit(**JIT)
def cull_pairs_at(header, margin):
    """:func:`cull_pairs` on the buffers of a :func:`ssv_pairs_at` header followed by two scratch addresses."""
    h = carray(_int64_pointer(header), (18,))
    m = h[14]
    n = h[15]
    return cull_pairs(
        carray(_float64_pointer(h[0]), (m, 3, 3)),
        carray(_float64_pointer(h[1]), (m,)),
        carray(_int64_pointer(h[2]), (m,)),
        carray(_int64_pointer(h[3]), (n,)),
        carray(_int64_pointer(h[4]), (n,)),
        margin,
        carray(_int64_pointer(h[8]), (n,)),
        carray(_float64_pointer(h[16]), (m, 3)),
        carray(_float64_pointer(h[17]), (m,)),
    )


@njit(**BORROW)
def frames_to_volumes(positions, rotations, half_lengths, vertices):
    """Volumes ``0..n`` from frames: a segment ``p -/+ h z`` (z: third column of the row-major rotation) where
    ``h > 0``, else the point ``p``; the unused vertex rows repeat the last vertex."""
    for i in range(half_lengths.shape[0]):
        h = half_lengths[i]
        for c in range(3):
            p = positions[i, c]
            a = h * rotations[i, 3 * c + 2]
            vertices[i, 0, c] = p - a
            vertices[i, 1, c] = p + a
            vertices[i, 2, c] = p + a


@njit(**JIT)
def near_pairs_at(header, margin, moving, frames):
    """:func:`near_pairs` on the buffers of a :func:`cull_pairs_at` header; first, when ``frames`` is nonzero,
    :func:`frames_to_volumes` from the int64 array at that address: positions, rotations, half lengths, count."""
    h = carray(_int64_pointer(header), (18,))
    m = h[14]
    v, r, k, ia, ib, sl, sw, st, ac, d, pa, pb, nn, td = _header_buffers(h)
    if frames != 0:
        f = carray(_int64_pointer(frames), (4,))
        nf = f[3]
        frames_to_volumes(
            carray(_float64_pointer(f[0]), (nf, 3)),
            carray(_float64_pointer(f[1]), (nf, 9)),
            carray(_float64_pointer(f[2]), (nf,)),
            v,
        )
    return near_pairs(
        v,
        r,
        k,
        ia,
        ib,
        sl,
        sw,
        st,
        ac,
        d,
        pa,
        pb,
        nn,
        td,
        carray(_float64_pointer(h[16]), (m, 3)),
        carray(_float64_pointer(h[17]), (m,)),
        margin,
        moving,
    )


@njit(**JIT)
def smallest_pair_at(header, margin, moving, frames):
    """:meth:`~redundancy_gym.geometry.PairBatch.smallest`: the exact smallest distance [m] of a pair batch (its
    header address; ``moving`` and ``frames`` as for :func:`near_pairs_at`), computing only the pairs near it,
    from a first ``margin`` [m] doubled while the minimum lies beyond it (every pair beyond 1e6 m)."""
    while True:
        d = near_pairs_at(header, margin, moving, frames)
        if d <= margin or margin == np.inf:
            return d
        margin = max(2.0 * margin, d) if np.isfinite(d) else 2.0 * margin
        if margin > 1e6:
            margin = np.inf
