"""Swept-sphere volumes as coal shapes: the peer the SSV benchmark and tests compare against.

A PSS is ``coal.Sphere``, an LSS ``coal.Capsule`` (placed along the segment) and a TSS a one-triangle
``coal.Convex`` with ``setSweptSphereRadius`` (``coal.TriangleP`` has no distance support).
"""

from __future__ import annotations

from typing import Any

import coal
import numpy as np

from ..geometry import LSS, PSS, SSV, TSS

__all__ = ["coal_distance", "coal_request", "to_coal"]


def _rotation_z_to(direction: np.ndarray) -> np.ndarray:
    """A rotation whose z axis is ``direction`` (unit or zero)."""
    z = direction / np.linalg.norm(direction) if np.linalg.norm(direction) > 0.0 else np.array([0.0, 0.0, 1.0])
    helper = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(z, x), z])


def to_coal(volume: SSV) -> tuple[Any, Any]:
    """``(coal geometry, coal.Transform3s)`` of one volume."""
    if isinstance(volume, PSS):
        return coal.Sphere(volume.radius), coal.Transform3s(np.eye(3), volume.center.copy())
    if isinstance(volume, LSS):
        p0, p1 = volume.points
        rot = _rotation_z_to(p1 - p0)
        return coal.Capsule(volume.radius, volume.length), coal.Transform3s(rot, 0.5 * (p0 + p1))
    if isinstance(volume, TSS):
        pts = coal.StdVec_Vec3s()
        for p in volume.points:
            pts.append(np.array(p, dtype=np.float64))
        tris = coal.StdVec_Triangle()
        tris.append(coal.Triangle(0, 1, 2))
        shape = coal.Convex(pts, tris)
        shape.setSweptSphereRadius(volume.radius)
        return shape, coal.Transform3s(np.eye(3), np.zeros(3))
    raise TypeError(f"expected PSS, LSS or TSS, got {type(volume).__name__}")


def coal_request(tolerance: float = 1e-12) -> Any:
    """A distance request with a tight GJK tolerance (coal 3 always computes nearest points)."""
    request = coal.DistanceRequest()
    request.gjk_tolerance = tolerance
    return request


def coal_distance(a: SSV, b: SSV, request: Any = None) -> tuple[float, np.ndarray, np.ndarray]:
    """coal's distance and nearest points (on the swept surfaces) of two separated volumes."""
    ga, ta = to_coal(a)
    gb, tb = to_coal(b)
    result = coal.DistanceResult()
    result.clear()
    coal.distance(ga, ta, gb, tb, request or coal_request(), result)
    return float(result.min_distance), np.array(result.getNearestPoint1()), np.array(result.getNearestPoint2())
