"""An exact, independent oracle for the distance of two generating primitives (points, segments, triangles).

The closest-point problem is a convex QP over the product of two simplices. Its minimum is attained at a
point that is the unique minimizer on the affine hull of some pair of faces, so enumerating every pair of
faces (non-empty vertex subsets), solving the equality-constrained least squares problem there by SVD and
keeping the feasible solutions finds it exactly. Slow (up to 49 small SVDs), but free of the branch logic
it checks.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from redundancy_gym.geometry import SSV


def _faces(n: int) -> list[tuple[int, ...]]:
    return [c for k in range(1, n + 1) for c in combinations(range(n), k)]


def primitive_distance(pa: np.ndarray, pb: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Distance between the convex hulls of the rows of ``pa`` and ``pb`` and a closest pair of points."""
    best = (np.inf, pa[0], pb[0])
    for fa in _faces(len(pa)):
        for fb in _faces(len(pb)):
            x0, y0 = pa[fa[0]], pb[fb[0]]
            e = (pa[list(fa[1:])] - x0).T if len(fa) > 1 else np.zeros((3, 0))
            f = (pb[list(fb[1:])] - y0).T if len(fb) > 1 else np.zeros((3, 0))
            mat = np.hstack([e, -f])
            if mat.shape[1]:
                sol = np.linalg.lstsq(mat, y0 - x0, rcond=1e-14)[0]
            else:
                sol = np.zeros(0)
            alpha, beta = sol[: e.shape[1]], sol[e.shape[1] :]
            lam = np.concatenate([[1.0 - alpha.sum()], alpha])
            mu = np.concatenate([[1.0 - beta.sum()], beta])
            if lam.min() < -1e-12 or mu.min() < -1e-12:
                continue
            x = x0 + e @ alpha
            y = y0 + f @ beta
            d = float(np.linalg.norm(x - y))
            if d < best[0]:
                best = (d, x, y)
    return best


def ssv_distance(a: SSV, b: SSV) -> float:
    """The SSV distance convention: primitive distance minus both radii."""
    return primitive_distance(a.points, b.points)[0] - a.radius - b.radius


def point_to_primitive(point: np.ndarray, volume: SSV) -> float:
    """Distance of a point to a volume's generating primitive (0 when the point lies on it)."""
    return primitive_distance(np.asarray(point).reshape(1, 3), volume.points)[0]
