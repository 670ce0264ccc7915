"""Closed-loop inverse kinematics (monograph 5.1-5.2): the redundancy resolution (5.20-5.24), the velocity-level
:class:`Clik` with its compiled twin :class:`CompiledClik`, and the acceleration-level :class:`AccelerationClik`."""

from .acceleration_clik import AccelerationClik, AccelerationClikResult, DriftTask
from .clik import Clik, ClikProblem, ClikResult
from .compiled_clik import CompiledClik
from .redundancy_resolution import METHODS, JointBounds, Method, Resolution, WeightMatrix, resolve

__all__ = [
    "METHODS",
    "AccelerationClik",
    "AccelerationClikResult",
    "Clik",
    "ClikProblem",
    "ClikResult",
    "CompiledClik",
    "DriftTask",
    "JointBounds",
    "Method",
    "Resolution",
    "WeightMatrix",
    "resolve",
]
