"""The joint-limit and posture objectives' fields in a fused kernel's flat buffers (``pack_fields``),
shared by the kernels that evaluate them (:mod:`~redundancy_gym.controllers.clik.clik_kernels`,
:mod:`~redundancy_gym.controllers.walking.whole_body_kernels`)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from .joint_limit_objective import JointLimitObjective
from .posture_objective import PostureObjective

__all__ = [
    "LIMIT_LOWER",
    "LIMIT_PARAMETERS",
    "LIMIT_UPPER",
    "OBJECTIVE_DIMS",
    "OBJECTIVE_FLOAT_FIELDS",
    "POSTURE_REFERENCE",
    "POSTURE_WEIGHTS",
    "objective_arrays",
]

OBJECTIVE_FLOAT_FIELDS: tuple[str, ...] = (
    "limit_lower",
    "limit_upper",
    "limit_parameters",
    "posture_reference",
    "posture_weights",
)
"""The objectives' float fields, in the order a fused kernel's buffer holds them (one block)."""
LIMIT_LOWER, LIMIT_UPPER, LIMIT_PARAMETERS, POSTURE_REFERENCE, POSTURE_WEIGHTS = range(len(OBJECTIVE_FLOAT_FIELDS))
"""Each field's offset from the block's first field index."""
OBJECTIVE_DIMS: tuple[str, ...] = ("limit_objectives", "posture_objectives")
"""The objective counts among a fused kernel's ``dims``."""


def objective_arrays(
    limits: Sequence[JointLimitObjective], postures: Sequence[PostureObjective]
) -> dict[str, NDArray[np.float64]]:
    """The fields of :data:`OBJECTIVE_FLOAT_FIELDS`: one row per objective (bounds [rad or m], the potential's
    ``(activation_distance, slope, switch_ratio, weight)``, reference posture and weights)."""
    return {
        "limit_lower": np.array([o.lower for o in limits]),
        "limit_upper": np.array([o.upper for o in limits]),
        "limit_parameters": np.array(
            [(o.potential.activation_distance, o.potential.slope, o.potential.switch_ratio, o.weight) for o in limits]
        ),
        "posture_reference": np.array([o.reference for o in postures]),
        "posture_weights": np.array([o.weights for o in postures]),
    }
