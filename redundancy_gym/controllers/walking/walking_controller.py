"""The walking controller: pattern, stabilizer and whole-body IK in one control step (monograph fig. 4.5).

Layers, each testable alone: :class:`WalkingPattern` (footholds, swing quintics, LIPM/DCM CoM with the
multi-body ZMP correction), :class:`Stabilizer` (measured ZMP and DCM -> CoM reference offset) and
:class:`WholeBodyIk` (task references -> joint position targets, with the angular-momentum weight (5.62) and
joint-limit, posture and self-collision objectives in the nullspace; run as one kernel call by
:class:`CompiledWholeBodyIk`). The IK integrates its own kinematic model; its joint angles are the position
targets sent to the servos, as on Lola.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple, TypeGuard

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...constants import GRAVITY
from ...geometry import SSV, CollisionModel
from ...kernel_options import BACKENDS, DEFAULT_BACKEND
from ...model import ModelError, RobotModel, collision_model_from_mjcf
from ...validation import as_real_array, check_backend
from ..exceptions import ControllerError
from ..objectives.actuated_objective import ActuatedObjective
from ..objectives.collision_objective import CollisionObjective
from ..objectives.joint_limit_objective import JointLimitObjective
from ..objectives.objective import Objective
from ..objectives.posture_objective import PostureObjective
from .compiled_servo_feedforward import CompiledServoFeedforward
from .compiled_whole_body_ik import CompiledWholeBodyIk
from .foot_force_control import FootForceControl, FootForceGains
from .gait_config import GaitConfig
from .measure_kernels import CompiledMeasurement
from .rca import Rca, RcaConfig, RcaState
from .servo_feedforward import ServoFeedforward
from .sole_tilt import SoleTilt, SoleTiltConfig, tilt_rotation
from .ssta import ObstacleBox, Ssta, SstaConfig, StopReason, bounding_boxes
from .stabilizer import Stabilizer, StabilizerGains, StabilizerOutput
from .step_adjuster import StepAdjuster, StepAdjusterConfig, StepAdjustment
from .support_polygon import support_margin, support_polygon
from .terrain_map import TerrainMap
from .walking_ikd import WalkingIkd, WalkingIkdConfig, WalkingIkdStep
from .walking_pattern import PatternSample, WalkingPattern, ZmpCorrection
from .whole_body_ik import REFERENCE_SIZE, WholeBodyIk, WholeBodyIkResult, WholeBodyReference
from .zmp_estimator import ZmpEstimate, estimate_zmp

# BACKENDS: kernel_options' one tuple of twins, exported here as before (WalkingIkConfig.backend's choices)
__all__ = ["BACKENDS", "FIRST_STEP_TABLES", "WalkingCommand", "WalkingController", "WalkingIkConfig"]

SSTA_REMAP = 0.01
"""How far [m] the map from the world into the plan's frame must have moved the obstacles (at the sole's reach)
since SSTA last planned for SSTA to plan again (at a step start)."""

_Measured = tuple[NDArray[np.float64], NDArray[np.float64], ZmpEstimate]
"""The measurement of one period: CoM [m], its velocity [m/s] (in the plan's frame) and the ZMP estimate."""
_FLOAT64 = np.dtype(np.float64)
_ReferenceBase = tuple[NDArray[np.float64], float, float, float, float]
"""A packed IK reference without the stabilizer's offset, and its CoM (x, y) [m] and CoM velocity (x, y) [m/s]."""


def _is_float_array(value: object, shape: tuple[int, ...]) -> TypeGuard[NDArray[np.float64]]:
    """Whether ``value`` is a float64 array of ``shape`` (what the compiled measurement reads without conversion)."""
    return type(value) is np.ndarray and value.dtype == _FLOAT64 and value.shape == shape


MAX_TERRAIN_TURN = 0.2
"""Largest sine of the plan's turn from the world [-] under which the terrain's lanes are mapped across into it."""
COMMAND_REPLAN_INTERVAL = 0.04
"""Shortest time [s] between two CoM replans for new walking commands (:meth:`WalkingController.set_command`)."""


FIRST_STEP_TABLES = 2
"""The first steps of a walk that get multi-body ZMP correction tables of their own (``correction_first_steps``):
the first two start from standing, and the steady tables put their whole-body ZMP up to 21 mm outside the soles
at 0.7 m/s (with their own tables 58 and 28 mm inside, ``plan_zmp``)."""


@dataclass(frozen=True)
class WalkingIkConfig:
    """Whole-body IK settings of :class:`WalkingController`.

    Attributes:
        gain: task feedback ``K`` [1/s].
        gamma: ``gamma`` of (5.62).
        beta: scale of (5.62) against the nullspace objectives.
        momentum_minimization: ``W = gamma I + J_Lz^T J_Lz`` (True) or ``W = I``.
        posture_weight: pull of the actuated joints towards the starting posture.
        joint_limit_weight: weight of the joint-limit potential (5.58) on the soft limits.
        joint_limit_activation: its ``d_a`` [rad].
        joint_limit_slope: its slope at the soft limit.
        self_collision_weight: weight of the self-collision potential (5.49) on the robot's swept-sphere
            volumes (0: off).
        self_collision_activation: its ``d_a`` [m].
        self_collision_slope: its slope ``|H'(0)|`` [1/m] at contact.
        backend: which twins the controller runs (:data:`~redundancy_gym.kernel_options.BACKENDS`):
            ``"compiled"`` (the default: :class:`CompiledWholeBodyIk`, one kernel call a period, and the
            measurement's :class:`~.measure_kernels.CompiledMeasurement`, with ``servo_stiffness``
            :class:`CompiledServoFeedforward`, with an IKD :class:`~redundancy_gym.controllers.ikd.CompiledBipedIkd`;
            the first two need a model of 1-DoF joints on a free flyer, which
            :class:`WalkingController` checks) or ``"python"`` (:class:`WholeBodyIk`, the measurement and
            :class:`ServoFeedforward` and :class:`~redundancy_gym.controllers.ikd.BipedIkd` on pinocchio and NumPy, the
            references); both give the same result to
            round-off.
    """

    gain: float = 100.0
    gamma: float = 0.008
    beta: float = 10.0
    momentum_minimization: bool = True
    posture_weight: float = 1.0
    joint_limit_weight: float = 1.0
    joint_limit_activation: float = 0.15
    joint_limit_slope: float = 2.0
    self_collision_weight: float = 1.0
    self_collision_activation: float = 0.04
    self_collision_slope: float = 10.0
    backend: str = DEFAULT_BACKEND

    def __post_init__(self) -> None:
        check_backend("backend", self.backend, error=ControllerError)


class WalkingCommand(NamedTuple):
    """One control step of :class:`WalkingController`.

    Attributes:
        joint_targets: position targets of the actuated joints [rad].
        pattern: the pattern sample at the start of the period.
        stabilizer: the stabilizer output.
        contact: the ZMP estimate from the ankle sensors (in the stance foot's frame where ``stance_frame``).
        ik: the whole-body IK result, or with an IKD (:class:`~redundancy_gym.controllers.ikd.WalkingIkd`) its step
            (``ik.q`` is the kinematic model's configuration either way).
        adjustment: the step adjustment made in this period (push recovery), or None.
        avoidance: the swing foot's reactive collision-avoidance modification (RCA) at the period's end, or None
            without obstacles or with RCA off.
    """

    joint_targets: NDArray[np.float64]
    pattern: PatternSample
    stabilizer: StabilizerOutput
    contact: ZmpEstimate
    ik: WholeBodyIkResult | WalkingIkdStep
    adjustment: StepAdjustment | None = None
    avoidance: RcaState | None = None


class PlanZmp(NamedTuple):
    """The whole-body ZMP of the walking plan (:meth:`WalkingController.plan_zmp`), one row per control period.

    Attributes:
        times: the periods' mid-times from the start of the walk [s] (n,).
        zmp: the ZMP of the kinematic model's motion [m] (n, 2), from its CoM and centroidal momentum rate.
        reference: the pattern's reference ZMP at those times [m] (n, 2).
        margin: ``zmp``'s signed distance [m] inside the planned support polygon (n,): negative outside.
        step_starts: the start times of the rolled-out steps and the end of the last [s] (steps + 1,).
    """

    times: NDArray[np.float64]
    zmp: NDArray[np.float64]
    reference: NDArray[np.float64]
    margin: NDArray[np.float64]
    step_starts: NDArray[np.float64]


class WalkingController:
    """Walks from a standing start at a commanded velocity and yaw rate (:meth:`set_command`).

    Args:
        model: the floating-base model (from the robot's MJCF).
        dt: control period [s].
        soft_lower, soft_upper: joint limits [rad] the IK keeps inside (actuated joints, length ``nv - 6``).
        gait: walking pattern parameters.
        gains: stabilizer gains.
        ik: whole-body IK settings.
        stepping: push recovery by step adjustment (:class:`StepAdjuster`; ``enabled=False`` turns it off).
        feet_frames: sole frames (right, left); ``ankle_frames``: the force/torque sensor frames.
        torso_frame: frame of the upper body whose orientation is kept upright.
        correction_iterations: kinematic rollouts that estimate the multi-body ZMP correction (0: plain LIPM).
        correction_samples: knots per step of the correction (``double_support_ratio`` must fall on one).
        stance_frame: measure the CoM, its velocity and the ZMP relative to the stance foot's sole, moved onto its
            planned pose (False: in the world frame).
        ssta: obstacle planning (:class:`Ssta`) for :meth:`set_obstacles` (None: the defaults, with the gait's step
            height, longest step and foot lanes).
        rca: reactive swing-leg collision avoidance (:class:`Rca`) for :meth:`set_obstacles` (None: the defaults).
        use_ssta, use_rca: switch either obstacle layer off (ablations); without both, obstacles are ignored.
        correction_configuration: the standing joint positions [rad] the ZMP correction is estimated from, once
            per speed (None: from each start's own standing state, about 0.26 s per start).
        ikd: generate the joint trajectory by Inverse Kineto-Dynamics
            (:class:`~redundancy_gym.controllers.ikd.WalkingIkd`, monograph 5.5) instead of the whole-body CLIK
            (None): the pattern's ZMP is then realized exactly, so ``correction_iterations`` should be 0 (the plain
            LIPM plan). The CLIK still moves the standing start onto the pattern's first reference.
        foot_force: ground contact by force (:class:`FootForceControl`, foot force difference control): the soles'
            height references follow the measured normal forces against the plan's load share (None: off).
        sole_tilt: stance soles on rough ground take their measured tilt into the IK's references and, in single
            support, are pressed towards the stabilizer's desired ZMP (:class:`SoleTilt`; None: off, the soles'
            references the plan's).
        correction_first_steps: the first steps of a walk (0-2) whose multi-body ZMP correction is estimated from
            their own rollout rather than taken from the steady steps' tables (:attr:`ZmpCorrection.first`).
        servo_stiffness: with ``ikd``, the position servos' ``k_p`` [N m/rad] per actuated joint: each period's
            joint targets are then shifted by the IKD motion's torques over them (:class:`ServoFeedforward`), so
            the servos do not sag under the plan's loads (None: the IKD's positions as they are). The CLIK has no
            joint accelerations to feed forward: ControllerError.
    """

    def __init__(
        self,
        model: RobotModel,
        dt: float,
        soft_lower: ArrayLike,
        soft_upper: ArrayLike,
        *,
        gait: GaitConfig | None = None,
        gains: StabilizerGains | None = None,
        ik: WalkingIkConfig | None = None,
        stepping: StepAdjusterConfig | None = None,
        feet_frames: tuple[str, str] = ("r_sole", "l_sole"),
        ankle_frames: tuple[str, str] = ("r_ankle_ft", "l_ankle_ft"),
        torso_frame: str = "imu",
        correction_iterations: int = 3,
        correction_samples: int = 20,
        stance_frame: bool = True,
        ssta: SstaConfig | None = None,
        rca: RcaConfig | None = None,
        use_ssta: bool = True,
        use_rca: bool = True,
        correction_configuration: ArrayLike | None = None,
        ikd: WalkingIkdConfig | None = None,
        servo_stiffness: ArrayLike | None = None,
        foot_force: FootForceGains | None = None,
        correction_first_steps: int = FIRST_STEP_TABLES,
        sole_tilt: SoleTiltConfig | None = None,
    ) -> None:
        if not np.isfinite(dt) or dt <= 0.0:
            raise ControllerError(f"dt must be finite and > 0, got {dt!r}")
        if not model.floating_base:
            raise ControllerError("the walking controller needs a floating-base model")
        if not isinstance(correction_iterations, (int, np.integer)) or correction_iterations < 0:
            raise ControllerError(f"correction_iterations must be an int >= 0, got {correction_iterations!r}")
        self.model = model
        self.dt = float(dt)
        self.gait = gait or GaitConfig()
        self.gains = gains or StabilizerGains()
        self.ik_config = ik or WalkingIkConfig()
        ratio_knot = self.gait.double_support_ratio * correction_samples
        if (
            correction_iterations
            and abs(correction_samples - ratio_knot - round(correction_samples - ratio_knot)) > 1e-9
        ):
            raise ControllerError(
                f"correction_samples={correction_samples} puts no knot at the single-support end "
                f"(double_support_ratio={self.gait.double_support_ratio})"
            )
        self._nq, self._nv = model.base_dofs
        self.soft_lower = np.asarray(soft_lower, dtype=np.float64)
        self.soft_upper = np.asarray(soft_upper, dtype=np.float64)
        if self.soft_lower.shape != (model.nv - self._nv,) or self.soft_upper.shape != self.soft_lower.shape:
            raise ControllerError(f"soft limits must have length {model.nv - self._nv}")
        self._feet = tuple(model.frame_id(f) for f in feet_frames)
        self._ankles = tuple(model.frame_id(f) for f in ankle_frames)
        # the per-period measurement: one kernel call with the compiled backend, which must then cover the model
        # (the compiled IK needs the same chain: better said here than at start()); pinocchio with "python"
        self._measurement: CompiledMeasurement | None = None
        if self.ik_config.backend == "compiled":
            try:
                self._measurement = CompiledMeasurement(model, self._ankles + self._feet)
            except ModelError as error:
                raise ControllerError(
                    f"backend='compiled' needs a model of 1-DoF joints on a free flyer ({error}); "
                    "WalkingIkConfig(backend='python') runs the pinocchio references on any model"
                ) from error
        self._sensors = np.zeros((2, 6))  # step()'s forces and torques, packed as the kernel reads them
        self.feet_frames, self.torso_frame = feet_frames, torso_frame
        self.correction_iterations = int(correction_iterations)
        self.correction_samples = int(correction_samples)
        if not isinstance(correction_first_steps, (int, np.integer)) or not 0 <= correction_first_steps <= 2:
            raise ControllerError(f"correction_first_steps must be an int in [0, 2], got {correction_first_steps!r}")
        self.correction_first_steps = int(correction_first_steps)
        self._corrections: dict[tuple[float, bool, bytes], ZmpCorrection] = {}
        self.correction_configuration: NDArray[np.float64] | None = None
        if correction_configuration is not None:
            joints = np.asarray(correction_configuration, dtype=np.float64)
            if joints.shape != (model.nq - self._nq,) or not np.all(np.isfinite(joints)):
                raise ControllerError(
                    f"correction_configuration must be {model.nq - self._nq} finite joint positions "
                    f"[rad], got shape {joints.shape}"
                )
            self.correction_configuration = joints
        self.stabilizer = Stabilizer(self.gains, np.sqrt(GRAVITY / self.gait.com_height))
        self.step_adjuster = StepAdjuster(stepping)
        self.stance_frame = stance_frame
        self._mass = model.total_mass
        self.pattern: WalkingPattern | None = None
        self.ik: WholeBodyIk | None = None
        self.solver: WholeBodyIk | CompiledWholeBodyIk | None = None
        self._collision_model: CollisionModel | None = None
        self.q_ref: NDArray[np.float64] | None = None
        self.time = 0.0
        self._command_replan = -np.inf
        self._next: PatternSample | None = None
        self.ssta_config = ssta or SstaConfig(
            step_height=self.gait.step_height,
            max_step_length=self.gait.max_step_length,
            toe_length=self.gait.toe_length,
        )
        self.ssta: Ssta | None = None
        self.obstacle_boxes: tuple[ObstacleBox, ...] = ()
        self.use_ssta, self.use_rca = bool(use_ssta), bool(use_rca)
        self._rca_config = rca
        self.rca: Rca | None = None  # built with the first obstacles: a walk on flat ground never needs its models
        self._obstacle_volumes: list[SSV] = []
        self._world_to_plan: tuple[NDArray[np.float64], NDArray[np.float64]] = (np.eye(3), np.zeros(3))
        self._ssta_map: tuple[NDArray[np.float64], NDArray[np.float64]] = (np.eye(3), np.zeros(3))
        self._obstacle_step = -1
        self.ikd_config = ikd
        self.ikd: WalkingIkd | None = None
        self.feedforward: ServoFeedforward | None = None
        if servo_stiffness is not None:
            if ikd is None:
                raise ControllerError("servo_stiffness needs the IKD (ikd=...): the CLIK gives no joint accelerations")
            twin = CompiledServoFeedforward if self.ik_config.backend == "compiled" else ServoFeedforward
            self.feedforward = twin(model, servo_stiffness, feet_frames)
        self._ikd_com = (np.zeros(3), np.zeros(3))
        self.foot_force_gains = foot_force or FootForceGains()
        self.foot_force = FootForceControl(self.foot_force_gains) if self.foot_force_gains.active else None
        self.sole_tilt = None if sole_tilt is None else SoleTilt(sole_tilt)
        # the measured soles' orientations and positions (plan frame), read by sole_tilt
        self._soles, self._sole_positions = np.zeros((2, 3, 3)), np.zeros((2, 3))
        self._base: tuple[PatternSample, _ReferenceBase] | None = None  # the last packed reference (its sample)

    # ------------------------------------------------------------------ start
    def _make_ik(self, posture: NDArray[np.float64]) -> WholeBodyIk:
        c = self.ik_config
        objectives: list[Objective] = []
        if c.posture_weight > 0.0:
            objectives.append(ActuatedObjective(PostureObjective(posture, c.posture_weight), self.model))
        if c.joint_limit_weight > 0.0:
            objectives.append(
                ActuatedObjective(
                    JointLimitObjective(
                        self.soft_lower,
                        self.soft_upper,
                        activation_distance=c.joint_limit_activation,
                        slope=c.joint_limit_slope,
                        weight=c.joint_limit_weight,
                    ),
                    self.model,
                )
            )
        if c.self_collision_weight > 0.0:
            if self._collision_model is None:  # the MJCF's volumes, read once
                self._collision_model = collision_model_from_mjcf(self.model)
            objectives.append(
                CollisionObjective(
                    self._collision_model,
                    activation_distance=c.self_collision_activation,
                    slope=c.self_collision_slope,
                    weight=c.self_collision_weight,
                )
            )
        return WholeBodyIk(
            self.model,
            feet_frames=self.feet_frames,
            torso_frame=self.torso_frame,
            gain=c.gain,
            gamma=c.gamma,
            momentum_minimization=c.momentum_minimization,
            beta=c.beta,
            objectives=tuple(objectives),
        )

    def start(self, q: ArrayLike, speed: float) -> None:
        """Begin a walk from the standing configuration ``q`` (pinocchio convention) at ``speed`` [m/s].

        The kinematic model starts at ``q`` with the CoM lowered or raised to ``com_height`` above the soles;
        the multi-body ZMP correction for ``speed`` is estimated by kinematic rollouts (about 0.3 s) from
        ``correction_configuration`` once per speed, or without it from ``q`` (kept for a start from the same state).
        """
        q = self.model.check_configuration(q)
        self.ik, self.solver, q_ref, start = self._stand(q)
        self.q_ref = q_ref
        if self.ikd_config is not None:
            # the CLIK's joint-limit objective (without it the IKD stretched a knee at 0.7 m/s); neither its posture
            # (the IKD has its own posture stiffness) nor its self-collision objective (evaluated in Python it took
            # some 230 us a period, and the IKD walks on BipedWalk kept 19 mm between the links without it)
            objectives = tuple(
                o
                for o in self.ik.objectives
                if isinstance(o, ActuatedObjective) and isinstance(o.objective, JointLimitObjective)
            )
            self.ikd = WalkingIkd(
                self.model,
                self.dt,
                self.ikd_config,
                omega=self.stabilizer.omega,
                posture=q_ref,
                feet_frames=self.feet_frames,
                torso_frame=self.torso_frame,
                objectives=objectives,
                backend=self.ik_config.backend,
            )
            self.ikd.start(q_ref)
            self.model.update(q_ref)
            self._ikd_com = (self.model.com().copy(), np.zeros(3))
        feet, com = start
        # from correction_configuration once per speed, else from this start's state (kept for the same state only):
        # a correction kept from an earlier walk's slightly different standing state made a walk's result depend on
        # the walks before it
        correction = self._correction(speed, q_ref, self.solver, start)
        self.pattern = WalkingPattern(self.gait, feet[0], feet[1], com, speed, correction)
        self.ssta = Ssta(self.ssta_config, lanes=(float(feet[0, 1]), float(feet[1, 1])))
        self.obstacle_boxes = ()
        self._obstacle_volumes = []
        self._world_to_plan = (np.eye(3), np.zeros(3))
        self._ssta_map = (np.eye(3), np.zeros(3))
        self._obstacle_step = -1
        if self.rca is not None:
            self.rca.reset()
            self.rca.set_obstacles(())
        self.stabilizer.reset()
        self.step_adjuster.reset()
        if self.foot_force is not None:
            self.foot_force.reset()
        if self.sole_tilt is not None:
            self.sole_tilt.reset()
        self.time = 0.0
        self._command_replan = -np.inf
        self._next = None
        self._base = None
        self.terrain: TerrainMap | None = None
        self._terrain_planned = -2  # the step of the last terrain planning
        self._scan_pose: tuple[float, float, float] | None = None  # x, y, yaw of the last scan written
        self._scan_reach = 0.0  # the farthest scan point from the pelvis [m]

    def observe_terrain(self, base: tuple[float, float, float, float], scan: ArrayLike, offsets: ArrayLike) -> None:
        """Add a height scan to the terrain map (:class:`TerrainMap`, made at the first scan of a walk, its lanes
        the starting feet's): the pelvis's world x, y, z [m] and yaw [rad] when it was taken, terrain minus pelvis
        heights [m] (N,) and the scan points' offsets (forward, left) [m] in the pelvis's heading frame (N, 2).
        The footholds not yet begun are placed on the map once a step (:meth:`WalkingPattern.set_terrain`)."""
        if self.pattern is None:
            raise ControllerError("call WalkingController.start(q, speed) before observe_terrain()")
        if self.terrain is None:
            feet = self.pattern.foothold(0), self.pattern.foothold(1)
            self.terrain = TerrainMap((float(feet[0][1]), float(feet[1][1])), backend=self.ik_config.backend)
            points = np.asarray(offsets, dtype=np.float64)
            self._scan_reach = float(np.max(np.hypot(points[:, 0], points[:, 1]))) if points.size else 0.0
        x, y, _, yaw = (float(v) for v in base)
        last = self._scan_pose
        # the terrain is static: a scan adds to the map only once its points have moved by half a map cell (the
        # pelvis moves 1-3 mm per period, so most periods' scans would write the same cells again)
        tolerance = 0.5 * self.terrain.config.cell
        if (
            last is not None
            and abs(x - last[0]) < tolerance
            and abs(y - last[1]) < tolerance
            and abs(yaw - last[2]) * self._scan_reach < tolerance
        ):
            return
        self._scan_pose = (x, y, yaw)
        self.terrain.observe(base, np.asarray(scan, dtype=np.float64), np.asarray(offsets, dtype=np.float64))

    @property
    def world_to_plan(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The rigid map ``(R, t)`` from the world to the plan's frame (``plan = R world + t``): the measured stance
        sole put on its planned pose (:meth:`_in_stance_frame`); identity before the first measurement."""
        rotation, translation = self._world_to_plan
        return rotation.copy(), translation.copy()

    def _support_height(self, sample: PatternSample) -> float:
        """The ground height [m] the ZMP is measured on: the planned height of the feet on the ground (their mean in
        double support); the pattern's ground without a terrain map."""
        assert self.pattern is not None
        if self.terrain is None:
            return self.pattern.ground
        heights = [float(sample.feet[i, 2]) for i in (0, 1) if sample.contact[i]]
        return sum(heights) / len(heights) if heights else self.pattern.ground

    def set_command(self, forward: float, lateral: float = 0.0, yaw_rate: float = 0.0) -> None:
        """Walk at ``forward`` and ``lateral`` [m/s] (in the frame of the walker's heading), turning at ``yaw_rate``
        [rad/s] (positive: to the left), from the next step that has not begun (:meth:`WalkingPattern.set_velocity`);
        the ZMP correction stays the one estimated at :meth:`start` (turned with the stance foot).

        The CoM plan follows a new command at once, but at most every :data:`COMMAND_REPLAN_INTERVAL` (a command
        changed every period would replan every period, 1 ms each); in between, the footholds change and the plan
        catches up at the next replan or step start.
        """
        if self.pattern is None:
            raise ControllerError("call WalkingController.start(q, speed) before set_command()")
        replan = self.time - self._command_replan >= COMMAND_REPLAN_INTERVAL - 1e-9
        self.pattern.set_velocity(self.time, forward, lateral, replan=replan, yaw_rate=yaw_rate)
        if replan:
            self._command_replan = self.time
            self._next = None  # the plan may have changed from now on

    def set_obstacles(self, volumes: tuple[SSV, ...] | list[SSV]) -> bool:
        """Plan around obstacles given as swept-sphere volumes (world frame): their bounding boxes go to SSTA
        (:meth:`WalkingPattern.set_obstacles`, monograph 5.4.2), which moves the footholds not yet begun and
        raises or shifts the swings that pass them; the volumes go to RCA (:class:`Rca`), which keeps the swing
        leg off them. Call it again when more obstacles come into view; obstacles already known are kept.
        Returns whether anything new was given.
        """
        if self.pattern is None or self.ssta is None:
            raise ControllerError("call WalkingController.start(q, speed) before set_obstacles()")
        volumes = list(volumes)
        for v in volumes:
            if not isinstance(v, SSV):
                raise ControllerError(f"obstacles must be swept-sphere volumes (PSS, LSS, TSS), got {type(v).__name__}")
        new_volumes = [v for v in volumes if v not in self._obstacle_volumes]
        if not new_volumes:
            return False
        self._obstacle_volumes += new_volumes
        if self.use_rca and self.rca is None:
            self.rca = Rca(self.model, self.soft_lower, self.soft_upper, self._rca_config, feet_frames=self.feet_frames)
        if self.rca is not None:
            self.rca.set_obstacles(self._obstacle_volumes)
        self._map_obstacles(force=True)
        return True

    @property
    def stop_reason(self) -> StopReason | None:
        """Why the walk stops in front of an obstacle now (:attr:`WalkingPattern.stop_reason`; the box in the plan's
        frame); None: it does not stop, or :meth:`start` was not called."""
        return None if self.pattern is None else self.pattern.stop_reason

    def _map_obstacles(self, force: bool = False) -> None:
        """Give SSTA and RCA the obstacles in the plan's frame: the world volumes moved by the rigid map that puts
        the measured stance sole on its planned pose (:meth:`_in_stance_frame`). The real robot drifts from the
        plan's world frame (its feet land relative to the real stance foot, which slips and turns a little); the
        obstacles are where they are relative to the real feet."""
        assert self.pattern is not None and self.ssta is not None
        rotation, translation = self._world_to_plan
        if self.rca is not None:
            self.rca.set_frame(rotation, translation)
        # SSTA plans again when the map moved the obstacles by more than a centimetre (or new ones came)
        last_rotation, last_translation = self._ssta_map
        moved = float(np.max(np.abs(translation - last_translation))) + 0.5 * float(
            np.max(np.abs(rotation - last_rotation))
        )
        if not force and moved < SSTA_REMAP:
            return
        self._ssta_map = (rotation.copy(), translation.copy())
        if self.use_ssta and not self.pattern.turned:  # SSTA plans straight walks; RCA still acts on a turned one
            mapped = [v.transformed(rotation, translation) for v in self._obstacle_volumes]
            self.obstacle_boxes = bounding_boxes(mapped)
            if self.pattern.set_obstacles(self.time, self.obstacle_boxes, self.ssta):
                self._next = None

    @staticmethod
    def _standing_reference(
        com: NDArray[np.float64], feet: NDArray[np.float64], rotations: NDArray[np.float64]
    ) -> WholeBodyReference:
        yaw = np.eye(3)
        return WholeBodyReference(com, np.zeros(3), feet, rotations, np.zeros((2, 6)), yaw, np.zeros(3))

    def _correction(
        self,
        speed: float,
        q_ref: NDArray[np.float64],
        solver: WholeBodyIk | CompiledWholeBodyIk,
        start: tuple[NDArray[np.float64], NDArray[np.float64]],
    ) -> ZmpCorrection | None:
        """The ZMP correction for a walk at ``speed`` [m/s] from ``q_ref`` with ``solver`` (``None`` without
        correction iterations),
        kept per speed (and per start where there is no :attr:`correction_configuration`)."""
        if not self.correction_iterations:
            return None
        # from correction_configuration once per speed, else from this start's state (kept for the same state only):
        # a correction kept from an earlier walk's slightly different standing state made a walk's result depend on
        # the walks before it
        canonical = self.correction_configuration is not None
        key = (round(float(speed), 9), self.ik_config.momentum_minimization, b"" if canonical else q_ref.tobytes())
        correction = self._corrections.get(key)
        if correction is None:
            correction = (
                self._canonical_correction(speed)
                if canonical
                else self._estimate_correction(q_ref, speed, solver, start)
            )
            if len(self._corrections) >= 16:
                self._corrections.pop(next(iter(self._corrections)))
            self._corrections[key] = correction
        return correction

    def _canonical_configuration(self) -> NDArray[np.float64]:
        """:attr:`correction_configuration`'s joints with the base level at the origin."""
        assert self.correction_configuration is not None
        q = np.zeros(self.model.nq)
        q[self._nq - 1] = 1.0  # the identity quaternion (x, y, z, w)
        q[self._nq :] = self.correction_configuration
        return q

    def _canonical_correction(self, speed: float) -> ZmpCorrection:
        """The ZMP correction for ``speed`` from :attr:`correction_configuration`: standing with the base level at the
        origin, its own IK (the same for every start, so no walk depends on the walks before it)."""
        _, solver, q_ref, start = self._stand(self._canonical_configuration())
        return self._estimate_correction(q_ref, speed, solver, start)

    def _stand(
        self, q: NDArray[np.float64]
    ) -> tuple[
        WholeBodyIk,
        WholeBodyIk | CompiledWholeBodyIk,
        NDArray[np.float64],
        tuple[NDArray[np.float64], NDArray[np.float64]],
    ]:
        """An IK with ``q``'s joints as its posture, and ``q`` moved by it onto the standing reference (the CoM
        ``com_height`` above the soles): ``(ik, solver, q_ref, (feet [m], CoM (x, y) [m]))``."""
        ik = self._make_ik(q[self._nq :].copy())
        solver: WholeBodyIk | CompiledWholeBodyIk = (
            CompiledWholeBodyIk(ik) if self.ik_config.backend == "compiled" else ik
        )
        self.model.update(q)
        feet = np.array([self.model.frame_position(f) for f in self._feet])
        rotations = np.array([self.model.frame_rotation(f) for f in self._feet])
        com, _ = self.model.com_and_centroidal_matrix()
        stand = self._standing_reference(
            np.array([com[0], com[1], float(feet[:, 2].mean()) + self.gait.com_height]), feet, rotations
        )
        q_ref = q.copy()
        for _ in range(20):
            q_ref = solver.step(q_ref, stand, stand, self.dt).q
        return ik, solver, q_ref, (feet, com[:2].copy())

    def _estimate_correction(
        self,
        q_start: NDArray[np.float64],
        speed: float,
        solver: WholeBodyIk | CompiledWholeBodyIk,
        start: tuple[NDArray[np.float64], NDArray[np.float64]],
    ) -> ZmpCorrection:
        """Kinematic rollouts with ``solver`` from ``q_start`` (feet and CoM ``start``): the ZMP shift
        ``(-Ldot_y, Ldot_x) / (m g)`` of the reference motion, per phase.

        Iterates ``correction_iterations`` times (each plans with the previous estimate); steps 2 and 3 (the
        first full steps of each foot) give the right- and left-swing tables.
        """
        feet, com = start
        n = self.correction_samples
        phases = np.arange(n) / n
        correction: ZmpCorrection | None = None
        for _ in range(self.correction_iterations):
            pattern = WalkingPattern(self.gait, feet[0], feet[1], com, speed, correction)
            end = pattern.step_start(4)
            q, t = q_start.copy(), 0.0
            start_ref = self._reference_array(pattern.sample(0.0), np.zeros(2), np.zeros(2))
            times, momentum = [], []
            while t < end:
                end_ref = self._reference_array(pattern.sample(t + self.dt), np.zeros(2), np.zeros(2))
                result = solver.step(q, start_ref, end_ref, self.dt)
                q, start_ref, t = result.q, end_ref, t + self.dt
                self.model.update(q)
                _, centroidal = self.model.com_and_centroidal_matrix()
                momentum.append(centroidal[3:5] @ result.qdot)
                times.append(t - 0.5 * self.dt)
            times_a, momentum_a = np.array(times), np.array(momentum)
            rate = np.gradient(momentum_a, times_a, axis=0)
            shift = np.stack([-rate[:, 1], rate[:, 0]], axis=1) / (self._mass * GRAVITY)
            tables = [self._step_table(pattern, k, phases, times_a, shift) for k in range(4)]
            offsets = np.array(tables[2:4])
            first = np.array(tables[: self.correction_first_steps])
            correction = ZmpCorrection(phases, offsets, first if self.correction_first_steps else None)
        assert correction is not None
        return correction

    @staticmethod
    def _step_table(
        pattern: WalkingPattern,
        k: int,
        phases: NDArray[np.float64],
        times: NDArray[np.float64],
        shift: NDArray[np.float64],
    ) -> NDArray[np.float64]:
        """Step ``k``'s ZMP shifts [m] (n, 2) at ``phases``: the mean of ``shift`` (per period, at ``times`` [s]) over
        the window of width ``1 / n`` of the step about each phase."""
        t0, duration, n = pattern.step_start(k), pattern.step_duration, phases.size
        rows = np.empty((n, 2))
        for j, phase in enumerate(phases):
            window = (times >= t0 + (phase - 0.5 / n) * duration) & (times < t0 + (phase + 0.5 / n) * duration)
            rows[j] = shift[window].mean(axis=0)
        return rows

    def plan_zmp(self, speed: float, steps: int = 4) -> PlanZmp:
        """The whole-body ZMP of the plan: a kinematic rollout of the IK (no balance feedback) on the pattern at
        ``speed`` [m/s] from the standing start of :attr:`correction_configuration`, with the multi-body correction
        the walks at that speed use (none with ``correction_iterations=0``), over its first ``steps`` steps after the
        weight shift.

        The ZMP on the soles' ground plane follows from the model's CoM ``c`` and centroidal momentum ``(p, L)``
        (rates by central differences): ``r = c_xy - (c_z - z_0) pdot_xy / F_z + (-Ldot_y, Ldot_x) / F_z``,
        ``F_z = pdot_z + m g``. This is the ZMP the planned motion demands of the ground, where the LIPM plan's own
        ZMP (``PatternSample.zmp``) leaves out the legs' angular momentum that the correction moves it by.

        Raises:
            ControllerError: a controller without :attr:`correction_configuration`, or ``steps`` < 1.
        """
        if self.correction_configuration is None:
            raise ControllerError("plan_zmp needs the controller's correction_configuration (the standing start)")
        if int(steps) != steps or steps < 1:
            raise ControllerError(f"steps must be an integer >= 1, got {steps!r}")
        _, solver, q, (feet, com) = self._stand(self._canonical_configuration())
        correction = self._correction(speed, q, solver, (feet, com))
        pattern = WalkingPattern(self.gait, feet[0], feet[1], com, speed, correction)
        ground = float(feet[:, 2].mean())
        begin, end = pattern.step_start(0), pattern.step_start(int(steps))
        t = 0.0
        start_ref = self._reference_array(pattern.sample(0.0), np.zeros(2), np.zeros(2))
        times, centres, momenta, references, polygons = [], [], [], [], []
        while t < end:
            sample = pattern.sample(t + self.dt)
            end_ref = self._reference_array(sample, np.zeros(2), np.zeros(2))
            result = solver.step(q, start_ref, end_ref, self.dt)
            q, start_ref, t = result.q, end_ref, t + self.dt
            self.model.update(q)
            centre, centroidal = self.model.com_and_centroidal_matrix()
            times.append(t)
            centres.append(centre)
            momenta.append(centroidal @ result.qdot)
            # read as the walk goes: the pattern replans its LIPM window at each step, and a later read of an
            # earlier time would see the new window
            references.append(pattern.reference_zmp(t))
            polygons.append(support_polygon(sample.feet, sample.contact, sample.feet_yaw))
        times_a, centres_a = np.array(times), np.array(centres)
        rate = np.gradient(np.array(momenta), times_a, axis=0)
        vertical = rate[:, 2] + self._mass * GRAVITY
        zmp = np.stack(
            [
                centres_a[:, 0] - (centres_a[:, 2] - ground) * rate[:, 0] / vertical - rate[:, 4] / vertical,
                centres_a[:, 1] - (centres_a[:, 2] - ground) * rate[:, 1] / vertical + rate[:, 3] / vertical,
            ],
            axis=1,
        )
        keep = (times_a >= begin) & (times_a < end)
        margin = np.array([support_margin(z, polygon) for z, polygon in zip(zmp, polygons, strict=True)])[keep]
        reference = np.array(references)[keep]
        starts = np.array([pattern.step_start(k) for k in range(int(steps) + 1)])
        return PlanZmp(times_a[keep], zmp[keep], reference, margin, starts)

    # ------------------------------------------------------------------ step
    @staticmethod
    def _reference_array(
        sample: PatternSample, offset: NDArray[np.float64], rate: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The IK reference of a pattern sample, packed (:meth:`WholeBodyReference.to_array`): the CoM moved by the
        stabilizer's ``offset`` [m] at ``rate`` [m/s], soles ``R_z(yaw) R_y(pitch)`` (angular velocity
        ``R_z(yaw) (0, pitch rate, 0) + (0, 0, yaw rate)``), torso upright along the mean heading of the feet."""
        return WalkingController._with_offset(WalkingController._reference_base(sample), offset, rate)

    @staticmethod
    def _with_offset(base: _ReferenceBase, offset: ArrayLike, rate: ArrayLike) -> NDArray[np.float64]:
        """A copy of the packed reference ``base`` with the CoM moved by ``offset`` [m] at ``rate`` [m/s] (x, y)."""
        (offset_x, offset_y), (rate_x, rate_y) = np.asarray(offset).tolist(), np.asarray(rate).tolist()
        return WalkingController._offset_reference(base, float(offset_x), float(offset_y), float(rate_x), float(rate_y))

    @staticmethod
    def _offset_reference(
        base: _ReferenceBase, offset_x: float, offset_y: float, rate_x: float, rate_y: float
    ) -> NDArray[np.float64]:
        """:meth:`_with_offset` on floats: the CoM offset [m] and its rate [m/s]."""
        packed, com_x, com_y, velocity_x, velocity_y = base
        a = packed.copy()
        a[0], a[1] = com_x + offset_x, com_y + offset_y
        a[3], a[4] = velocity_x + rate_x, velocity_y + rate_y
        return a

    @staticmethod
    def _reference_base(sample: PatternSample) -> _ReferenceBase:
        """:meth:`_reference_array` without the stabilizer's offset: the packed reference with the horizontal CoM and
        its velocity left at zero, and those four [m, m/s] (the end of one period is the start of the next: its
        reference is packed once, then offset twice)."""
        a = np.zeros(REFERENCE_SIZE)
        com, velocity = sample.com.tolist(), sample.com_velocity.tolist()
        a[2], a[5] = com[2], velocity[2]
        a[6:12] = sample.feet.ravel()
        pitches, pitch_rates = sample.feet_pitch.tolist(), sample.feet_pitch_rate.tolist()
        yaws, yaw_rates = sample.feet_yaw.tolist(), sample.feet_yaw_rate.tolist()
        a[30:33], a[36:39] = sample.feet_velocity
        for i in range(2):
            pitch = pitches[i]
            c, s = math.cos(pitch), math.sin(pitch)
            yaw, yaw_rate = yaws[i], yaw_rates[i]
            if yaw == 0.0 and yaw_rate == 0.0:
                a[12 + 9 * i : 21 + 9 * i] = c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c
                a[34 + 6 * i] = pitch_rates[i]
                continue
            cz, sz = math.cos(yaw), math.sin(yaw)
            a[12 + 9 * i : 21 + 9 * i] = cz * c, -sz, cz * s, sz * c, cz, sz * s, -s, 0.0, c
            pitch_rate = pitch_rates[i]
            a[33 + 6 * i : 36 + 6 * i] = -sz * pitch_rate, cz * pitch_rate, yaw_rate
        torso, torso_rate = 0.5 * (yaws[0] + yaws[1]), 0.5 * (yaw_rates[0] + yaw_rates[1])
        if torso == 0.0 and torso_rate == 0.0:
            a[42:51] = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
        else:
            cz, sz = math.cos(torso), math.sin(torso)
            a[42:51] = cz, -sz, 0.0, sz, cz, 0.0, 0.0, 0.0, 1.0
            a[53] = torso_rate
        return a, com[0], com[1], velocity[0], velocity[1]

    def _packed_base(self, sample: PatternSample) -> _ReferenceBase:
        """:meth:`_reference_base` of ``sample``, kept from the last period where it is that sample."""
        cached = self._base
        if cached is not None and cached[0] is sample:
            return cached[1]
        base = self._reference_base(sample)
        self._base = (sample, base)
        return base

    def _in_stance_frame(
        self,
        sample: PatternSample,
        com: NDArray[np.float64],
        com_velocity: NDArray[np.float64],
        rotations: NDArray[np.float64],
        positions: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], ...]:
        """The measurement moved rigidly (yaw about z and a horizontal shift) so that the measured stance sole lies on
        its planned pose (its planned position and heading) (rows 2, 3 of ``rotations``/``positions``: the soles
        right, left).

        The IK's kinematic model stands on the planned footholds; the real robot stands where its feet landed and
        turns with its stance foot when that slips about the vertical (a long, quick swing). Its joints track the
        model's, so the real swing foot lands where the plan puts it relative to the real stance foot: measuring
        the CoM, its velocity and the ZMP relative to the stance foot keeps the plan, the stabilizer and the step
        adjuster in one frame (in the world frame a 10 deg yaw slip made footholds 0.17 m off the plan, which the
        feedback then pulled the CoM towards).
        """
        k = sample.step
        stance = (k + 1) % 2 if k >= 0 else 1  # the standing start: the left foot, the first stance foot
        rotation = rotations[2 + stance]
        yaw = math.atan2(rotation[1, 0], rotation[0, 0])
        planned_yaw = float(sample.feet_yaw[stance])
        if planned_yaw != 0.0:  # turned: onto the planned heading (R_z(planned - measured))
            yaw -= planned_yaw
        c, s = math.cos(yaw), math.sin(yaw)
        turn = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # R_z(-yaw)
        planned = sample.feet[stance]
        real = positions[2 + stance]
        shift = np.array([planned[0], planned[1], 0.0]) - turn @ np.array([real[0], real[1], 0.0])
        self._world_to_plan = (turn, shift)
        return (turn @ com + shift, turn @ com_velocity, turn @ rotations, positions @ turn.T + shift)

    def _reference(
        self, sample: PatternSample, offset: NDArray[np.float64], rate: NDArray[np.float64]
    ) -> WholeBodyReference:
        return WholeBodyReference.from_array(self._reference_array(sample, offset, rate))

    def step(self, q: ArrayLike, v: ArrayLike, forces: ArrayLike, torques: ArrayLike) -> WalkingCommand:
        """One control period from the measured state and the ankle wrenches (sensor frames, rows right/left).

        Args:
            q, v: measured configuration and velocity (pinocchio convention; the base from the IMU/estimator).
            forces, torques: ankle force/torque sensor readings [N, N m] (2, 3).

        The measurement runs on the backend's twin (:attr:`WalkingIkConfig.backend`): the compiled kernel reads
        float64 arrays of these shapes as they are and any other array-like after the checks (never the pinocchio
        path in its place); both backends raise the same errors.

        Raises:
            ModelError: ``q`` or ``v`` of the wrong shape or with a non-finite value.
            ControllerError: ``forces`` or ``torques`` of the wrong shape or non-finite (naming which), or no
                :meth:`start` yet.
        """
        start = self._start_sample()
        if self._measurement is None:  # backend "python": the reference, every input checked
            return self._step(start, *self._measure_python(q, v, forces, torques, start))
        measured = None
        if (
            _is_float_array(q, (self.model.nq,))
            and _is_float_array(v, (self.model.nv,))
            and _is_float_array(forces, (2, 3))
            and _is_float_array(torques, (2, 3))
        ):
            sensors = self._sensors
            sensors[:, :3] = forces
            sensors[:, 3:] = torques
            measured = self._measure_compiled(q, v, sensors.reshape(-1), False, start)
        if measured is None:  # other input types, or a value the kernel rejects: checked, the bad one named
            measured = self._measure_checked(*self._checked_state(q, v, forces, torques), start)
        return self._step(start, *measured)

    def step_mujoco(self, qpos: ArrayLike, qvel: ArrayLike, wrenches: ArrayLike) -> WalkingCommand:
        """:meth:`step` from MuJoCo's state: the same as ``step(*model.from_mujoco_state(qpos, qvel),
        wrenches[:, :3], wrenches[:, 3:])`` to round-off, with the conversion in the measurement's kernel.

        Args:
            qpos, qvel: MuJoCo's ``qpos`` and ``qvel`` of the robot (free joint first).
            wrenches: the ankle sensor readings (2, 6) or (12,): per foot (right, left) force [N] then torque [N m].
        """
        start = self._start_sample()
        measured = None
        if (
            self._measurement is not None
            and _is_float_array(qpos, (self.model.nq,))
            and _is_float_array(qvel, (self.model.nv,))
            and _is_float_array(wrenches, (12,))
        ):
            measured = self._measure_compiled(qpos, qvel, wrenches, True, start)
        if measured is None:
            q, v = self.model.from_mujoco_state(qpos, qvel)
            wrench = np.asarray(wrenches, dtype=np.float64).reshape(2, 6)
            if self._measurement is None:  # backend "python"
                measured = self._measure_python(q, v, wrench[:, :3], wrench[:, 3:], start)
            else:  # other input types, or a value the kernel rejects: checked, the bad one named
                measured = self._measure_checked(*self._checked_state(q, v, wrench[:, :3], wrench[:, 3:]), start)
        return self._step(start, *measured)

    def _start_sample(self) -> PatternSample:
        """The pattern at the period's start (kept from the previous period's end where it is that instant)."""
        if self.pattern is None or self.solver is None or self.q_ref is None:
            raise ControllerError("call WalkingController.start(q, speed) before step()")
        nxt = self._next
        return nxt if nxt is not None and nxt.time == self.time else self.pattern.sample(self.time)

    def _measure_compiled(
        self,
        q: NDArray[np.float64],
        v: NDArray[np.float64],
        sensors: NDArray[np.float64],
        mujoco: bool,
        start: PatternSample,
    ) -> _Measured | None:
        """The measurement (CoM, its velocity, the ZMP) in one kernel call (:class:`CompiledMeasurement`): the
        same as :meth:`_measure_python` to round-off; None for a non-finite input or a zero base quaternion
        (:meth:`_checked_state` names it)."""
        assert self.pattern is not None and self._measurement is not None
        k = start.step
        stance = (k + 1) % 2 if k >= 0 else 1  # the standing start: the left foot, the first stance foot
        planned = start.feet[stance]
        m = self._measurement.measure(
            q,
            v,
            sensors,
            mujoco=mujoco,
            stance_frame=self.stance_frame,
            stance=stance,
            planned=(planned.item(0), planned.item(1), start.feet_yaw.item(stance)),
            ground=self._support_height(start),
        )
        if m is None:
            return None
        if self.stance_frame:
            self._world_to_plan = (m.turn.copy(), m.shift.copy())
        if self.sole_tilt is not None:
            self._soles[:], self._sole_positions[:] = m.rotations[2:4], m.positions[2:4]
        # copies: the estimate outlives the period (WalkingCommand.contact), the kernel's buffers do not
        contact = ZmpEstimate(
            None if m.zmp is None else m.zmp.copy(), m.cop.copy(), m.normal_force.copy(), m.moment.copy()
        )
        return m.com.copy(), m.com_velocity.copy(), contact

    def _checked_state(
        self, q: ArrayLike, v: ArrayLike, forces: ArrayLike, torques: ArrayLike
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """The pinocchio ``q``, ``v`` and the 12 ankle sensor floats as the measurement's kernel reads them, checked
        with the errors of :meth:`_measure_python`: :class:`ModelError` for a configuration or velocity of the
        wrong shape or with a non-finite value, :class:`ControllerError` naming the ankle sensor input."""
        model = self.model
        q = model.check_configuration(q)
        velocity = as_real_array("velocity", v, error=ModelError)
        if velocity.shape != (model.nv,):
            raise ModelError(f"velocity must have shape ({model.nv},), got {velocity.shape}")
        if not np.all(np.isfinite(velocity)):
            raise ModelError("velocity contains non-finite values")
        sensors = np.empty((2, 6))
        for columns, name, value in ((slice(0, 3), "forces", forces), (slice(3, 6), "torques", torques)):
            reading = as_real_array(name, value, error=ControllerError)
            if reading.shape != (2, 3):
                raise ControllerError(f"the ankle sensor {name} must have shape (2, 3), got {reading.shape}")
            if not np.all(np.isfinite(reading)):
                raise ControllerError(f"the ankle sensor {name} must be finite, got {reading.tolist()}")
            sensors[:, columns] = reading
        return q, velocity, sensors.reshape(-1)

    def _measure_checked(
        self, q: NDArray[np.float64], v: NDArray[np.float64], sensors: NDArray[np.float64], start: PatternSample
    ) -> _Measured:
        """:meth:`_measure_compiled` on a :meth:`_checked_state` (pinocchio's convention), which the kernel reads."""
        measured = self._measure_compiled(q, v, sensors, False, start)
        if measured is None:  # finite, and no quaternion to convert: the kernel has nothing to reject
            raise ControllerError("the compiled measurement rejected a checked state; report it (backend='python')")
        return measured

    def _measure_python(
        self, q: ArrayLike, v: ArrayLike, forces: ArrayLike, torques: ArrayLike, start: PatternSample
    ) -> _Measured:
        """The measurement through pinocchio and NumPy, with every input checked (the errors name the bad one)."""
        assert self.pattern is not None
        model = self.model
        q = model.check_configuration(q)
        v = np.asarray(v, dtype=np.float64)
        com, com_velocity, rotations, positions = model.measure(q, v, self._ankles + self._feet)
        if self.stance_frame:
            com, com_velocity, rotations, positions = self._in_stance_frame(
                start, com, com_velocity, rotations, positions
            )
        if self.sole_tilt is not None:
            self._soles[:], self._sole_positions[:] = rotations[2:4], positions[2:4]
        contact = estimate_zmp(rotations[:2], positions[:2], forces, torques, ground=self._support_height(start))
        return com, com_velocity, contact

    def _step(
        self, start: PatternSample, com: NDArray[np.float64], com_velocity: NDArray[np.float64], contact: ZmpEstimate
    ) -> WalkingCommand:
        """The period after the measurement: obstacles, step adjustment, stabilizer, IK."""
        assert self.pattern is not None and self.solver is not None and self.q_ref is not None
        if self._obstacle_volumes and start.step != self._obstacle_step:
            # once a step, the obstacles are mapped into the plan's frame again as the robot drifts from it
            self._obstacle_step = start.step
            # a walk stepping in place in front of a passable box plans on from where its feet stand
            self._map_obstacles(force=self.pattern.resumable(self.time))
            if self._next is None:
                start = self.pattern.sample(self.time)
        if self.terrain is not None and start.step != self._terrain_planned and not self.pattern.turned:
            # once a step, the footholds not yet begun are placed on the terrain as the map knows it then, in the
            # plan's frame: the world's shifted by the real stance foot's drift (terrain planning is for straight
            # walks, as SSTA's: a walk turned by a yaw-rate command plans over flat ground)
            self._terrain_planned = start.step
            rotation, translation = self._world_to_plan
            # across, the lanes are mapped into the plan's frame while its heading is near the world's (a plan
            # turned further is a walk already lost: its footholds stay where the pattern puts them)
            straight = abs(float(rotation[1, 0])) <= MAX_TERRAIN_TURN
            self.pattern.set_terrain(
                self.time,
                self.terrain,
                float(translation[0]),
                (float(rotation[1, 0]), float(rotation[1, 1]), float(translation[1])) if straight else (0.0, 1.0, 0.0),
            )
            self._next = None
            start = self.pattern.sample(self.time)
        # the measured DCM, c + c_dot / omega (x, y), in floats
        (com_x, com_y, _), (velocity_x, velocity_y, _) = com.tolist(), com_velocity.tolist()
        omega = self.stabilizer.omega
        # on terrain the landings are chosen surfaces and the swings pass edges: push recovery, which moves a
        # landing and re-times its swing over flat ground, acts only on a step over level ground
        adjustment = (
            None
            if self.terrain is not None and not self.pattern.level_step(self.time)
            else self.step_adjuster.update(
                self.pattern,
                self.time,
                np.array((com_x + velocity_x / omega, com_y + velocity_y / omega)),
                planned=start.dcm,
            )
        )
        if adjustment is not None:
            start = self.pattern.sample(self.time)  # the plan changed from now on
        end = self.pattern.sample(self.time + self.dt)
        self._next = end
        if self.ikd is not None:  # the feedback acts about the CoM the IKD's joint trajectory has
            ikd_com, ikd_velocity = self._ikd_com
            (ikd_x, ikd_y, _), (ikd_vx, ikd_vy, _) = ikd_com.tolist(), ikd_velocity.tolist()
            ikd_dcm = np.array((ikd_x + ikd_vx / omega, ikd_y + ikd_vy / omega))  # its DCM, in floats
            feedback = self.stabilizer.update(self.dt, ikd_com, ikd_dcm, start.zmp, com, com_velocity, contact.zmp)
        else:
            feedback = self.stabilizer.update(self.dt, start.com, start.dcm, start.zmp, com, com_velocity, contact.zmp)
        # the offset at the period's end, offset + rate dt, in floats (the same operations on x and y)
        (offset_x, offset_y), (rate_x, rate_y) = feedback.offset.tolist(), feedback.rate.tolist()
        start_ref = self._offset_reference(self._packed_base(start), offset_x, offset_y, rate_x, rate_y)
        end_ref = self._offset_reference(
            self._packed_base(end), offset_x + rate_x * self.dt, offset_y + rate_y * self.dt, rate_x, rate_y
        )
        if self.foot_force is not None:
            self._press_feet(start, contact, start_ref, end_ref)
        if self.sole_tilt is not None:
            self._tilt_soles(start, contact, start_ref, end_ref, feedback.desired_zmp)
        avoidance = None
        if self.rca is not None and self._obstacle_volumes:
            avoidance = self._avoid(start_ref, end_ref)
        result: WholeBodyIkResult | WalkingIkdStep
        if self.ikd is not None:
            result = self._ikd_step(start, start_ref, end_ref, feedback)
        else:
            result = self.solver.step(self.q_ref, start_ref, end_ref, self.dt)
        self.q_ref = result.q
        self.time += self.dt
        targets = result.q[self._nq :].copy()
        if self.feedforward is not None and isinstance(result, WalkingIkdStep):
            # the targets hold from the period's end: its state, and the feet's loads planned there
            torques = self.feedforward.torques(result.q, result.qdot, result.qddot, end.contact, end.right_load)
            targets += torques.offsets
        return WalkingCommand(targets, start, feedback, contact, result, adjustment, avoidance)

    def _ikd_step(
        self,
        start: PatternSample,
        start_ref: NDArray[np.float64],
        end_ref: NDArray[np.float64],
        feedback: StabilizerOutput,
    ) -> WalkingIkdStep:
        """The IKD's period: the pattern's soles, torso and ZMP, the balance feedback's CoM offset on the soles."""
        assert self.ikd is not None and self.pattern is not None
        k = start.step
        window = None
        if k >= 0:
            window = (self.pattern.step_start(k) + self.pattern.step_single(k), self.pattern.step_start(k + 1))
        result = self.ikd.step(
            start, start_ref, end_ref, window, feedback.offset, feedback.rate, self.pattern.reference_zmp(start.time)
        )
        self._ikd_com = (result.com + result.com_velocity * self.dt, result.com_velocity)
        return result

    def _press_feet(
        self,
        start: PatternSample,
        contact: ZmpEstimate,
        start_ref: NDArray[np.float64],
        end_ref: NDArray[np.float64],
    ) -> None:
        """Foot force difference control (:class:`FootForceControl`): the soles' height references of this period
        moved by half the height difference each (the left up, the right down), from the measured normal forces
        against the plan's load share."""
        assert self.foot_force is not None
        right, left = contact.normal_force.tolist()
        before = self.foot_force.offset
        after, rate = self.foot_force.update(self.dt, right, left, start.right_load)
        start_ref[8] -= 0.5 * before
        start_ref[11] += 0.5 * before
        end_ref[8] -= 0.5 * after
        end_ref[11] += 0.5 * after
        start_ref[32] -= 0.5 * rate
        start_ref[38] += 0.5 * rate
        end_ref[32] -= 0.5 * rate
        end_ref[38] += 0.5 * rate

    def _tilt_soles(
        self,
        start: PatternSample,
        contact: ZmpEstimate,
        start_ref: NDArray[np.float64],
        end_ref: NDArray[np.float64],
        desired_zmp: NDArray[np.float64],
    ) -> None:
        """:class:`SoleTilt`: the soles' orientation references of this period turned by their tilts, measured on the
        footholds planned on rough ground, a single support's stance sole pressed towards ``desired_zmp`` (x, y) [m]
        (the stabilizer's)."""
        assert self.sole_tilt is not None and self.pattern is not None
        tilt_control = self.sole_tilt
        k = start.step
        limits = [0.0, 0.0]
        if k >= 0:
            # in step k the stance sole stands on foothold k + 1, the swing sole lands on k + 2
            for i in range(2):
                limits[i] = tilt_control.limit(self.pattern.foothold_roughness(k + 1 if i == (k + 1) % 2 else k + 2))
        if limits[0] == 0.0 and limits[1] == 0.0 and not any(tilt_control.tilt.ravel().tolist()):
            return  # flat footholds, soles as planned: the update would change nothing
        right, left = contact.normal_force.tolist()
        tipping = [False, False]
        errors: list[tuple[float, float] | None] = [None, None]
        for i in range(2):
            if limits[i] > 0.0 and start.contact[i]:
                # the centre of pressure in the sole's frame (its heading from the measured orientation)
                rotation, position = self._soles[i], self._sole_positions[i]
                dx, dy = float(contact.cop[i, 0] - position[0]), float(contact.cop[i, 1] - position[1])
                if not math.isfinite(dx + dy):
                    continue
                heading = math.atan2(rotation[1, 0], rotation[0, 0])
                c, s = math.cos(heading), math.sin(heading)
                tipping[i] = tilt_control.tipping((c * dx + s * dy, -s * dx + c * dy))
                if not start.contact[1 - i]:
                    ex = float(desired_zmp[0] - contact.cop[i, 0])
                    ey = float(desired_zmp[1] - contact.cop[i, 1])
                    errors[i] = (c * ex + s * ey, -s * ex + c * ey)
        planned = start_ref[12:30].reshape(2, 3, 3)
        tilt = tilt_control.update(
            self.dt,
            start.contact,
            (limits[0], limits[1]),
            (right, left),
            planned,
            self._soles,
            (tipping[0], tipping[1]),
            (errors[0], errors[1]),
        ).tolist()
        for i in range(2):
            roll, pitch = tilt[i]
            if roll == 0.0 and pitch == 0.0:
                continue
            turn = tilt_rotation(roll, pitch)
            for ref in (start_ref, end_ref):
                sole = slice(12 + 9 * i, 21 + 9 * i)
                ref[sole] = (ref[sole].reshape(3, 3) @ turn).ravel()

    def _avoid(self, start_ref: NDArray[np.float64], end_ref: NDArray[np.float64]) -> RcaState:
        """RCA (5.80)-(5.83): move the swing foot's position references of this period by the modification
        before and after its update (on the IK's kinematic model)."""
        assert self.rca is not None and self.pattern is not None and self.q_ref is not None
        k, _, remaining = self.pattern.swing_state(self.time + self.dt)
        before = self.rca.state
        side = k % 2 if k >= 0 else 0
        position, velocity = slice(6 + 3 * side, 9 + 3 * side), slice(30 + 6 * side, 33 + 6 * side)
        after = self.rca.update(self.q_ref, side, k, remaining, self.dt, end_ref[position], self.pattern.ground)
        if before.offset.any() or before.velocity.any():  # most periods: no modification to add
            start_ref[position] += before.offset
            start_ref[velocity] += before.velocity
        if after.offset.any() or after.velocity.any():
            end_ref[position] += after.offset
            end_ref[velocity] += after.velocity
        return after
