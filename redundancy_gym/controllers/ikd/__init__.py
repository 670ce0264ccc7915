"""Inverse Kineto-Dynamics (monograph 5.5): joint trajectories for hybrid tasks of prescribed forces and task
coordinates (the biped form (5.88-5.91), the general form (5.96), their stabilizers). The walking controller's use of
it, :class:`~redundancy_gym.controllers.walking.WalkingIkd`, lives in the walking package."""

from ..._moved import forward_attributes
from .biped_ikd import BipedIkd, BipedIkdReference, BipedIkdResult
from .compiled_biped_ikd import CompiledBipedIkd
from .error_compensation import ErrorCompensation, ErrorCompensationOutput
from .general_ikd import WEIGHTINGS, GeneralIkd, GeneralIkdResult
from .plan_stabilizer import PlanStabilizer, PlanStabilizerOutput

__all__ = [
    "WEIGHTINGS",
    "BipedIkd",
    "BipedIkdReference",
    "BipedIkdResult",
    "CompiledBipedIkd",
    "ErrorCompensation",
    "ErrorCompensationOutput",
    "GeneralIkd",
    "GeneralIkdResult",
    "PlanStabilizer",
    "PlanStabilizerOutput",
]

# the walking IKD (a walking controller's IK) moved to redundancy_gym.controllers.walking in 0.2, so that ikd/ and
# walking/ no longer import each other (the old names warn and go in 0.3)
__getattr__ = forward_attributes(
    __name__,
    dict.fromkeys(
        ("WalkingIkd", "WalkingIkdConfig", "WalkingIkdStep"), "redundancy_gym.controllers.walking.walking_ikd"
    ),
)
