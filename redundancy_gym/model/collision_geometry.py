"""Collision segments from the MJCF geoms, through pinocchio's MJCF geometry loader (monograph 5.2.2).

Sphere geoms become PSS, capsule geoms LSS, and mesh geoms whose name starts with ``triangle_prefix`` TSS
(a triangle mesh of 3 vertices, or a thin triangular prism of 6 whose mid-plane triangle is the TSS and whose
half thickness is the radius: MuJoCo simulates the prism, the controller sees the TSS). Geoms moving with one joint
form one segment, named after their body and attached to the joint's frame; world geoms form environment segments.
Other geom types are left out and listed, since a scene "models only what it needs". Pairs never checked: a segment
and its nearest ancestor segment (joints without geoms in between, as in a compact wrist, do not separate them), and
the body pairs of the MJCF's ``<contact><exclude/>`` entries (``world`` standing for every world geom).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pinocchio as pin

from ..geometry import LSS, PSS, SSV, TSS, CollisionModel, Segment
from .exceptions import ModelError
from .robot_model import RobotModel

__all__ = ["CollisionGeometry", "box_volumes", "collision_geometry_from_mjcf", "collision_model_from_mjcf"]

TRIANGLE_PREFIX = "tss"


@dataclass(frozen=True)
class CollisionGeometry:
    """Segments read from an MJCF: robot (per joint), environment (world geoms), excluded (adjacent) pairs, skipped
    geoms."""

    robot: tuple[Segment, ...]
    environment: tuple[Segment, ...]
    adjacent: tuple[tuple[str, str], ...]
    skipped: tuple[str, ...]

    def collision_model(
        self, environment: tuple[Segment, ...] | list[Segment] = (), **kwargs: object
    ) -> CollisionModel:
        """A :class:`CollisionModel` of these robot segments (adjacent links excluded) plus the MJCF's world
        geoms and ``environment``; ``kwargs`` go to :class:`CollisionModel`. Reading the MJCF once and calling
        this per episode saves the parse."""
        return CollisionModel(self.robot, tuple(self.environment) + tuple(environment), exclude=self.adjacent, **kwargs)  # type: ignore[arg-type]


def _triangle(points: np.ndarray, name: str) -> tuple[np.ndarray, float]:
    """Mid-plane triangle and half thickness of a 3-vertex triangle or a 6-vertex triangular prism."""
    if len(points) == 3:
        return points, 0.0
    if len(points) != 6:
        raise ModelError(f"geom {name!r}: a TSS mesh needs 3 or 6 vertices, got {len(points)}")
    center = points.mean(axis=0)
    normal = np.linalg.svd(points - center)[2][-1]
    height = (points - center) @ normal
    top, bottom = points[height >= 0.0], points[height < 0.0]
    if len(top) != 3:
        raise ModelError(f"geom {name!r}: the 6 vertices are not a triangular prism")
    # pair each top vertex with the bottom vertex whose in-plane position matches
    mid = []
    for p in top:
        flat = bottom - np.outer((bottom - p) @ normal, normal)
        q = bottom[int(np.argmin(np.linalg.norm(flat - p, axis=1)))]
        mid.append(0.5 * (p + q))
    return np.array(mid), float(0.5 * (height.max() - height.min()))


def _volume(obj: pin.GeometryObject, prefix: str) -> SSV | None:
    shape = obj.geometry
    placement = obj.placement
    rot, pos = placement.rotation, placement.translation
    kind = type(shape).__name__
    if kind == "Sphere":
        return PSS(pos, shape.radius)
    if kind == "Capsule":
        axis = rot[:, 2] * shape.halfLength
        return LSS(pos - axis, pos + axis, shape.radius)
    if kind == "Convex" and obj.name.startswith(prefix):
        local = np.array([np.asarray(shape.points(i)) for i in range(shape.num_points)])
        tri, radius = _triangle(local, obj.name)
        world = tri @ rot.T + pos
        return TSS(world[0], world[1], world[2], radius)
    return None


def collision_geometry_from_mjcf(
    model: RobotModel, path: str | Path | None = None, *, triangle_prefix: str = TRIANGLE_PREFIX
) -> CollisionGeometry:
    """Segments of an MJCF (default: the file ``model`` was built from)."""
    source = Path(path if path is not None else model.source)
    if not source.is_file():
        raise ModelError(f"MJCF file not found: {source}")
    pm = model.pinocchio_model
    try:
        geom = pin.buildGeomFromMJCF(pm, str(source), pin.GeometryType.COLLISION)
    except Exception as exc:  # pinocchio raises plain RuntimeError/ValueError
        raise ModelError(f"pinocchio could not read the geoms of {source}: {exc}") from exc
    per_joint: dict[int, list[SSV]] = {}
    body: dict[int, str] = {}
    environment: list[Segment] = []
    skipped: list[str] = []
    for obj in geom.geometryObjects:
        volume = _volume(obj, triangle_prefix)
        if volume is None:
            skipped.append(obj.name)
        elif obj.parentJoint == 0:
            environment.append(Segment(obj.name, (volume,)))
        else:
            per_joint.setdefault(int(obj.parentJoint), []).append(volume)
            body.setdefault(int(obj.parentJoint), pm.frames[obj.parentFrame].name)
    # named after the body, attached to the joint frame the geom placements are relative to
    robot = tuple(Segment(body[j], tuple(v), frame=pm.names[j]) for j, v in sorted(per_joint.items()))
    present = set(per_joint)
    adjacent: list[tuple[str, str]] = []
    for j in sorted(present):
        # the nearest ancestor that carries geoms: joints without geoms (a compact wrist) do not separate links
        parent = pm.parents[j]
        while parent > 0 and parent not in present:
            parent = pm.parents[parent]
        if parent in present:
            adjacent.append((body[parent], body[j]))
    names = {s.name for s in robot} | {s.name for s in environment}
    for a, b in _mjcf_excludes(source):
        # MJCF names the world body "world"; its geoms are environment segments named after the geoms
        pairs_a = [e.name for e in environment] if a == "world" else [a]
        pairs_b = [e.name for e in environment] if b == "world" else [b]
        adjacent.extend((x, y) for x in pairs_a for y in pairs_b if x in names and y in names)
    return CollisionGeometry(robot, tuple(environment), tuple(adjacent), tuple(skipped))


def _mjcf_excludes(path: Path) -> list[tuple[str, str]]:
    """Body pairs of the MJCF's ``<contact><exclude body1 body2/>`` entries."""
    try:
        root = ElementTree.parse(path).getroot()
    except ElementTree.ParseError as exc:
        raise ModelError(f"{path} is not valid XML: {exc}") from exc
    return [(e.get("body1", ""), e.get("body2", "")) for e in root.iter("exclude")]


def box_volumes(
    model: RobotModel, names: tuple[str, ...] | list[str], path: str | Path | None = None
) -> dict[str, tuple[TSS, ...]]:
    """Swept-sphere covers of the MJCF's box geoms ``names``, by the segment they move with (the segment names of
    :func:`collision_geometry_from_mjcf`, in its coordinates): each box as two TSS on its mid-plane across its
    thinnest axis, of radius its half thickness, which hold the box with its edges rounded (its rim reaches at most
    the half thickness beyond the box's sides).

    Boxes are contact geoms that :func:`collision_geometry_from_mjcf` leaves out (the biped's soles); a model that
    wants them in its distances adds these.

    Raises:
        ModelError: a name that is not a box geom of the MJCF.
    """
    source = Path(path if path is not None else model.source)
    pm = model.pinocchio_model
    try:
        geom = pin.buildGeomFromMJCF(pm, str(source), pin.GeometryType.COLLISION)
    except Exception as exc:  # pinocchio raises plain RuntimeError/ValueError
        raise ModelError(f"pinocchio could not read the geoms of {source}: {exc}") from exc
    boxes = {obj.name: obj for obj in geom.geometryObjects if type(obj.geometry).__name__ == "Box"}
    missing = [n for n in names if n not in boxes]
    if missing:
        raise ModelError(f"box geoms {missing} not in {source}; its boxes: {sorted(boxes)}")
    covers: dict[str, list[TSS]] = {}
    for name in names:
        obj = boxes[name]
        half = np.asarray(obj.geometry.halfSide, dtype=np.float64)
        rot, center = obj.placement.rotation, obj.placement.translation
        thin = int(np.argmin(half))
        a, b = (rot[:, k] * half[k] for k in range(3) if k != thin)
        corners = (center - a - b, center + a - b, center + a + b, center - a + b)
        radius = float(half[thin])
        segment = pm.frames[obj.parentFrame].name
        covers.setdefault(segment, []).extend(
            (TSS(corners[0], corners[1], corners[2], radius), TSS(corners[0], corners[2], corners[3], radius))
        )
    return {segment: tuple(v) for segment, v in covers.items()}


def collision_model_from_mjcf(
    model: RobotModel,
    environment: tuple[Segment, ...] | list[Segment] = (),
    path: str | Path | None = None,
    **kwargs: object,
) -> CollisionModel:
    """A :class:`CollisionModel` of the MJCF's robot geoms (adjacent links excluded) plus ``environment``
    (and the MJCF's own world geoms); ``kwargs`` go to :class:`CollisionModel`."""
    return collision_geometry_from_mjcf(model, path).collision_model(environment, **kwargs)
