"""PlanarReach-v0: a planar 4-DoF arm whose TCP follows a vertical line past a sphere obstacle (monograph 5.6.2)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import mujoco
import numpy as np
from gymnasium import spaces, utils
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv
from numpy.typing import NDArray

from ..assets import (
    PLANAR_ARM_FEEDFORWARDS,
    PLANAR_ARM_JOINTS,
    PLANAR_ARM_LINK_GEOMS,
    PLANAR_ARM_SERVOS,
    PLANAR_ARM_TCP,
    PLANAR_ARM_XML,
    PLANAR_OBSTACLE_GEOM,
)
from ..assets.planar_arm_scene import planar_arm_scene_xml
from .command_kernels import velocity_commands
from .dynamics import ARM_ITEMS, DynamicsRandomization, parse_dynamics
from .exceptions import EnvConfigError
from .planar_kernels import planar_state
from .validation import (
    MAX_FRAME_SKIP,
    as_action,
    check_backend,
    check_bool,
    check_int,
    check_known_arguments,
    check_noise,
    check_real,
    check_real_array,
    check_render_arguments,
    constructor_arguments,
    constructor_defaults,
    init_mujoco_env,
    non_finite_action,
    warn_if_time_limit_short,
)

__all__ = ["PlanarReachEnv", "default_config"]

_TIMESTEP = 0.001  # [s], the MJCF option; the control period is frame_skip * _TIMESTEP
_CLEARANCE_HORIZON = 10.0  # [m] distances beyond this are reported as this value


def default_config() -> dict[str, Any]:
    """Default keyword arguments of :class:`PlanarReachEnv`, the rendering ones left out (a fresh dict each call),
    read from its signature: the one place they are written."""
    return constructor_defaults(PlanarReachEnv.__init__)


MIN_OBSTACLE_RADIUS = 1e-6
"""Smallest ``obstacle_radius`` [m] (MuJoCo's XML parser rejects subnormal numbers)."""
MAX_OBSTACLE_RADIUS = 2.0
"""Largest ``obstacle_radius`` [m] (the arm reaches 1.4 m)."""
MAX_OBSTACLE_DISTANCE = 10.0
"""Largest ``obstacle_center`` coordinate [m]."""


class PlanarReachEnv(MujocoEnv, utils.EzPickle):
    r"""## Description
    A planar 4-DoF arm moving in the vertical x-z plane (the motivational example of monograph 5.6.2,
    fig. 5.30). Its tool centre point (TCP) must follow a straight vertical line from ``line_start`` (top) to
    ``line_end`` (bottom) in ``duration`` seconds along a rest-to-rest quintic time law, then hold the end
    point until the time limit. The arm has four joints for a two-dimensional task: two degrees of redundancy
    that a controller may use, for example to keep clear of the optional sphere obstacle near the line (the
    reference path itself does not touch it, but the links may).

    The plant is the MJCF in ``redundancy_gym/assets/planar_arm.xml``: link lengths 0.5/0.4/0.3/0.2 m,
    masses 4/3/2/1 kg, gravity compensated, each joint driven by a stiff servo on the integrated velocity
    command with velocity feed-forward (a position-controlled robot taking velocity commands).

    ## Action Space
    ``Box(-1, 1, (4,), float32)``: joint velocity commands normalized by ``max_joint_speed``,
    ``qdot_cmd = max_joint_speed * clip(action, -1, 1)`` [rad/s]. Non-finite actions raise
    :class:`~redundancy_gym.envs.InvalidActionError`.

    ## Observation Space
    ``Box(-inf, inf, (20,), float64)``; the slices are in :attr:`OBSERVATION_LAYOUT`:

    | index | name | unit |
    |-------|------|------|
    | 0-3   | ``q``: joint angles | rad |
    | 4-7   | ``qdot``: joint velocities | rad/s |
    | 8-9   | ``tcp``: TCP position (x, z) | m |
    | 10-11 | ``tcp_ref``: reference TCP position (x, z) | m |
    | 12-13 | ``tcp_ref_vel``: reference TCP velocity (x, z) | m/s |
    | 14    | ``phase``: ``min(t / duration, 1)`` | - |
    | 15-16 | ``obstacle_center``: (x, z), zeros without obstacle | m |
    | 17    | ``obstacle_radius``: 0 without obstacle | m |
    | 18-19 | ``tcp_error``: ``tcp_ref - tcp`` (from the observed, possibly noisy, entries) | m |

    ## Rewards
    The reward is the sum of the terms reported in ``info``:

    - ``reward_tracking = -tracking_weight * |tcp - tcp_ref|`` [m]
    - ``reward_energy = -energy_weight * qdot^T qdot * dt`` (the pseudoenergy increment)
    - ``reward_collision = -collision_penalty`` on the step that collides, else 0

    ``info`` also holds ``tracking_error`` [m] (``|tcp - tcp_ref|``: the TCP against the reference point on the
    line at the current time), ``goal_error`` [m] (TCP to ``line_end``), ``goal_reached`` (``goal_error <=
    success_tolerance``), ``pseudoenergy`` (``qdot^T qdot dt`` of the step, [rad^2/s]),
    ``min_clearance`` [m] (smallest distance between a link capsule and the obstacle; ``inf`` without
    obstacle), ``collision`` (bool), ``joint_limit_margin`` [rad] (smallest distance of a joint to a limit),
    ``line_finished`` (the reference has reached ``line_end``), ``peak_joint_speed`` (``max |qdot_i|``
    [rad/s]), ``max_tracking_error`` (largest ``tracking_error`` of the episode so far), ``is_success`` (line
    finished, no collision, ``max_tracking_error <= success_tolerance``), ``time`` [s], ``tcp`` and ``tcp_ref``.

    ## Starting State
    ``q = q_0 + u`` with ``u ~ U(-reset_noise_scale, reset_noise_scale)^4`` drawn from the env's generator,
    then projected by a minimum-norm Newton iteration onto the configurations whose TCP is exactly at
    ``line_start`` (so the redundant posture varies but the task starts without error). ``q_0`` is
    ``initial_configuration`` projected the same way. Joint velocities are zero; servo targets equal ``q``.

    ## Episode End
    - Termination: a link touches the obstacle (``min_clearance <= 0``).
    - Truncation: the time limit of the registration (250 steps = 2.5 s at the default 100 Hz). Keep it at
      least ``duration / dt`` steps when changing ``duration`` (``gym.make(..., max_episode_steps=N)``).

    ## Arguments
    - ``obstacle`` (bool): include the sphere obstacle in the scene.
    - ``obstacle_center`` ((x, z) [m], within +-10 m), ``obstacle_radius`` ([m], in [1e-6, 2]).
    - ``line_start``, ``line_end`` ((x, z) [m]): the TCP line, both inside the reach of 1.4 m.
    - ``duration`` ([s], > 0): time to traverse the line.
    - ``initial_configuration`` (4 angles [rad]): seed of the starting posture.
    - ``max_joint_speed`` ([rad/s], > 0): velocity command at action 1.
    - ``tracking_weight``, ``energy_weight``, ``collision_penalty`` (>= 0): reward weights.
    - ``reset_noise_scale`` ([rad], >= 0): joint noise of the starting posture.
    - ``success_tolerance`` ([m], > 0): largest TCP error of a successful episode.
    - ``frame_skip`` (int in [1, 1000]): physics steps of 1 ms per control step.
    - ``obs_noise`` (fault, default None = off): zero-mean Gaussian noise added to the measured channels of the
      observation at every step and reset, drawn from the env's generator (``reset(seed=...)`` reproduces it);
      a float std applies to ``q`` [rad], ``qdot`` [rad/s] and ``tcp`` [m] alike, a dict gives one per group
      (``{"q": 0.001, "qdot": 0.01, "tcp": 0.001}``; groups not named get none). The episode constants
      (reference, phase, obstacle) stay exact, and ``info`` and the rewards use the true state.
    - ``dynamics`` (default None = off): per-reset randomization of the simulated plant, drawn from the env's
      generator (:mod:`redundancy_gym.envs.dynamics`): a level ``L`` in [0, 0.3] (every body's mass and inertia,
      joint damping and armature and servo gains scaled in ``(1 - L, 1 + L)``, CoM offsets and the base's
      placement up to ``L / 10`` [m] per axis, a payload up to ``10 L`` [kg] at the TCP, ``floor(10 L)`` control
      periods of actuation latency) or a dict of items: ``mass``, ``servo_gain`` (scale ranges), ``damping``,
      ``frictionloss``, ``armature`` (scale ranges or ``{"range": (low, high)}``), ``com_offset``,
      ``placement`` [m], ``payload`` [kg range], ``latency`` [control periods: an int or a range], and ``level``
      for the rest. The controllers keep the nominal model; ``info["dynamics"]`` of a reset says what was drawn.
    - ``backend`` (``"compiled"`` or ``"python"``): how a step computes its commands, observation and ``info``: in
      two compiled kernels, or with NumPy, the readable reference the tests hold them equal to (to round-off).
    - ``render_mode``, ``width``, ``height``, ``camera_name``: as for Gymnasium's MuJoCo envs.

    ## Version History
    - v0: initial release (0.1.0)
    """

    metadata = {"render_modes": ["human", "rgb_array", "depth_array"], "render_fps": 100}
    OBSERVATION_LAYOUT: dict[str, slice] = {
        "q": slice(0, 4),
        "qdot": slice(4, 8),
        "tcp": slice(8, 10),
        "tcp_ref": slice(10, 12),
        "tcp_ref_vel": slice(12, 14),
        "phase": slice(14, 15),
        "obstacle_center": slice(15, 17),
        "obstacle_radius": slice(17, 18),
        "tcp_error": slice(18, 20),
    }
    ROBOT_XML = PLANAR_ARM_XML
    TCP_FRAME = PLANAR_ARM_TCP
    TASK_AXES = "xz"
    # what the policies and wrappers may rely on (redundancy_gym.policies.CAPABILITY_ATTRIBUTES)
    CAPABILITIES = frozenset({"tcp_tracking", "tcp_reference"})

    def __init__(
        self,
        obstacle: bool = True,
        obstacle_center: Sequence[float] = (0.7, -0.12),
        obstacle_radius: float = 0.1,
        line_start: Sequence[float] = (0.9, 0.45),
        line_end: Sequence[float] = (0.9, -0.45),
        duration: float = 2.0,
        initial_configuration: Sequence[float] = (-1.3, 1.0, 0.9, 0.5),
        max_joint_speed: float = 3.0,
        tracking_weight: float = 10.0,
        energy_weight: float = 40.0,
        collision_penalty: float = 100.0,
        reset_noise_scale: float = 0.1,
        success_tolerance: float = 1e-3,
        frame_skip: int = 10,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
        camera_name: str | None = "side",
        obs_noise: float | dict[str, float] | None = None,
        backend: str = "compiled",
        dynamics: float | dict[str, Any] | None = None,
        **kwargs: Any,
    ) -> None:
        check_known_arguments(kwargs, PlanarReachEnv.__init__)
        utils.EzPickle.__init__(self, **constructor_arguments(PlanarReachEnv.__init__, locals()))
        self._noise = check_noise(
            "obs_noise",
            obs_noise,
            {k: (self.OBSERVATION_LAYOUT[k],) for k in ("q", "qdot", "tcp")},
            ("q", "qdot", "tcp"),
        )
        self._backend = check_backend("backend", backend)
        spec = parse_dynamics(dynamics, ARM_ITEMS)
        self._dynamics = None if spec is None else DynamicsRandomization(spec, "link1", "tcp")
        self._drawn: dict[str, Any] | None = None
        self._obstacle = check_bool("obstacle", obstacle)
        self._obstacle_center = _point(obstacle_center, "obstacle_center")
        if np.max(np.abs(self._obstacle_center)) > MAX_OBSTACLE_DISTANCE:
            raise EnvConfigError(
                f"obstacle_center must lie within +-{MAX_OBSTACLE_DISTANCE} m of the base in x and z, "
                f"got {tuple(self._obstacle_center)}"
            )
        # an obstacle larger than the workspace (1.4 m reach) makes no task; MuJoCo's geometry overflows far beyond
        self._obstacle_radius = check_real(
            "obstacle_radius", obstacle_radius, low=MIN_OBSTACLE_RADIUS, high=MAX_OBSTACLE_RADIUS, unit="m"
        )
        self._line_start = _point(line_start, "line_start")
        self._line_end = _point(line_end, "line_end")
        for name, p in (("line_start", self._line_start), ("line_end", self._line_end)):
            if np.linalg.norm(p) >= 1.4:
                raise EnvConfigError(f"{name} {tuple(p)} is outside the arm's reach of 1.4 m from (0, 0)")
        self._duration = check_real("duration", duration, low=0.0, low_open=True, unit="s")
        self._max_joint_speed = check_real("max_joint_speed", max_joint_speed, low=0.0, low_open=True, unit="rad/s")
        self._joint_speeds = np.full(4, self._max_joint_speed)  # [rad/s] per joint, for the compiled commands
        self._tracking_weight = check_real("tracking_weight", tracking_weight, low=0.0)
        self._energy_weight = check_real("energy_weight", energy_weight, low=0.0)
        self._collision_penalty = check_real("collision_penalty", collision_penalty, low=0.0)
        self._reset_noise_scale = check_real("reset_noise_scale", reset_noise_scale, low=0.0, unit="rad")
        self._success_tolerance = check_real("success_tolerance", success_tolerance, low=0.0, low_open=True, unit="m")
        frame_skip = check_int("frame_skip", frame_skip, low=1, high=MAX_FRAME_SKIP)
        seed_q = check_real_array(
            "initial_configuration", initial_configuration, shape=(4,), what="4 joint angles [rad], finite real numbers"
        )
        width, height = check_render_arguments(render_mode, width, height, camera_name)
        self._scene_xml = planar_arm_scene_xml(
            obstacle_center=self._obstacle_center.tolist() if self._obstacle else None,
            obstacle_radius=self._obstacle_radius,
            line_start=self._line_start.tolist(),
            line_end=self._line_end.tolist(),
        )
        init_mujoco_env(self, str(PLANAR_ARM_XML), frame_skip, _TIMESTEP, 20, (render_mode, width, height, camera_name))
        self._resolve_names()
        self._time = 0.0
        self._max_tracking_error = 0.0
        self._collided = False
        nominal_q = self._project_to_line_start(np.clip(seed_q, self._lower, self._upper))
        if nominal_q is None:
            raise EnvConfigError(
                f"no configuration near initial_configuration {tuple(seed_q)} puts the TCP at "
                f"line_start {tuple(self._line_start)}"
            )
        self._nominal_q: NDArray[np.float64] = nominal_q

    # ------------------------------------------------------------------ gymnasium API
    def _initialize_simulation(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        model = mujoco.MjModel.from_xml_string(self._scene_xml)
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, self.width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, self.height)
        if abs(model.opt.timestep - _TIMESTEP) > 1e-12:
            raise EnvConfigError(f"the planar arm MJCF must use a {_TIMESTEP} s timestep")
        # velocity command range follows max_joint_speed (servo and feed-forward actuators alike)
        model.actuator_ctrlrange[:] = [-self._max_joint_speed, self._max_joint_speed]
        return model, mujoco.MjData(model)

    def _set_action_space(self) -> spaces.Box:
        self.action_space = spaces.Box(-1.0, 1.0, shape=(4,), dtype=np.float32)
        return self.action_space

    def _step_mujoco_simulation(self, ctrl: NDArray[np.float64], n_frames: int) -> None:
        self.data.ctrl[:] = ctrl if self._dynamics is None else self._dynamics.delay(ctrl)
        mujoco.mj_step(self.model, self.data, nstep=n_frames)
        # mj_step leaves positions of the state before the last integration; observe the current one
        mujoco.mj_kinematics(self.model, self.data)

    # Gymnasium's MujocoEnv annotates step's reward as np.float64 and info as dict[str, np.float64], narrower than
    # gymnasium.Env's SupportsFloat and dict[str, Any], which this env returns (a float reward, mixed info values)
    def step(  # type: ignore[override]
        self, action: NDArray[np.floating]
    ) -> tuple[NDArray[np.float64], float, bool, bool, dict[str, Any]]:
        if self._backend == "python":
            action = as_action(action, 4)
            qdot_cmd = self._max_joint_speed * np.clip(action, -1.0, 1.0)
            self.do_simulation(np.concatenate([qdot_cmd, qdot_cmd]), self.frame_skip)
            self._time += self.dt
            observation = self._get_obs()
            metrics = self._metrics(self.data.qvel[self._qvel])
        else:
            action = as_action(action, 4, finite=False)
            ctrl = np.empty(8)
            if not velocity_commands(action, self._joint_speeds, ctrl):
                raise non_finite_action(action)
            dt = self.dt
            # MujocoEnv.do_simulation less its check of ctrl's shape, which holds by construction
            self._step_mujoco_simulation(ctrl, self.frame_skip)
            self._time += dt
            observation, metrics = self._compiled_state(dt)
        reward, terms = self._get_rew(metrics)
        info = {**terms, **metrics}
        if self.render_mode == "human":
            self.render()
        return observation, reward, bool(metrics["collision"]), False, info

    def reset_model(self) -> NDArray[np.float64]:
        warn_if_time_limit_short(self, self._duration, f"the line (duration={self._duration:g})")
        self._time = 0.0
        self._max_tracking_error = 0.0
        self._collided = False
        if self._dynamics is not None:
            self._drawn = self._dynamics.apply(self.model, self.data, self.np_random)
        q = None
        for _ in range(20):
            noise = self.np_random.uniform(-self._reset_noise_scale, self._reset_noise_scale, size=4)
            q = self._project_to_line_start(np.clip(self._nominal_q + noise, self._lower, self._upper))
            if q is not None:
                break
        if q is None:  # the noise kept leaving the line's reach; start from the nominal posture
            q = self._nominal_q.copy()
        self.set_state(q, np.zeros(4))
        self.data.act[self._servo_act] = q
        mujoco.mj_forward(self.model, self.data)
        if self._dynamics is not None:
            self._dynamics.start_delay(self.data.ctrl)
        return self._get_obs()

    def _get_reset_info(self) -> dict[str, Any]:
        info = self._metrics(np.zeros(4))
        if self._drawn is not None:
            info["dynamics"] = self._drawn
        return info

    # ------------------------------------------------------------------ task
    @property
    def has_obstacle(self) -> bool:
        """Whether the scene contains the obstacle sphere."""
        return self._obstacle

    def reference(self, time: float) -> tuple[NDArray[np.float64], NDArray[np.float64], float]:
        """TCP reference position [m], velocity [m/s] and phase at ``time`` [s] (quintic rest-to-rest law)."""
        tau, s, sdot = self._law(time)
        delta = self._line_end - self._line_start
        return self._line_start + s * delta, sdot * delta, tau

    def _law(self, time: float) -> tuple[float, float, float]:
        """The reference's phase ``tau`` [-], path parameter ``s(tau)`` [-] and ``ds/dt`` [1/s] at ``time`` [s]."""
        tau = min(max(time / self._duration, 0.0), 1.0)
        s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
        sdot = 30.0 * tau**2 * (1.0 - tau) ** 2 / self._duration if tau < 1.0 else 0.0
        return tau, s, sdot

    @property
    def nominal_configuration(self) -> NDArray[np.float64]:
        """Starting posture before noise [rad]: ``initial_configuration`` projected onto the line start."""
        return self._nominal_q.copy()

    @property
    def max_joint_speed(self) -> float:
        """Joint velocity command at action 1 [rad/s]."""
        return self._max_joint_speed

    @property
    def tcp_position(self) -> NDArray[np.float64]:
        """Current TCP position (x, z) [m]."""
        return self.data.site_xpos[self._tcp_site][[0, 2]].copy()

    def _get_obs(self) -> NDArray[np.float64]:
        ref_pos, ref_vel, phase = self.reference(self._time)
        center = self._obstacle_center if self._obstacle else np.zeros(2)
        radius = self._obstacle_radius if self._obstacle else 0.0
        obs = np.concatenate(
            [
                self.data.qpos[self._qpos],
                self.data.qvel[self._qvel],
                self.tcp_position,
                ref_pos,
                ref_vel,
                [phase],
                center,
                [radius],
                np.zeros(2),
            ]
        )
        if self._noise is not None:
            index, std = self._noise
            obs[index] += std * self.np_random.standard_normal(index.size)
        # the tracking error as its own entries: a learner reads a millimetre directly, not as the difference of
        # two entries of half a metre (behaviour cloning of the CLIK tracked to 1.5-3 mm without it, 0.7 mm with)
        obs[18:20] = obs[10:12] - obs[8:10]
        return obs

    def _get_rew(self, metrics: dict[str, Any]) -> tuple[float, dict[str, float]]:
        """``(reward, terms)`` from the step's metrics: the reward is the sum of ``terms``."""
        terms = {
            "reward_tracking": -self._tracking_weight * metrics["tracking_error"],
            "reward_energy": -self._energy_weight * metrics["pseudoenergy"],
            "reward_collision": -self._collision_penalty if metrics["collision"] else 0.0,
        }
        return float(sum(terms.values())), terms

    def _metrics(self, qdot: NDArray[np.float64]) -> dict[str, Any]:
        """Step metrics for ``info``; also advances the episode's running max error and collision flag."""
        ref_pos, _, phase = self.reference(self._time)
        tcp = self.tcp_position
        clearance = self._min_clearance()
        q = self.data.qpos[self._qpos]
        error = float(np.linalg.norm(tcp - ref_pos))
        self._max_tracking_error = max(self._max_tracking_error, error)
        self._collided = self._collided or clearance <= 0.0
        finished = bool(phase >= 1.0)
        goal = float(np.linalg.norm(tcp - self._line_end))
        return {
            "tracking_error": error,
            "goal_error": goal,
            "goal_reached": goal <= self._success_tolerance,
            "pseudoenergy": float(qdot @ qdot) * self.dt,
            "min_clearance": clearance,
            "collision": bool(clearance <= 0.0),
            "joint_limit_margin": float(np.min(np.minimum(q - self._lower, self._upper - q))),
            "line_finished": finished,
            "peak_joint_speed": float(np.max(np.abs(qdot))),
            "max_tracking_error": self._max_tracking_error,
            "is_success": finished and not self._collided and self._max_tracking_error <= self._success_tolerance,
            "time": self._time,
            "tcp": tcp,
            "tcp_ref": ref_pos,
        }

    def _compiled_state(self, dt: float) -> tuple[NDArray[np.float64], dict[str, Any]]:
        """:meth:`_get_obs` and :meth:`_metrics` in one compiled pass (``backend="compiled"``)."""
        d = self.data
        obs, error, goal, energy, margin, peak, tcp, ref, phase = planar_state(
            d.qpos,
            d.qvel,
            self._qpos,
            self._qvel,
            d.site_xpos[self._tcp_site],
            self._line_start,
            self._line_end,
            self._law(self._time),
            self._obstacle_features,
            self._lower,
            self._upper,
        )
        if self._noise is not None:
            index, std = self._noise
            obs[index] += std * self.np_random.standard_normal(index.size)
            obs[18:20] = obs[10:12] - obs[8:10]  # from the observed, possibly noisy, TCP
        clearance = self._min_clearance()
        self._max_tracking_error = max(self._max_tracking_error, error)
        self._collided = self._collided or clearance <= 0.0
        finished = phase >= 1.0
        return obs, {
            "tracking_error": error,
            "goal_error": goal,
            "goal_reached": goal <= self._success_tolerance,
            "pseudoenergy": energy * dt,
            "min_clearance": clearance,
            "collision": clearance <= 0.0,
            "joint_limit_margin": margin,
            "line_finished": finished,
            "peak_joint_speed": peak,
            "max_tracking_error": self._max_tracking_error,
            "is_success": finished and not self._collided and self._max_tracking_error <= self._success_tolerance,
            "time": self._time,
            "tcp": tcp,
            "tcp_ref": ref,
        }

    def _min_clearance(self) -> float:
        if self._obstacle_geom is None:
            return float("inf")
        return float(
            min(
                mujoco.mj_geomDistance(self.model, self.data, self._obstacle_geom, g, _CLEARANCE_HORIZON, None)
                for g in self._link_geoms
            )
        )

    # ------------------------------------------------------------------ helpers
    def _resolve_names(self) -> None:
        m = self.model
        joints = [m.joint(n) for n in PLANAR_ARM_JOINTS]
        self._qpos = np.array([j.qposadr[0] for j in joints])
        self._qvel = np.array([j.dofadr[0] for j in joints])
        self._lower = np.array([j.range[0] for j in joints])
        self._upper = np.array([j.range[1] for j in joints])
        self._servo_act = np.array([m.actuator_actadr[m.actuator(n).id] for n in PLANAR_ARM_SERVOS])
        servo_ids = [m.actuator(n).id for n in PLANAR_ARM_SERVOS]
        ff_ids = [m.actuator(n).id for n in PLANAR_ARM_FEEDFORWARDS]
        if servo_ids + ff_ids != list(range(8)):
            raise EnvConfigError("planar arm actuators must be the 4 servos followed by the 4 feed-forwards")
        self._tcp_site = m.site(PLANAR_ARM_TCP).id
        self._link_geoms = [m.geom(n).id for n in PLANAR_ARM_LINK_GEOMS]
        self._obstacle_geom = m.geom(PLANAR_OBSTACLE_GEOM).id if self._obstacle else None
        self._obstacle_features = (
            np.array([*self._obstacle_center, self._obstacle_radius]) if self._obstacle else np.zeros(3)
        )
        self._jacp = np.zeros((3, m.nv))
        self._scratch = mujoco.MjData(m)  # for the start-posture projection, so reset allocates nothing

    def _project_to_line_start(self, q: NDArray[np.float64], iterations: int = 50) -> NDArray[np.float64] | None:
        """Minimum-norm Newton steps from ``q`` onto ``tcp(q) == line_start``; ``None`` if it does not converge."""
        data = self._scratch
        q = q.copy()
        for _ in range(iterations):
            data.qpos[self._qpos] = q
            mujoco.mj_kinematics(self.model, data)
            mujoco.mj_comPos(self.model, data)
            error = self._line_start - data.site_xpos[self._tcp_site][[0, 2]]
            if np.linalg.norm(error) < 1e-12:
                return q
            mujoco.mj_jacSite(self.model, data, self._jacp, None, self._tcp_site)
            jac = self._jacp[[0, 2]][:, self._qvel]
            q = q + jac.T @ np.linalg.solve(jac @ jac.T + 1e-10 * np.eye(2), error)
            if np.any(q < self._lower) or np.any(q > self._upper):
                return None
        return q if np.linalg.norm(error) < 1e-9 else None


def _point(value: Sequence[float], name: str) -> NDArray[np.float64]:
    point = check_real_array(name, value, shape=(2,), what="an (x, z) pair [m] of finite real numbers")
    return np.round(point, 12) + 0.0  # to the picometre: MuJoCo's XML parser rejects subnormal numbers (no -0.0)
