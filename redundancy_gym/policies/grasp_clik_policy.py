"""The ``clik`` reference policy of grasp-approach tasks (AgriReach): a task-space path to the pre-grasp pose,
a straight radial approach, and velocity-level CLIK with nullspace collision and joint-limit avoidance.

Monograph 5.3 (Baur et al. 2012 setup): the 5-D task (TCP position and tool axis) leaves four of the nine
degrees of freedom to the nullspace, where the gradient of the self- and plant-collision potential (5.49)-(5.61)
and of the joint-limit potential is projected (5.14); with ``W = I`` the particular solution is the minimum
joint-velocity one. Like :mod:`.clik_policy` it reads the env by duck typing and imports no simulator.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..controllers.clik.clik import Clik, ClikResult
from ..controllers.clik.clik_kernels import OK
from ..controllers.clik.compiled_clik import CompiledClik
from ..controllers.objectives.collision_objective import CollisionObjective
from ..controllers.objectives.joint_limit_objective import JointLimitObjective
from ..controllers.tasks.frame_axis_task import FrameAxisTask
from ..geometry import SSV, Segment
from ..geometry.grasp_path import GraspPath, GraspPathTiming
from ..kernel_options import DEFAULT_BACKEND, LazyEntryPoint
from ..model import RobotModel, collision_geometry_from_mjcf
from .exceptions import PolicyError
from .grasp_clik_kernels import grasp_clik_action
from .options import config_from_options, control_period, env_with_attributes
from .per_env_policy import PerEnvPolicy
from .plant_compensation import delay_compensation, tcp_offset

__all__ = ["GraspClikConfig", "GraspClikPolicy", "GraspPath"]

# grasp_clik_action(f, i, obs, q_start, time_index, path, speeds, action, result); obs in any layout (a row of a
# batch, a strided view), the others are the policy's own contiguous arrays
_FUSED_SIGNATURE = (
    "int64(float64[::1], int64[::1], float64[:], int64, int64, float64[::1], float64[::1], float32[::1], float64[::1])"
)


@dataclass(frozen=True)
class GraspClikConfig:
    """Defaults of the grasp-approach CLIK policy.

    Attributes:
        method: ``"pseudoinverse"``, ``"dls"`` or ``"transpose"`` (see :class:`Clik`).
        gain: task-space feedback ``K`` [1/s].
        nullspace_gain: ``alpha`` of (5.14).
        max_speed: average TCP speed of the move to the pre-grasp pose [m/s].
        max_turn_rate: average tool-axis turn rate of that move [rad/s].
        min_duration: shortest move to the pre-grasp pose [s].
        approach_speed: average TCP speed of the straight approach [m/s].
            These four, left ``None``, take the env's reference path timing (``reference_timing``, see
            :class:`~redundancy_gym.geometry.GraspPathTiming`), so the policy follows the path that the env
            measures ``tracking_error`` against.
        collision_avoidance: ``"on"`` or ``"off"``: the nullspace collision objective on self pairs and the
            observed hard obstacles.
        collision_activation: ``d_a`` [m]; collision_slope: ``|H'(0)|`` [1/m]; collision_weight: weight.
        avoid_leaves: also keep clear of observed leaves and petioles (soft obstacles).
        joint_limit_activation: ``d_a`` of the joint-limit potential [rad or m]; joint_limit_weight: its weight.
        base_calibration: at an episode's start, take the observed TCP less the model's as the robot's placement
            error, and plan the path and place the obstacles less it, in the model's frame
            (:mod:`~redundancy_gym.policies.plant_compensation`).
        latency: actuation delay [control periods] to compensate (a Smith predictor; 0: none; None: measured at
            each episode's start, from the observed joint velocities' response to the first command). With a
            latency the compiled backend composes its calls instead of the one-call step.
        backend: ``"compiled"`` (:class:`CompiledClik`, one fused kernel per step) or ``"python"``
            (:class:`Clik`); both give the same commands to round-off.
    """

    method: str = "dls"
    gain: float = 10.0
    nullspace_gain: float = 1.0
    max_speed: float | None = None
    max_turn_rate: float | None = None
    min_duration: float | None = None
    approach_speed: float | None = None
    collision_avoidance: str = "on"
    collision_activation: float = 0.1
    collision_slope: float = 4.0
    collision_weight: float = 10.0
    avoid_leaves: bool = False
    joint_limit_activation: float = 0.2
    joint_limit_weight: float = 0.5
    base_calibration: bool = True
    latency: int | None = None
    backend: str = DEFAULT_BACKEND


def _tool_axis(quaternion: NDArray[np.float64]) -> NDArray[np.float64]:
    """The x axis of the rotation ``(w, x, y, z)``."""
    w, x, y, z = quaternion / np.linalg.norm(quaternion)
    return np.array([1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y + w * z), 2.0 * (x * z - w * y)])


def obstacle_volumes(block: NDArray[np.float64]) -> list[tuple[SSV, bool]]:
    """The valid rows of an observation's obstacle block as ``(volume, hard)``."""
    rows = np.asarray(block, dtype=np.float64).reshape(-1, 15)
    out: list[tuple[SSV, bool]] = []
    for row in rows:
        if row[0] < 0.5:
            continue
        v = row[5:14].reshape(3, 3)
        r = float(row[14])
        out.append((SSV.from_kind(int(np.argmax(row[1:4])), v, r), bool(row[4] > 0.5)))
    return out


class GraspClikPolicy(PerEnvPolicy):
    """Velocity-level CLIK along a :class:`GraspPath`, as a policy (observation in, normalized joint velocities out).

    At the first observation of an episode (``episode_start``, or the observation's ``time`` ~0 or going back) it
    plans the path from the observed TCP pose and builds its collision model: the robot's own segments from the
    robot MJCF (non-adjacent links, the lift column) and one segment per observed obstacle. A batch of observations
    gets one such state per env index (:class:`~redundancy_gym.policies.PerEnvPolicy`).
    :attr:`last_result` keeps the last :class:`ClikResult`. With the compiled backend a step is one kernel call
    (:func:`~.grasp_clik_kernels.grasp_clik_action`: observation to action, the same numbers as the separate
    calls of the Python backend's path).

    Args:
        env: an env exposing ``observation_layout`` (``q``, ``tcp_position``, ``tcp_quaternion``,
            ``grasp_position``, ``approach``, ``pregrasp_position``, ``time``, ``obstacles``), ``ROBOT_XML``,
            ``TCP_FRAME`` and ``max_joint_speeds`` (e.g. AgriReach-v0).
        **kwargs: fields of :class:`GraspClikConfig`.
    """

    def __init__(self, env: Any, **kwargs: Any) -> None:
        self.config = config_from_options(GraspClikConfig, kwargs)
        if self.config.collision_avoidance not in ("on", "off"):
            raise PolicyError(f"unknown collision_avoidance {self.config.collision_avoidance!r}; valid: on, off")
        base = env_with_attributes(
            env, ("observation_layout", "ROBOT_XML", "TCP_FRAME", "max_joint_speeds"), "grasp clik"
        )
        self._layout = dict(base.observation_layout)
        self._speeds = np.array(base.max_joint_speeds, dtype=np.float64)  # own contiguous copy: the kernel reads it
        self._period = control_period(base)  # the command keeps every joint inside its range over one period
        env_timing = getattr(base, "reference_timing", None)
        env_timing = env_timing if isinstance(env_timing, GraspPathTiming) else GraspPathTiming()
        c = self.config
        self.timing = GraspPathTiming(
            *(
                env if own is None else float(own)
                for own, env in zip(
                    (c.max_speed, c.max_turn_rate, c.min_duration, c.approach_speed), env_timing, strict=False
                )
            )
        )
        self.model = RobotModel.from_mjcf(base.ROBOT_XML)
        self._geometry = collision_geometry_from_mjcf(self.model)  # the arm's own segments, read once
        self.joint_limits = JointLimitObjective.from_model(
            self.model,
            activation_distance=self.config.joint_limit_activation,
            slope=1.0,
            weight=self.config.joint_limit_weight,
        )
        self.task = FrameAxisTask(base.TCP_FRAME, axis=0)
        self.collision: CollisionObjective | None = None
        self.path: GraspPath | None = None
        self.controller: Clik | CompiledClik | None = None  # built by the first observation (observed obstacles)
        self._last_result: ClikResult | None = None
        self._time = self._layout["time"].start if "time" in self._layout else None  # predict needs it
        # the one-call step (compiled backend): its entry point, the path's constants, the configuration's start in
        # the observation and the copy of the last step's outputs that last_result is built from when asked for
        self._fused: Any = None
        self._path_params = np.zeros(0)
        q_slice = self._layout["q"]
        self._q_start = q_slice.start if q_slice.step in (None, 1) and q_slice.start is not None else None
        self._outputs = np.zeros(0)
        self._result_pending = False
        self._nv = self.model.nv
        self._delay = delay_compensation(self.config.latency, self._period, self._nv)
        self._init_per_env(env, kwargs, self._layout)

    def build_controller(self, environment: list[Segment]) -> Clik | CompiledClik:
        """The CLIK controller of this configuration (compiled unless ``backend="python"``) with ``environment``
        (world-fixed obstacle segments) in its collision model; also sets :attr:`collision`."""
        objectives: list[Any] = [self.joint_limits]
        self.collision = None
        if self.config.collision_avoidance == "on":
            model = self._geometry.collision_model(environment)
            self.collision = CollisionObjective(
                model,
                activation_distance=self.config.collision_activation,
                slope=self.config.collision_slope,
                weight=self.config.collision_weight,
            )
            objectives.append(self.collision)
        clik = Clik(
            self.model,
            self.task,
            method=self.config.method,
            gain=self.config.gain,
            nullspace_gain=self.config.nullspace_gain,
            objectives=objectives,
            period=self._period,
        )
        return CompiledClik(clik) if self.config.backend == "compiled" else clik

    def plan(self, obs: NDArray[np.float64]) -> None:
        """A new episode: the grasp path from the observed TCP pose and grasp, and the controller with the
        observed obstacles (done by :meth:`predict` at an episode start)."""
        lay = self._layout
        start = obs[lay["tcp_position"]]
        axis = _tool_axis(obs[lay["tcp_quaternion"]])
        pregrasp, grasp, approach = obs[lay["pregrasp_position"]], obs[lay["grasp_position"]], obs[lay["approach"]]
        c = self.config
        self._delay.reset()
        offset = np.zeros(3)
        if c.base_calibration:
            offset = tcp_offset(self.model, self.task.frame, obs[lay["q"]], start, (0, 1, 2))
        # the path and the obstacles in the model's frame: the world's less the base's offset
        self.path = GraspPath.plan(start - offset, axis, pregrasp - offset, grasp - offset, approach, self.timing)
        environment = []
        for k, (volume, hard) in enumerate(obstacle_volumes(obs[lay["obstacles"]])):
            if hard or c.avoid_leaves:
                environment.append(Segment(f"obstacle_{k}", (volume.transformed(np.eye(3), -offset),)))
        if self.controller is None or self.config.collision_avoidance == "on":
            _ = self.last_result  # a pending result is read from the buffers of the controller being replaced
            self.controller = self.build_controller(environment)
        self._path_params = self.path.params.copy()  # the constants the one-call step samples the path from (a
        # writable copy: the entry point is compiled for writable arrays)
        self._fused = None
        if (
            isinstance(self.controller, CompiledClik)
            and self._q_start is not None
            and self._time is not None
            and self._speeds.shape == (self._nv,)
        ):
            self._fused = LazyEntryPoint(self, "_fused", grasp_clik_action, _FUSED_SIGNATURE)
            if self._outputs.size != self.controller.output_size:
                self._outputs = np.zeros(self.controller.output_size)

    @property
    def last_result(self) -> ClikResult | None:
        """The :class:`ClikResult` of the last step (None before the first); built when asked for, since most
        callers never read it."""
        if self._result_pending:
            self._result_pending = False
            assert isinstance(self.controller, CompiledClik)
            self._last_result = self.controller.result(self._outputs)
        return self._last_result

    @property
    def max_joint_speeds(self) -> NDArray[np.float64]:
        """The env's joint speed limits [rad/s or m/s] (nv): an action of 1 commands them."""
        return self._speeds.copy()

    def task_reference(
        self, obs: NDArray[np.float64], starting: bool
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """The configuration, task target ``[p_d, a_d]`` and target velocity ``[v_d, omega_d]`` of one observation,
        for :attr:`controller`; at a new episode (``starting``, or the observation's time ~0 or going back) it
        plans the path and builds the controller first (:meth:`plan`)."""
        if self._new_episode(obs, starting) or self.path is None:
            self.plan(obs)
        assert self.path is not None and self.controller is not None and self._time is not None
        target, velocity = self.path(obs.item(self._time))
        return obs[self._layout["q"]], target, velocity

    def _act(self, obs: NDArray[np.float64], starting: bool) -> NDArray[np.float32]:
        """Normalized joint velocity command for one observation."""
        if self._new_episode(obs, starting) or self.path is None:
            self.plan(obs)
        delay = self._delay
        delay.observe(obs[self._layout["qdot"]], None if self._time is None else obs.item(self._time))
        fused = self._fused if delay.latency == 0 else None
        if fused is not None:  # the compiled backend: one kernel call from observation to action
            f, i = self.controller.kernel_buffers()  # type: ignore[union-attr]
            action = np.empty(self._nv, dtype=np.float32)
            if (
                fused(f, i, obs, self._q_start, self._time, self._path_params, self._speeds, action, self._outputs)
                == OK
            ):
                self._result_pending = True
                if not delay.idle:
                    delay.sent(action * self._speeds)
                return action
        # the Python backend, or an input the kernel rejects: the separate calls raise the controller's error
        assert self.path is not None and self.controller is not None and self._time is not None
        # with a latency: the joints and the path where and when this command starts acting
        target, velocity = self.path(obs.item(self._time) + delay.latency * delay.period)
        result = self.controller.step(delay.predict(obs[self._layout["q"]]), target, velocity)
        self._result_pending = False
        self._last_result = result
        action = np.clip(result.qdot / self._speeds, -1.0, 1.0)
        if not delay.idle:
            delay.sent(action * self._speeds)
        return action.astype(np.float32)

    def describe(self) -> dict[str, Any]:
        """The configuration, for reports."""
        return asdict(self.config)
