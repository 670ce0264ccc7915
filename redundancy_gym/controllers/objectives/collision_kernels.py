"""Compiled collision avoidance in the nullspace (monograph 5.3, (5.49)-(5.61)), shared by the fused control
steps (:mod:`.clik_kernels`, :mod:`.walking.whole_body_kernels`): places the robot's swept-sphere volumes on
the joint frames of a :class:`~redundancy_gym.model.SerialChain` and sums ``H_c23`` of the pair distances with
its gradient ``H'(d) n^T (J_b(p_b) - J_a(p_a))``, formed without a Jacobian.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ...geometry import CollisionLayout
from ...geometry.potentials import piecewise_potential_kernel
from ...geometry.ssv_kernels import volume_pair_distance
from ...kernel_options import BORROW
from ...model import RobotModel
from ...model.chain_kernels import chain_jacobian_transpose_times, place_frame
from ..kernels.buffers import borrowed_float_field, borrowed_int_field
from .collision_objective import CollisionObjective

__all__ = [
    "COLLISION_COUNTS",
    "COLLISION_FLOAT_FIELDS",
    "COLLISION_INT_FIELDS",
    "CollisionFields",
    "bounding_spheres",
    "close_pair_rows",
    "collision_fields",
    "collision_potential",
    "collision_views",
    "no_collision_arrays",
]

COLLISION_FLOAT_FIELDS: tuple[str, ...] = (
    "segment_rotation",
    "segment_translation",
    "segment_center",
    "segment_radius",
    "segment_world_center",
    "local",
    "vertices",
    "radii",
    "collision_parameters",
)
"""The float fields of :func:`collision_fields`, in the order a fused kernel's buffer holds them (one block)."""
COLLISION_INT_FIELDS: tuple[str, ...] = (
    "segment_joint",
    "segment_starts",
    "kinds",
    "segment_pairs",
    "pair_starts",
    "volume_a",
    "volume_b",
)
"""The int fields of :func:`collision_fields`, in the order a fused kernel's buffer holds them (one block)."""
COLLISION_COUNTS: tuple[str, ...] = ("segments", "volumes", "pairs", "volume_pairs")
"""The counts :func:`collision_fields` gives (``CollisionFields.counts``), in a fused kernel's ``dims``."""


def no_collision_arrays() -> tuple[dict[str, NDArray[np.float64]], dict[str, NDArray[np.int64]], dict[str, int]]:
    """``(floats, ints, counts)`` of a controller without a collision objective: every field of
    :data:`COLLISION_FLOAT_FIELDS` and :data:`COLLISION_INT_FIELDS` empty, every count 0."""
    return (
        {name: np.zeros(0) for name in COLLISION_FLOAT_FIELDS},
        {name: np.zeros(0, dtype=np.int64) for name in COLLISION_INT_FIELDS},
        dict.fromkeys(COLLISION_COUNTS, 0),
    )


# the kernels only borrow their arrays (the callers' buffers): no reference counting (BORROW); callers that count
# references may call them too, since nothing borrowed is returned


@njit(**BORROW)
def _closest_volumes(p, a, b, pair_starts, vol_a, vol_b, seg_radius, seg_world, vertices, radii, kinds, margin):
    """``(distance, p_a, p_b, n)`` of segment pair ``p``'s (segments ``a``, ``b``) closest volume pair, or an
    infinite distance when the segments' bounding spheres are farther apart than ``margin`` (the pair cannot be
    nearer than that)."""
    dx = seg_world[a, 0] - seg_world[b, 0]
    dy = seg_world[a, 1] - seg_world[b, 1]
    dz = seg_world[a, 2] - seg_world[b, 2]
    reach = seg_radius[a] + seg_radius[b] + margin
    best = np.inf
    best_pa = (0.0, 0.0, 0.0)
    best_pb = (0.0, 0.0, 0.0)
    best_n = (0.0, 0.0, 1.0)
    if dx * dx + dy * dy + dz * dz > reach * reach:
        return best, best_pa, best_pb, best_n
    for k in range(pair_starts[p], pair_starts[p + 1]):
        d, pa, pb, n = volume_pair_distance(vertices, radii, kinds, vol_a[k], vol_b[k])
        if d < best:
            best, best_pa, best_pb, best_n = d, pa, pb, n
    return best, best_pa, best_pb, best_n


@njit(inline="always", **BORROW)  # inlined: it returns views (see kernels.buffers.borrowed_float_field)
def collision_views(f, i, first_float, first_int, ns, nvol, npairs):
    """``(coll_i, coll_f, params)`` of :func:`collision_potential` from the buffers of
    :func:`~redundancy_gym.controllers.kernels.buffers.pack_fields` whose fields :data:`COLLISION_FLOAT_FIELDS`
    start at field index ``first_float`` and :data:`COLLISION_INT_FIELDS` at ``first_int``; ``ns`` segments,
    ``nvol`` volumes and ``npairs`` segment pairs."""
    coll_i = (
        borrowed_int_field(i, first_int),
        borrowed_int_field(i, first_int + 1),
        borrowed_int_field(i, first_int + 2),
        borrowed_int_field(i, first_int + 3).reshape((npairs, 2)),
        borrowed_int_field(i, first_int + 4),
        borrowed_int_field(i, first_int + 5),
        borrowed_int_field(i, first_int + 6),
    )
    coll_f = (
        borrowed_float_field(f, i, first_float).reshape((ns, 3, 3)),
        borrowed_float_field(f, i, first_float + 1).reshape((ns, 3)),
        borrowed_float_field(f, i, first_float + 2).reshape((ns, 3)),
        borrowed_float_field(f, i, first_float + 3),
        borrowed_float_field(f, i, first_float + 4).reshape((ns, 3)),
        borrowed_float_field(f, i, first_float + 5).reshape((nvol, 3, 3)),
        borrowed_float_field(f, i, first_float + 6).reshape((nvol, 3, 3)),
        borrowed_float_field(f, i, first_float + 7),
    )
    return coll_i, coll_f, borrowed_float_field(f, i, first_float + 8)


@njit(inline="always", **BORROW)  # inlined: it ran in the callers' pair loops before they shared it
def _add_distance_row(chain, seg_joint, a, b, pa, pb, n, scale, out):
    """``out += scale n^T (J_b(p_b) - J_a(p_a))`` (5.61): ``scale`` times the gradient of the distance of the
    points ``pa`` on segment ``a`` and ``pb`` on ``b`` along their normal ``n`` (environment segments, joint -1,
    do not move); segment ``b``'s term first."""
    for end in range(2):
        segment, point, sign = (b, pb, scale) if end == 0 else (a, pa, -scale)
        joint = seg_joint[segment]
        if joint >= 0:
            chain_jacobian_transpose_times(*chain, joint, point[0], point[1], point[2], n[0], n[1], n[2], sign, out)


@njit(**BORROW)
def collision_potential(coll_i, coll_f, params, chain, gradient, scratch):
    """Place the robot volumes, then ``H_c`` (5.49) and its gradient (5.61) over the pairs within ``d_a``:
    ``(value, smallest distance computed)``; the gradient is added to ``gradient`` (nv).

    ``coll_i`` is ``(seg_joint, seg_starts, kinds, seg_pairs, pair_starts, vol_a, vol_b)`` and ``coll_f``
    ``(seg_rot, seg_pos, seg_center, seg_radius, seg_world, local, vertices, radii)``: the fields of
    :data:`COLLISION_INT_FIELDS` and :data:`COLLISION_FLOAT_FIELDS` but the last (:func:`collision_views`);
    ``chain`` is the kinematics ``(parent, joint_type, v_index, rotation, position, world_axis)`` of
    :func:`~redundancy_gym.model.chain_kernels.chain_forward`.

    Segment ``s`` moves with joint ``seg_joint[s]`` at ``(seg_rot[s], seg_pos[s])`` in its frame (-1: an
    environment segment whose world ``vertices`` and ``seg_world`` centre the owner keeps up to date); its volumes
    ``seg_starts[s]:seg_starts[s + 1]`` have ``local`` vertices, ``radii`` and ``kinds``; pair ``p`` of
    ``seg_pairs`` checks the volume pairs ``vol_a``/``vol_b`` from ``pair_starts[p]``. ``params`` is
    ``(d_a, slope, switch ratio, weight)``. Pairs whose segments' bounding spheres (``seg_center``,
    ``seg_radius``) are farther apart than ``d_a`` contribute nothing and are skipped (their distance is at
    least the spheres'). ``scratch`` needs 12 entries.
    """
    seg_joint, seg_starts, kinds, seg_pairs, pair_starts, vol_a, vol_b = coll_i
    seg_rot, seg_pos, seg_center, seg_radius, seg_world, local, vertices, radii = coll_f
    rotation, position = chain[3], chain[4]
    ns, npairs = seg_joint.shape[0], seg_pairs.shape[0]
    da, slope, ratio, weight = params[0], params[1], params[2], params[3]
    rot = scratch[0:9].reshape((3, 3))
    pos = scratch[9:12]
    for s in range(ns):
        jnt = seg_joint[s]
        if jnt < 0:  # environment: world vertices and centre are kept up to date by the owner
            continue
        place_frame(rotation, position, jnt, seg_rot[s], seg_pos[s], rot, pos)
        for r in range(3):
            seg_world[s, r] = (
                pos[r] + rot[r, 0] * seg_center[s, 0] + rot[r, 1] * seg_center[s, 1] + rot[r, 2] * seg_center[s, 2]
            )
        for v in range(seg_starts[s], seg_starts[s + 1]):
            for k in range(3):
                for r in range(3):
                    vertices[v, k, r] = (
                        pos[r] + rot[r, 0] * local[v, k, 0] + rot[r, 1] * local[v, k, 1] + rot[r, 2] * local[v, k, 2]
                    )
    value = 0.0
    smallest = np.inf
    for p in range(npairs):
        a = seg_pairs[p, 0]
        b = seg_pairs[p, 1]
        best, best_pa, best_pb, best_n = _closest_volumes(
            p, a, b, pair_starts, vol_a, vol_b, seg_radius, seg_world, vertices, radii, kinds, da
        )
        if best == np.inf:
            continue
        smallest = min(smallest, best)
        if not best < da:
            continue
        h, dh, _ = piecewise_potential_kernel(best, da, slope, ratio)
        value += weight * h
        _add_distance_row(chain, seg_joint, a, b, best_pa, best_pb, best_n, weight * dh, gradient)
    return value, smallest


@njit(**BORROW)
def close_pair_rows(coll_i, coll_f, chain, limit, distances, rows):
    """Distances and ``dd/dq = n^T (J_b(p_b) - J_a(p_a))`` rows (5.61) of the pairs nearer than ``limit``, at the
    placement that :func:`collision_potential` last left in ``vertices`` and ``seg_world`` (and the kinematics in
    ``rotation``, ``position``, ``world_axis``); returns how many. At most ``rows.shape[0]`` pairs are kept: the
    nearest ones. ``distances`` (K) and ``rows`` (K x nv) are filled from the start. The arguments are
    :func:`collision_potential`'s."""
    seg_joint, _, kinds, seg_pairs, pair_starts, vol_a, vol_b = coll_i
    seg_radius, seg_world, vertices, radii = coll_f[3], coll_f[4], coll_f[6], coll_f[7]
    count = 0
    capacity = rows.shape[0]
    for p in range(seg_pairs.shape[0]):
        a = seg_pairs[p, 0]
        b = seg_pairs[p, 1]
        best, best_pa, best_pb, best_n = _closest_volumes(
            p, a, b, pair_starts, vol_a, vol_b, seg_radius, seg_world, vertices, radii, kinds, limit
        )
        if not best < limit:
            continue
        slot = count
        if count == capacity:  # full: replace the farthest kept pair if this one is nearer
            slot = 0
            for r in range(1, capacity):
                if distances[r] > distances[slot]:
                    slot = r
            if not best < distances[slot]:
                continue
        else:
            count += 1
        distances[slot] = best
        rows[slot, :] = 0.0
        _add_distance_row(chain, seg_joint, a, b, best_pa, best_pb, best_n, 1.0, rows[slot])
    return count


class CollisionFields(NamedTuple):
    """The kernel fields of one :class:`CollisionObjective` (see :func:`collision_potential`).

    Attributes:
        floats: ``segment_rotation``, ``segment_translation``, ``segment_center``, ``segment_radius``,
            ``segment_world_center``, ``local``, ``vertices``, ``radii``, ``collision_parameters``.
        ints: ``segment_joint``, ``segment_starts``, ``kinds``, ``segment_pairs``, ``pair_starts``,
            ``volume_a``, ``volume_b``.
        counts: ``segments``, ``volumes``, ``pairs``, ``volume_pairs``.
        world_fixed: ``(segment, R, p)`` of robot segments on world-fixed frames (placed by the owner).
        layout: the collision model's layout.
        robot_segments: how many segments are the robot's (they come first).
    """

    floats: dict[str, NDArray[np.float64]]
    ints: dict[str, NDArray[np.int64]]
    counts: dict[str, int]
    world_fixed: tuple[tuple[int, NDArray[np.float64], NDArray[np.float64]], ...]
    layout: CollisionLayout
    robot_segments: int


def bounding_spheres(
    local: NDArray[np.float64], kinds: NDArray[np.int64], radii: NDArray[np.float64], starts: NDArray[np.int64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per segment a sphere (centre in the segment's coordinates, radius) holding all its volumes."""
    n = starts.size - 1
    centers, bounds = np.zeros((n, 3)), np.zeros(n)
    for s in range(n):
        points = np.concatenate([local[v, : kinds[v] + 1] for v in range(starts[s], starts[s + 1])])
        reach = np.concatenate([np.full(kinds[v] + 1, radii[v]) for v in range(starts[s], starts[s + 1])])
        centers[s] = points.mean(axis=0)
        # a small relative margin so that rounding never culls a pair that is within reach
        bounds[s] = float(np.max(np.linalg.norm(points - centers[s], axis=1) + reach)) * (1.0 + 1e-9) + 1e-12
    return centers, bounds


def collision_fields(collision: CollisionObjective, model: RobotModel) -> CollisionFields:
    """The segments, volumes and pairs of ``collision`` as kernel fields, each robot segment attached to its
    :meth:`~redundancy_gym.model.RobotModel.serial_chain` joint. The environment's vertices and every
    bounding sphere are left for the owner to fill (they change with the environment)."""
    layout = collision.collision_model.layout()
    ns = len(layout.frames)
    joints, rotations, translations = [], [], []
    world_fixed = []
    for s, frame in enumerate(layout.frames):
        if frame is None:
            joints.append(-1)
            rotations.append(np.eye(3))
            translations.append(np.zeros(3))
        else:
            j, r, p = model.frame_attachment(frame)
            joints.append(j)
            rotations.append(r)
            translations.append(p)
            if j < 0:  # a robot segment on a world-fixed frame: placed once, like the environment
                world_fixed.append((s, r, p))
    potential = collision.potential
    floats = {
        "segment_rotation": np.array(rotations).reshape(ns, 3, 3),
        "segment_translation": np.array(translations).reshape(ns, 3),
        "segment_center": np.zeros((ns, 3)),
        "segment_radius": np.zeros(ns),
        "segment_world_center": np.zeros((ns, 3)),
        "local": layout.local,
        "vertices": layout.local.copy(),
        "radii": layout.radii,
        "collision_parameters": np.array(
            [potential.activation_distance, potential.slope, potential.switch_ratio, collision.weight]
        ),
    }
    ints = {
        "segment_joint": np.array(joints, dtype=np.int64),
        "segment_starts": layout.segment_starts,
        "kinds": layout.kinds,
        "segment_pairs": layout.segment_pairs,
        "pair_starts": layout.pair_starts,
        "volume_a": layout.volume_a,
        "volume_b": layout.volume_b,
    }
    counts = {
        "segments": ns,
        "volumes": len(layout.kinds),
        "pairs": len(layout.segment_pairs),
        "volume_pairs": len(layout.volume_a),
    }
    return CollisionFields(floats, ints, counts, tuple(world_fixed), layout, sum(f is not None for f in layout.frames))
