"""Biped walking (monograph chapter 4 and 5.1-5.3): step planner, LIPM/DCM CoM planner, swing quintics,
stabilizer and whole-body IK with angular-momentum minimization (5.62), or the walking IKD (5.5.4) in its place,
each a separate layer."""

from .compiled_servo_feedforward import CompiledServoFeedforward
from .compiled_whole_body_ik import CompiledWholeBodyIk
from .dcm_planner import GRAVITY, ComState, DcmPlan, DcmPlanner
from .foot_force_control import FootForceControl, FootForceGains
from .gait_config import GaitConfig
from .measure_kernels import CompiledMeasurement, MeasurementResult, renamed_attribute
from .quintic import PiecewiseQuintic, Quintic
from .rca import LEG_SEGMENTS, Rca, RcaConfig, RcaState, return_quintic_no_overshoot_time
from .servo_feedforward import ServoFeedforward, ServoFeedforwardTorques
from .sole_tilt import SoleTilt, SoleTiltConfig
from .ssta import (
    BLOCKED_COST,
    OBSTACLE_CLASSES,
    STOP_CAUSES,
    LinePlan,
    ObstacleBox,
    ObstacleDecision,
    Ssta,
    SstaConfig,
    StopReason,
    SwingModification,
    bounding_boxes,
)
from .stabilizer import Stabilizer, StabilizerGains, StabilizerOutput
from .step_adjuster import StepAdjuster, StepAdjusterConfig, StepAdjustment
from .support_polygon import SOLE_HALF_WIDTH, SOLE_X, sole_corners, support_margin, support_polygon
from .walking_controller import BACKENDS, FIRST_STEP_TABLES, PlanZmp, WalkingCommand, WalkingController, WalkingIkConfig
from .walking_ikd import WalkingIkd, WalkingIkdConfig, WalkingIkdStep
from .walking_pattern import PatternSample, WalkingPattern, ZmpCorrection
from .whole_body_ik import (
    REFERENCE_LAYOUT,
    REFERENCE_SIZE,
    TASK_ROWS,
    WholeBodyIk,
    WholeBodyIkResult,
    WholeBodyReference,
)
from .zmp_estimator import ZmpEstimate, estimate_zmp

__all__ = [
    "BACKENDS",
    "BLOCKED_COST",
    "CompiledMeasurement",
    "CompiledServoFeedforward",
    "CompiledWholeBodyIk",
    "FIRST_STEP_TABLES",
    "GRAVITY",
    "LEG_SEGMENTS",
    "OBSTACLE_CLASSES",
    "REFERENCE_LAYOUT",
    "REFERENCE_SIZE",
    "SOLE_HALF_WIDTH",
    "SOLE_X",
    "STOP_CAUSES",
    "TASK_ROWS",
    "ComState",
    "DcmPlan",
    "DcmPlanner",
    "FootForceControl",
    "FootForceGains",
    "GaitConfig",
    "MeasurementResult",
    "LinePlan",
    "ObstacleBox",
    "ObstacleDecision",
    "PatternSample",
    "PlanZmp",
    "PiecewiseQuintic",
    "Quintic",
    "Rca",
    "RcaConfig",
    "RcaState",
    "ServoFeedforward",
    "ServoFeedforwardTorques",
    "SoleTilt",
    "SoleTiltConfig",
    "Ssta",
    "SstaConfig",
    "Stabilizer",
    "StabilizerGains",
    "StabilizerOutput",
    "StepAdjuster",
    "StepAdjusterConfig",
    "StepAdjustment",
    "StopReason",
    "SwingModification",
    "WalkingCommand",
    "WalkingController",
    "WalkingIkConfig",
    "WalkingIkd",
    "WalkingIkdConfig",
    "WalkingIkdStep",
    "WalkingPattern",
    "WholeBodyIk",
    "WholeBodyIkResult",
    "WholeBodyReference",
    "ZmpCorrection",
    "ZmpEstimate",
    "bounding_boxes",
    "estimate_zmp",
    "return_quintic_no_overshoot_time",
    "sole_corners",
    "support_margin",
    "support_polygon",
]


def __getattr__(name: str) -> object:
    """``Measurement``, the old name of :class:`MeasurementResult` (a result, not the measurement), for one release
    with a :class:`DeprecationWarning`."""
    return renamed_attribute(__name__, name)
