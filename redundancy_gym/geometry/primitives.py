"""Swept-sphere volumes (monograph 5.2.2, figure 5.4, (5.26)-(5.28)): PSS, LSS and TSS.

A swept-sphere volume is the set of points within ``radius`` of a generating primitive: a point (PSS), a line
segment (LSS) or a triangle (TSS). Every volume stores its vertices as a (3, 3) array, unused rows repeating
the last vertex, plus a kind code, which is the layout the compiled kernels read.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..validation import check_real
from .exceptions import GeometryError
from .ssv_kernels import KIND_LSS, KIND_PSS, KIND_TSS

__all__ = ["LSS", "PSS", "SSV", "TSS", "KIND_NAMES"]

KIND_NAMES = ("PSS", "LSS", "TSS")


def _point(value: ArrayLike, name: str) -> NDArray[np.float64]:
    try:
        given = np.asarray(value)
    except ValueError:  # a ragged sequence
        given = np.asarray(None)
    if given.dtype.kind not in "iuf":  # strings, bools, objects are not coordinates
        raise GeometryError(f"{name} must be a 3-vector of finite real numbers [m], got {value!r}")
    p = np.array(given, dtype=np.float64).reshape(-1)
    if p.shape != (3,):
        raise GeometryError(f"{name} must be a 3-vector, got shape {np.shape(value)}")
    if not np.all(np.isfinite(p)):
        raise GeometryError(f"{name} must be finite, got {p.tolist()}")
    p.setflags(write=False)
    return p


def _radius(value: float) -> float:
    radius = check_real("radius", value, low=0.0, unit="m", error=GeometryError)
    assert radius is not None  # not optional: a float or GeometryError
    return radius


class SSV:
    """Base of the three swept-sphere volumes: ``vertices`` (3, 3) [m], ``radius`` [m] and ``kind``."""

    kind: ClassVar[int]
    radius: float
    vertices: NDArray[np.float64]

    @staticmethod
    def from_kind(kind: int, vertices: ArrayLike, radius: float) -> SSV:
        """The volume of kind ``kind`` (0 PSS, 1 LSS, 2 TSS) on the first 1, 2 or 3 rows of ``vertices`` [m] (the
        packed form of observations and :class:`PackedVolumes`: unused rows are ignored)."""
        v = np.asarray(vertices, dtype=np.float64)
        if kind == 0:
            return PSS(v[0], radius)
        if kind == 1:
            return LSS(v[0], v[1], radius)
        if kind == 2:
            return TSS(v[0], v[1], v[2], radius)
        raise GeometryError(f"kind must be 0 (PSS), 1 (LSS) or 2 (TSS), got {kind!r}")

    @property
    def kind_name(self) -> str:
        """``"PSS"``, ``"LSS"`` or ``"TSS"``."""
        return KIND_NAMES[self.kind]

    @property
    def points(self) -> NDArray[np.float64]:
        """The generating vertices actually used (1, 2 or 3 rows) [m]."""
        return self.vertices[: self.kind + 1]

    def transformed(self, rotation: ArrayLike, translation: ArrayLike) -> SSV:
        """The volume moved by ``x -> R x + p``."""
        rot = np.asarray(rotation, dtype=np.float64)
        if rot.shape != (3, 3):
            raise GeometryError(f"rotation must be 3 x 3, got {rot.shape}")
        moved = self.points @ rot.T + _point(translation, "translation")
        return SSV.from_kind(self.kind, moved, self.radius)

    def __repr__(self) -> str:
        pts = ", ".join(np.array2string(p, precision=4) for p in self.points)
        return f"{self.kind_name}({pts}, radius={self.radius:g})"

    def __eq__(self, other: object) -> bool:
        return (
            type(other) is type(self)
            and self.radius == other.radius
            and bool(np.array_equal(self.vertices, other.vertices))
        )

    def __hash__(self) -> int:
        return hash((self.kind, self.radius, self.vertices.tobytes()))


class PSS(SSV):
    """Point swept sphere (5.26): a sphere of ``radius`` [m] around ``center`` [m]."""

    kind = KIND_PSS

    def __init__(self, center: ArrayLike, radius: float) -> None:
        c = _point(center, "center")
        self.radius = _radius(radius)
        self.vertices = np.array([c, c, c])
        self.vertices.setflags(write=False)

    @property
    def center(self) -> NDArray[np.float64]:
        """The generating point [m]."""
        return self.vertices[0]


class LSS(SSV):
    """Line swept sphere (5.27): a capsule of ``radius`` [m] around the segment ``[p0, p1]`` [m].

    ``p0 == p1`` is allowed (the capsule is then a sphere).
    """

    kind = KIND_LSS

    def __init__(self, p0: ArrayLike, p1: ArrayLike, radius: float) -> None:
        a = _point(p0, "p0")
        b = _point(p1, "p1")
        self.radius = _radius(radius)
        self.vertices = np.array([a, b, b])
        self.vertices.setflags(write=False)

    @property
    def length(self) -> float:
        """Segment length [m]."""
        return float(np.linalg.norm(self.vertices[1] - self.vertices[0]))


class TSS(SSV):
    """Triangle swept sphere (5.28): the triangle ``(p0, p1, p2)`` [m] thickened by ``radius`` [m].

    Degenerate triangles (collinear or coincident vertices) are allowed and behave as the segment or point
    they collapse to.
    """

    kind = KIND_TSS

    def __init__(self, p0: ArrayLike, p1: ArrayLike, p2: ArrayLike, radius: float) -> None:
        self.radius = _radius(radius)
        self.vertices = np.array([_point(p0, "p0"), _point(p1, "p1"), _point(p2, "p2")])
        self.vertices.setflags(write=False)

    @property
    def normal(self) -> NDArray[np.float64]:
        """Unit normal ``(p1 - p0) x (p2 - p0)``; zeros for a degenerate triangle."""
        n = np.cross(self.vertices[1] - self.vertices[0], self.vertices[2] - self.vertices[0])
        norm = float(np.linalg.norm(n))
        return n / norm if norm > 0.0 else np.zeros(3)
