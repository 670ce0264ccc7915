"""AgriReach-v0: a CROPS-like 9-DoF arm reaching a sweet pepper's grasp pose among stems and leaves."""

from __future__ import annotations

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
from ..assets.crop_row import DIFFICULTIES, CropRow, crop_row_defaults, generate_crop_row
from ..geometry import LSS, PackedVolumes, PairBatch, indexed_distances
from .exceptions import EnvConfigError, InvalidActionError
from .validation import non_negative as _non_negative
from .validation import positive as _positive

__all__ = ["AgriReachEnv", "default_config"]

_REACH = 1.29  # [m] shoulder axis to TCP
_SHOULDER_Z = (0.55, 1.35)  # [m] shoulder height over the lift range
_ARM_RADIUS = 0.075  # [m] thickest arm volume
_CORRIDOR = (0.02, 0.55, 0.05)  # behind the grasp point along -approach: from, to [m], radius [m]
_OBSTACLE_FEATURES = 15  # mask, one-hot kind (3), hard, 9 vertex coordinates, radius


def default_config() -> dict[str, Any]:
    """Default keyword arguments of :class:`AgriReachEnv` (a fresh dict each call)."""
    return {
        "difficulty": "medium",
        "leaves_per_stem": None,
        "fruits_per_stem": None,
        "shoot_probability": None,
        "cluster_spread": None,
        "row_distance": 1.05,
        "row_gap": 0.45,
        "row_length": 8.0,
        "stem_spacing": (0.25, 0.35),
        "stem_diameter": (0.010, 0.015),
        "fruit_diameter": (0.08, 0.09),
        "harvest_band": (0.9, 1.3),
        "prune": True,
        "pregrasp_distance": 0.15,
        "approach_elevation": (0.0, 30.0),
        "observed_obstacles": 32,
        "max_joint_speed": 1.5,
        "max_lift_speed": 0.4,
        "position_weight": 1.0,
        "orientation_weight": 0.2,
        "energy_weight": 0.01,
        "leaf_penalty": 0.1,
        "collision_penalty": 10.0,
        "success_bonus": 10.0,
        "success_position_tolerance": 0.01,
        "success_angle_tolerance": 10.0,
        "clearance_horizon": 0.1,
        "reset_noise_scale": 0.05,
        "frame_skip": 2,
    }


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
    ``Box(-inf, inf, (33 + 15 K,), float64)`` with ``K = observed_obstacles``; slices in
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
    | ``obstacles`` | 15 K | the K plant parts nearest to the approach corridor, each ``[mask, PSS, LSS, TSS, hard, v0, v1, v2, radius]`` (one-hot kind, vertices [m], radius [m]; unused rows repeat the last vertex; zero rows with mask 0 pad) |

    ## Rewards
    The reward is the sum of the terms in ``info``: ``reward_position = -position_weight * |p_tcp - p_grasp|``,
    ``reward_orientation = -orientation_weight * angle(tool axis, approach)``, ``reward_energy =
    -energy_weight * qdot^T qdot dt``, ``reward_leaf = -leaf_penalty * (leaves touched this step)``,
    ``reward_collision = -collision_penalty`` on a collision, ``reward_success = success_bonus`` on success.

    ``info`` also holds ``task_error`` (position error [m]), ``orientation_error`` [rad], ``pseudoenergy``
    [rad^2/s], ``min_clearance`` [m] (smallest swept-sphere distance to a hard obstacle or between non-adjacent
    links; values beyond ``clearance_horizon`` are reported as the horizon), ``collision``, ``leaf_contacts``
    (this step), ``leaf_contacts_total``, ``joint_limit_margin`` (smallest distance to a limit [m or rad]),
    ``peak_joint_speed``, ``is_success`` (TCP within ``success_position_tolerance`` and
    ``success_angle_tolerance`` of the grasp pose, no collision), ``time`` [s] and ``tcp``.

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
    - ``row_distance``, ``row_gap``, ``row_length`` [m]; ``stem_spacing``, ``stem_diameter``,
      ``fruit_diameter`` (ranges [m]); ``harvest_band`` ((low, high) [m]).
    - ``prune`` (bool): place only the parts within the arm's reach.
    - ``pregrasp_distance`` [m]; ``approach_elevation`` ((min, max) [deg] of the upward tilt of the approach).
    - ``observed_obstacles`` (K >= 0).
    - ``max_joint_speed`` [rad/s], ``max_lift_speed`` [m/s]: velocity commands at action 1.
    - ``position_weight``, ``orientation_weight``, ``energy_weight``, ``leaf_penalty``, ``collision_penalty``,
      ``success_bonus`` (>= 0): reward weights.
    - ``success_position_tolerance`` [m], ``success_angle_tolerance`` [deg].
    - ``clearance_horizon`` [m]: pairs farther than this (by bounding spheres) are not computed exactly.
    - ``reset_noise_scale`` [m, rad]; ``frame_skip`` (physics steps of 5 ms per control step).
    - ``render_mode`` (``"rgb_array"``), ``width``, ``height``, ``camera_name`` (``"side"`` or ``"front"``).

    ## Version History
    - v0: initial version.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": 100}
    ROBOT_XML = AGRI_ARM_XML
    TCP_FRAME = AGRI_ARM_TCP

    def __init__(self, difficulty: str = "medium", leaves_per_stem: int | None = None,
                 fruits_per_stem: Sequence[int] | None = None, shoot_probability: float | None = None,
                 cluster_spread: float | None = None, row_distance: float = 1.05, row_gap: float = 0.45,
                 row_length: float = 8.0, stem_spacing: Sequence[float] = (0.25, 0.35),
                 stem_diameter: Sequence[float] = (0.010, 0.015), fruit_diameter: Sequence[float] = (0.08, 0.09),
                 harvest_band: Sequence[float] = (0.9, 1.3), prune: bool = True, pregrasp_distance: float = 0.15,
                 approach_elevation: Sequence[float] = (0.0, 30.0), observed_obstacles: int = 32,
                 max_joint_speed: float = 1.5, max_lift_speed: float = 0.4, position_weight: float = 1.0,
                 orientation_weight: float = 0.2, energy_weight: float = 0.01, leaf_penalty: float = 0.1,
                 collision_penalty: float = 10.0, success_bonus: float = 10.0,
                 success_position_tolerance: float = 0.01, success_angle_tolerance: float = 10.0,
                 clearance_horizon: float = 0.1, reset_noise_scale: float = 0.05, frame_skip: int = 2,
                 render_mode: str | None = None, width: int = 480, height: int = 480, camera_name: str = "side",
                 **kwargs: Any) -> None:
        if kwargs:
            valid = ", ".join(sorted(default_config()) + ["render_mode", "width", "height", "camera_name"])
            raise EnvConfigError(f"unknown keyword argument(s) {', '.join(sorted(kwargs))}; valid: {valid}")
        utils.EzPickle.__init__(self, difficulty, leaves_per_stem, fruits_per_stem, shoot_probability, cluster_spread,
                                row_distance, row_gap, row_length, stem_spacing, stem_diameter, fruit_diameter,
                                harvest_band, prune, pregrasp_distance, approach_elevation, observed_obstacles,
                                max_joint_speed, max_lift_speed, position_weight, orientation_weight, energy_weight,
                                leaf_penalty, collision_penalty, success_bonus, success_position_tolerance,
                                success_angle_tolerance, clearance_horizon, reset_noise_scale, frame_skip,
                                render_mode, width, height, camera_name)
        if difficulty not in DIFFICULTIES:
            raise EnvConfigError(f"unknown difficulty {difficulty!r}; valid: {', '.join(DIFFICULTIES)}")
        scene = crop_row_defaults(difficulty)
        if leaves_per_stem is not None:
            scene["leaves_per_stem"] = _count(leaves_per_stem, "leaves_per_stem")
        if fruits_per_stem is not None:
            scene["fruits_per_stem"] = _int_range(fruits_per_stem, "fruits_per_stem")
        if shoot_probability is not None:
            p = _non_negative(shoot_probability, "shoot_probability")
            if p > 1.0:
                raise EnvConfigError(f"shoot_probability must be in [0, 1], got {shoot_probability!r}")
            scene["shoot_probability"] = p
        if cluster_spread is not None:
            scene["cluster_spread"] = _non_negative(cluster_spread, "cluster_spread")
        scene.update(row_distance=_positive(row_distance, "row_distance"), row_gap=_positive(row_gap, "row_gap"),
                     row_length=_positive(row_length, "row_length"),
                     stem_spacing=_range(stem_spacing, "stem_spacing"),
                     stem_diameter=_range(stem_diameter, "stem_diameter"),
                     fruit_diameter=_range(fruit_diameter, "fruit_diameter"),
                     harvest_band=_range(harvest_band, "harvest_band"))
        if scene["harvest_band"][1] - scene["harvest_band"][0] < scene["cluster_spread"]:
            raise EnvConfigError("harvest_band must be at least cluster_spread high")
        self._scene = scene
        self._difficulty = difficulty
        self._prune = bool(prune)
        self._pregrasp_distance = _positive(pregrasp_distance, "pregrasp_distance")
        elevation = _range(approach_elevation, "approach_elevation")
        if elevation[0] < 0.0 or elevation[1] > 60.0:
            raise EnvConfigError(f"approach_elevation must lie in [0, 60] deg, got {approach_elevation!r}")
        self._elevation = np.deg2rad(elevation)
        self._k = _count(observed_obstacles, "observed_obstacles")
        self._max_joint_speed = _positive(max_joint_speed, "max_joint_speed")
        self._max_lift_speed = _positive(max_lift_speed, "max_lift_speed")
        self._weights = {name: _non_negative(value, name) for name, value in (
            ("position_weight", position_weight), ("orientation_weight", orientation_weight),
            ("energy_weight", energy_weight), ("leaf_penalty", leaf_penalty),
            ("collision_penalty", collision_penalty), ("success_bonus", success_bonus))}
        self._success_position = _positive(success_position_tolerance, "success_position_tolerance")
        self._success_angle = np.deg2rad(_positive(success_angle_tolerance, "success_angle_tolerance"))
        self._horizon = _positive(clearance_horizon, "clearance_horizon")
        self._reset_noise_scale = _non_negative(reset_noise_scale, "reset_noise_scale")
        if not isinstance(frame_skip, (int, np.integer)) or frame_skip < 1:
            raise EnvConfigError(f"frame_skip must be an int >= 1, got {frame_skip!r}")
        self.frame_skip = int(frame_skip)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise EnvConfigError(f"unknown render_mode {render_mode!r}; valid: {', '.join(self.metadata['render_modes'])}")
        if camera_name not in ("side", "front"):
            raise EnvConfigError(f"unknown camera_name {camera_name!r}; valid: side, front")
        self.render_mode = render_mode
        self.width, self.height, self.camera_name = int(width), int(height), camera_name

        self.model = mujoco.MjModel.from_xml_string(agri_scene_xml(self._pool_capacity()))
        self.model.vis.global_.offwidth = max(self.model.vis.global_.offwidth, self.width)
        self.model.vis.global_.offheight = max(self.model.vis.global_.offheight, self.height)
        self.data = mujoco.MjData(self.model)
        self.dt = float(self.model.opt.timestep * self.frame_skip)
        self.metadata = {"render_modes": ["rgb_array"], "render_fps": int(np.round(1.0 / self.dt))}
        self._resolve_names()
        self._renderer: mujoco.Renderer | None = None

        self.action_space = spaces.Box(-1.0, 1.0, shape=(9,), dtype=np.float32)
        sizes = {"q": 9, "qdot": 9, "tcp_position": 3, "tcp_quaternion": 4, "grasp_position": 3, "approach": 3,
                 "pregrasp_position": 3, "time": 1, "obstacles": _OBSTACLE_FEATURES * self._k}
        self.observation_layout: dict[str, slice] = {}
        start = 0
        for name, size in sizes.items():
            self.observation_layout[name] = slice(start, start + size)
            start += size
        self.observation_space = spaces.Box(-np.inf, np.inf, shape=(start,), dtype=np.float64)
        self._dynamic = np.empty(self.observation_layout["obstacles"].start)  # the per-step part of the observation
        self._speed_scale = np.array([self._max_lift_speed] + [self._max_joint_speed] * 8)
        self._reset_episode_state()
        self._row: CropRow | None = None

    # ------------------------------------------------------------------ gymnasium API
    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[NDArray[np.float64], dict[str, Any]]:
        super().reset(seed=seed)
        self._reset_episode_state()
        rng = self.np_random
        for _ in range(50):
            row = generate_crop_row(rng, **self._scene)
            if self._prune:
                row = row.subset(self._reachable(row))
            target = self._choose_target(row, rng)
            if target is not None:
                break
        else:
            raise EnvConfigError("no reachable pepper with a clear approach in 50 generated rows; loosen the scene "
                                 "(fewer shoots or clusters, a wider harvest_band, a row_distance near 1.05 m)")
        self._row = row
        self._target = target
        self._place_scene(row, target)
        self._build_collision_pairs(row, target)
        self._obstacle_block = self._observed_obstacles(row, target)
        q = self._start_configuration(rng)
        mujoco.mj_resetData(self.model, self.data)
        self.data.qpos[self._qpos] = q
        self.data.act[self._servo_act] = q
        mujoco.mj_forward(self.model, self.data)
        metrics = self._metrics(np.zeros(9))
        return self._get_obs(), metrics

    def step(self, action: NDArray[np.floating]) -> tuple[NDArray[np.float64], float, bool, bool, dict[str, Any]]:
        action = np.asarray(action, dtype=np.float64)
        if action.shape != (9,):
            raise InvalidActionError(f"action must have shape (9,), got {action.shape}")
        if not np.all(np.isfinite(action)):
            raise InvalidActionError(f"action must be finite, got {action}")
        if self._row is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        qdot_cmd = self._speed_scale * np.clip(action, -1.0, 1.0)
        self._ctrl[:9] = qdot_cmd
        self._ctrl[9:] = qdot_cmd
        self.data.ctrl[:] = self._ctrl
        mujoco.mj_step(self.model, self.data, nstep=self.frame_skip)
        mujoco.mj_kinematics(self.model, self.data)  # positions of the state after the last integration
        self._time += self.dt
        metrics = self._metrics(self.data.qvel[self._qvel])
        reward, terms = self._get_rew(metrics)
        metrics.update(terms)
        terminated = bool(metrics["collision"] or metrics["is_success"])
        return self._get_obs(), reward, terminated, False, metrics

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

    def _get_obs(self) -> NDArray[np.float64]:
        d = self._dynamic
        lay = self.observation_layout
        d[lay["q"]] = self.data.qpos[self._qpos]
        d[lay["qdot"]] = self.data.qvel[self._qvel]
        d[lay["tcp_position"]] = self.data.site_xpos[self._tcp_site]
        mujoco.mju_mat2Quat(self._quat, self.data.site_xmat[self._tcp_site])
        d[lay["tcp_quaternion"]] = self._quat
        d[lay["grasp_position"]] = self._grasp
        d[lay["approach"]] = self._approach
        d[lay["pregrasp_position"]] = self._pregrasp
        d[lay["time"]] = self._time
        return np.concatenate([d, self._obstacle_block])

    def _get_rew(self, metrics: dict[str, Any]) -> tuple[float, dict[str, float]]:
        """``(reward, terms)`` from the step's metrics: the reward is the sum of ``terms``."""
        w = self._weights
        terms = {
            "reward_position": -w["position_weight"] * metrics["task_error"],
            "reward_orientation": -w["orientation_weight"] * metrics["orientation_error"],
            "reward_energy": -w["energy_weight"] * metrics["pseudoenergy"],
            "reward_leaf": -w["leaf_penalty"] * metrics["leaf_contacts"],
            "reward_collision": -w["collision_penalty"] if metrics["collision"] else 0.0,
            "reward_success": w["success_bonus"] if metrics["is_success"] else 0.0,
        }
        return float(sum(terms.values())), terms

    def _metrics(self, qdot: NDArray[np.float64]) -> dict[str, Any]:
        """Step metrics for ``info``; also advances the episode's contact counters."""
        tcp = self.data.site_xpos[self._tcp_site].copy()
        axis = self.data.site_xmat[self._tcp_site][[0, 3, 6]]
        error = float(np.linalg.norm(tcp - self._grasp))
        angle = float(np.arccos(min(1.0, max(-1.0, float(axis @ self._approach)))))
        clearance, leaves = self._contacts()
        collision = clearance <= 0.0
        self._collided = self._collided or collision
        self._leaf_total += leaves
        q = self.data.qpos[self._qpos]
        success = (not self._collided) and error <= self._success_position and angle <= self._success_angle
        return {
            "task_error": error,
            "orientation_error": angle,
            "pseudoenergy": float(qdot @ qdot) * self.dt,
            "min_clearance": clearance,
            "collision": bool(collision),
            "leaf_contacts": leaves,
            "leaf_contacts_total": self._leaf_total,
            "joint_limit_margin": float(np.min(np.minimum(q - self._lower, self._upper - q))),
            "peak_joint_speed": float(np.max(np.abs(qdot))),
            "is_success": bool(success),
            "time": self._time,
            "tcp": tcp,
        }

    def _contacts(self) -> tuple[float, int]:
        """Smallest hard/self clearance (capped at the horizon) and the number of leaves touched."""
        batch = self._batch
        xpos = self.data.geom_xpos[self._arm_geoms]
        axis = self.data.geom_xmat[self._arm_geoms][:, 2::3] * self._half_length[:, None]  # local z
        v = batch.vertices
        v[:self._n_arm, 0] = xpos - axis
        v[:self._n_arm, 1] = xpos + axis
        v[:self._n_arm, 2] = v[:self._n_arm, 1]
        if batch.cull(self._horizon) == 0:
            return self._horizon, 0
        d = batch.compute().distance
        n_hard = self._n_hard_pairs  # pairs are ordered hard (arm-plant, self) first, then soft
        clearance = min(float(d[:n_hard].min()) if n_hard else np.inf, self._horizon)
        touched = self._soft_part[d[n_hard:] <= 0.0]
        return clearance, (int(np.unique(touched).size) if touched.size else 0)

    # ------------------------------------------------------------------ scene
    def _pool_capacity(self) -> dict[str, int]:
        """Upper bounds of the number of parts per category the (pruned) scene can hold."""
        s = self._scene
        length = min(s["row_length"], 2.0 * (_REACH + _ARM_RADIUS) + 0.2) if self._prune else s["row_length"]
        stems = 2 * (int(np.ceil(length / s["stem_spacing"][0])) + 2)
        return {"stem": stems, "shoot": stems, "fruit": stems * s["fruits_per_stem"][1],
                "petiole": stems * s["leaves_per_stem"], "leaf": 2 * stems * s["leaves_per_stem"]}

    def _reachable(self, row: CropRow) -> NDArray[np.int64]:
        """Parts that can meet the arm: within its reach capsule around the lift column."""
        reach = LSS([0.0, 0.0, _SHOULDER_Z[0]], [0.0, 0.0, _SHOULDER_Z[1]], _REACH + _ARM_RADIUS)
        return np.flatnonzero(_distances_to(row, np.arange(len(row)), reach) <= 0.0)

    def _choose_target(self, row: CropRow, rng: np.random.Generator) -> int | None:
        """A pepper of the near row facing the arm, reachable, with a clear approach corridor (or None)."""
        fruits = np.flatnonzero((row.category == "fruit") & row.near_row[row.plant])
        rng.shuffle(fruits)
        hard = np.flatnonzero(row.hard)
        for f in fruits:
            center = row.vertices[f, 0]
            stem = row.stem_point(int(row.plant[f]), float(center[2]))
            radial = center - stem
            radial[2] = 0.0
            radial /= max(np.linalg.norm(radial), 1e-9)
            towards_arm = -center[:2] / max(np.linalg.norm(center[:2]), 1e-9)
            if radial[:2] @ towards_arm < np.cos(np.deg2rad(50.0)):
                continue
            beta = rng.uniform(*self._elevation)
            approach = -np.cos(beta) * radial + np.array([0.0, 0.0, np.sin(beta)])
            pregrasp = center - self._pregrasp_distance * approach
            if np.linalg.norm(pregrasp[:2]) > _REACH - 0.35 or not (0.6 < pregrasp[2] < 1.5):
                continue
            corridor = LSS(center - _CORRIDOR[0] * approach, center - _CORRIDOR[1] * approach, _CORRIDOR[2])
            others = hard[hard != f]
            if others.size and _distances_to(row, others, corridor).min() < 0.01:
                continue
            self._grasp = center.copy()
            self._approach = approach
            self._pregrasp = pregrasp
            return int(f)
        return None

    def _place_scene(self, row: CropRow, target: int) -> None:
        """Move the pooled plant geoms onto the row's parts; hide the spare ones."""
        m = self.model
        used = dict.fromkeys(POOL_CATEGORIES, 0)
        for ids in self._pool.values():
            m.geom_rgba[ids] = 0.0
            m.geom_pos[ids] = (0.0, 0.0, -10.0)
        for k in range(len(row)):
            category = str(row.category[k])
            g = self._pool[category][used[category]]
            used[category] += 1
            v = row.vertices[k]
            r = float(row.radius[k])
            m.geom_rgba[g] = TARGET_COLOR if k == target else PLANT_COLORS[category]
            if category == "fruit":
                m.geom_pos[g] = v[0]
                m.geom_size[g] = (r, r, r)
            elif category == "leaf":
                _place_box(m, g, v, r)
            else:
                _place_capsule(m, g, v[0], v[1], max(r, 1e-3))
        _place_capsule(m, self._approach_line, self._pregrasp, self._grasp, 0.003)

    def _build_collision_pairs(self, row: CropRow, target: int) -> None:
        """The pair batch of the episode: arm vs hard parts, arm vs leaves/petioles, non-adjacent arm pairs."""
        n_arm = self._n_arm
        parts = np.array([k for k in range(len(row)) if k != target], dtype=np.int64)
        m = self.model
        arm = PackedVolumes(np.zeros((n_arm, 3, 3)), m.geom_size[self._arm_geoms, 0].copy(),
                            np.where(self._half_length > 0.0, 1, 0).astype(np.int64))
        volumes = PackedVolumes(np.concatenate([arm.vertices, row.vertices[parts]]),
                                np.concatenate([arm.radii, row.radius[parts]]),
                                np.concatenate([arm.kinds, row.kind[parts]]))
        moving = np.arange(1, n_arm)  # the column (0) is fixed: it only meets the arm
        hard = n_arm + np.flatnonzero(row.hard[parts])
        soft = n_arm + np.flatnonzero(~row.hard[parts])
        ia_h, ib_h = np.repeat(moving, hard.size), np.tile(hard, moving.size)
        ia_s, ib_s = np.repeat(moving, soft.size), np.tile(soft, moving.size)
        ia_r, ib_r = self._self_pairs[:, 0], self._self_pairs[:, 1]
        ia = np.concatenate([ia_h, ia_r, ia_s])
        ib = np.concatenate([ib_h, ib_r, ib_s])
        self._batch = PairBatch(volumes, ia, ib)
        self._n_hard_pairs = ia_h.size + ia_r.size
        self._soft_part = ib_s  # leaves are counted per part

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
        self._ctrl = np.zeros(18)
        self._quat = np.zeros(4)

    def _resolve_names(self) -> None:
        m = self.model
        joints = [m.joint(n) for n in AGRI_ARM_JOINTS]
        self._qpos = np.array([j.qposadr[0] for j in joints])
        self._qvel = np.array([j.dofadr[0] for j in joints])
        self._lower = np.array([j.range[0] for j in joints])
        self._upper = np.array([j.range[1] for j in joints])
        servo_ids = [m.actuator(n).id for n in AGRI_ARM_SERVOS]
        ff_ids = [m.actuator(n).id for n in AGRI_ARM_FEEDFORWARDS]
        if servo_ids + ff_ids != list(range(18)):
            raise EnvConfigError("agri arm actuators must be the 9 servos followed by the 9 feed-forwards")
        self._servo_act = np.array([m.actuator_actadr[i] for i in servo_ids])
        self._tcp_site = m.site(AGRI_ARM_TCP).id
        self._arm_geoms = np.array([m.geom(n).id for n in AGRI_ARM_GEOMS])
        self._n_arm = len(AGRI_ARM_GEOMS)
        self._half_length = np.where(m.geom_type[self._arm_geoms] == mujoco.mjtGeom.mjGEOM_CAPSULE,
                                     m.geom_size[self._arm_geoms, 1], 0.0)
        self._self_pairs = _self_collision_pairs(m, self._arm_geoms)
        self._pool = {c: np.array([m.geom(pool_geom_name(c, k)).id for k in range(n)], dtype=np.int64)
                      for c, n in self._pool_capacity().items()}
        self._approach_line = m.geom("approach_line").id


def _distances_to(row: CropRow, parts: NDArray[np.int64], volume: LSS) -> NDArray[np.float64]:
    """SSV distances of the row's ``parts`` to one volume, in one compiled call."""
    n = parts.size
    packed = PackedVolumes(np.concatenate([row.vertices[parts], volume.vertices[None]]),
                           np.concatenate([row.radius[parts], [volume.radius]]),
                           np.concatenate([row.kind[parts], [volume.kind]]))
    return indexed_distances(packed, np.arange(n), np.full(n, n)).distance


def _self_collision_pairs(m: mujoco.MjModel, geoms: NDArray[np.int64]) -> NDArray[np.int64]:
    """Index pairs (into ``geoms``) of arm volumes that can collide: not on one body, not on a body and its
    nearest ancestor carrying geoms, and not excluded by an MJCF ``<exclude>``."""
    body = m.geom_bodyid[geoms]
    carriers = set(body.tolist())

    def carrier_parent(b: int) -> int:
        p = int(m.body_parentid[b])
        while p > 0 and p not in carriers:
            p = int(m.body_parentid[p])
        return p

    excluded = {frozenset((int(s >> 16), int(s & 0xFFFF))) for s in m.exclude_signature}
    pairs = []
    for i in range(len(geoms)):
        for j in range(i + 1, len(geoms)):
            a, b = int(body[i]), int(body[j])
            if a == b or carrier_parent(a) == b or carrier_parent(b) == a or frozenset((a, b)) in excluded:
                continue
            pairs.append((i, j))
    return np.array(pairs, dtype=np.int64).reshape(-1, 2)


def _place_capsule(m: mujoco.MjModel, g: int, p0: NDArray[np.float64], p1: NDArray[np.float64], r: float) -> None:
    axis = p1 - p0
    length = float(np.linalg.norm(axis))
    m.geom_pos[g] = 0.5 * (p0 + p1)
    m.geom_size[g] = (r, max(0.5 * length, 1e-4), 0.0)
    quat = np.zeros(4)
    z = axis / length if length > 0.0 else np.array([0.0, 0.0, 1.0])
    mujoco.mju_quatZ2Vec(quat, z)
    m.geom_quat[g] = quat


def _place_box(m: mujoco.MjModel, g: int, points: NDArray[np.float64], half_thickness: float) -> None:
    """A thin box over a leaf triangle (principal axes of its vertices; drawn, not simulated)."""
    center = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - center)
    frame = vt.T.copy()
    if np.linalg.det(frame) < 0.0:
        frame[:, 2] = -frame[:, 2]
    extent = np.abs((points - center) @ frame).max(axis=0)
    m.geom_pos[g] = center
    m.geom_size[g] = (max(extent[0], 1e-3), max(0.6 * extent[1], 1e-3), max(half_thickness, 1e-3))
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, frame.reshape(-1))
    m.geom_quat[g] = quat


def _count(value: int, name: str) -> int:
    if not isinstance(value, (int, np.integer)) or value < 0:
        raise EnvConfigError(f"{name} must be an int >= 0, got {value!r}")
    return int(value)


def _range(value: Sequence[float], name: str) -> tuple[float, float]:
    r = np.asarray(value, dtype=np.float64)
    if r.shape != (2,) or not np.all(np.isfinite(r)) or r[0] > r[1] or r[0] < 0.0:
        raise EnvConfigError(f"{name} must be a (low, high) pair with 0 <= low <= high, got {value!r}")
    return float(r[0]), float(r[1])


def _int_range(value: Sequence[int], name: str) -> tuple[int, int]:
    low, high = _range(value, name)
    if low != int(low) or high != int(high):
        raise EnvConfigError(f"{name} must be a pair of ints, got {value!r}")
    return int(low), int(high)
