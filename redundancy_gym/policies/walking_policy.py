"""The ``walking`` reference policy: the walking controller reading the BipedWalk observation."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..controllers.walking import (
    FIRST_STEP_TABLES,
    FootForceGains,
    GaitConfig,
    RcaConfig,
    SoleTiltConfig,
    SstaConfig,
    StabilizerGains,
    StepAdjusterConfig,
    WalkingCommand,
    WalkingController,
    WalkingIkConfig,
    WalkingIkdConfig,
)
from ..geometry import SSV
from ..model import RobotModel
from .exceptions import PolicyError
from .options import config_from_options, env_with_attributes
from .per_env_policy import PerEnvPolicy
from .registry import CAPABILITY_ATTRIBUTES

__all__ = ["CLIK_FOOT_FORCE_GAIN", "IKD_FEEDFORWARD_GAINS", "WalkingPolicy", "WalkingPolicyConfig", "obstacle_volumes"]

OBSTACLE_ROW = 14
"""Entries of one obstacle row of the observation: ``[mask, PSS, LSS, TSS, v0 (3), v1 (3), v2 (3), radius]``."""

DEFAULT_GAINS = (1.0, 1.0)
"""``(zmp_gain, com_gain)`` of the CLIK walker and of the IKD walker without feedforward."""
IKD_FEEDFORWARD_GAINS = (0.3, 0.3)
"""``(zmp_gain, com_gain)`` [-, 1/s] of the IKD walker with ``ikd_feedforward``: with the servos' sag fed forward,
the full gains over-correct (``bench walk``'s measured ZMP 74.9 mm rms from the reference at 1.0 / 1.0, 52.8 mm at
0.3 / 0.3; docs/walking.md)."""
CLIK_FOOT_FORCE_GAIN = 4e-4
"""``foot_force_gain`` [m/(N s)] of the CLIK walker: its landing foot takes its load late (``bench walk``'s measured
ZMP 71.5 mm rms from the reference without, 59.3 mm with). The IKD walker's 0 (off): its ZMP got worse with it
(45.4 against 46.9 mm at 2e-4; docs/walking.md)."""


def obstacle_volumes(rows: NDArray[np.float64]) -> list[SSV]:
    """The swept-sphere volumes of the observation's obstacle rows (world frame; rows with mask 0 skipped)."""
    rows = np.asarray(rows, dtype=np.float64).reshape(-1, OBSTACLE_ROW)
    volumes: list[SSV] = []
    for row in rows:
        if row[0] < 0.5:
            continue
        volumes.append(SSV.from_kind(int(np.argmax(row[1:4])), row[4:13].reshape(3, 3), float(row[13])))
    return volumes


@dataclass(frozen=True)
class WalkingPolicyConfig:
    """Options of the ``walking`` policy (defaults of :class:`GaitConfig`, :class:`StabilizerGains` and
    :class:`WalkingIkConfig` otherwise).

    Attributes:
        momentum_minimization: ``W = gamma I + J_Lz^T J_Lz`` (5.62) in the IK (False: ``W = I``).
        gamma: ``gamma`` of (5.62).
        beta: scale of (5.62) against the nullspace objectives.
        stabilizer: balance feedback on (False: the planned references only).
        dcm_gain, zmp_gain, com_gain: stabilizer gains ``k_dcm`` [-], ``k_zmp``, ``k_com`` [1/s]; ``zmp_gain``
            and ``com_gain`` None: the walker's own (1.0; with ``ik="ikd"`` and ``ikd_feedforward``
            :data:`IKD_FEEDFORWARD_GAINS`, as the fed-forward servos track the plan closer and need less feedback).
        step_duration: nominal step duration [s].
        com_height: LIPM CoM height [m].
        correction_iterations: kinematic rollouts for the multi-body ZMP correction (0: plain LIPM).
        self_collision_weight: weight of self-collision avoidance (5.49) in the IK's nullspace (0: off).
        self_collision_activation: its activation distance ``d_a`` [m].
        self_collision_slope: its slope at contact [1/m].
        backend: ``"compiled"`` (:class:`~redundancy_gym.controllers.walking.CompiledWholeBodyIk` and
            :class:`~redundancy_gym.controllers.walking.CompiledMeasurement`) or ``"python"`` (the pinocchio
            references); see :class:`WalkingIkConfig`.
        push_recovery: step adjustment from the measured DCM (:class:`StepAdjuster`: landing and timing of the
            current step) on.
        step_min_remaining: shortest single support left after a re-timing [s].
        step_max_forward, step_max_backward: reachable landing ahead of / behind the stance foot [m].
        step_min_width, step_max_width: reachable landing beside the stance foot [m].
        ssta: plan footholds and swings around the observed obstacles (step sequence and heuristic trajectory
            adaption, monograph 5.4.2) on; needs the observation's ``obstacles`` rows (BipedObstacles-v0).
        rca: reactive collision avoidance of the swing leg (task-space modification (5.80)) on.
        obstacle_clearance: height [m] of a swing sole above an obstacle's bounding box it steps over.
        step_over_duration: single-support duration [s] of a step over an obstacle (0: the nominal one).
        ik: the joint trajectory from the whole-body CLIK (``"clik"``) or from Inverse Kineto-Dynamics (``"ikd"``,
            :class:`~redundancy_gym.controllers.ikd.WalkingIkd`: the pattern's ZMP realized exactly, hybrid
            stabilization; ``correction_iterations`` is then not used, the plan is the plain LIPM's).
        moment_gain: with ``ik="ikd"``, ``k`` of the contact-moment stabilization (5.97) (``K_p = k 40 / dt``).
        ikd_planning: with ``ik="ikd"``, stabilization via planning on (with ``moment_gain`` > 0: hybrid).
        ikd_feedforward: with ``ik="ikd"``, the IKD motion's joint torques fed forward through the position servos
            (:class:`~redundancy_gym.controllers.walking.ServoFeedforward`, over the env's ``servo_stiffness``): the
            targets lead by ``tau / k_p`` so the servos do not sag under the plan's loads. Not used with ``"clik"``,
            which computes no joint accelerations.
        correction_first_steps: the first steps (0-2) with multi-body ZMP correction tables of their own (0: the
            steady tables from the first step on, as before 2026-12-03; None: the walker's own,
            :data:`~redundancy_gym.controllers.walking.FIRST_STEP_TABLES` with ``ik="clik"``, 0 with ``"ikd"``, whose
            walks with them ended in a self-collision at 1.0 m/s and did worse on random obstacle courses).
        foot_force_gain: ``k`` [m/(N s)] of the ground contact by force
            (:class:`~redundancy_gym.controllers.walking.FootForceControl`: the soles' heights follow the measured
            normal forces against the plan's load share; 0: off; None: the walker's own,
            :data:`CLIK_FOOT_FORCE_GAIN` with ``ik="clik"``, 0 with ``"ikd"``).
        sole_tilt: stance soles on footholds planned on rough ground take their measured tilt into the IK's
            references and, in single support, are pressed towards the desired ZMP
            (:class:`~redundancy_gym.controllers.walking.SoleTilt`); None: on where the observation has
            a height scan (BipedTerrain-v0), off elsewhere (no terrain map, so no rough footholds either).
    """

    momentum_minimization: bool = True
    gamma: float = 0.008
    beta: float = 10.0
    stabilizer: bool = True
    dcm_gain: float = 1.0
    zmp_gain: float | None = None
    com_gain: float | None = None
    step_duration: float = 0.8
    com_height: float = 0.91
    correction_iterations: int = 3
    self_collision_weight: float = WalkingIkConfig.self_collision_weight
    self_collision_activation: float = WalkingIkConfig.self_collision_activation
    self_collision_slope: float = WalkingIkConfig.self_collision_slope
    backend: str = WalkingIkConfig.backend
    push_recovery: bool = StepAdjusterConfig.enabled
    step_min_remaining: float = StepAdjusterConfig.min_remaining
    step_max_forward: float = StepAdjusterConfig.max_forward
    step_max_backward: float = StepAdjusterConfig.max_backward
    step_min_width: float = StepAdjusterConfig.min_width
    step_max_width: float = StepAdjusterConfig.max_width
    ssta: bool = True
    rca: bool = True
    obstacle_clearance: float = SstaConfig.clearance
    step_over_duration: float = 0.0
    ik: str = "clik"
    moment_gain: float = WalkingIkdConfig.moment_gain
    ikd_planning: bool = WalkingIkdConfig.planning
    ikd_feedforward: bool = True
    correction_first_steps: int | None = None
    foot_force_gain: float | None = None
    sole_tilt: bool | None = None


class WalkingPolicy(PerEnvPolicy):
    """Walks at the observation's commanded speed with :class:`~redundancy_gym.controllers.walking.WalkingController`.

    The controller restarts (a new walking pattern from the observed standing state) at every episode start:
    ``episode_start``, or the observation's ``time`` ~0 or going back. A batch of observations gets one controller
    per env index (:class:`~redundancy_gym.policies.PerEnvPolicy`).
    The last :class:`WalkingCommand` is kept in :attr:`last_command` for diagnostics and plots.

    Args:
        env: an env exposing ``OBSERVATION_LAYOUT`` (base pose and velocity, ``q``, ``qdot``, ankle wrenches,
            ``command``), ``ROBOT_XML``, ``SOFT_LIMIT_MARGIN``, ``joint_limits``, ``nominal_configuration``,
            ``action_scale`` and ``dt`` (BipedWalk-v0).
        **kwargs: fields of :class:`WalkingPolicyConfig`.
    """

    def __init__(self, env: Any, **kwargs: Any) -> None:
        self.config = config_from_options(WalkingPolicyConfig, kwargs)
        base = env_with_attributes(env, CAPABILITY_ATTRIBUTES["biped"], "walking")  # what a biped env promises
        layout = base.OBSERVATION_LAYOUT
        needed = ("base_position", "q", "qdot", "right_force", "left_torque", "command")
        if any(k not in layout for k in needed):
            raise PolicyError(f"the walking policy needs {', '.join(needed)} in OBSERVATION_LAYOUT")
        self._qpos = slice(layout["base_position"].start, layout["q"].stop)
        self._qvel = slice(layout["base_linear_velocity"].start, layout["qdot"].stop)
        if self._qpos.stop != self._qvel.start:
            raise PolicyError("the walking policy needs MuJoCo's qpos then qvel at the start of the observation")
        self._wrench = slice(layout["right_force"].start, layout["left_torque"].stop)
        self._command = layout["command"]
        self._obstacles = layout.get("obstacles")
        # a height scan (BipedTerrain-v0): the terrain map's input, with the env's scan points
        self._scan = layout.get("height_scan")
        self._scan_points = None if self._scan is None else np.asarray(base.scan_points, dtype=np.float64)
        self._last_rows: bytes | None = None
        self._nominal = np.asarray(base.nominal_configuration, dtype=np.float64)
        self._scale = np.asarray(base.action_scale, dtype=np.float64)
        self.model = RobotModel.from_mjcf(base.ROBOT_XML)
        lower, upper = base.joint_limits
        c = self.config
        stiffness = None
        if c.ik == "ikd" and c.ikd_feedforward:
            stiffness = getattr(base, "servo_stiffness", None)
            if stiffness is None:
                raise PolicyError("ikd_feedforward needs the env's servo_stiffness (the servos' k_p); set it False")
        if c.step_min_width > c.step_max_width:  # StepAdjusterConfig checks it too, without the options' names
            raise PolicyError(f"step_min_width={c.step_min_width!r} exceeds step_max_width={c.step_max_width!r} [m]")
        try:
            gait = GaitConfig(
                step_duration=c.step_duration,
                com_height=c.com_height,
                min_step_duration=min(GaitConfig.min_step_duration, c.step_duration),
            )
            zmp_default, com_default = IKD_FEEDFORWARD_GAINS if stiffness is not None else DEFAULT_GAINS
            gains = (
                StabilizerGains(
                    dcm=c.dcm_gain,
                    zmp=zmp_default if c.zmp_gain is None else c.zmp_gain,
                    com=com_default if c.com_gain is None else c.com_gain,
                )
                if c.stabilizer
                else StabilizerGains(dcm=0.0, zmp=0.0, com=0.0)
            )
            ik = WalkingIkConfig(
                gamma=c.gamma,
                beta=c.beta,
                momentum_minimization=c.momentum_minimization,
                self_collision_weight=c.self_collision_weight,
                self_collision_activation=c.self_collision_activation,
                self_collision_slope=c.self_collision_slope,
                backend=c.backend,
            )
            stepping = StepAdjusterConfig(
                enabled=c.push_recovery,
                min_remaining=c.step_min_remaining,
                max_forward=c.step_max_forward,
                max_backward=c.step_max_backward,
                min_width=c.step_min_width,
                max_width=c.step_max_width,
            )
            ssta = SstaConfig(
                clearance=c.obstacle_clearance,
                step_height=gait.step_height,
                max_step_length=gait.max_step_length,
                toe_length=gait.toe_length,
                step_over_single=c.step_over_duration or None,
            )
            self.controller = WalkingController(
                self.model,
                float(base.dt),
                np.asarray(lower) + base.SOFT_LIMIT_MARGIN,
                np.asarray(upper) - base.SOFT_LIMIT_MARGIN,
                gait=gait,
                gains=gains,
                ik=ik,
                stepping=stepping,
                correction_iterations=c.correction_iterations,
                ssta=ssta,
                rca=RcaConfig(),
                use_ssta=c.ssta,
                use_rca=c.rca,
                correction_configuration=self._nominal,
                ikd=WalkingIkdConfig(moment_gain=c.moment_gain, planning=c.ikd_planning) if c.ik == "ikd" else None,
                servo_stiffness=stiffness,
                foot_force=FootForceGains(
                    gain=(CLIK_FOOT_FORCE_GAIN if c.ik == "clik" else 0.0)
                    if c.foot_force_gain is None
                    else c.foot_force_gain
                ),
                correction_first_steps=(FIRST_STEP_TABLES if c.ik == "clik" else 0)
                if c.correction_first_steps is None
                else c.correction_first_steps,
                sole_tilt=SoleTiltConfig()
                if (self._scan is not None if c.sole_tilt is None else c.sole_tilt)
                else None,
            )
        except ValueError as exc:  # ControllerError from the parts names the bad value
            raise PolicyError(f"invalid walking option: {exc}") from exc
        self.last_command: WalkingCommand | None = None
        self._init_per_env(env, kwargs, layout)

    def _state(self, obs: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        return self.model.from_mujoco_state(obs[self._qpos], obs[self._qvel])

    def begin(self, obs: NDArray[np.float64]) -> None:
        """Start a walk from the observed standing state at the observation's commanded speed."""
        q, _ = self._state(obs)
        self.controller.start(q, float(obs[self._command][0]))
        self._last_rows = None
        self._observe_obstacles(obs)
        self._observe_terrain(obs)

    def _observe_terrain(self, obs: NDArray[np.float64]) -> None:
        """Give the controller's terrain map the observation's height scan, taken at the observed pelvis pose."""
        if self._scan is None or self._scan_points is None:
            return
        x, y, z, w, qx, qy, qz = obs[self._qpos][:7].tolist()
        yaw = math.atan2(2.0 * (w * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
        self.controller.observe_terrain((x, y, z, yaw), obs[self._scan], self._scan_points)

    def _observe_obstacles(self, obs: NDArray[np.float64]) -> None:
        """Give the controller the obstacle volumes of the observation's rows when they changed."""
        if self._obstacles is None or not (self.config.ssta or self.config.rca):
            return
        rows = obs[self._obstacles]
        key = rows.tobytes()  # a bytes compare: cheaper than array_equal, run every period
        if key == self._last_rows:
            return
        self._last_rows = key
        volumes = obstacle_volumes(rows)
        if volumes:
            self.controller.set_obstacles(volumes)

    def command(self, obs: NDArray[np.float64]) -> NDArray[np.float32]:
        """One control period of the walk under way: normalized joint position targets for ``obs``."""
        self._observe_obstacles(obs)
        self._observe_terrain(obs)
        # MuJoCo's state and the ankle wrenches as they lie in the observation: the controller converts them in its
        # measurement kernel (WalkingController.step_mujoco)
        command = self.controller.step_mujoco(obs[self._qpos], obs[self._qvel], obs[self._wrench])
        self.last_command = command
        # np.minimum(np.maximum(...)) is np.clip (NaN included) without its Python-side dispatch, once per period
        action = (command.joint_targets - self._nominal) / self._scale
        return np.minimum(np.maximum(action, -1.0, out=action), 1.0, out=action).astype(np.float32)

    def _act(self, obs: NDArray[np.float64], starting: bool) -> NDArray[np.float32]:
        """Normalized joint position targets for one observation."""
        if self._new_episode(obs, starting) or self.controller.pattern is None:
            self.begin(obs)
        return self.command(obs)

    @property
    def stop_reason(self) -> str | None:
        """Why the walk of the first env stops in front of an obstacle now, in one line
        (:meth:`~redundancy_gym.controllers.walking.StopReason.describe`; None: it does not stop). The evaluation
        records it at each episode's end (``stop_reason`` in ``per_episode``)."""
        reason = self.controller.stop_reason
        return None if reason is None else reason.describe()

    def describe(self) -> dict[str, Any]:
        """The configuration, for reports."""
        return asdict(self.config)
