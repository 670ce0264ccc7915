"""AgriReach-v0: a CROPS-like 9-DoF arm reaching a sweet pepper's grasp pose among stems and leaves."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces, utils
from numpy.typing import NDArray

from ..assets import (
    AGRI_ARM_FEEDFORWARDS,
    AGRI_ARM_GEOMS,
    AGRI_ARM_JOINTS,
    AGRI_ARM_SERVOS,
    AGRI_ARM_TCP,
    AGRI_ARM_XML,
)
from ..assets.agri_scene import PLANT_COLORS, POOL_CATEGORIES, TARGET_COLOR, agri_scene_xml, pool_geom_name
from ..assets.crop_row import DIFFICULTIES, PART_REACH, CropRow, crop_row_defaults, generate_crop_row
from ..geometry import LSS, GraspPath, GraspPathTiming, PackedVolumes, PairBatch, indexed_distances
from .agri_kernels import agri_state
from .command_kernels import velocity_commands
from .dynamics import ARM_ITEMS, DynamicsRandomization, parse_dynamics
from .exceptions import EnvConfigError, InvalidActionError
from .self_collision import self_collision_pairs as _self_collision_pairs
from .validation import (
    MAX_FRAME_SKIP,
    as_action,
    check_backend,
    check_bool,
    check_choice,
    check_int,
    check_known_arguments,
    check_noise,
    check_range_pair,
    check_real,
    check_render_arguments,
    constructor_arguments,
    constructor_defaults,
    non_finite_action,
    warn_if_time_limit_short,
)

__all__ = ["AgriReachEnv", "default_config"]

_REACH = 1.29  # [m] shoulder axis to TCP
_SHOULDER_Z = (0.55, 1.35)  # [m] shoulder height over the lift range
_ARM_RADIUS = 0.075  # [m] thickest arm volume
MAX_PREGRASP_DISTANCE = 0.5
"""Longest ``pregrasp_distance`` [m]: the pre-grasp point must stay within the arm's reach of the near row."""
MIN_FRUIT_DIAMETER = 0.07
"""Smallest ``fruit_diameter`` [m] whose peppers leave the approach corridor clear of their own stem."""
_CORRIDOR = (0.02, 0.55, 0.05)  # behind the grasp point along -approach: from, to [m], radius [m]
_OBSTACLE_FEATURES = 15  # mask, one-hot kind (3), hard, 9 vertex coordinates, radius


def default_config() -> dict[str, Any]:
    """Default keyword arguments of :class:`AgriReachEnv`, the rendering ones left out (a fresh dict each call),
    read from its signature: the one place they are written."""
    return constructor_defaults(AgriReachEnv.__init__)


class AgriReachEnv(gym.Env, utils.EzPickle):
    r"""## Description
    A CROPS-like redundant agricultural manipulator (monograph 5.3, figs. 5.8-5.10): one prismatic lift and
    eight revolute joints (``redundancy_gym/assets/agri_arm.xml``) on a trolley in the path of a double-row
    sweet-pepper crop. The task is to bring the tool centre point (TCP) to the grasp pose of one reachable
    pepper: at the fruit centre with the tool axis along the approach direction, which points radially
    towards the stem, tilted 0-30 deg up (approach from below). A sensible motion passes the pre-grasp pose
    ``pregrasp_distance`` in front of the fruit and approaches in a straight line, as the ``clik`` reference does.

    Stems, side shoots and other peppers are hard obstacles: touching one (swept-sphere distance <= 0) is a
    collision and ends the episode; so does a self-collision (non-adjacent links, or a link and the lift
    column). Leaves and petioles are soft: contact is allowed, counted and penalized. Contacts are judged on
    the swept-sphere model (arm capsules/spheres, stems LSS, leaves TSS, peppers PSS); MuJoCo simulates the
    arm with contacts disabled and draws the plants. With ``prune`` (default) only the plant parts within the
    arm's reach (a capsule around the lift column) are placed into the scene, the collision model and the
    observation candidates; the scene is compiled once with room for them, and a reset never recompiles.

    ## Action Space
    ``Box(-1, 1, (9,), float32)``: joint velocity commands normalized by ``max_lift_speed`` [m/s] (lift) and
    ``max_joint_speed`` [rad/s] (the eight revolute joints). Non-finite actions raise
    :class:`~redundancy_gym.envs.InvalidActionError`.

    ## Observation Space
    ``Box(-inf, inf, (48 + 15 K,), float64)`` with ``K = observed_obstacles``; slices in
    :attr:`observation_layout` (robot base frame = world frame, the trolley stands at the origin):

    | name | size | content |
    |------|------|---------|
    | ``q`` | 9 | joint positions [m, rad] |
    | ``qdot`` | 9 | joint velocities [m/s, rad/s] |
    | ``tcp_position`` | 3 | TCP position [m] |
    | ``tcp_quaternion`` | 4 | TCP orientation (w, x, y, z); its x axis is the tool axis |
    | ``grasp_position`` | 3 | grasp point (pepper centre) [m] |
    | ``approach`` | 3 | unit approach direction (the tool axis at the grasp pose) |
    | ``pregrasp_position`` | 3 | ``grasp - pregrasp_distance * approach`` [m] |
    | ``time`` | 1 | time since reset [s] |
    | ``tcp_reference`` | 6 | the reference path's TCP position [m] and tool axis (unit) now (``info["tcp_ref"]``) |
    | ``tcp_reference_velocity`` | 6 | the reference's velocity [m/s] and angular velocity [rad/s] now |
    | ``tcp_error`` | 3 | reference position minus the observed, possibly noisy, TCP position [m] |
    | ``obstacles`` | 15 K | the K plant parts nearest to the approach corridor, one row each (below) |

    Each ``obstacles`` row is ``[mask, PSS, LSS, TSS, hard, v0, v1, v2, radius]``: one-hot kind, vertices [m],
    radius [m]; unused vertices repeat the last one; zero rows with mask 0 pad.

    ## Rewards
    The reward is the sum of the terms in ``info``: ``reward_position = -position_weight * |p_tcp - p_grasp|``,
    ``reward_orientation = -orientation_weight * angle(tool axis, approach)``, ``reward_energy =
    -energy_weight * qdot^T qdot dt``, ``reward_leaf = -leaf_penalty * (leaves touched this step)``,
    ``reward_collision = -collision_penalty`` on a collision, ``reward_success = success_bonus`` on success.

    ``info`` also holds ``goal_error`` (TCP distance to the grasp point [m]), ``orientation_error`` [rad]
    (tool axis against the approach direction), ``goal_reached`` (both within the success tolerances),
    ``tracking_error`` (TCP distance [m] to the env's reference path at the current time: a quintic move from
    the start pose to the pre-grasp pose, then a straight approach, timed by the ``reference_*`` arguments; the
    ``clik`` reference follows this path, a learned policy need not), ``pseudoenergy``
    [rad^2/s], ``min_clearance`` [m] (the smaller of ``min_obstacle_clearance``, the smallest swept-sphere distance
    between the arm and a hard plant part, and ``min_self_clearance``, between non-adjacent
    links; values beyond ``clearance_horizon`` are reported as the horizon), ``collision``, ``leaf_contacts``
    (this step), ``leaf_contacts_total``, ``joint_limit_margin`` (smallest distance to a limit [m or rad]),
    ``peak_joint_speed``, ``is_success`` (TCP within ``success_position_tolerance`` and
    ``success_angle_tolerance`` of the grasp pose, no collision), ``time`` [s], ``tcp`` and ``tcp_ref`` (the
    reference path's point) [m].

    ## Starting State
    A new crop row is drawn from the env's generator at every reset (difficulty presets plus explicit
    quantities), then a target: a pepper of the near row in the harvest band facing the arm, whose pre-grasp
    pose is reachable and whose approach corridor is clear of hard obstacles. The arm starts folded towards
    the row, with the lift at the target's height, plus ``U(-reset_noise_scale, reset_noise_scale)`` joint noise.

    ## Episode End
    - Termination: success, or a collision with a hard obstacle or between links.
    - Truncation: the time limit of the registration (500 steps = 5 s at the default 100 Hz).

    ## Arguments
    - ``difficulty``: ``"easy" | "medium" | "hard"`` presets of ``leaves_per_stem``, ``fruits_per_stem``,
      ``shoot_probability`` (occluding side shoots) and ``cluster_spread`` (fruit clusters); each may be given
      explicitly instead (``None`` keeps the preset).
    - ``row_distance``, ``row_gap``, ``row_length`` [m] (> 0); ``stem_spacing``, ``stem_diameter``,
      ``fruit_diameter`` (ranges (low, high) [m], both > 0, fruits at least 0.07 m; the stem spacing at least the
      largest stem diameter); ``harvest_band`` ((low, high) [m], >= 0, at least ``cluster_spread`` high).
    - ``prune`` (bool): place only the parts within the arm's reach.
    - ``pregrasp_distance`` [m], in (0, 0.5]; ``approach_elevation`` ((min, max) [deg] of the upward tilt of the
      approach).
    - ``observed_obstacles`` (K >= 0).
    - ``max_joint_speed`` [rad/s], ``max_lift_speed`` [m/s]: velocity commands at action 1.
    - ``position_weight``, ``orientation_weight``, ``energy_weight``, ``leaf_penalty``, ``collision_penalty``,
      ``success_bonus`` (>= 0): reward weights.
    - ``success_position_tolerance`` [m], ``success_angle_tolerance`` [deg].
    - ``clearance_horizon`` [m]: pairs farther than this (by bounding spheres) are not computed exactly.
    - ``reset_noise_scale`` [m, rad]; ``frame_skip`` (int in [1, 1000]: physics steps of 10 ms per control step).
    - ``reference_speed`` [m/s], ``reference_turn_rate`` [rad/s], ``reference_min_duration`` [s],
      ``reference_approach_speed`` [m/s]: the timing of the reference path (average TCP speed and tool-axis turn
      rate of the move to the pre-grasp pose, its shortest duration, the approach speed). The shortest
      duration of 1.5 s keeps the path within the joints' speed limits: with 1.0 s the ``clik`` reference
      saturated at ``max_joint_speed`` for about 0.5 s and lagged up to 24 mm behind the path (0.5 mm rms
      and 4 mm max with 1.5 s, over 30 seeds).
    - ``obs_noise`` (fault, default None = off): zero-mean Gaussian noise added to the measured channels of the
      observation at every step and reset, drawn from the env's generator (``reset(seed=...)`` reproduces it);
      a float std applies to ``q`` [m, rad], ``qdot`` [m/s, rad/s] and ``tcp`` (``tcp_position``) [m] alike, a
      dict gives one per group (``{"q": 0.001, "qdot": 0.01, "tcp": 0.001, "tcp_quaternion": 0.001}``; groups
      not named get none; the quaternion's entries are not renormalized). The episode constants (grasp,
      approach, pre-grasp, obstacles), ``time`` and the reference entries stay exact (``tcp_error`` is computed
      from the noisy TCP), and ``info`` and the rewards use the true state.
    - ``dynamics`` (default None = off): per-reset randomization of the simulated plant, drawn from the env's
      generator (:mod:`redundancy_gym.envs.dynamics`): a level ``L`` in [0, 0.3] (every body's mass and inertia,
      joint damping and armature and servo gains scaled in ``(1 - L, 1 + L)``, CoM offsets and the base's
      placement up to ``L / 10`` [m] per axis, a payload up to ``10 L`` [kg] at the TCP, ``floor(10 L)`` control
      periods of actuation latency) or a dict of items: ``mass``, ``servo_gain`` (scale ranges), ``damping``,
      ``frictionloss``, ``armature`` (scale ranges or ``{"range": (low, high)}``), ``com_offset``,
      ``placement`` [m], ``payload`` [kg range], ``latency`` [control periods: an int or a range], and ``level``
      for the rest. The controllers keep the nominal model; ``info["dynamics"]`` of a reset says what was drawn.
    - ``backend`` (``"compiled"`` or ``"python"``): how a step computes its commands, its observation and the
      numbers of ``info``: in two compiled kernels, the reference path sampled once, or with NumPy, the readable
      reference the tests hold them equal to (bit for bit; ``goal_error`` and ``tracking_error`` to round-off).
    - ``render_mode`` (``"rgb_array"``), ``width``, ``height``, ``camera_name`` (``"side"`` or ``"front"``).

    ## Version History
    - v0: initial release (0.1.0)
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 100}
    ROBOT_XML = AGRI_ARM_XML
    TCP_FRAME = AGRI_ARM_TCP
    # what the policies and wrappers may rely on (redundancy_gym.policies.CAPABILITY_ATTRIBUTES)
    CAPABILITIES = frozenset({"grasp_task"})
    # the episode's running state (set at reset by _reset_episode_state): time [s], any collision so far, leaves touched
    _time: float
    _collided: bool
    _leaf_total: int

    def __init__(
        self,
        difficulty: str = "medium",
        leaves_per_stem: int | None = None,
        fruits_per_stem: Sequence[int] | None = None,
        shoot_probability: float | None = None,
        cluster_spread: float | None = None,
        row_distance: float = 1.05,
        row_gap: float = 0.45,
        row_length: float = 8.0,
        stem_spacing: Sequence[float] = (0.25, 0.35),
        stem_diameter: Sequence[float] = (0.010, 0.015),
        fruit_diameter: Sequence[float] = (0.08, 0.09),
        harvest_band: Sequence[float] = (0.9, 1.3),
        prune: bool = True,
        pregrasp_distance: float = 0.15,
        approach_elevation: Sequence[float] = (0.0, 30.0),
        observed_obstacles: int = 32,
        max_joint_speed: float = 1.5,
        max_lift_speed: float = 0.4,
        position_weight: float = 1.0,
        orientation_weight: float = 0.2,
        energy_weight: float = 10.0,
        leaf_penalty: float = 0.1,
        collision_penalty: float = 200.0,
        success_bonus: float = 10.0,
        success_position_tolerance: float = 0.01,
        success_angle_tolerance: float = 10.0,
        clearance_horizon: float = 0.1,
        reset_noise_scale: float = 0.05,
        frame_skip: int = 1,
        reference_speed: float = 0.35,
        reference_turn_rate: float = 0.8,
        reference_min_duration: float = 1.5,
        reference_approach_speed: float = 0.12,
        render_mode: str | None = None,
        width: int = 480,
        height: int = 480,
        camera_name: str = "side",
        obs_noise: float | dict[str, float] | None = None,
        backend: str = "compiled",
        dynamics: float | dict[str, Any] | None = None,
        **kwargs: Any,
    ) -> None:
        check_known_arguments(kwargs, AgriReachEnv.__init__)
        utils.EzPickle.__init__(self, **constructor_arguments(AgriReachEnv.__init__, locals()))
        check_choice("difficulty", difficulty, DIFFICULTIES)
        scene = crop_row_defaults(difficulty)
        if leaves_per_stem is not None:
            scene["leaves_per_stem"] = check_int("leaves_per_stem", leaves_per_stem, low=0)
        if fruits_per_stem is not None:
            scene["fruits_per_stem"] = check_range_pair("fruits_per_stem", fruits_per_stem, low=0, integer=True)
        if shoot_probability is not None:
            scene["shoot_probability"] = check_real("shoot_probability", shoot_probability, low=0.0, high=1.0)
        if cluster_spread is not None:
            scene["cluster_spread"] = check_real("cluster_spread", cluster_spread, low=0.0, unit="m")
        positive: dict[str, Any] = {"low": 0.0, "low_open": True, "unit": "m"}  # a length > 0 [m]
        scene.update(
            row_distance=check_real("row_distance", row_distance, **positive),
            row_gap=check_real("row_gap", row_gap, **positive),
            row_length=check_real("row_length", row_length, **positive),
            stem_spacing=check_range_pair("stem_spacing", stem_spacing, **positive),
            stem_diameter=check_range_pair("stem_diameter", stem_diameter, **positive),
            fruit_diameter=check_range_pair("fruit_diameter", fruit_diameter, **positive),
            harvest_band=check_range_pair("harvest_band", harvest_band, low=0.0, unit="m"),
        )
        if scene["stem_spacing"][0] < scene["stem_diameter"][1]:
            raise EnvConfigError(
                f"stem_spacing must not let stems overlap: its low {scene['stem_spacing'][0]:g} m "
                f"is below the largest stem_diameter {scene['stem_diameter'][1]:g} m"
            )
        if scene["fruit_diameter"][0] < MIN_FRUIT_DIAMETER:
            raise EnvConfigError(
                f"fruit_diameter must be at least {MIN_FRUIT_DIAMETER} m (a smaller pepper sits so close "
                f"to its stem that the gripper's approach corridor, {_CORRIDOR[2]} m in radius, "
                f"touches the stem), got {fruit_diameter!r}"
            )
        if scene["row_length"] < 2.0 * scene["stem_spacing"][1]:
            raise EnvConfigError(
                f"row_length must hold at least two plants: >= 2 x the largest stem_spacing = "
                f"{2.0 * scene['stem_spacing'][1]:g} m, got {scene['row_length']:g} m"
            )
        if scene["harvest_band"][1] - scene["harvest_band"][0] < scene["cluster_spread"]:
            raise EnvConfigError(
                f"harvest_band must be at least cluster_spread = {scene['cluster_spread']:g} m high, "
                f"got {harvest_band!r}"
            )
        self._scene = scene
        self._difficulty = difficulty
        self._prune = check_bool("prune", prune)
        self._pregrasp_distance = check_real(
            "pregrasp_distance", pregrasp_distance, high=MAX_PREGRASP_DISTANCE, **positive
        )
        elevation = check_range_pair("approach_elevation", approach_elevation, low=0.0, high=60.0, unit="deg")
        self._elevation = np.deg2rad(elevation)
        self._k = check_int("observed_obstacles", observed_obstacles, low=0)
        self._max_joint_speed = check_real("max_joint_speed", max_joint_speed, low=0.0, low_open=True, unit="rad/s")
        self._max_lift_speed = check_real("max_lift_speed", max_lift_speed, low=0.0, low_open=True, unit="m/s")
        self._weights = {
            name: check_real(name, value, low=0.0)
            for name, value in (
                ("position_weight", position_weight),
                ("orientation_weight", orientation_weight),
                ("energy_weight", energy_weight),
                ("leaf_penalty", leaf_penalty),
                ("collision_penalty", collision_penalty),
                ("success_bonus", success_bonus),
            )
        }
        self._success_position = check_real("success_position_tolerance", success_position_tolerance, **positive)
        self._success_angle = np.deg2rad(
            check_real("success_angle_tolerance", success_angle_tolerance, low=0.0, low_open=True, unit="deg")
        )
        self._horizon = check_real("clearance_horizon", clearance_horizon, **positive)
        self.reference_timing = GraspPathTiming(
            check_real("reference_speed", reference_speed, low=0.0, low_open=True, unit="m/s"),
            check_real("reference_turn_rate", reference_turn_rate, low=0.0, low_open=True, unit="rad/s"),
            check_real("reference_min_duration", reference_min_duration, low=0.0, unit="s"),
            check_real("reference_approach_speed", reference_approach_speed, low=0.0, low_open=True, unit="m/s"),
        )
        self._path: GraspPath | None = None
        self._reset_noise_scale = check_real("reset_noise_scale", reset_noise_scale, low=0.0)
        self.frame_skip = check_int("frame_skip", frame_skip, low=1, high=MAX_FRAME_SKIP)
        check_choice("camera_name", camera_name, ("side", "front"))
        width, height = check_render_arguments(
            render_mode, width, height, camera_name, tuple(self.metadata["render_modes"])
        )
        self.render_mode = render_mode
        self.width, self.height, self.camera_name = width, height, camera_name

        self.model = mujoco.MjModel.from_xml_string(agri_scene_xml(self._pool_capacity()))
        self.model.vis.global_.offwidth = max(self.model.vis.global_.offwidth, self.width)
        self.model.vis.global_.offheight = max(self.model.vis.global_.offheight, self.height)
        self.data = mujoco.MjData(self.model)
        self.dt = float(self.model.opt.timestep * self.frame_skip)
        self.metadata = {"render_modes": ["rgb_array"], "render_fps": int(np.round(1.0 / self.dt))}
        self._resolve_names()
        self._renderer: mujoco.Renderer | None = None

        self.action_space = spaces.Box(-1.0, 1.0, shape=(9,), dtype=np.float32)
        sizes = {
            "q": 9,
            "qdot": 9,
            "tcp_position": 3,
            "tcp_quaternion": 4,
            "grasp_position": 3,
            "approach": 3,
            "pregrasp_position": 3,
            "time": 1,
            "tcp_reference": 6,
            "tcp_reference_velocity": 6,
            "tcp_error": 3,
            "obstacles": _OBSTACLE_FEATURES * self._k,
        }
        self.observation_layout: dict[str, slice] = {}
        start = 0
        for name, size in sizes.items():
            self.observation_layout[name] = slice(start, start + size)
            start += size
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(start,), dtype=np.float64)
        self._obs = np.zeros(start)
        lay = self.observation_layout
        self._noise = check_noise(
            "obs_noise",
            obs_noise,
            {
                "q": (lay["q"],),
                "qdot": (lay["qdot"],),
                "tcp": (lay["tcp_position"],),
                "tcp_quaternion": (lay["tcp_quaternion"],),
            },
            ("q", "qdot", "tcp"),
        )
        self._speed_scale = np.array([self._max_lift_speed] + [self._max_joint_speed] * 8)
        self._backend = check_backend("backend", backend)
        spec = parse_dynamics(dynamics, ARM_ITEMS)
        self._dynamics = None if spec is None else DynamicsRandomization(spec, "carriage", "tcp")
        self._slots = np.array(
            [
                lay[k].start
                for k in ("q", "qdot", "tcp_position", "time", "tcp_reference", "tcp_reference_velocity", "tcp_error")
            ],
            dtype=np.int64,
        )
        self._quat_slice = lay["tcp_quaternion"]
        self._sample = np.empty(12)  # the reference path's sample of the compiled step
        self._reset_episode_state()
        self._row: CropRow | None = None
        self._part_geoms = np.zeros(0, dtype=np.int64)

    # ------------------------------------------------------------------ gymnasium API
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float64], dict[str, Any]]:
        super().reset(seed=seed)
        self._reset_episode_state()
        rng = self.np_random
        for _ in range(50):
            row = generate_crop_row(rng, **self._scene)
            target = self._choose_target(row, rng)
            if target is None:
                continue
            if self._prune:
                keep = row.whole_blades(self._reachable(row))
                if not np.isin(target, keep):  # cannot happen for a reachable pre-grasp pose; guarded anyway
                    continue
                target = int(np.searchsorted(keep, target))
                row = row.subset(keep)
            if self._fits(row):
                break
        else:
            s = self._scene
            raise EnvConfigError(
                "no reachable pepper with a clear approach in 50 generated rows; loosen the scene (fewer shoots or "
                "clusters, a wider harvest_band, a row_distance near 1.05 m, a longer row_length): row_distance="
                f"{s['row_distance']:g} m, row_length={s['row_length']:g} m, stem_spacing={s['stem_spacing']}, "
                f"harvest_band={s['harvest_band']}"
            )
        self._row = row
        self._target = target
        self._place_scene(row, target)
        self._build_collision_pairs(row, target)
        lay = self.observation_layout
        self._obs[lay["obstacles"]] = self._observed_obstacles(row, target)
        self._obs[lay["grasp_position"]] = self._grasp
        self._obs[lay["approach"]] = self._approach
        self._obs[lay["pregrasp_position"]] = self._pregrasp
        q = self._start_configuration(rng)
        mujoco.mj_resetData(self.model, self.data)
        drawn = None
        if self._dynamics is not None:
            drawn = self._dynamics.apply(self.model, self.data, rng)
        self.data.qpos[self._qpos] = q
        self.data.act[self._servo_act] = q
        mujoco.mj_forward(self.model, self.data)
        if self._dynamics is not None:
            self._dynamics.start_delay(self.data.ctrl)
        self._path = GraspPath.plan(
            self.data.site_xpos[self._tcp_site].copy(),
            self.data.site_xmat[self._tcp_site].reshape(3, 3)[:, 0].copy(),
            self._pregrasp,
            self._grasp,
            self._approach,
            self.reference_timing,
        )
        warn_if_time_limit_short(self, self._path.duration, "this episode's reference path")
        metrics = self._metrics(np.zeros(9))
        if drawn is not None:
            metrics["dynamics"] = drawn
        return self._get_obs(), metrics

    def step(self, action: NDArray[np.floating]) -> tuple[NDArray[np.float64], float, bool, bool, dict[str, Any]]:
        if self._backend == "python":
            return self._step_python(action)
        action = as_action(action, 9, finite=False)
        if self._row is None:
            if not np.isfinite(action).all():
                raise non_finite_action(action)
            raise gym.error.ResetNeeded("call reset() before step()")
        if not velocity_commands(action, self._speed_scale, self.data.ctrl):
            raise non_finite_action(action)
        self._advance()
        observation, metrics = self._compiled_state()
        reward, terms = self._get_rew(metrics)
        metrics.update(terms)
        terminated = bool(metrics["collision"] or metrics["is_success"])
        return observation, reward, terminated, False, metrics

    def _step_python(
        self, action: NDArray[np.floating]
    ) -> tuple[NDArray[np.float64], float, bool, bool, dict[str, Any]]:
        """:meth:`step` with NumPy: the readable reference of the compiled step (``backend="python"``)."""
        try:
            action = np.asarray(action, dtype=np.float64)
        except (TypeError, ValueError) as exc:  # a dict, strings, None: not an action
            raise InvalidActionError(f"action must be an array of numbers, got {type(action).__name__}") from exc
        if action.shape != (9,):
            raise InvalidActionError(f"action must have shape (9,), got {action.shape}")
        # a finite sum proves every entry finite (the full check only runs when it is not)
        if not math.isfinite(float(action.sum())) and not np.isfinite(action).all():
            raise InvalidActionError(f"action must be finite, got {action}")
        if self._row is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        qdot_cmd = self._speed_scale * action.clip(-1.0, 1.0)
        ctrl = self.data.ctrl
        ctrl[:9] = qdot_cmd  # servo set-points integrate the command; the feed-forwards apply it directly
        ctrl[9:] = qdot_cmd
        self._advance()
        metrics = self._metrics(self.data.qvel[self._qvel])
        reward, terms = self._get_rew(metrics)
        metrics.update(terms)
        terminated = bool(metrics["collision"] or metrics["is_success"])
        return self._get_obs(), reward, terminated, False, metrics

    def _advance(self) -> None:
        """One control step of the physics for the controls set, and the clock."""
        if self._dynamics is not None:
            self.data.ctrl[:] = self._dynamics.delay(self.data.ctrl.copy())
        # mj_step1 of the current state ran at the end of the last step (or in reset): finish that step with
        # mj_step2, then run the new state's position/velocity stages once, for the observation and next step
        mujoco.mj_step2(self.model, self.data)
        if self.frame_skip > 1:
            mujoco.mj_step(self.model, self.data, nstep=self.frame_skip - 1)
        mujoco.mj_step1(self.model, self.data)
        self._time += self.dt

    def _compiled_state(self) -> tuple[NDArray[np.float64], dict[str, Any]]:
        """:meth:`_get_obs` and :meth:`_metrics` with the path sampled once, in one compiled pass."""
        d = self.data
        o = self._obs
        error, tracking, angle, energy, margin, peak, tcp, ref, obstacle, own, leaf = agri_state(
            d.qpos,
            d.qvel,
            self._qpos_index,
            self._qvel_index,
            self._lower,
            self._upper,
            d.site_xpos[self._tcp_site],
            d.site_xmat[self._tcp_site],
            self._reference_path.params,
            self._sample,
            self._time,
            self._grasp,
            self._approach,
            o,
            self._slots,
            (self._hard_batch.address, self._self_batch.address, self._soft_batch.address),
            self._horizon,
        )
        mujoco.mju_mat2Quat(self._quat, d.site_xmat[self._tcp_site])
        o[self._quat_slice] = self._quat
        metrics = self._metrics_from(
            error, tracking, angle, energy * self.dt, margin, peak, tcp, ref, (obstacle, own, self._leaves(leaf))
        )
        if self._noise is None:
            return o.copy(), metrics
        index, std = self._noise
        obs = o.copy()
        obs[index] += std * self.np_random.standard_normal(index.size)
        lay = self.observation_layout
        obs[lay["tcp_error"]] = o[lay["tcp_reference"]][:3] - obs[lay["tcp_position"]]  # from the observed TCP
        return obs, metrics

    def render(self) -> NDArray[np.uint8] | None:
        """An RGB frame from ``camera_name`` (``render_mode="rgb_array"``)."""
        if self.render_mode is None:
            gym.logger.warn("render() called without render_mode; pass render_mode='rgb_array' to gym.make")
            return None
        if self._renderer is None:
            self._renderer = mujoco.Renderer(self.model, self.height, self.width)
        self._renderer.update_scene(self.data, camera=self.camera_name)
        return self._renderer.render()

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # ------------------------------------------------------------------ task
    @property
    def max_joint_speeds(self) -> NDArray[np.float64]:
        """Velocity command of each joint at action 1 [m/s, rad/s]."""
        return self._speed_scale.copy()

    @property
    def crop_row(self) -> CropRow | None:
        """The plant parts of the current episode (after pruning)."""
        return self._row

    @property
    def part_geoms(self) -> NDArray[np.int64]:
        """MuJoCo geom id drawing each part of :attr:`crop_row` (both triangles of a leaf blade share one)."""
        return self._part_geoms.copy()

    @property
    def target_index(self) -> int:
        """Index of the target pepper in :attr:`crop_row`."""
        return self._target

    @property
    def grasp_pose(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Grasp position [m] and unit approach direction of the episode."""
        return self._grasp.copy(), self._approach.copy()

    @property
    def difficulty(self) -> str:
        """The difficulty preset."""
        return self._difficulty

    @property
    def _reference_path(self) -> GraspPath:
        """The episode's reference path (planned at reset)."""
        if self._path is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        return self._path

    def _get_obs(self) -> NDArray[np.float64]:
        o = self._obs  # episode-constant entries (targets, obstacle block) were written at reset
        lay = self.observation_layout
        o[lay["q"]] = self.data.qpos[self._qpos]
        o[lay["qdot"]] = self.data.qvel[self._qvel]
        o[lay["tcp_position"]] = self.data.site_xpos[self._tcp_site]
        mujoco.mju_mat2Quat(self._quat, self.data.site_xmat[self._tcp_site])
        o[lay["tcp_quaternion"]] = self._quat
        o[lay["time"]] = self._time
        # the reference path is planned from the start pose, which a policy sees only at the first step: without
        # these entries the tracking error is measured against something the observation does not hold
        target, velocity = self._reference_path(self._time)
        o[lay["tcp_reference"]] = target
        o[lay["tcp_reference_velocity"]] = velocity
        if self._noise is None:
            o[lay["tcp_error"]] = target[:3] - o[lay["tcp_position"]]
            return o.copy()
        index, std = self._noise
        obs = o.copy()
        obs[index] += std * self.np_random.standard_normal(index.size)
        obs[lay["tcp_error"]] = target[:3] - obs[lay["tcp_position"]]  # from the observed, possibly noisy, TCP
        return obs

    def _get_rew(self, metrics: dict[str, Any]) -> tuple[float, dict[str, float]]:
        """``(reward, terms)`` from the step's metrics: the reward is the sum of ``terms``."""
        w = self._weights
        terms = {
            "reward_position": -w["position_weight"] * metrics["goal_error"],
            "reward_orientation": -w["orientation_weight"] * metrics["orientation_error"],
            "reward_energy": -w["energy_weight"] * metrics["pseudoenergy"],
            "reward_leaf": -w["leaf_penalty"] * metrics["leaf_contacts"],
            "reward_collision": -w["collision_penalty"] if metrics["collision"] else 0.0,
            "reward_success": w["success_bonus"] if metrics["is_success"] else 0.0,
        }
        return float(sum(terms.values())), terms

    def _metrics(self, qdot: NDArray[np.float64]) -> dict[str, Any]:
        """Step metrics for ``info``; also advances the episode's contact counters."""
        # scalar math on Python floats: NumPy's per-call overhead on 3-vectors would dominate this function
        x, y, z = self.data.site_xpos[self._tcp_site].tolist()
        gx, gy, gz = self._grasp_tuple
        error = math.sqrt((x - gx) ** 2 + (y - gy) ** 2 + (z - gz) ** 2)
        rx, ry, rz = self._reference_path.position(self._time)
        tracking = math.sqrt((x - rx) ** 2 + (y - ry) ** 2 + (z - rz) ** 2)
        m = self.data.site_xmat[self._tcp_site]
        ax, ay, az = self._approach_tuple
        cos_angle = float(m[0]) * ax + float(m[3]) * ay + float(m[6]) * az  # tool axis: the site's local x
        angle = math.acos(min(1.0, max(-1.0, cos_angle)))
        qd = qdot.tolist()
        margin = min(
            min(a - lo, hi - a)
            for a, lo, hi in zip(self.data.qpos[self._qpos].tolist(), self._lower_list, self._upper_list, strict=False)
        )
        return self._metrics_from(
            error,
            tracking,
            angle,
            sum(v * v for v in qd) * self.dt,
            margin,
            max(map(abs, qd)),
            np.array((x, y, z)),
            np.array((rx, ry, rz)),
        )

    def _metrics_from(
        self,
        error: float,
        tracking: float,
        angle: float,
        pseudoenergy: float,
        margin: float,
        peak: float,
        tcp: NDArray[np.float64],
        reference: NDArray[np.float64],
        contacts: tuple[float, float, int] | None = None,
    ) -> dict[str, Any]:
        """The step's ``info`` from its numbers and the clearances (``contacts``: as :meth:`_contacts` returns
        them, computed here when None); advances the episode's contact counters."""
        obstacle_clearance, self_clearance, leaves = self._contacts() if contacts is None else contacts
        clearance = min(obstacle_clearance, self_clearance)
        collision = clearance <= 0.0
        self._collided = self._collided or collision
        self._leaf_total += leaves
        at_goal = bool(error <= self._success_position and angle <= self._success_angle)
        success = (not self._collided) and at_goal
        return {
            "tracking_error": tracking,
            "goal_error": error,
            "goal_reached": at_goal,
            "orientation_error": angle,
            "pseudoenergy": pseudoenergy,
            "min_clearance": clearance,
            "min_obstacle_clearance": obstacle_clearance,
            "min_self_clearance": self_clearance,
            "collision": collision,
            "leaf_contacts": leaves,
            "leaf_contacts_total": self._leaf_total,
            "joint_limit_margin": margin,
            "peak_joint_speed": peak,
            "is_success": success,
            "time": self._time,
            "tcp": tcp,
            "tcp_ref": reference,
        }

    def _contacts(self) -> tuple[float, float, int]:
        """Smallest clearance to a hard plant part and between non-adjacent arm volumes (each capped at the
        horizon), and the number of leaves touched."""
        obstacle = min(self._hard_batch.compute_near(self._horizon), self._horizon)
        own = min(self._self_batch.compute_near(self._horizon), self._horizon)
        return obstacle, own, self._leaves(self._soft_batch.compute_near(0.0))

    def _leaves(self, nearest: float) -> int:
        """The number of leaves touched, from the leaf batch's last ``compute_near(0)`` and its minimum
        ``nearest`` [m]: leaves only count when touched."""
        if nearest > 0.0:
            return 0
        touched = self._soft_part[self._soft_batch.result.distance <= 0.0]
        return int(np.unique(touched).size) if touched.size else 0

    # ------------------------------------------------------------------ scene
    def _pool_capacity(self) -> dict[str, int]:
        """Upper bounds of the number of parts per category the (pruned) scene can hold (``leaf``: blades)."""
        s = self._scene
        stems = 0
        for x0 in (s["row_distance"], s["row_distance"] + s["row_gap"]):
            length = s["row_length"]
            if self._prune:  # the stretch of this row whose plants can reach into the pruning capsule
                far = _REACH + _ARM_RADIUS + PART_REACH
                length = min(length, 2.0 * np.sqrt(max(far * far - (x0 - 0.02) ** 2, 0.0)))
            stems += int(np.floor(length / s["stem_spacing"][0])) + 1 if length > 0.0 else 0
        return {
            "stem": stems,
            "shoot": stems,
            "fruit": stems * s["fruits_per_stem"][1],
            "petiole": stems * s["leaves_per_stem"],
            "leaf": stems * s["leaves_per_stem"],
        }

    def _fits(self, row: CropRow) -> bool:
        """Whether the row's parts fit the compiled geom pools (a row that would not is drawn again)."""
        counts = {c: int(np.count_nonzero(row.category == c)) for c in POOL_CATEGORIES}
        counts["leaf"] //= 2
        return all(counts[c] <= self._pool[c].size for c in POOL_CATEGORIES)

    def _reachable(self, row: CropRow) -> NDArray[np.int64]:
        """Parts that can meet the arm: within its reach capsule around the lift column."""
        reach = LSS([0.0, 0.0, _SHOULDER_Z[0]], [0.0, 0.0, _SHOULDER_Z[1]], _REACH + _ARM_RADIUS)
        return np.flatnonzero(_distances_to(row, np.arange(len(row)), reach) <= 0.0)

    def _choose_target(self, row: CropRow, rng: np.random.Generator) -> int | None:
        """A pepper of the near row facing the arm, reachable, with a clear approach corridor (or None)."""
        fruits = np.flatnonzero((row.category == "fruit") & row.near_row[row.plant])
        center = row.vertices[fruits, 0]
        plant = row.plant[fruits]
        stem = row.stem_base[plant] + (
            (center[:, 2] - row.stem_base[plant, 2]) / (row.stem_top[plant, 2] - row.stem_base[plant, 2])
        )[:, None] * (row.stem_top[plant] - row.stem_base[plant])
        radial = center[:, :2] - stem[:, :2]
        radial /= np.maximum(np.linalg.norm(radial, axis=1), 1e-9)[:, None]
        towards_arm = -center[:, :2] / np.maximum(np.linalg.norm(center[:, :2], axis=1), 1e-9)[:, None]
        beta = rng.uniform(self._elevation[0], self._elevation[1], fruits.size)
        approach = np.column_stack([-np.cos(beta)[:, None] * radial, np.sin(beta)])
        pregrasp = center - self._pregrasp_distance * approach
        ok = (
            (np.sum(radial * towards_arm, axis=1) >= np.cos(np.deg2rad(50.0)))
            & (np.linalg.norm(pregrasp[:, :2], axis=1) <= _REACH - 0.35)
            & (pregrasp[:, 2] > 0.6)
            & (pregrasp[:, 2] < 1.5)
        )
        candidates = np.flatnonzero(ok)
        rng.shuffle(candidates)
        hard = np.flatnonzero(row.hard)
        for c in candidates:
            f = fruits[c]
            corridor = LSS(center[c] - _CORRIDOR[0] * approach[c], center[c] - _CORRIDOR[1] * approach[c], _CORRIDOR[2])
            others = hard[hard != f]
            if others.size and _distances_to(row, others, corridor).min() < 0.01:
                continue
            self._grasp = center[c].copy()
            self._approach = approach[c].copy()
            self._pregrasp = pregrasp[c].copy()
            self._grasp_tuple = tuple(self._grasp.tolist())
            self._approach_tuple = tuple(self._approach.tolist())
            return int(f)
        return None

    def _place_scene(self, row: CropRow, target: int) -> None:
        """Move the pooled plant geoms onto the row's parts (vectorized per category); hide the spare ones."""
        m = self.model
        m.geom_rgba[self._pool_all] = 0.0
        m.geom_pos[self._pool_all] = (0.0, 0.0, -10.0)
        v, r = row.vertices, row.radius
        self._part_geoms = np.empty(len(row), dtype=np.int64)
        for category in POOL_CATEGORIES:
            k = np.flatnonzero(row.category == category)
            self._part_geoms[k] = self._pool[category][
                np.arange(k.size) // 2 if category == "leaf" else np.arange(k.size)
            ]
        for category in ("stem", "shoot", "petiole"):
            k = np.flatnonzero(row.category == category)
            g = self._pool[category][: k.size]
            m.geom_rgba[g] = PLANT_COLORS[category]
            _place_capsules(m, g, v[k, 0], v[k, 1], np.maximum(r[k], 1e-3))
        k = np.flatnonzero(row.category == "fruit")
        g = self._pool["fruit"][: k.size]
        m.geom_rgba[g] = PLANT_COLORS["fruit"]
        m.geom_rgba[g[k == target]] = TARGET_COLOR
        m.geom_pos[g] = v[k, 0]
        m.geom_size[g] = r[k, None]
        k = np.flatnonzero(row.category == "leaf")  # the two triangles of a blade are adjacent
        g = self._pool["leaf"][: k.size // 2]
        m.geom_rgba[g] = PLANT_COLORS["leaf"]
        _place_blades(m, g, v[k[0::2]], v[k[1::2], 2], r[k[0::2]])
        _place_capsules(m, np.array([self._approach_line]), self._pregrasp[None], self._grasp[None], np.array([0.003]))

    def _build_collision_pairs(self, row: CropRow, target: int) -> None:
        """The pair batches of the episode: arm vs hard parts, non-adjacent arm pairs, and arm vs
        leaves/petioles (only touching counts there, so it is culled at margin 0).

        Volumes are ordered moving arm volumes, the fixed column, then the plant parts, so the broad phase only
        refreshes the arm's bounding spheres, read from MuJoCo's geom frames inside the compiled call."""
        n_moving = self._n_arm - 1
        parts = np.flatnonzero(np.arange(len(row)) != target)
        m = self.model
        arm = self._arm_geoms[np.r_[1 : self._n_arm, 0]]  # the column (AGRI_ARM_GEOMS[0]) is fixed
        vertices = np.zeros((self._n_arm, 3, 3))
        vertices[-1, :2] = m.geom_pos[arm[-1]] + np.outer((-1.0, 1.0), self._column_half_axis)  # world geom
        vertices[-1, 2] = vertices[-1, 1]
        kinds = np.where(self._half_length[np.r_[1 : self._n_arm, 0]] > 0.0, 1, 0)
        moving = np.arange(n_moving)
        volume_of = np.r_[n_moving, 0:n_moving]  # AGRI_ARM_GEOMS index -> volume index
        g0, g1 = self._moving_geoms
        batches = []
        for hard in (True, False):
            k = parts[row.hard[parts] == hard]
            volumes = PackedVolumes(
                np.concatenate([vertices, row.vertices[k]]),
                np.concatenate([m.geom_size[arm, 0], row.radius[k]]),
                np.concatenate([kinds, row.kind[k]]),
            )
            ia = np.repeat(moving, k.size)
            ib = np.tile(self._n_arm + np.arange(k.size), n_moving)
            if not hard:
                self._soft_part = np.tile(k, n_moving)  # leaves are counted per part
            batches.append(PairBatch(volumes, ia, ib, moving=n_moving))
        own = PackedVolumes(vertices, m.geom_size[arm, 0], kinds)
        batches.append(
            PairBatch(own, volume_of[self._self_pairs[:, 0]], volume_of[self._self_pairs[:, 1]], moving=n_moving)
        )
        for batch in batches:
            batch.attach_frames(self.data.geom_xpos[g0:g1], self.data.geom_xmat[g0:g1], self._half_length[1:])
        self._hard_batch, self._soft_batch, self._self_batch = batches

    def _observed_obstacles(self, row: CropRow, target: int) -> NDArray[np.float64]:
        """The static obstacle block of the observation: the K parts nearest to the approach corridor."""
        block = np.zeros((self._k, _OBSTACLE_FEATURES))
        parts = np.array([k for k in range(len(row)) if k != target], dtype=np.int64)
        if self._k == 0 or parts.size == 0:
            return block.reshape(-1)
        corridor = LSS(self._grasp, self._grasp - (_CORRIDOR[1] + 0.3) * self._approach, 0.0)
        d = _distances_to(row, parts, corridor)
        # hard obstacles first at equal distance: they are what a controller must avoid
        order = parts[np.lexsort((~row.hard[parts], d))][: self._k]
        for r, k in enumerate(order):
            block[r, 0] = 1.0
            block[r, 1 + row.kind[k]] = 1.0
            block[r, 4] = float(row.hard[k])
            block[r, 5:14] = row.vertices[k].reshape(-1)
            block[r, 14] = row.radius[k]
        return block.reshape(-1)

    def _start_configuration(self, rng: np.random.Generator) -> NDArray[np.float64]:
        """Folded posture facing the row, lift at the target's height, plus uniform noise."""
        # upper arm raised, elbow folded, tool level: the TCP 0.74 m out and 0.11 m above the shoulder
        q = np.array([0.0, 0.0, -1.42, 1.77, 0.0, 1.12, 0.0, -1.31, 0.0])
        q[0] = self._pregrasp[2] - 0.656
        q[1] = np.arctan2(self._pregrasp[1], self._pregrasp[0])
        q += rng.uniform(-self._reset_noise_scale, self._reset_noise_scale, 9)
        return np.clip(q, self._lower + 0.02, self._upper - 0.02)

    def _reset_episode_state(self) -> None:
        self._time = 0.0
        self._collided = False
        self._leaf_total = 0
        self._quat = np.zeros(4)

    def _resolve_names(self) -> None:
        m = self.model
        joints = [m.joint(n) for n in AGRI_ARM_JOINTS]
        qpos = np.array([j.qposadr[0] for j in joints])
        qvel = np.array([j.dofadr[0] for j in joints])
        if np.any(np.diff(qpos) != 1) or np.any(np.diff(qvel) != 1):
            raise EnvConfigError("agri arm joints must have consecutive qpos and dof addresses")
        # slices: views instead of fancy-indexed copies on the per-step path
        self._qpos = slice(int(qpos[0]), int(qpos[-1]) + 1)
        self._qvel = slice(int(qvel[0]), int(qvel[-1]) + 1)
        self._qpos_index = np.arange(self._qpos.start, self._qpos.stop, dtype=np.int64)  # for the compiled step
        self._qvel_index = np.arange(self._qvel.start, self._qvel.stop, dtype=np.int64)
        self._lower = np.array([j.range[0] for j in joints])
        self._upper = np.array([j.range[1] for j in joints])
        self._lower_list, self._upper_list = self._lower.tolist(), self._upper.tolist()
        servo_ids = [m.actuator(n).id for n in AGRI_ARM_SERVOS]
        ff_ids = [m.actuator(n).id for n in AGRI_ARM_FEEDFORWARDS]
        if servo_ids + ff_ids != list(range(18)):
            raise EnvConfigError("agri arm actuators must be the 9 servos followed by the 9 feed-forwards")
        self._servo_act = np.array([m.actuator_actadr[i] for i in servo_ids])
        self._tcp_site = m.site(AGRI_ARM_TCP).id
        self._arm_geoms = np.array([m.geom(n).id for n in AGRI_ARM_GEOMS])
        self._n_arm = len(AGRI_ARM_GEOMS)
        self._half_length = np.where(
            m.geom_type[self._arm_geoms] == mujoco.mjtGeom.mjGEOM_CAPSULE, m.geom_size[self._arm_geoms, 1], 0.0
        )
        moving = self._arm_geoms[1:]
        if m.geom_bodyid[self._arm_geoms[0]] != 0 or np.any(np.diff(moving) != 1):
            raise EnvConfigError("agri arm geoms must be the world-fixed column, then the moving geoms in id order")
        # contiguous ids: the per-step contact check reads MuJoCo's geom frames through slices, not copies
        self._moving_geoms = (int(moving[0]), int(moving[-1]) + 1)
        column_frame = np.zeros(9)
        mujoco.mju_quat2Mat(column_frame, m.geom_quat[self._arm_geoms[0]])
        self._column_half_axis = column_frame[2::3] * self._half_length[0]
        self._self_pairs = _self_collision_pairs(m, self._arm_geoms)
        self._pool = {
            c: np.array([m.geom(pool_geom_name(c, k)).id for k in range(n)], dtype=np.int64)
            for c, n in self._pool_capacity().items()
        }
        self._pool_all = np.concatenate(list(self._pool.values()))
        self._approach_line = m.geom("approach_line").id


def _distances_to(row: CropRow, parts: NDArray[np.int64], volume: LSS) -> NDArray[np.float64]:
    """SSV distances of the row's ``parts`` to one volume, in one compiled call."""
    n = parts.size
    packed = PackedVolumes(
        np.concatenate([row.vertices[parts], volume.vertices[None]]),
        np.concatenate([row.radius[parts], [volume.radius]]),
        np.concatenate([row.kind[parts], [volume.kind]]),
    )
    return indexed_distances(packed, np.arange(n), np.full(n, n)).distance


def _place_capsules(
    m: mujoco.MjModel, g: NDArray[np.int64], p0: NDArray[np.float64], p1: NDArray[np.float64], r: NDArray[np.float64]
) -> None:
    """Capsule geoms ``g`` from ``p0`` to ``p1`` (rows) with radii ``r``."""
    axis = p1 - p0
    length = np.linalg.norm(axis, axis=1)
    z = np.where(length[:, None] > 0.0, axis / np.maximum(length, 1e-12)[:, None], (0.0, 0.0, 1.0))
    m.geom_pos[g] = 0.5 * (p0 + p1)
    m.geom_size[g] = np.column_stack([r, np.maximum(0.5 * length, 1e-4), np.zeros_like(r)])
    m.geom_quat[g] = _quat_z_to(z)


def _quat_z_to(z: NDArray[np.float64]) -> NDArray[np.float64]:
    """Unit quaternions (w, x, y, z) turning the z axis onto the unit rows of ``z`` (shortest arc)."""
    q = np.column_stack([1.0 + z[:, 2], -z[:, 1], z[:, 0], np.zeros(len(z))])
    flip = q[:, 0] < 1e-9  # z = -e_z: any half turn about a horizontal axis
    q[flip] = (0.0, 1.0, 0.0, 0.0)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _place_blades(
    m: mujoco.MjModel,
    g: NDArray[np.int64],
    first: NDArray[np.float64],
    right: NDArray[np.float64],
    half_thickness: NDArray[np.float64],
) -> None:
    """Flat ellipsoids over leaf blades (drawn, not simulated): ``first`` holds the (end, left, tip) triangle of
    each blade, ``right`` its other side corner."""
    end, left, tip = first[:, 0], first[:, 1], first[:, 2]
    x = tip - end
    length = np.linalg.norm(x, axis=1)
    x /= np.maximum(length, 1e-12)[:, None]
    y = left - right
    y -= np.sum(y * x, axis=1)[:, None] * x
    width = np.linalg.norm(y, axis=1)
    y /= np.maximum(width, 1e-12)[:, None]
    frame = np.stack([x, y, np.cross(x, y)], axis=2).reshape(-1, 9)  # columns: blade axis, side, normal
    m.geom_pos[g] = 0.5 * (end + tip)
    m.geom_size[g] = np.column_stack(
        [np.maximum(0.5 * length, 1e-3), np.maximum(0.5 * width, 1e-3), np.maximum(half_thickness, 1e-3)]
    )
    quat = np.empty(4)
    for gi, f in zip(g, frame, strict=False):
        mujoco.mju_mat2Quat(quat, f)
        m.geom_quat[gi] = quat
