"""Which of a robot's swept-sphere geoms can collide with each other (shared by the envs)."""

from __future__ import annotations

import mujoco
import numpy as np
from numpy.typing import NDArray

__all__ = ["self_collision_pairs"]


def self_collision_pairs(m: mujoco.MjModel, geoms: NDArray[np.int64]) -> NDArray[np.int64]:
    """Index pairs (into ``geoms``) of robot volumes that can collide: not on one body, not on a body and its
    nearest ancestor carrying geoms, and not excluded by an MJCF ``<exclude>``."""
    body = m.geom_bodyid[geoms]
    carriers = set(body.tolist())

    def carrier_parent(b: int) -> int:
        p = int(m.body_parentid[b])
        while p > 0 and p not in carriers:
            p = int(m.body_parentid[p])
        return p

    excluded = {frozenset((int(s >> 16), int(s & 0xFFFF))) for s in m.exclude_signature}
    pairs = []
    for i in range(len(geoms)):
        for j in range(i + 1, len(geoms)):
            a, b = int(body[i]), int(body[j])
            if a == b or carrier_parent(a) == b or carrier_parent(b) == a or frozenset((a, b)) in excluded:
                continue
            pairs.append((i, j))
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)
