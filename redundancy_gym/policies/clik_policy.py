"""The ``clik`` reference policy of tracking tasks (PlanarReach): velocity-level CLIK (5.14) on the env's task with
nullspace joint-limit, posture and collision objectives. It reads the env by duck typing and imports no
simulator."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..controllers import (
    Clik,
    ClikResult,
    CollisionObjective,
    CompiledClik,
    FramePositionTask,
    JointLimitObjective,
    Objective,
    PostureObjective,
)
from ..geometry import PSS, Segment
from ..kernel_options import DEFAULT_BACKEND
from ..model import RobotModel, collision_model_from_mjcf
from .exceptions import PolicyError
from .options import config_from_options, control_period, env_with_attributes
from .per_env_policy import PerEnvPolicy
from .plant_compensation import delay_compensation, tcp_offset

__all__ = ["COLLISION_MODES", "OBSTACLE_SEGMENT", "ClikPolicy", "ClikPolicyConfig"]


@dataclass(frozen=True)
class ClikPolicyConfig:
    """Defaults of the CLIK reference policy (see :class:`~redundancy_gym.controllers.Clik`).

    Attributes:
        method: ``"pseudoinverse"``, ``"dls"`` or ``"transpose"``.
        gain: task-space feedback ``K`` [1/s] of (5.5).
        nullspace_gain: ``alpha`` of (5.14).
        joint_limit_activation: ``d_a`` of the joint-limit potential [rad].
        joint_limit_slope: slope of the joint-limit potential at the limit.
        joint_limit_weight: weight of the joint-limit objective (0 switches it off).
        posture_weight: weight of a pull towards the env's starting posture (0 switches it off).
        dls_threshold: ``eps`` of the DLS damping law.
        dls_max_damping: ``k_max`` of the DLS damping law.
        collision_avoidance: ``"auto"`` (on when the env has an obstacle), ``"on"`` or ``"off"``: the
            nullspace collision objective (5.49)-(5.61) on the robot's geoms and the env's obstacle.
        collision_activation: ``d_a`` of the collision potential [m].
        collision_slope: slope of the collision potential at contact [1/m].
        collision_weight: weight of the collision objective.
        self_collision: also avoid robot-robot pairs (non-adjacent links).
        base_calibration: at an episode's start, take the observed TCP less the model's as the robot's placement
            error and track the targets less it (:mod:`~redundancy_gym.policies.plant_compensation`).
        latency: actuation delay [control periods] to compensate (a Smith predictor; 0: none; None: measured at
            each episode's start, from the observed joint velocities' response to the first command).
        backend: ``"compiled"`` (:class:`~redundancy_gym.controllers.CompiledClik`, one fused kernel per step)
            or ``"python"`` (:class:`~redundancy_gym.controllers.Clik`); same commands to round-off.
    """

    method: str = "dls"
    gain: float = 20.0
    nullspace_gain: float = 1.0
    joint_limit_activation: float = 0.35
    joint_limit_slope: float = 1.0
    joint_limit_weight: float = 1.0
    posture_weight: float = 0.0
    dls_threshold: float = 0.05
    dls_max_damping: float = 0.01
    collision_avoidance: str = "auto"
    collision_activation: float = 0.15
    collision_slope: float = 5.0
    collision_weight: float = 1.0
    self_collision: bool = True
    base_calibration: bool = True
    latency: int | None = None
    backend: str = DEFAULT_BACKEND


COLLISION_MODES = ("auto", "on", "off")
OBSTACLE_SEGMENT = "obstacle"


class ClikPolicy(PerEnvPolicy):
    """Velocity-level CLIK (5.14) on the env's task, as a policy: observation in, normalized joint velocities out.

    The joint configuration and the task reference (position and velocity) are read from the observation;
    the model is the env's robot MJCF loaded by pinocchio. The last :class:`ClikResult` is kept in
    :attr:`last_result` for diagnostics.

    Args:
        env: an env exposing ``OBSERVATION_LAYOUT`` (with ``q``, ``tcp_ref``, ``tcp_ref_vel``), ``ROBOT_XML``,
            ``TCP_FRAME``, ``TASK_AXES`` and ``max_joint_speed`` (e.g. PlanarReach-v0).
        **kwargs: fields of :class:`ClikPolicyConfig`.
    """

    def __init__(self, env: Any, **kwargs: Any) -> None:
        self.config = config_from_options(ClikPolicyConfig, kwargs)
        base = env_with_attributes(
            env, ("OBSERVATION_LAYOUT", "ROBOT_XML", "TCP_FRAME", "TASK_AXES", "max_joint_speed"), "clik"
        )
        self._layout = base.OBSERVATION_LAYOUT
        self._speed = float(base.max_joint_speed)
        self.model = RobotModel.from_mjcf(base.ROBOT_XML)
        objectives: list[Objective] = []
        if self.config.joint_limit_weight > 0.0:
            objectives.append(
                JointLimitObjective.from_model(
                    self.model,
                    activation_distance=self.config.joint_limit_activation,
                    slope=self.config.joint_limit_slope,
                    weight=self.config.joint_limit_weight,
                )
            )
        if self.config.posture_weight > 0.0:
            reference = getattr(base, "nominal_configuration", None)
            if reference is None:
                raise PolicyError("posture_weight > 0 needs an env with nominal_configuration")
            objectives.append(PostureObjective(reference, self.config.posture_weight))
        self.collision: CollisionObjective | None = None
        self._obstacle_slices: tuple[slice, slice] | None = None
        self._obstacle_seen: tuple[float, ...] | None = None
        if self.config.collision_avoidance not in COLLISION_MODES:
            raise PolicyError(
                f"unknown collision_avoidance {self.config.collision_avoidance!r}; valid: {', '.join(COLLISION_MODES)}"
            )
        has_obstacle = bool(getattr(base, "has_obstacle", False))
        wanted = self.config.collision_avoidance == "on" or (self.config.collision_avoidance == "auto" and has_obstacle)
        if wanted:
            self.collision = self._collision_objective(base, has_obstacle)
            objectives.append(self.collision)
        clik = Clik(
            self.model,
            FramePositionTask(base.TCP_FRAME, base.TASK_AXES),
            method=self.config.method,
            gain=self.config.gain,
            nullspace_gain=self.config.nullspace_gain,
            objectives=objectives,
            dls_threshold=self.config.dls_threshold,
            dls_max_damping=self.config.dls_max_damping,
            period=control_period(base),
        )
        self.controller: Clik | CompiledClik = CompiledClik(clik) if self.config.backend == "compiled" else clik
        self.last_result: ClikResult | None = None
        self._frame, self._axes = base.TCP_FRAME, tuple("xyz".index(a) for a in base.TASK_AXES)
        self._delay = delay_compensation(self.config.latency, control_period(base), self.model.nv)
        self._offset: NDArray[np.float64] | None = None  # the placement error of this episode [m]
        self._init_per_env(env, kwargs, self._layout)  # the episode state: the placement error, commands in flight

    def _collision_objective(self, base: Any, has_obstacle: bool) -> CollisionObjective:
        """Robot segments from the robot MJCF; the obstacle (a sphere, read from the observation) as a PSS."""
        environment = []
        if has_obstacle:
            if "obstacle_center" not in self._layout or "obstacle_radius" not in self._layout:
                raise PolicyError(
                    f"{type(base).__name__} has an obstacle but no obstacle_center/obstacle_radius "
                    "in OBSERVATION_LAYOUT"
                )
            # a unit sphere at the origin, moved and scaled from the observation in predict()
            environment.append(Segment(OBSTACLE_SEGMENT, (PSS(np.zeros(3), 1.0),)))
            self._obstacle_slices = (self._layout["obstacle_center"], self._layout["obstacle_radius"])
        model = collision_model_from_mjcf(self.model, environment, self_collision=self.config.self_collision)
        return CollisionObjective(
            model,
            activation_distance=self.config.collision_activation,
            slope=self.config.collision_slope,
            weight=self.config.collision_weight,
        )

    def update_obstacle(self, obs: NDArray[np.float64]) -> None:
        """Place the collision model's obstacle where the observation says (done by :meth:`predict`)."""
        if self.collision is None or self._obstacle_slices is None:
            return
        center_slice, radius_slice = self._obstacle_slices
        center = obs[center_slice]
        radius = float(obs[radius_slice][0])
        seen = (*center.tolist(), radius)
        if seen == self._obstacle_seen:  # placing the environment again would only redo the same transforms
            return
        self._obstacle_seen = seen
        # planar envs give (x, z); the sphere is scaled by its radius about the origin, then moved
        position = np.array([center[0], 0.0, center[1]]) if center.size == 2 else np.asarray(center, dtype=np.float64)
        self.collision.collision_model.set_environment_placement(OBSTACLE_SEGMENT, np.eye(3), position)
        self.collision.collision_model.set_environment_radius(OBSTACLE_SEGMENT, max(radius, 0.0))

    @property
    def max_joint_speeds(self) -> NDArray[np.float64]:
        """The env's joint speed limits [rad/s] (nv): an action of 1 commands them."""
        return np.full(self.model.nv, self._speed)

    def task_reference(
        self, obs: NDArray[np.float64], starting: bool
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """The configuration, task target and target velocity of one observation, for :attr:`controller`
        (places the observed obstacle in the collision model); at a new episode (``starting``, or the observation's
        phase ~0 or going back) it takes the placement error (``base_calibration``), which the target is shifted
        by for the episode."""
        self.update_obstacle(obs)
        lay = self._layout
        q, target = obs[lay["q"]], obs[lay["tcp_ref"]]
        if self._new_episode(obs, starting) or self._offset is None:
            self._delay.reset()
            self._offset = np.zeros(len(self._axes))
            if self.config.base_calibration and "tcp" in lay:
                self._offset = tcp_offset(self.model, self._frame, q, obs[lay["tcp"]], self._axes)
        return q, target - self._offset, obs[lay["tcp_ref_vel"]]

    def _act(self, obs: NDArray[np.float64], starting: bool) -> NDArray[np.float32]:
        """Normalized joint velocity command for one observation."""
        q, target, velocity = self.task_reference(obs, starting)
        delay = self._delay
        delay.observe(obs[self._layout["qdot"]], None if self._time_index is None else obs.item(self._time_index))
        target, velocity = delay.reference(target, velocity)
        result = self.controller.step(delay.predict(q), target, velocity)
        self.last_result = result
        action = np.clip(result.qdot / self._speed, -1.0, 1.0)
        if not delay.idle:
            delay.sent(action * self._speed)
        return action.astype(np.float32)

    def describe(self) -> dict[str, Any]:
        """The configuration, for reports."""
        return asdict(self.config)
