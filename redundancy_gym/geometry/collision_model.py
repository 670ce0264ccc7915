"""Collision model (monograph 5.2.2, (5.29)-(5.34)): robot and environment segments, collision pairs, and
pair distances with their gradients (5.61).

A :class:`Segment` is a rigid set of SSVs fixed to a robot frame (or to the world, for the environment).
:class:`CollisionModel` forms the collision pairs (robot-robot without excluded neighbours, robot-environment),
gives every multi-volume segment a bounding LSS so that far pairs are skipped, and evaluates all pairs in one
compiled batch. It reads the robot's kinematics through a small protocol (:class:`Kinematics`, satisfied by
``redundancy_gym.model.RobotModel``) and imports no model code itself.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import NamedTuple, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .distance import PackedVolumes, PairBatch
from .exceptions import GeometryError
from .primitives import LSS, SSV

__all__ = ["CollisionLayout", "CollisionModel", "CollisionState", "Kinematics", "Segment", "bounding_lss"]


class Kinematics(Protocol):
    """What the collision model needs from a robot model (``RobotModel`` after ``update(q)``)."""

    @property
    def nv(self) -> int: ...

    def frame_placement(self, frame: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...

    def point_jacobian(self, frame: str, point: ArrayLike) -> NDArray[np.float64]: ...


@dataclass(frozen=True)
class Segment:
    """A rigid set of swept-sphere volumes (5.30), (5.32).

    Attributes:
        name: unique name.
        volumes: the SSVs, in the coordinates of ``frame`` [m].
        frame: the robot frame they move with; ``None`` for an environment segment (world coordinates).
    """

    name: str
    volumes: tuple[SSV, ...]
    frame: str | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "volumes", tuple(self.volumes))
        if not self.volumes:
            raise GeometryError(f"segment {self.name!r} has no volumes")
        for v in self.volumes:
            if not isinstance(v, SSV):
                raise GeometryError(f"segment {self.name!r}: {type(v).__name__} is not a PSS, LSS or TSS")


def bounding_lss(volumes: Sequence[SSV]) -> LSS:
    """A capsule containing every volume: axis along the principal direction of the vertices.

    The axis spans the extreme projections of the vertices; the radius is the largest distance of a vertex
    from the axis segment plus that volume's radius, so every volume lies inside (5.2.2, figure 5.13).
    """
    points = np.concatenate([v.points for v in volumes])
    radii = np.concatenate([np.full(len(v.points), v.radius) for v in volumes])
    center = points.mean(axis=0)
    centered = points - center
    axis = (
        np.linalg.svd(centered, full_matrices=False)[2][0]
        if np.ptp(points, axis=0).max() > 0.0
        else np.array([0.0, 0.0, 1.0])
    )
    proj = centered @ axis
    p0, p1 = center + proj.min() * axis, center + proj.max() * axis
    seg = p1 - p0
    length2 = float(seg @ seg)
    s = np.clip(((points - p0) @ seg) / length2, 0.0, 1.0) if length2 > 0.0 else np.zeros(len(points))
    gaps = np.linalg.norm(points - (p0 + s[:, None] * seg), axis=1)
    return LSS(p0, p1, float(np.max(gaps + radii)) * (1.0 + 1e-12))


class CollisionState(NamedTuple):
    """Distances of every collision pair at one configuration.

    Attributes:
        pairs: ``(segment_from, segment_to)`` names, in the model's pair order.
        distance: (P,) SSV distance of each pair [m] (the smallest over its volume pairs). For a pair skipped
            by its bounding volumes it is the bounding distance, a lower bound (see ``exact``).
        point_a, point_b: (P, 3) witness points on the generating primitives of ``from`` and ``to`` [m].
        normal: (P, 3) unit vector from ``point_a`` to ``point_b``.
        exact: (P,) False where the pair was skipped by its bounding volumes.
    """

    pairs: tuple[tuple[str, str], ...]
    distance: NDArray[np.float64]
    point_a: NDArray[np.float64]
    point_b: NDArray[np.float64]
    normal: NDArray[np.float64]
    exact: NDArray[np.bool_]


@dataclass(frozen=True)
class CollisionLayout:
    """A :class:`CollisionModel` as flat arrays, for compiled consumers (the fused CLIK step).

    Attributes:
        frames: (S,) each segment's robot frame, ``None`` for the environment; robot segments come first.
        segment_starts: (S + 1,) segment ``s`` owns volumes ``segment_starts[s]:segment_starts[s + 1]``.
        local: (M, 3, 3) volume vertices in their segment's frame (environment: before its placement) [m].
        radii: (M,) volume radii [m] (environment radii can change later; see
            :meth:`CollisionModel.environment_volumes`).
        kinds: (M,) volume kinds (0 PSS, 1 LSS, 2 TSS).
        segment_pairs: (P, 2) segment indices of each collision pair, in :attr:`CollisionModel.pairs` order.
        pair_starts: (P + 1,) pair ``p`` owns volume pairs ``pair_starts[p]:pair_starts[p + 1]``.
        volume_a, volume_b: (V,) volume indices of each volume pair.
    """

    frames: tuple[str | None, ...]
    segment_starts: NDArray[np.int64]
    local: NDArray[np.float64]
    radii: NDArray[np.float64]
    kinds: NDArray[np.int64]
    segment_pairs: NDArray[np.int64]
    pair_starts: NDArray[np.int64]
    volume_a: NDArray[np.int64]
    volume_b: NDArray[np.int64]


class CollisionModel:
    """Robot and environment segments with their collision pairs (5.33), (5.34).

    Args:
        robot: robot segments (each with a ``frame``).
        environment: environment segments (``frame`` None, world coordinates).
        exclude: segment-name pairs never checked (typically adjacent links, whose volumes overlap at the
            joint; joint-limit avoidance covers them, as 5.3 notes).
        self_collision: check robot-robot pairs.
        bounding: skip a pair when the bounding capsules of its segments are farther apart than
            ``bounding_margin`` (only pairs with a multi-volume segment have a bounding test).
        bounding_margin: [m], >= 0; pairs closer than this are always computed exactly.
    """

    def __init__(
        self,
        robot: Sequence[Segment],
        environment: Sequence[Segment] = (),
        *,
        exclude: Iterable[tuple[str, str]] = (),
        self_collision: bool = True,
        bounding: bool = True,
        bounding_margin: float = 0.2,
    ) -> None:
        self.robot = tuple(robot)
        self.environment = tuple(environment)
        names = [s.name for s in self.robot + self.environment]
        if len(set(names)) != len(names):
            raise GeometryError(f"segment names must be unique, got {names}")
        for s in self.robot:
            if s.frame is None:
                raise GeometryError(f"robot segment {s.name!r} needs a frame")
        for s in self.environment:
            if s.frame is not None:
                raise GeometryError(f"environment segment {s.name!r} must not have a frame (world coordinates)")
        if not np.isfinite(bounding_margin) or bounding_margin < 0.0:
            raise GeometryError(f"bounding_margin must be finite and >= 0, got {bounding_margin!r}")
        excluded = {frozenset(p) for p in exclude}
        unknown = {n for p in excluded for n in p} - set(names)
        if unknown:
            raise GeometryError(f"exclude names unknown segments {sorted(unknown)}; segments: {names}")
        self.segments = self.robot + self.environment
        self.bounding_margin = float(bounding_margin)
        index = {s.name: i for i, s in enumerate(self.segments)}
        self._segment_index = index
        pairs: list[tuple[int, int]] = []
        nr = len(self.robot)
        if self_collision:
            pairs += [
                (i, j)
                for i in range(nr)
                for j in range(i + 1, nr)
                if frozenset((self.segments[i].name, self.segments[j].name)) not in excluded
            ]
        pairs += [
            (i, index[e.name])
            for i in range(nr)
            for e in self.environment
            if frozenset((self.segments[i].name, e.name)) not in excluded
        ]
        self.pairs = tuple((self.segments[i].name, self.segments[j].name) for i, j in pairs)
        self._pairs = np.array(pairs, dtype=np.int64).reshape(-1, 2)

        # every volume of every segment in one array; volume pairs grouped contiguously per segment pair
        volumes: list[SSV] = []
        self._slices: list[slice] = []
        for s in self.segments:
            self._slices.append(slice(len(volumes), len(volumes) + len(s.volumes)))
            volumes.extend(s.volumes)
        ia, ib, owner = [], [], []
        for p, (i, j) in enumerate(pairs):
            for a in range(self._slices[i].start, self._slices[i].stop):
                for b in range(self._slices[j].start, self._slices[j].stop):
                    ia.append(a)
                    ib.append(b)
                    owner.append(p)
        self._local = PackedVolumes.from_volumes(volumes).vertices.copy()
        self._batch = PairBatch(volumes, ia, ib)
        self._owner = np.array(owner, dtype=np.int64)
        self._volume_a = np.array(ia, dtype=np.int64)
        self._volume_b = np.array(ib, dtype=np.int64)
        self._starts = np.searchsorted(self._owner, np.arange(len(pairs))).astype(np.int64)
        self._one_each = len(owner) == len(pairs)  # every segment pair is a single volume pair
        self._env_placement = {s.name: (np.eye(3), np.zeros(3)) for s in self.environment}
        self._env_dirty = True
        self._version = 0

        # bounding capsules (one per segment with several volumes) and the pairs they can skip
        self.bounding = bool(bounding)
        bounds = [bounding_lss(s.volumes) for s in self.segments]
        prunable = [
            p
            for p, (i, j) in enumerate(pairs)
            if len(self.segments[i].volumes) > 1 or len(self.segments[j].volumes) > 1
        ]
        self._prunable = np.array(prunable, dtype=np.int64)
        self._has_bounds = self.bounding and bool(prunable)
        self._bound_row = np.full(len(pairs), -1, dtype=np.int64)
        self._bound_row[self._prunable] = np.arange(len(prunable))
        self._bound_local = PackedVolumes.from_volumes(bounds).vertices.copy()
        self._bound_batch = PairBatch(
            bounds, self._pairs[prunable, 0] if prunable else [], self._pairs[prunable, 1] if prunable else []
        )

    @property
    def num_pairs(self) -> int:
        """Number of segment pairs."""
        return len(self.pairs)

    @property
    def num_volume_pairs(self) -> int:
        """Number of volume pairs behind the segment pairs."""
        return len(self._batch)

    @property
    def version(self) -> int:
        """Counts the changes of environment placements and radii (compiled consumers re-read on a change)."""
        return self._version

    def layout(self) -> CollisionLayout:
        """The segments, volumes and pairs as flat arrays (copies)."""
        starts = np.array([sl.start for sl in self._slices] + [len(self._local)], dtype=np.int64)
        return CollisionLayout(
            tuple(s.frame for s in self.segments),
            starts,
            self._local.copy(),
            self._batch.radii.copy(),
            self._batch.kinds.copy(),
            self._pairs.copy(),
            np.append(self._starts, len(self._owner)).astype(np.int64),
            self._volume_a.copy(),
            self._volume_b.copy(),
        )

    def environment_volumes(self) -> PackedVolumes:
        """The environment segments' volumes in world coordinates with their current radii, in segment order
        (the volumes after the robot's in :meth:`layout`)."""
        first = self._slices[len(self.robot)].start if self.environment else len(self._local)
        vertices = np.empty((len(self._local) - first, 3, 3))
        for s, sl in zip(self.environment, self._slices[len(self.robot) :], strict=False):
            rot, pos = self._env_placement[s.name]
            vertices[sl.start - first : sl.stop - first] = self._local[sl] @ rot.T + pos
        return PackedVolumes(vertices, self._batch.radii[first:].copy(), self._batch.kinds[first:].copy())

    def set_environment_placement(self, name: str, rotation: ArrayLike, translation: ArrayLike) -> None:
        """Move an environment segment: its volumes are mapped by ``x -> R x + p`` from their given coordinates."""
        if name not in self._env_placement:
            raise GeometryError(f"unknown environment segment {name!r}; valid: {sorted(self._env_placement)}")
        rot = np.asarray(rotation, dtype=np.float64)
        pos = np.asarray(translation, dtype=np.float64)
        if rot.shape != (3, 3) or pos.shape != (3,) or not (np.all(np.isfinite(rot)) and np.all(np.isfinite(pos))):
            raise GeometryError("rotation must be a finite 3 x 3 matrix and translation a finite 3-vector")
        self._env_placement[name] = (rot.copy(), pos.copy())
        self._env_dirty = True
        self._version += 1

    def set_environment_radius(self, name: str, radius: float) -> None:
        """Change the radius of a single-volume environment segment (a sphere obstacle that grows or shrinks)."""
        if name not in self._env_placement:
            raise GeometryError(f"unknown environment segment {name!r}; valid: {sorted(self._env_placement)}")
        k = self._segment_index[name]
        if len(self.segments[k].volumes) != 1:
            raise GeometryError(f"segment {name!r} has several volumes; give it new volumes instead")
        r = float(radius)
        if not np.isfinite(r) or r < 0.0:
            raise GeometryError(f"radius must be finite and >= 0, got {radius!r}")
        self._batch.radii[self._slices[k].start] = r
        self._bound_batch.radii[k] = r
        self._version += 1

    def _place(self, kinematics: Kinematics) -> None:
        """World coordinates of every volume (and bounding capsule) into the batches' buffers."""
        for k, (s, sl) in enumerate(zip(self.segments, self._slices, strict=False)):
            if s.frame is None:
                if not self._env_dirty:
                    continue
                rot, pos = self._env_placement[s.name]
            else:
                rot, pos = kinematics.frame_placement(s.frame)
            self._batch.vertices[sl] = self._local[sl] @ rot.T + pos
            if self._has_bounds:
                self._bound_batch.vertices[k] = self._bound_local[k] @ rot.T + pos
        self._env_dirty = False

    def evaluate(self, kinematics: Kinematics) -> CollisionState:
        """All pair distances at the configuration ``kinematics`` was last updated to."""
        self._place(kinematics)
        n = self.num_pairs
        if n == 0:
            empty = np.zeros((0, 3))
            return CollisionState((), np.zeros(0), empty, empty.copy(), empty.copy(), np.zeros(0, dtype=bool))
        exact = np.ones(n, dtype=bool)
        bound = None
        if self._has_bounds:
            bound = self._bound_batch.compute()
            exact[self._prunable[bound.distance > self.bounding_margin]] = False
            self._batch.set_active(exact[self._owner])
        res = self._batch.compute()
        dist = res.distance
        # the closest volume pair of each segment pair: sorted by (pair, distance), each pair's first entry
        which = self._starts if self._one_each else np.lexsort((dist, self._owner))[self._starts]
        distance = dist[which]
        point_a = res.point_a[which]
        point_b = res.point_b[which]
        normal = res.normal[which]
        if bound is not None and not exact.all():
            skipped = np.flatnonzero(~exact)
            rows = self._bound_row[skipped]
            distance[skipped] = bound.distance[rows]
            point_a[skipped], point_b[skipped], normal[skipped] = (
                bound.point_a[rows],
                bound.point_b[rows],
                bound.normal[rows],
            )
        return CollisionState(self.pairs, distance, point_a, point_b, normal, exact)

    def distance_gradient(
        self, kinematics: Kinematics, state: CollisionState, pairs: ArrayLike | None = None
    ) -> NDArray[np.float64]:
        """``dd/dq`` (5.61) of the chosen pairs (default all), one row each (len(pairs) x nv).

        ``dd/dq = n^T (J_T - J_F)`` with ``n`` the unit vector from the ``from`` witness to the ``to`` witness
        and ``J`` the translational Jacobians of the witness points on their segments (zero for the
        environment); (5.61) writes the same with ``r_c / d``.
        """
        rows = np.arange(self.num_pairs) if pairs is None else np.asarray(pairs, dtype=np.int64).reshape(-1)
        grad = np.zeros((rows.size, kinematics.nv))
        for out, p in enumerate(rows):
            i, j = self._pairs[p]
            n = state.normal[p]
            frame_a, frame_b = self.segments[i].frame, self.segments[j].frame
            if frame_b is not None:
                grad[out] += n @ kinematics.point_jacobian(frame_b, state.point_b[p])
            if frame_a is not None:
                grad[out] -= n @ kinematics.point_jacobian(frame_a, state.point_a[p])
        return grad
