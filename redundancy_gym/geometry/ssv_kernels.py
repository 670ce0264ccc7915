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
public entry points are :func:`ssv_pair` (one pair) and :func:`ssv_pairs_indexed` (many pairs given as
indices into one array of volumes, the layout of a collision model).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["KIND_LSS", "KIND_PSS", "KIND_TSS", "ssv_pair", "ssv_pairs_indexed"]

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


@njit(cache=True)
def _sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@njit(cache=True)
def _add_scaled(a, s, d):
    return (a[0] + s * d[0], a[1] + s * d[1], a[2] + s * d[2])


@njit(cache=True)
def _dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True)
def _cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True)
def _dist2(a, b):
    dx = a[0] - b[0]
    dy = a[1] - b[1]
    dz = a[2] - b[2]
    return dx * dx + dy * dy + dz * dz


@njit(cache=True)
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


@njit(cache=True)
def segment_segment(a0, a1, b0, b1):
    """Closest points of segments ``[a0, a1]`` and ``[b0, b1]`` (5.44)-(5.48): ``(d2, point_a, point_b)``."""
    d1 = _sub(a1, a0)
    d2 = _sub(b1, b0)
    r = _sub(a0, b0)
    aa = _dot(d1, d1)
    ee = _dot(d2, d2)
    bb = _dot(d1, d2)
    det = aa * ee - bb * bb
    best = _INF
    pa = a0
    pb = b0
    if det > _SINGULAR * aa * ee:
        # unconstrained minimum of |r + s d1 - t d2|^2 (5.46)
        cc = _dot(d1, r)
        ff = _dot(d2, r)
        s = (bb * ff - cc * ee) / det
        t = (aa * ff - bb * cc) / det
        if 0.0 <= s <= 1.0 and 0.0 <= t <= 1.0:
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
    if det <= _SINGULAR * aa * ee and aa > 0.0 and ee > 0.0:
        # parallel: when the projections overlap, return the middle of the minimizing region (5.48)
        tb0 = _dot(_sub(b0, a0), d1) / aa
        tb1 = _dot(_sub(b1, a0), d1) / aa
        lo = max(0.0, min(tb0, tb1))
        hi = min(1.0, max(tb0, tb1))
        if lo <= hi:
            ma = _add_scaled(a0, 0.5 * (lo + hi), d1)
            e, mb = point_segment(ma, b0, b1)
            if e <= best * (1.0 + 1e-9) + 1e-300:
                best, pa, pb = e, ma, mb
    return best, pa, pb


@njit(cache=True)
def _in_triangle(x, v0, e0, e1, aa, bb, cc, det):
    """Barycentric coordinates ``(s, t)`` of ``x`` projected onto the triangle plane and whether they are inside."""
    w = _sub(x, v0)
    r0 = _dot(e0, w)
    r1 = _dot(e1, w)
    s = (cc * r0 - bb * r1) / det
    t = (aa * r1 - bb * r0) / det
    return s, t, (s >= 0.0 and t >= 0.0 and s + t <= 1.0)


@njit(cache=True)
def point_triangle(p, v0, v1, v2):
    """Closest point of triangle ``(v0, v1, v2)`` to ``p``: ``(squared distance, point)``.

    Unconstrained minimum in the plane when it lies inside (5.28), otherwise the best of the three edges; a
    degenerate (collinear or coincident) triangle is the union of its edges, so the edges alone are exact.
    """
    e0 = _sub(v1, v0)
    e1 = _sub(v2, v0)
    aa = _dot(e0, e0)
    bb = _dot(e0, e1)
    cc = _dot(e1, e1)
    det = aa * cc - bb * bb
    best = _INF
    q = v0
    if det > _SINGULAR * aa * cc:
        s, t, inside = _in_triangle(p, v0, e0, e1, aa, bb, cc, det)
        if inside:
            q = (v0[0] + s * e0[0] + t * e1[0], v0[1] + s * e0[1] + t * e1[1], v0[2] + s * e0[2] + t * e1[2])
            best = _dist2(p, q)
            if det > _WELL_CONDITIONED * aa * cc:
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


@njit(cache=True)
def _segment_pierces(p0, p1, v0, v1, v2):
    """Where segment ``[p0, p1]`` crosses the interior of a non-degenerate triangle: ``(hit, point)``."""
    e0 = _sub(v1, v0)
    e1 = _sub(v2, v0)
    aa = _dot(e0, e0)
    bb = _dot(e0, e1)
    cc = _dot(e1, e1)
    det = aa * cc - bb * bb
    if not det > _SINGULAR * aa * cc:
        return False, p0
    n = _cross(e0, e1)
    h0 = _dot(n, _sub(p0, v0))
    h1 = _dot(n, _sub(p1, v0))
    if h0 * h1 > 0.0 or h0 == h1:  # same side, or parallel to the plane (in-plane cases are edge cases)
        return False, p0
    x = _add_scaled(p0, h0 / (h0 - h1), _sub(p1, p0))
    s, t, inside = _in_triangle(x, v0, e0, e1, aa, bb, cc, det)
    if inside:
        return True, (v0[0] + s * e0[0] + t * e1[0], v0[1] + s * e0[1] + t * e1[1], v0[2] + s * e0[2] + t * e1[2])
    return False, p0


@njit(cache=True)
def segment_triangle(p0, p1, v0, v1, v2):
    """Closest points of a segment and a triangle: ``(d2, point_on_segment, point_on_triangle)``.

    The unconstrained minimum of the line/plane problem is the piercing point (distance 0); otherwise the
    minimum is attained at a segment end against the triangle or at the segment against a triangle edge.
    """
    hit, x = _segment_pierces(p0, p1, v0, v1, v2)
    if hit:
        return 0.0, x, x
    best, q = point_triangle(p0, v0, v1, v2)
    pa = p0
    pb = q
    e, q = point_triangle(p1, v0, v1, v2)
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


@njit(cache=True)
def triangle_triangle(a0, a1, a2, b0, b1, b2):
    """Closest points of two triangles: ``(d2, point_a, point_b)``.

    Intersecting triangles are found by the edges that pierce the other triangle; otherwise the minimum is
    one of the 6 vertex/triangle and 9 edge/edge queries of 5.2.3.
    """
    hit, x = _segment_pierces(a0, a1, b0, b1, b2)
    if not hit:
        hit, x = _segment_pierces(a1, a2, b0, b1, b2)
    if not hit:
        hit, x = _segment_pierces(a2, a0, b0, b1, b2)
    if not hit:
        hit, x = _segment_pierces(b0, b1, a0, a1, a2)
    if not hit:
        hit, x = _segment_pierces(b1, b2, a0, a1, a2)
    if not hit:
        hit, x = _segment_pierces(b2, b0, a0, a1, a2)
    if hit:
        return 0.0, x, x
    best, q = point_triangle(a0, b0, b1, b2)
    pa = a0
    pb = q
    e, q = point_triangle(a1, b0, b1, b2)
    if e < best:
        best, pa, pb = e, a1, q
    e, q = point_triangle(a2, b0, b1, b2)
    if e < best:
        best, pa, pb = e, a2, q
    e, q = point_triangle(b0, a0, a1, a2)
    if e < best:
        best, pa, pb = e, q, b0
    e, q = point_triangle(b1, a0, a1, a2)
    if e < best:
        best, pa, pb = e, q, b1
    e, q = point_triangle(b2, a0, a1, a2)
    if e < best:
        best, pa, pb = e, q, b2
    for i in range(3):
        if i == 0:
            s0, s1 = a0, a1
        elif i == 1:
            s0, s1 = a1, a2
        else:
            s0, s1 = a2, a0
        e, qa, qb = segment_segment(s0, s1, b0, b1)
        if e < best:
            best, pa, pb = e, qa, qb
        e, qa, qb = segment_segment(s0, s1, b1, b2)
        if e < best:
            best, pa, pb = e, qa, qb
        e, qa, qb = segment_segment(s0, s1, b2, b0)
        if e < best:
            best, pa, pb = e, qa, qb
    return best, pa, pb


@njit(cache=True)
def _vertex(v, i, origin):
    return (v[i, 0] - origin[0], v[i, 1] - origin[1], v[i, 2] - origin[2])


@njit(cache=True)
def _centroid(v, kind, origin):
    n = kind + 1
    c0 = 0.0
    c1 = 0.0
    c2 = 0.0
    for i in range(n):
        c0 += v[i, 0] - origin[0]
        c1 += v[i, 1] - origin[1]
        c2 += v[i, 2] - origin[2]
    return (c0 / n, c1 / n, c2 / n)


@njit(cache=True)
def _pair_ordered(va, ka, vb, kb, origin):
    """Squared distance and witnesses for ``ka <= kb`` (vertices shifted by ``origin``)."""
    a0 = _vertex(va, 0, origin)
    b0 = _vertex(vb, 0, origin)
    if ka == KIND_PSS:
        if kb == KIND_PSS:
            return _dist2(a0, b0), a0, b0
        if kb == KIND_LSS:
            e, q = point_segment(a0, b0, _vertex(vb, 1, origin))
            return e, a0, q
        e, q = point_triangle(a0, b0, _vertex(vb, 1, origin), _vertex(vb, 2, origin))
        return e, a0, q
    a1 = _vertex(va, 1, origin)
    if ka == KIND_LSS:
        if kb == KIND_LSS:
            return segment_segment(a0, a1, b0, _vertex(vb, 1, origin))
        return segment_triangle(a0, a1, b0, _vertex(vb, 1, origin), _vertex(vb, 2, origin))
    return triangle_triangle(a0, a1, _vertex(va, 2, origin), b0, _vertex(vb, 1, origin), _vertex(vb, 2, origin))


@njit(cache=True)
def _pair(va, ra, ka, vb, rb, kb, out_pa, out_pb, out_n):
    """One SSV pair: writes witness points and the unit normal (from a to b); returns the SSV distance."""
    # shifting to a vertex of ``a`` keeps large coordinates from eating the digits of small distances
    origin = (va[0, 0], va[0, 1], va[0, 2])
    if ka <= kb:
        d2, pa, pb = _pair_ordered(va, ka, vb, kb, origin)
    else:
        d2, pb, pa = _pair_ordered(vb, kb, va, ka, origin)
    dist = np.sqrt(d2)
    dx = pb[0] - pa[0]
    dy = pb[1] - pa[1]
    dz = pb[2] - pa[2]
    if dist > 0.0:
        nx, ny, nz = dx / dist, dy / dist, dz / dist
    else:
        # touching or intersecting primitives: the witness points coincide, so use the centroid direction
        ca = _centroid(va, ka, origin)
        cb = _centroid(vb, kb, origin)
        cx, cy, cz = cb[0] - ca[0], cb[1] - ca[1], cb[2] - ca[2]
        cn = np.sqrt(cx * cx + cy * cy + cz * cz)
        if cn > 0.0:
            nx, ny, nz = cx / cn, cy / cn, cz / cn
        else:
            nx, ny, nz = 0.0, 0.0, 1.0
    out_pa[0] = pa[0] + origin[0]
    out_pa[1] = pa[1] + origin[1]
    out_pa[2] = pa[2] + origin[2]
    out_pb[0] = pb[0] + origin[0]
    out_pb[1] = pb[1] + origin[1]
    out_pb[2] = pb[2] + origin[2]
    out_n[0] = nx
    out_n[1] = ny
    out_n[2] = nz
    return dist - ra - rb


@njit(cache=True)
def ssv_pair(va, ra, ka, vb, rb, kb, out_pa, out_pb, out_n):
    """SSV distance of one pair; ``va``/``vb`` are (3, 3) vertex arrays, outputs are length-3 arrays."""
    return _pair(va, ra, ka, vb, rb, kb, out_pa, out_pb, out_n)


@njit(cache=True)
def ssv_pairs_indexed(vertices, radii, kinds, index_a, index_b, out_d, out_pa, out_pb, out_n):
    """SSV distances of the pairs ``(index_a[k], index_b[k])`` of one volume array.

    Args:
        vertices: (M, 3, 3) generating vertices [m].
        radii: (M,) sphere radii [m].
        kinds: (M,) kind codes (0 PSS, 1 LSS, 2 TSS).
        index_a, index_b: (K,) volume indices of each pair.
        out_d: (K,) SSV distances [m], written.
        out_pa, out_pb, out_n: (K, 3) witness points and unit normals, written.
    """
    for k in range(index_a.shape[0]):
        i = index_a[k]
        j = index_b[k]
        out_d[k] = _pair(vertices[i], radii[i], kinds[i], vertices[j], radii[j], kinds[j],
                         out_pa[k], out_pb[k], out_n[k])
