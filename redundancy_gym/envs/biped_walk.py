"""BipedWalk-v0: the Lola-like biped walks forward on flat ground at a commanded speed."""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np
from gymnasium import spaces, utils
from gymnasium.envs.mujoco.mujoco_env import MujocoEnv
from gymnasium.envs.mujoco.mujoco_rendering import MujocoRenderer
from numpy.typing import NDArray

from ..assets import (
    BIPED_ANKLE_SITES,
    BIPED_JOINTS,
    BIPED_SERVOS,
    BIPED_SOFT_LIMIT_MARGIN,
    BIPED_SOLE_GEOMS,
    BIPED_XML,
)
from ..assets.biped_scene import BIPED_FLOOR_GEOM, biped_scene_xml
from ..geometry import PackedVolumes, PairBatch
from .biped_kernels import biped_metrics, biped_observation, biped_targets
from .contact_pressure import ContactPressure, contact_layout, contact_pressure, foot_of_geom
from .dynamics import BIPED_ITEMS, DynamicsRandomization, parse_dynamics
from .exceptions import EnvConfigError
from .faults import PushSchedule
from .self_collision import self_collision_pairs
from .validation import (
    MAX_FRAME_SKIP,
    as_action,
    check_backend,
    check_bool,
    check_int,
    check_known_arguments,
    check_noise,
    check_real,
    check_render_arguments,
    constructor_arguments,
    constructor_defaults,
    init_mujoco_env,
    non_finite_action,
)

__all__ = [
    "MAX_TARGET_SPEED",
    "NOMINAL_POSTURE",
    "STANDING_PELVIS_HEIGHT",
    "SUCCESS_SPEED_TOLERANCE",
    "BipedWalkEnv",
    "default_config",
]

_TIMESTEP = 0.002  # [s], the MJCF option
_NO_ENTRIES = np.zeros(0)
NOMINAL_POSTURE: dict[str, float] = {
    "r_hip_pitch": -0.5002,
    "r_knee": 0.9921,
    "r_ankle_pitch": -0.4919,
    "l_hip_pitch": -0.5002,
    "l_knee": 0.9921,
    "l_ankle_pitch": -0.4919,
    "r_shoulder_roll": -0.1835,
    "r_elbow": -0.2976,
    "l_shoulder_roll": 0.1835,
    "l_elbow": -0.2976,
}
"""Standing posture [rad] (joints not named are 0): knees bent so that the CoM is 0.91 m high, feet flat."""
MAX_TARGET_SPEED = 1.0
"""Largest ``target_speed`` [m/s]: the walking reference's fastest gait (``GaitConfig``: 0.6 m steps every 0.6 s);
it walks reliably up to about 0.9 m/s, and a command beyond its gait is walked as this one (and falls)."""
STANDING_PELVIS_HEIGHT = 0.9187
"""Pelvis height [m] of the starting posture :data:`NOMINAL_POSTURE` with the soles on the ground;
``min_base_height`` must lie below it, or every episode ends as a fall at its first step."""
SUCCESS_SPEED_TOLERANCE = 0.02
"""Smallest band [m/s] around ``target_speed`` in which the mean speed counts as a success (10 % of the command
above 0.2 m/s): standing still at ``target_speed=0`` is a success."""
_UPPER_BODY = (
    "pelvis_roll",
    "pelvis_yaw",
    "r_shoulder_pitch",
    "r_shoulder_roll",
    "r_elbow",
    "l_shoulder_pitch",
    "l_shoulder_roll",
    "l_elbow",
)


def default_config() -> dict[str, Any]:
    """Default keyword arguments of :class:`BipedWalkEnv`, the rendering ones left out (a fresh dict each call),
    read from its signature: the one place they are written."""
    return constructor_defaults(BipedWalkEnv.__init__)


class BipedWalkEnv(MujocoEnv, utils.EzPickle):
    r"""## Description
    The Lola-like biped of ``redundancy_gym/assets/biped.xml`` (1.80 m, 60 kg, 22 position-controlled joints
    on a free-floating base: 7 per leg with an active toe, pelvis roll and yaw, 3 per arm) stands on flat
    ground and must walk forward (+x) at ``target_speed``. The monograph's model-based walking controller
    (policy ``walking``) is the reference; learned policies see the same observation.

    ## Action Space
    ``Box(-1, 1, (22,), float32)``: joint position targets normalized around the standing posture,
    ``q_target = q_nominal + a * s`` with ``s`` per joint the larger distance from ``q_nominal`` to a joint
    limit, then clipped into the joint range (the order is :data:`~redundancy_gym.assets.BIPED_JOINTS`).
    The servos are MuJoCo position actuators (``kp``, ``kv``, torque limits of the MJCF); with
    ``velocity_feedforward`` the servo also tracks the targets' rate (their difference over one control period),
    as a servo drive interpolating its set points does: ``ctrl = q_target + (kv / kp) dq_target / dt``.
    Non-finite actions raise :class:`~redundancy_gym.envs.InvalidActionError`.

    ## Observation Space
    ``Box(-inf, inf, (81,), float64)``; the slices are in :attr:`OBSERVATION_LAYOUT`:

    | name | size | unit |
    |------|------|------|
    | ``base_position``: pelvis position (world) | 3 | m |
    | ``base_quaternion``: pelvis orientation ``(w, x, y, z)`` | 4 | - |
    | ``q``: joint angles | 22 | rad |
    | ``base_linear_velocity``: world frame | 3 | m/s |
    | ``base_angular_velocity``: pelvis frame | 3 | rad/s |
    | ``qdot``: joint velocities | 22 | rad/s |
    | ``right_force``, ``right_torque``: ankle sensor, sensor frame (the foot's load on the shank) | 3 + 3 | N, N m |
    | ``left_force``, ``left_torque`` | 3 + 3 | N, N m |
    | ``imu_acceleration``: torso accelerometer (includes gravity) | 3 | m/s^2 |
    | ``imu_gyro``: torso angular velocity, IMU frame | 3 | rad/s |
    | ``imu_orientation``: torso orientation ``(w, x, y, z)`` | 4 | - |
    | ``command``: ``target_speed`` | 1 | m/s |
    | ``time``: since the reset | 1 | s |

    The first 29 + 28 entries are MuJoCo's ``qpos`` and ``qvel`` (free joint first, then the joints).

    ## Rewards
    The reward is the sum of the terms in ``info``:

    - ``reward_speed = speed_weight * exp(-((v_x - target_speed) / speed_scale)^2)`` (``v_x`` the pelvis velocity
      [m/s]; at most ``speed_weight``; standing still earns ``exp(-(target_speed / speed_scale)^2)``, 0.02 at the
      defaults)
    - ``reward_lateral = -lateral_weight * v_y^2``
    - ``reward_healthy = healthy_reward`` while not fallen
    - ``reward_energy = -energy_weight * qdot^T qdot * dt`` (the pseudoenergy increment)
    - ``reward_fall = -fall_penalty`` on the step that ends the episode by a fall or a self-collision

    ``info`` also holds ``forward_speed`` (``v_x``), ``distance`` [m] (pelvis x travelled since the reset),
    ``time`` [s], ``cop`` (centre of pressure (x, y) per foot from the contact forces, rows right and left; 0
    for a foot off the ground, which ``cop_valid`` (one flag per foot) tells), ``zmp`` ((x, y) of both feet; 0 in
    flight, which ``zmp_valid`` tells), ``normal_force`` [N] per foot,
    ``contact_moments`` (ankle sensor moments in the world frame [N m], rows right and left),
    ``angular_momentum`` (whole-body, about the CoM, world frame [kg m^2/s]), ``com`` [m],
    ``min_self_clearance`` and ``min_clearance`` [m] (smallest swept-sphere distance between non-adjacent
    robot volumes), ``self_collision``, ``collision`` (the same), ``fell``, ``torso_tilt`` [rad],
    ``joint_limit_margin`` [rad], ``pseudoenergy``, ``peak_joint_speed`` [rad/s], ``speed_error``
    (``|v_x - target_speed|`` [m/s], instantaneous: it swings within every step), ``mean_speed_error``
    (``|distance / time - target_speed|`` [m/s], the episode so far) and ``is_success`` (no fall or self-collision
    so far and the mean speed ``distance / time`` within ``max(10 % of target_speed, 0.02 m/s)`` of the command: at
    ``target_speed=0`` a robot that stands, drifting less than 2 cm/s on average, succeeds; see
    :data:`SUCCESS_SPEED_TOLERANCE`).

    ## Starting State
    The standing posture :data:`NOMINAL_POSTURE` with both soles flat on the ground and the pelvis at the
    origin; the upper-body joints (pelvis, arms) get noise ``U(-reset_noise_scale, reset_noise_scale)`` [rad]
    from the env's generator; velocities are zero and the servo targets equal the joint angles.

    ## Episode End
    - Termination: a fall (pelvis below ``min_base_height`` [m] or torso tilted more than ``max_torso_tilt``
      [rad] from upright) or a self-collision (``min_self_clearance <= 0``).
    - Truncation: the time limit of the registration, 2500 steps = 10 s at the default 250 Hz.

    ## Arguments
    - ``target_speed`` ([m/s], in [0, 1]): commanded forward speed, at most :data:`MAX_TARGET_SPEED` (the walking
      reference's fastest gait).
    - ``speed_weight``, ``lateral_weight``, ``healthy_reward``, ``energy_weight``, ``fall_penalty`` (>= 0);
      ``speed_scale`` ([m/s], > 0): the width of the speed reward.
    - ``min_base_height`` ([m], in (0, 0.9187)), ``max_torso_tilt`` ([rad], in (0, pi]): the fall rule
      (``min_base_height`` below the standing pelvis height :data:`STANDING_PELVIS_HEIGHT`).
    - ``reset_noise_scale`` ([rad], >= 0): upper-body joint noise of the starting posture.
    - ``velocity_feedforward`` (bool): servo velocity feedforward from the target rate.
    - ``floor_friction`` (> 0): sliding friction of the floor.
    - ``frame_skip`` (int in [1, 1000]): physics steps of 2 ms per control step.
    - ``sensor_noise`` (fault, default None = off): zero-mean Gaussian noise added to the observation's sensor
      channels at every step and reset, drawn from the env's generator (``reset(seed=...)`` reproduces it). A
      float is the std of every sensor group, in each group's unit; a dict gives a std per group (others get
      none): ``"q"`` [rad], ``"qdot"`` [rad/s], ``"force"`` (both ankle forces) [N], ``"torque"`` (both ankle
      moments) [N m], ``"imu"`` (accelerometer [m/s^2] and gyro [rad/s]), ``"imu_orientation"`` (the quaternion's
      entries, not renormalized), ``"base"`` (the free base's position [m], quaternion, linear [m/s] and
      angular [rad/s] velocity; not in the float's groups). Example: ``{"q": 0.001, "qdot": 0.01, "force": 5.0,
      "imu": 0.01}``. ``info`` and the rewards use the true state.
    - ``push`` (fault, default None = off): external forces on a body through ``data.xfrc_applied`` (world
      frame, at the body's CoM), at control-step resolution (a push acts on the control steps that start inside
      its window), one push at a time, cleared when its window ends and at every reset. Either an explicit
      schedule, a list of ``{"time": t0 [s], "force": (fx, fy, fz) [N], "duration": d [s], "body": name}`` (the
      force acts during ``[t0, t0 + d)`` of each episode; ``body`` defaults to ``"torso"``), or a random push
      process ``{"rate": [1/s], "force": (min, max) [N], "duration": d [s], "body": name, "direction":
      "lateral" | "forward" | "any"}``: the waits before each push (from the reset, then from the end of the
      last push) are exponential with mean ``1 / rate``, the magnitude uniform in ``(min, max)``, the
      direction horizontal: ``lateral`` +-y, ``forward`` +-x (sign drawn), ``any`` uniform; all drawn from the
      env's generator. ``info["push_force"]`` is the force [N] applied during the step (zeros without one).
    - ``actuator_torque_scale`` (fault, in (0, 1], default 1): scales every servo's torque limit
      (``actuator_forcerange`` of the MJCF, 30-250 N m) as weak or worn drives; gains are unchanged.
    - ``dynamics`` (default None = off): per-reset randomization of the simulated plant, drawn from the env's
      generator (:mod:`redundancy_gym.envs.dynamics`): a level ``L`` in [0, 0.3] (every body's mass and inertia,
      joint damping and armature and servo gains scaled in ``(1 - L, 1 + L)``, CoM offsets up to ``L / 10``
      [m] per axis, the ground's friction scaled in ``(1 - 3 L, 1 + 3 L)``, ``floor(10 L)`` control periods of
      actuation latency) or a dict of items: ``mass``, ``servo_gain``, ``friction`` (scale ranges),
      ``damping``, ``frictionloss``, ``armature`` (scale ranges or ``{"range": (low, high)}``), ``com_offset``
      [m], ``latency`` [control periods: an int or a range], and ``level`` for the rest. The controllers keep the
      nominal model; ``info["dynamics"]`` of a reset says what was drawn.
    - ``backend`` (``"compiled"`` or ``"python"``): how ``info``'s contact metrics (``cop``, ``zmp``,
      ``normal_force``) are computed: one compiled pass over MuJoCo's contact arrays, or its readable reference,
      ``mj_contactForce`` per contact; both give the same values (the tests hold them equal bit for bit).
    - ``render_mode``, ``width``, ``height``, ``camera_name``: as for Gymnasium's MuJoCo envs.

    ## Version History
    - v0: initial release (0.1.0)
    """

    metadata = {"render_modes": ["human", "rgb_array", "depth_array"], "render_fps": 250}
    _SIZES = (
        ("base_position", 3),
        ("base_quaternion", 4),
        ("q", 22),
        ("base_linear_velocity", 3),
        ("base_angular_velocity", 3),
        ("qdot", 22),
        ("right_force", 3),
        ("right_torque", 3),
        ("left_force", 3),
        ("left_torque", 3),
        ("imu_acceleration", 3),
        ("imu_gyro", 3),
        ("imu_orientation", 4),
        ("command", 1),
        ("time", 1),
    )
    OBSERVATION_LAYOUT: dict[str, slice] = {}
    _start = 0
    for _name, _size in _SIZES:
        OBSERVATION_LAYOUT[_name] = slice(_start, _start + _size)
        _start += _size
    OBSERVATION_SIZE = _start
    del _name, _size, _start
    ROBOT_XML = BIPED_XML
    JOINTS = BIPED_JOINTS
    SOFT_LIMIT_MARGIN = BIPED_SOFT_LIMIT_MARGIN
    # what the policies and wrappers may rely on (redundancy_gym.policies.CAPABILITY_ATTRIBUTES)
    CAPABILITIES = frozenset({"biped"})
    _self_clearance_hint: float  # [m] the bounding-sphere margin of the next compiled self-clearance
    _mirror_clearance_hint: float  # [m] that of the mirror batch's clearance
    _bound: tuple[Any, ...] | None  # _compiled_arguments of the model's data, made at first use

    def __init__(
        self,
        target_speed: float = 0.5,
        speed_weight: float = 1.0,
        lateral_weight: float = 0.5,
        healthy_reward: float = 0.05,
        energy_weight: float = 0.001,
        fall_penalty: float = 10.0,
        min_base_height: float = 0.55,
        max_torso_tilt: float = 0.8,
        reset_noise_scale: float = 0.02,
        velocity_feedforward: bool = True,
        floor_friction: float = 1.0,
        frame_skip: int = 2,
        render_mode: str | None = None,
        width: int = 640,
        height: int = 480,
        camera_name: str | None = "track",
        sensor_noise: float | dict[str, float] | None = None,
        push: list[dict[str, Any]] | dict[str, Any] | None = None,
        actuator_torque_scale: float = 1.0,
        speed_scale: float = 0.25,
        backend: str = "compiled",
        dynamics: float | dict[str, Any] | None = None,
        **kwargs: Any,
    ) -> None:
        check_known_arguments(kwargs, BipedWalkEnv.__init__)
        utils.EzPickle.__init__(self, **constructor_arguments(BipedWalkEnv.__init__, locals()))
        self._target_speed = check_real(
            "target_speed",
            target_speed,
            low=0.0,
            high=MAX_TARGET_SPEED,
            unit="m/s",
            note="the walking reference's fastest gait, 0.6 m steps every 0.6 s; it walks reliably up to about 0.9 m/s",
        )
        self._speed_weight = check_real("speed_weight", speed_weight, low=0.0)
        self._speed_scale = check_real("speed_scale", speed_scale, low=0.0, low_open=True, unit="m/s")
        self._lateral_weight = check_real("lateral_weight", lateral_weight, low=0.0)
        self._healthy_reward = check_real("healthy_reward", healthy_reward, low=0.0)
        self._energy_weight = check_real("energy_weight", energy_weight, low=0.0)
        self._fall_penalty = check_real("fall_penalty", fall_penalty, low=0.0)
        self._min_base_height = check_real(
            "min_base_height",
            min_base_height,
            low=0.0,
            high=STANDING_PELVIS_HEIGHT,
            low_open=True,
            high_open=True,
            unit="m",
            note=f"a fall is the pelvis below it; the standing pelvis height is {STANDING_PELVIS_HEIGHT:g} m",
        )
        self._max_torso_tilt = check_real(
            "max_torso_tilt", max_torso_tilt, low=0.0, high=np.pi, low_open=True, unit="rad"
        )
        self._reset_noise_scale = check_real("reset_noise_scale", reset_noise_scale, low=0.0, unit="rad")
        self._velocity_feedforward = check_bool("velocity_feedforward", velocity_feedforward)
        self._floor_friction = check_real("floor_friction", floor_friction, low=0.0, low_open=True)
        frame_skip = check_int("frame_skip", frame_skip, low=1, high=MAX_FRAME_SKIP)
        self._torque_scale = check_real(
            "actuator_torque_scale",
            actuator_torque_scale,
            low=0.0,
            high=1.0,
            low_open=True,
            note="a fraction of the servos' torque limits",
        )
        layout = self.OBSERVATION_LAYOUT
        self._noise = check_noise(
            "sensor_noise",
            sensor_noise,
            {
                "q": (layout["q"],),
                "qdot": (layout["qdot"],),
                "force": (layout["right_force"], layout["left_force"]),
                "torque": (layout["right_torque"], layout["left_torque"]),
                "imu": (layout["imu_acceleration"], layout["imu_gyro"]),
                "imu_orientation": (layout["imu_orientation"],),
                "base": (
                    layout["base_position"],
                    layout["base_quaternion"],
                    layout["base_linear_velocity"],
                    layout["base_angular_velocity"],
                ),
            },
            ("q", "qdot", "force", "torque", "imu"),
        )
        self._push = None if push is None else PushSchedule(push, "torso")
        spec = parse_dynamics(dynamics, BIPED_ITEMS)
        self._dynamics = None if spec is None else DynamicsRandomization(spec, "pelvis")
        self._drawn: dict[str, Any] | None = None
        self._backend = check_backend("backend", backend)
        width, height = check_render_arguments(render_mode, width, height, camera_name)
        init_mujoco_env(
            self,
            str(BIPED_XML),
            frame_skip,
            _TIMESTEP,
            self.OBSERVATION_SIZE,
            (render_mode, width, height, camera_name),
        )
        self._resolve_names()
        if self._push is not None:
            ids = []
            for body in self._push.bodies:
                ids.append(mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, body))
                if ids[-1] <= 0:
                    raise EnvConfigError(
                        f"push names the body {body!r}, which the biped does not have (e.g. torso, pelvis, r_thigh)"
                    )
            self._push_bodies = ids
        self._push_force = np.zeros(3)
        self._time = 0.0
        self._start_x = 0.0
        self._targets = self._nominal.copy()
        self._fell = False
        self._self_collided = False

    # ------------------------------------------------------------------ gymnasium API
    def _scene_xml(self) -> str:
        """MJCF text of the scene to simulate (a subclass adds to it)."""
        return biped_scene_xml(floor_friction=self._floor_friction)

    def _initialize_simulation(self) -> tuple[mujoco.MjModel, mujoco.MjData]:
        model = mujoco.MjModel.from_xml_string(self._scene_xml())
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, self.width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, self.height)
        if abs(model.opt.timestep - _TIMESTEP) > 1e-12:
            raise EnvConfigError(f"the biped MJCF must use a {_TIMESTEP} s timestep")
        # the env clips targets into the joint range itself; the feedforward may take ctrl past it
        model.actuator_ctrllimited[:] = 0
        if self._torque_scale != 1.0:
            model.actuator_forcerange[: len(BIPED_SERVOS)] *= self._torque_scale
        return model, mujoco.MjData(model)

    def _recompile(self) -> None:
        """Compile the model again from :meth:`_scene_xml` (a subclass's scene changed: a new course or terrain).

        MuJoCo's renderer holds the model (and its meshes, uploaded to the GL context), so it is closed and made
        again for the new model; it opens its context lazily, at the next ``render()``. The old renderer is in no
        reference cycle, so it and its ``MjrContext`` are freed when this method returns, before the new context
        exists: an ``MjrContext`` freed later (by the cyclic garbage collector) would delete the GL objects of
        whichever context is current then, and the new renderer's frames would come out black.
        """
        old = self.mujoco_renderer
        old.close()
        self.model, self.data = self._initialize_simulation()
        self._resolve_names()
        self.mujoco_renderer = MujocoRenderer(
            self.model,
            self.data,
            old.default_cam_config,
            self.width,
            self.height,
            old.max_geom,
            self.camera_id,
            self.camera_name,
        )

    def _set_action_space(self) -> spaces.Box:
        self.action_space = spaces.Box(-1.0, 1.0, shape=(len(BIPED_JOINTS),), dtype=np.float32)
        return self.action_space

    # Gymnasium's MujocoEnv annotates step's reward as np.float64 and info as dict[str, np.float64], narrower than
    # gymnasium.Env's SupportsFloat and dict[str, Any], which this env returns (a float reward, mixed info values)
    def step(  # type: ignore[override]
        self, action: NDArray[np.floating]
    ) -> tuple[NDArray[np.float64], float, bool, bool, dict[str, Any]]:
        dt = self._dt  # MujocoEnv.dt reads the model: once per episode, at reset
        if self._backend == "python":
            action = as_action(action, len(BIPED_JOINTS))
            targets = self.targets_from_action(action)
            ctrl = targets.copy()
            if self._velocity_feedforward:
                ctrl += self._servo_lead * (targets - self._targets) / dt
        else:
            action = as_action(action, len(BIPED_JOINTS), finite=False)
            targets, ctrl = np.empty(len(BIPED_JOINTS)), np.empty(len(BIPED_JOINTS))
            if not biped_targets(
                action,
                self._nominal,
                self._scale,
                self._lower,
                self._upper,
                self._targets,
                self._servo_lead,
                dt,
                self._velocity_feedforward,
                targets,
                ctrl,
            ):
                raise non_finite_action(action)
        self._targets = targets
        x_before = float(self.data.qpos[0])
        if self._push is not None:
            self._apply_push(self._push)
        if self._dynamics is not None:
            ctrl = self._dynamics.delay(ctrl)
        # MujocoEnv.do_simulation less its check of ctrl's shape, which holds by construction
        self._step_mujoco_simulation(ctrl, self.frame_skip)
        self._time += dt
        metrics = self._metrics((float(self.data.qpos[0]) - x_before) / dt)
        reward, terms = self._get_rew(metrics)
        terminated = self._terminated(metrics)
        if self.render_mode == "human":
            self.render()
        return self._get_obs(), reward, terminated, False, {**terms, **metrics, "push_force": self._push_force.copy()}

    def _terminated(self, metrics: dict[str, Any]) -> bool:
        """Whether the step's ``metrics`` end the episode: a fall or a self-collision."""
        return bool(metrics["fell"] or metrics["self_collision"])

    def _apply_push(self, push: PushSchedule) -> None:
        """Set ``xfrc_applied`` for the coming control step from the push schedule (clear it after a push)."""
        acting = push.force_at(self._time, self.np_random)
        xfrc = self.data.xfrc_applied
        if acting is None:
            if self._push_force.any():
                xfrc[self._push_bodies, :3] = 0.0
                self._push_force = np.zeros(3)
            return
        force, body = acting
        if self._push_force.any():
            xfrc[self._push_bodies, :3] = 0.0
        xfrc[self._push_bodies[body], :3] = force
        self._push_force = np.array(force, dtype=np.float64)

    def reset_model(self) -> NDArray[np.float64]:
        if self._dynamics is not None:
            self._drawn = self._dynamics.apply(self.model, self.data, self.np_random)
        self._dt = self.dt
        self._time = 0.0
        self.data.xfrc_applied[:] = 0.0
        self._push_force = np.zeros(3)
        self._fell = False
        self._self_collided = False
        q = self._nominal.copy()
        q[self._upper_body] += self.np_random.uniform(
            -self._reset_noise_scale, self._reset_noise_scale, size=self._upper_body.size
        )
        q = np.clip(q, self._lower, self._upper)
        qpos = self.init_qpos.copy()
        qpos[:7] = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
        qpos[7:] = q
        self.set_state(qpos, np.zeros(self.model.nv))
        # stand the soles on the ground: lift the base by the lowest sole corner's depth
        qpos[2] = -self._lowest_sole_point()
        self.set_state(qpos, np.zeros(self.model.nv))
        self._targets = q.copy()
        self.data.ctrl[:] = q
        if self._dynamics is not None:
            self._dynamics.start_delay(self.data.ctrl)
        self._start_x = float(self.data.qpos[0])
        if self._push is not None:
            self._push.reset(self.np_random)
        return self._get_obs()

    def _get_reset_info(self) -> dict[str, Any]:
        info = {**self._metrics(0.0), "push_force": np.zeros(3)}
        if self._drawn is not None:
            info["dynamics"] = self._drawn
        return info

    # ------------------------------------------------------------------ task
    @property
    def target_speed(self) -> float:
        """Commanded forward speed [m/s]."""
        return self._target_speed

    @property
    def nominal_configuration(self) -> NDArray[np.float64]:
        """The standing posture of the joints [rad] (action 0)."""
        return self._nominal.copy()

    @property
    def action_scale(self) -> NDArray[np.float64]:
        """Target per unit action [rad] per joint."""
        return self._scale.copy()

    @property
    def servo_stiffness(self) -> NDArray[np.float64]:
        """The position servos' stiffness ``k_p`` [N m/rad] per joint in :data:`BIPED_JOINTS` order, as the model
        file gives it (what a model-based controller knows of its plant: the IKD walker feeds its torques forward
        over it)."""
        return self._stiffness.copy()

    @property
    def joint_limits(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Hardware joint limits [rad] (lower, upper) in :data:`BIPED_JOINTS` order."""
        return self._lower.copy(), self._upper.copy()

    def targets_from_action(self, action: NDArray[np.floating]) -> NDArray[np.float64]:
        """Joint position targets [rad] of a normalized action (clipped into the joint range)."""
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        return np.clip(self._nominal + a * self._scale, self._lower, self._upper)

    def action_from_targets(self, targets: NDArray[np.floating]) -> NDArray[np.float64]:
        """The normalized action that commands ``targets`` [rad] (inverse of :meth:`targets_from_action`)."""
        return np.clip((np.asarray(targets, dtype=np.float64) - self._nominal) / self._scale, -1.0, 1.0)

    def _get_obs(self) -> NDArray[np.float64]:
        d = self.data
        tail = self._observation_tail()
        if self._backend == "python":
            obs = np.concatenate([d.qpos, d.qvel, d.sensordata[self._sensors], [self._target_speed, self._time], tail])
        else:
            qpos, qvel, sensordata, sensors = self._compiled_arguments()[2]
            obs = biped_observation(qpos, qvel, sensordata, sensors, self._target_speed, self._time, tail)
        if self._noise is not None:
            index, std = self._noise
            obs[index] += std * self.np_random.standard_normal(index.size)
        return obs

    def _observation_tail(self) -> NDArray[np.float64]:
        """The observation's entries after ``time`` (none here; a subclass's own)."""
        return _NO_ENTRIES

    def _get_rew(self, metrics: dict[str, Any]) -> tuple[float, dict[str, float]]:
        """``(reward, terms)`` from the step's metrics: the reward is the sum of ``terms``."""
        ended = metrics["fell"] or metrics["self_collision"]
        terms = {
            # a bounded tracking reward: standing still (v_x = 0) earns exp(-(target / scale)^2), 2 % at 0.5 m/s
            "reward_speed": self._speed_weight
            * math.exp(-(((metrics["forward_speed"] - self._target_speed) / self._speed_scale) ** 2)),
            "reward_lateral": -self._lateral_weight * metrics["lateral_speed"] ** 2,
            "reward_healthy": 0.0 if ended else self._healthy_reward,
            "reward_energy": -self._energy_weight * metrics["pseudoenergy"],
            "reward_fall": -self._fall_penalty if ended else 0.0,
        }
        return float(sum(terms.values())), terms

    # ------------------------------------------------------------------ metrics
    def _metrics(self, forward_speed: float) -> dict[str, Any]:
        if self._backend == "python":
            return self._metrics_python(forward_speed)
        data, state, _, own, other = self._compiled_arguments()
        mujoco.mj_subtreeVel(self.model, data)
        contacts = data.contact
        (tilt, margin, energy, peak, moments, angmom, com, cop, cop_valid, zmp, zmp_valid, normal, clearance, other) = (
            biped_metrics(
                state,
                (
                    contacts.dist,
                    data.ncon,
                    self._contact_layout,
                    data.efc_force,
                    data.efc_type,
                    self._foot_of_geom,
                    self._ground[0],
                    self._ground[1],
                ),
                (*own, self._self_clearance_hint, *other, self._mirror_clearance_hint),
            )
        )
        # exact: only the pairs near the last step's clearances were computed (the limbs move little in a step)
        if clearance <= 1e6:
            self._self_clearance_hint = max(clearance, 0.0) + 0.05
        self._mirror_clearance = other
        pressure = ContactPressure(cop, cop_valid, zmp, bool(zmp_valid), normal)
        return self._metrics_info(
            forward_speed, pressure, tilt, clearance, (moments, angmom, com), (margin, energy * self._dt, peak)
        )

    def _compiled_arguments(self) -> tuple[Any, ...]:
        """The compiled step's arguments that stay while ``data`` does: ``(data, biped_metrics' state tuple,
        biped_observation's arrays, the robot batch's address, the mirror batch's)``, made once per MjData (each
        attribute read of an MjData makes a new array view: some twenty a step otherwise)."""
        bound = self._bound
        if bound is not None and bound[0] is self.data:
            return bound
        d = self.data
        mirror = self._mirror_batch
        state = (
            d.qpos,
            d.qvel,
            self._lower,
            self._upper,
            d.xmat[self._torso],
            d.site_xmat,
            self._ankle_sites_array,
            d.sensordata,
            self._torque_adr_array,
            d.geom_xpos,
            d.geom_xmat,
            self._ssv_geoms,
            self._half_length,
            self._batch.vertices,
            self._batch.vertices if mirror is None else mirror.vertices,
            d.subtree_angmom,
            d.subtree_com,
            self._pelvis,
        )
        observation = (d.qpos, d.qvel, d.sensordata, self._sensors)
        other = (0, 0, 0) if mirror is None else mirror.address
        bound = (d, state, observation, self._batch.address, other)
        self._bound = bound
        return bound

    def _metrics_info(
        self,
        forward_speed: float,
        pressure: ContactPressure,
        tilt: float,
        clearance: float,
        loads: tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]],
        joints: tuple[float, float, float],
    ) -> dict[str, Any]:
        """The step's ``info`` from its numbers, both backends' (``loads``: contact moments [N m], angular
        momentum [kg m^2/s], CoM [m]; ``joints``: limit margin [rad], pseudoenergy, peak speed [rad/s]); advances
        the episode's fall and self-collision flags."""
        d = self.data
        moments, angmom, com = loads
        margin, pseudoenergy, peak = joints
        fell = bool(d.qpos[2] - self._ground_under_base() < self._min_base_height or tilt > self._max_torso_tilt)
        self._fell = self._fell or fell
        self._self_collided = self._self_collided or clearance <= 0.0
        distance = float(d.qpos[0]) - self._start_x
        mean_speed = distance / self._time if self._time > 0.0 else 0.0
        ok = not (self._fell or self._self_collided)
        speed = float(forward_speed)
        mean_error = abs(mean_speed - self._target_speed)
        return {
            "time": self._time,
            "forward_speed": speed,
            "lateral_speed": float(d.qvel[1]),
            "distance": distance,
            "cop": pressure.cop,
            "cop_valid": pressure.cop_valid,
            "zmp": pressure.zmp,
            "zmp_valid": pressure.zmp_valid,
            "normal_force": pressure.normal,
            "contact_moments": moments,
            "angular_momentum": angmom,
            "com": com,
            "min_self_clearance": clearance,
            "min_clearance": clearance,
            "self_collision": bool(clearance <= 0.0),
            "collision": bool(clearance <= 0.0),
            "fell": fell,
            "torso_tilt": tilt,
            "joint_limit_margin": margin,
            "pseudoenergy": pseudoenergy,
            "peak_joint_speed": peak,
            "speed_error": abs(speed - self._target_speed),
            "mean_speed_error": mean_error,
            "is_success": bool(
                ok and self._time > 0.0 and mean_error <= max(0.1 * self._target_speed, SUCCESS_SPEED_TOLERANCE)
            ),
        }

    def _metrics_python(self, forward_speed: float) -> dict[str, Any]:
        """:meth:`_metrics` with NumPy: the readable reference of the compiled one (``backend="python"``)."""
        m, d = self.model, self.data
        qdot = d.qvel[6:]
        pressure = contact_pressure(m, d, self._ground, self._foot_of_geom)
        torso = d.xmat[self._torso].reshape(3, 3)
        tilt = float(np.arccos(np.clip(torso[2, 2], -1.0, 1.0)))
        clearance = self._self_clearance()
        mujoco.mj_subtreeVel(m, d)
        moments = np.array(
            [
                d.site_xmat[s].reshape(3, 3) @ -d.sensordata[a : a + 3]
                for s, a in zip(self._ankle_sites, self._torque_adr, strict=False)
            ]
        )
        angmom, com = d.subtree_angmom[self._pelvis].copy(), d.subtree_com[self._pelvis].copy()
        margin = float(np.min(np.minimum(d.qpos[7:] - self._lower, self._upper - d.qpos[7:])))
        joints = (margin, float(qdot @ qdot) * self.dt, float(np.max(np.abs(qdot))))
        return self._metrics_info(forward_speed, pressure, tilt, clearance, (moments, angmom, com), joints)

    def _ground_under_base(self) -> float:
        """Height [m] of the ground under the pelvis, which the fall rule's ``min_base_height`` is measured from
        (flat ground here: 0; BipedTerrain's terrain height)."""
        return 0.0

    def _self_clearance(self) -> float:
        """Smallest SSV distance between non-adjacent robot volumes [m] (capsules -> LSS, spheres -> PSS)."""
        d = self.data
        positions = d.geom_xpos[self._ssv_geoms]
        axes = d.geom_xmat[self._ssv_geoms][:, [2, 5, 8]]  # the local z axis: capsules lie along it
        offset = axes * self._half_length[:, None]
        vertices = self._batch.vertices
        vertices[:, 0] = positions - offset
        vertices[:, 1] = positions + offset
        vertices[:, 2] = vertices[:, 1]
        return float(np.min(self._batch.compute().distance))

    def _lowest_sole_point(self) -> float:
        mujoco.mj_kinematics(self.model, self.data)
        lowest = np.inf
        for g in self._sole_geoms:
            center, frame, half = self.data.geom_xpos[g], self.data.geom_xmat[g].reshape(3, 3), self.model.geom_size[g]
            corners = center + (np.array(np.meshgrid(*[[-1, 1]] * 3)).reshape(3, -1).T * half) @ frame.T
            lowest = min(lowest, float(corners[:, 2].min()))
        return lowest

    def _resolve_names(self) -> None:
        m = self.model
        joints = [m.joint(j).id for j in BIPED_JOINTS]
        if [m.jnt_qposadr[j] for j in joints] != list(range(7, 7 + len(joints))):
            raise EnvConfigError("the biped's hinge joints must follow the free joint in BIPED_JOINTS order")
        if [m.actuator(s).id for s in BIPED_SERVOS] != list(range(len(BIPED_SERVOS))):
            raise EnvConfigError("the biped's servos must be the first actuators in BIPED_SERVOS order")
        self._lower = m.jnt_range[joints, 0].copy()
        self._upper = m.jnt_range[joints, 1].copy()
        self._nominal = np.array([NOMINAL_POSTURE.get(j, 0.0) for j in BIPED_JOINTS])
        self._scale = np.maximum(self._nominal - self._lower, self._upper - self._nominal)
        self._stiffness = m.actuator_gainprm[: len(BIPED_SERVOS), 0].copy()
        self._servo_lead = -m.actuator_biasprm[: len(BIPED_SERVOS), 2] / self._stiffness
        self._upper_body = np.array([BIPED_JOINTS.index(j) for j in _UPPER_BODY])
        names = (
            "r_ankle_force",
            "r_ankle_torque",
            "l_ankle_force",
            "l_ankle_torque",
            "imu_accelerometer",
            "imu_gyro",
            "imu_orientation",
        )
        self._sensors = np.concatenate(
            [np.arange(m.sensor(n).adr[0], m.sensor(n).adr[0] + m.sensor(n).dim[0]) for n in names]
        )
        self._torque_adr = [int(m.sensor(n).adr[0]) for n in ("r_ankle_torque", "l_ankle_torque")]
        self._ankle_sites = [m.site(s).id for s in BIPED_ANKLE_SITES]
        self._torque_adr_array = np.array(self._torque_adr, dtype=np.int64)
        self._ankle_sites_array = np.array(self._ankle_sites, dtype=np.int64)
        self._pelvis = m.body("pelvis").id
        self._torso = m.body("torso").id
        floor = m.geom(BIPED_FLOOR_GEOM).id
        # the ground's geom ids [low, high): the floor (BipedTerrain's terrain geoms follow it)
        self._ground = (floor, floor + 1)
        self._sole_geoms = [m.geom(g).id for g in BIPED_SOLE_GEOMS]
        self._contact_layout = contact_layout(self.data)
        self._foot_of_geom = foot_of_geom(
            m.ngeom, {g: (0 if BIPED_SOLE_GEOMS[k].startswith("r_") else 1) for k, g in enumerate(self._sole_geoms)}
        )
        robot = [
            g
            for g in range(m.ngeom)
            if m.geom_bodyid[g] != 0
            and int(m.geom_type[g]) in (int(mujoco.mjtGeom.mjGEOM_SPHERE), int(mujoco.mjtGeom.mjGEOM_CAPSULE))
        ]
        self._ssv_geoms = np.array(robot, dtype=np.int64)
        capsule = m.geom_type[self._ssv_geoms] == int(mujoco.mjtGeom.mjGEOM_CAPSULE)
        self._half_length = np.where(capsule, m.geom_size[self._ssv_geoms, 1], 0.0)
        pairs = self_collision_pairs(m, self._ssv_geoms)
        volumes = PackedVolumes(
            np.zeros((len(robot), 3, 3)), m.geom_size[self._ssv_geoms, 0].copy(), capsule.astype(np.int64)
        )
        self._batch = PairBatch(volumes, pairs[:, 0], pairs[:, 1])
        # a pair batch holding the robot's volumes first (BipedObstacles' obstacles): the compiled step places them
        # there too and returns its smallest distance from this margin [m]
        self._mirror_batch: PairBatch | None = None
        self._bound = None
        self._mirror_clearance_hint = 0.25
        self._mirror_clearance = math.inf
        self._self_clearance_hint = 0.05  # [m] the first bounding-sphere margin of the compiled self-clearance
