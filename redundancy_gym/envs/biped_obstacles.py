"""BipedObstacles-v0: the Lola-like biped walks forward over and around obstacles on its path."""

from __future__ import annotations

import bisect
import math
from collections.abc import Mapping, Sequence
from typing import Any

import mujoco
import numpy as np
from gymnasium import utils
from numpy.typing import NDArray

from ..assets.biped_scene import obstacle_geom_name, obstacle_scene_xml
from ..assets.obstacle_course import (
    MAX_OBSTACLE_DEPTH,
    OBSTACLE_KINDS,
    OBSTACLE_SHAPES,
    Obstacle,
    beam_course,
    random_course,
    triangle_course,
)
from ..geometry import SSV, PackedVolumes, PairBatch
from .biped_walk import BipedWalkEnv
from .contact_pressure import compiled_touches_geoms, touches_geoms
from .exceptions import EnvConfigError
from .validation import (
    check_choice,
    check_int,
    check_known_arguments,
    check_range_pair,
    check_real,
    check_real_array,
    constructor_arguments,
    constructor_defaults,
    warn_if_time_limit_short,
)

__all__ = [
    "COURSES",
    "MAX_EPISODE_STEPS",
    "OBSTACLE_FEATURES",
    "OBSTACLE_LOOKBEHIND",
    "WALK_START_TIME",
    "BipedObstaclesEnv",
    "default_config",
]

COURSES = ("beam", "triangle", "random")
"""Values of ``course``: the monograph's two experiments and a seeded random course per reset."""
OBSTACLE_FEATURES = 14
"""Entries per observed obstacle volume: mask, one-hot kind (PSS, LSS, TSS), three vertices, radius."""
OBSTACLE_LOOKBEHIND = 0.6
"""An obstacle volume is observed while its bounding box's largest x is at least the pelvis x minus this [m]: the
rear foot may still be passing it (with 0.32 m steps the trailing heel stays within about 0.4 m behind the pelvis;
0.6 m leaves room for longer steps)."""
WALK_START_TIME = 0.4
"""Duration [s] of the walking reference's weight shift before its first step (``GaitConfig.start_duration``)."""
_WALK_SPEED = 0.4  # [m/s] default target speed: the monograph's experiments
_MIN_FIRST_DISTANCE = 0.5  # [m]: a random course's deepest obstacle (0.4 m) then starts 0.11 m ahead of the toes
_OBSTACLE_KEYS = ("shape", "center", "size", "yaw", "kind")


def default_config() -> dict[str, Any]:
    """Default keyword arguments of :class:`BipedObstaclesEnv`, the rendering ones left out (a fresh dict each call),
    read from its signature: the one place they are written."""
    return constructor_defaults(BipedObstaclesEnv.__init__)


class BipedObstaclesEnv(BipedWalkEnv):
    r"""## Description
    The Lola-like biped of :class:`~redundancy_gym.envs.BipedWalkEnv` (same robot, servos, sensors and fall rules)
    walks forward (+x) at ``target_speed`` (0.4 m/s by default) over a course of static obstacles that it must step
    over or swing its feet around without touching them, then walk on ``success_distance`` past the last one. The
    courses are the monograph's two experiments (chapter 5.4: ``"beam"``, a 16.1 cm high block across the path at
    the 5th foothold; ``"triangle"``, a 30 cm high triangular prism between the feet), a seeded ``"random"`` course
    drawn at every reset (3-6 obstacles of three classes, :func:`~redundancy_gym.assets.obstacle_course.random_course`),
    or explicit ``obstacles``.

    The obstacles are MuJoCo geoms of the world body (boxes, cylinders, triangular prisms as meshes) that collide
    with the robot's sole boxes and body capsules; touching one is an obstacle contact (penalized, and no success),
    not an end. Controllers see each obstacle as swept-sphere volumes that contain it
    (:meth:`~redundancy_gym.assets.obstacle_course.Obstacle.volumes`: a box is two TSS, a prism one TSS, a post one
    LSS), in the observation and in :attr:`obstacle_volumes`.

    A fixed course is compiled once. A random course changes at every reset, and the scene is recompiled with it
    (a triangular prism of new dimensions needs a new mesh): about 7 ms per reset against 0.3 ms for a fixed course
    (measured here: 0.6 ms to add the obstacles to the cached scene text, 4.3 ms to compile, 0.7 ms for the ids and
    the collision pairs, the rest for MjData and the reset itself), while an episode of a course takes seconds.
    ``model``, ``data`` and the renderer are then new objects: read ``env.unwrapped.model`` after the reset. A reset
    with the same seed draws the same course and does not recompile.

    ## Action Space
    As BipedWalk: ``Box(-1, 1, (22,), float32)``, joint position targets normalized around the standing posture.

    ## Observation Space
    ``Box(-inf, inf, (81 + 14 K,), float64)`` with ``K = observed_obstacles`` (193 for the default 8); the slices
    are in :attr:`OBSERVATION_LAYOUT` (the class attribute holds the default K's, an instance its own):

    | name | size | unit |
    |------|------|------|
    | BipedWalk's entries (``base_position`` ... ``time``) | 81 | as BipedWalk |
    | ``obstacles``: K rows ``[mask, PSS, LSS, TSS, v0, v1, v2, radius]`` | 14 K | -, m (world frame) |

    The obstacle rows hold the course's swept-sphere volumes (not obstacles: a box gives two rows) whose bounding
    box (vertices +- radius) reaches at least :data:`OBSTACLE_LOOKBEHIND` = 0.6 m behind the pelvis (largest x
    >= pelvis x - 0.6), the first K of them ordered by their bounding box's smallest x: a one-hot kind, the three
    generating vertices in the world frame (unused ones repeat the last), the radius. Rows past the observed volumes
    are zero (mask 0). ``sensor_noise`` does not apply to them.

    ## Rewards
    BipedWalk's terms (``reward_speed``, ``reward_lateral``, ``reward_healthy``, ``reward_energy``,
    ``reward_fall``) plus ``reward_obstacle = -contact_weight`` on every step with an obstacle contact.

    ``info`` holds every BipedWalk metric, plus ``min_obstacle_clearance`` [m] (smallest swept-sphere distance
    between the robot's volumes, the sphere and capsule geoms of ``min_self_clearance``, and the obstacle volumes;
    negative when they overlap), ``obstacle_contact`` (a MuJoCo contact of a robot geom with an obstacle geom at
    any physics step of this control step), ``obstacle_contacts`` (control steps with one so far in the episode),
    ``obstacles_passed`` (obstacles whose bounding box lies wholly behind the pelvis x) and ``course_end`` (the
    pelvis x [m] to pass: the largest x of the obstacles' bounding boxes plus ``success_distance``). Changed:
    ``min_clearance`` is the smaller of ``min_self_clearance`` and ``min_obstacle_clearance``; ``collision`` is a
    self-collision or an obstacle contact; ``is_success`` is the pelvis past ``course_end`` with no fall, no
    self-collision and no obstacle contact in the episode (the mean speed does not count).

    ## Starting State
    As BipedWalk: the standing posture with the soles on the ground at the origin, upper-body noise. A random course
    is drawn from the env's generator first (``reset(seed=...)`` reproduces course and posture).

    ## Episode End
    - Termination: BipedWalk's (a fall or a self-collision), and success (the course is done).
    - Truncation: the time limit of the registration, :data:`MAX_EPISODE_STEPS` = 11250 steps of 4 ms (45 s): the
      longest default random course (first obstacle at 1.5 m, 6 obstacles 3 m apart, the last up to 0.2 m deep
      beyond its centre, then 1 m: ``course_end`` = 17.7 m) takes 0.4 s of start plus 44.25 s at 0.4 m/s = 44.65 s.
      A reset warns once when the course needs longer at ``target_speed`` (slower speeds, longer courses) and
      names the ``max_episode_steps`` to pass to ``gym.make``.

    ## Arguments
    Every argument of BipedWalk (``target_speed`` defaults to 0.4 m/s here), and:

    - ``course`` (``"beam" | "triangle" | "random"``, default ``"random"``): :func:`~redundancy_gym.assets.
      obstacle_course.beam_course`, :func:`~redundancy_gym.assets.obstacle_course.triangle_course`, or a new
      random course per reset.
    - ``obstacles`` (default None): an explicit course overriding ``course``, a non-empty list of dicts
      ``{"shape": "box" | "prism" | "cylinder", "center": [x, y, z], "size": [...], "yaw": 0.0}`` (``center`` of
      the bounding box [m]; ``size`` (depth, width, height) [m] of a box or prism, (radius, height) [m] of a
      cylinder; ``yaw`` [rad], optional; ``"kind"`` optional, a class name for reports, default ``"custom"``).
      Every obstacle must be clear of the standing robot's swept-sphere volumes (the toes reach x = 0.19 m).
    - ``n_obstacles`` (ints (low, high), >= 1; default (3, 6)), ``obstacle_spacing`` ((low, high) [m] between
      consecutive centres, low >= 0.4 so that obstacles never overlap; default (1.2, 3.0)),
      ``first_obstacle_distance`` ([m], >= 0.5: x of the first centre; default 1.5): the random course.
    - ``observed_obstacles`` (K, int >= 0; default 8): obstacle volumes in the observation.
    - ``contact_weight`` (>= 0; default 1.0): penalty per step with an obstacle contact.
    - ``success_distance`` ([m], >= 0; default 1.0): how far past the last obstacle the pelvis must walk.

    ## Version History
    - v0: initial release (0.1.0)
    """

    OBSTACLE_FEATURES = OBSTACLE_FEATURES
    OBSERVATION_LAYOUT: dict[str, slice] = {  # noqa: RUF012 - the default K's; an instance holds its own
        **BipedWalkEnv.OBSERVATION_LAYOUT,
        "obstacles": slice(BipedWalkEnv.OBSERVATION_SIZE, BipedWalkEnv.OBSERVATION_SIZE + OBSTACLE_FEATURES * 8),
    }
    OBSERVATION_SIZE = BipedWalkEnv.OBSERVATION_SIZE + OBSTACLE_FEATURES * 8
    # what the policies and wrappers may rely on (redundancy_gym.policies.CAPABILITY_ATTRIBUTES)
    CAPABILITIES = frozenset({"biped"})

    def __init__(
        self,
        target_speed: float = _WALK_SPEED,
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
        course: str = "random",
        obstacles: Sequence[Mapping[str, Any]] | None = None,
        n_obstacles: Sequence[int] = (3, 6),
        obstacle_spacing: Sequence[float] = (1.2, 3.0),
        first_obstacle_distance: float = 1.5,
        observed_obstacles: int = 8,
        contact_weight: float = 1.0,
        success_distance: float = 1.0,
        speed_scale: float = 0.25,
        backend: str = "compiled",
        dynamics: float | dict[str, Any] | None = None,
        **kwargs: Any,
    ) -> None:
        check_known_arguments(kwargs, BipedObstaclesEnv.__init__)
        # read before any argument is rebound; recorded after BipedWalkEnv's constructor, which records its own
        arguments = constructor_arguments(BipedObstaclesEnv.__init__, locals())
        check_choice("course", course, COURSES)
        self._course = course
        fewest, most = check_range_pair("n_obstacles", n_obstacles, low=1, integer=True)
        self._n_obstacles = (int(fewest), int(most))
        self._spacing = check_range_pair(
            "obstacle_spacing",
            obstacle_spacing,
            low=MAX_OBSTACLE_DEPTH,
            unit="m",
            note=f"obstacles up to {MAX_OBSTACLE_DEPTH:g} m deep must not overlap",
        )
        self._first_distance = check_real(
            "first_obstacle_distance",
            first_obstacle_distance,
            low=_MIN_FIRST_DISTANCE,
            unit="m",
            note="the standing toes reach x = 0.19 m and an obstacle may be 0.4 m deep",
        )
        self._k = check_int("observed_obstacles", observed_obstacles, low=0)
        self._contact_weight = check_real("contact_weight", contact_weight, low=0.0)
        self._success_distance = check_real("success_distance", success_distance, low=0.0, unit="m")
        self._explicit = obstacles is not None
        if obstacles is not None:
            self._obstacles = _parse_obstacles(obstacles)
        elif course == "beam":
            self._obstacles = beam_course()
        elif course == "triangle":
            self._obstacles = triangle_course()
        else:
            self._obstacles = ()  # drawn at every reset
        start = BipedWalkEnv.OBSERVATION_SIZE
        self.OBSERVATION_LAYOUT = {
            **BipedWalkEnv.OBSERVATION_LAYOUT,
            "obstacles": slice(start, start + OBSTACLE_FEATURES * self._k),
        }
        self.OBSERVATION_SIZE = start + OBSTACLE_FEATURES * self._k
        self._base_xml: str | None = None
        self._touched = False
        self._contact_steps = 0
        super().__init__(**constructor_arguments(BipedWalkEnv.__init__, arguments))  # every BipedWalk argument
        utils.EzPickle.__init__(self, **arguments)
        if self._explicit:
            self._check_clear_of_standing_robot()

    # ------------------------------------------------------------------ scene
    def _scene_xml(self) -> str:
        if self._base_xml is None:  # composing the robot file costs about 27 ms: once per env
            self._base_xml = super()._scene_xml()
        return obstacle_scene_xml(self._base_xml, self._obstacles)

    def _set_course(self, course: tuple[Obstacle, ...]) -> None:
        """Make ``course`` the scene's obstacles: recompile the model (:meth:`BipedWalkEnv._recompile`) when it
        differs from the current one."""
        if course == self._obstacles:
            return
        self._obstacles = course
        self._recompile()

    def _resolve_names(self) -> None:
        super()._resolve_names()
        self._resolve_obstacles()

    def _resolve_obstacles(self) -> None:
        """Geom ids, swept-sphere volumes, the robot-obstacle pair batch and the observation rows of the course."""
        m = self.model
        ids = np.array([m.geom(obstacle_geom_name(k)).id for k in range(len(self._obstacles))], dtype=np.int64)
        if ids.size and np.any(np.diff(ids) != 1):
            raise EnvConfigError("the obstacle geoms must have consecutive ids")
        # contacts are tested against an id range: one comparison pair per contact instead of a set lookup
        self._obstacle_ids = (int(ids[0]), int(ids[-1]) + 1) if ids.size else (0, 0)
        volumes: list[SSV] = []
        owner: list[int] = []
        for k, obstacle in enumerate(self._obstacles):
            for volume in obstacle.volumes():
                volumes.append(volume)
                owner.append(k)
        self._volumes = tuple(volumes)
        self._volume_owner = np.array(owner, dtype=np.int64)
        boxes = [o.bounding_box() for o in self._obstacles]
        self._obstacle_max_x = np.array([upper[0] for _, upper in boxes])
        self._obstacle_max_x_sorted = sorted(self._obstacle_max_x.tolist())  # obstacles passed: a bisection
        self._course_end = (float(self._obstacle_max_x.max()) if boxes else 0.0) + self._success_distance
        # observation rows, ordered by the volumes' bounding boxes' smallest x
        n_robot = len(self._ssv_geoms)
        rows = np.zeros((len(volumes), OBSTACLE_FEATURES))
        low_x = np.zeros(len(volumes))
        high_x = np.zeros(len(volumes))
        for i, v in enumerate(volumes):
            rows[i, 0] = 1.0
            rows[i, 1 + v.kind] = 1.0
            rows[i, 4:13] = v.vertices.reshape(-1)
            rows[i, 13] = v.radius
            low_x[i] = v.points[:, 0].min() - v.radius
            high_x[i] = v.points[:, 0].max() + v.radius
        order = np.argsort(low_x, kind="stable")
        self._rows = rows[order]
        self._row_max_x = high_x[order]
        self._max_x_sorted = sorted(high_x.tolist())
        self._blocks: dict[int, NDArray[np.float64]] = {}
        self._mirror_batch = None
        if not volumes:
            self._obstacle_batch: PairBatch | None = None
            return
        packed = PackedVolumes.from_volumes(volumes)
        robot = self._batch  # BipedWalk's self-collision batch: the robot's volumes are its first n_robot
        all_volumes = PackedVolumes(
            np.concatenate([robot.vertices, packed.vertices]),
            np.concatenate([robot.radii, packed.radii]),
            np.concatenate([robot.kinds, packed.kinds]),
        )
        index_a = np.repeat(np.arange(n_robot), len(volumes))
        index_b = np.tile(n_robot + np.arange(len(volumes)), n_robot)
        self._obstacle_batch = PairBatch(all_volumes, index_a, index_b, moving=n_robot)
        self._mirror_batch = self._obstacle_batch  # the compiled step places the robot's volumes here too
        self._clearance_hint = self._mirror_clearance_hint = 0.25  # [m] the first bounding-sphere margin
        self._pair_obstacle = self._volume_owner[index_b - n_robot]

    def _check_clear_of_standing_robot(self) -> None:
        """Raise when an explicit obstacle overlaps the standing robot's volumes (it would start in collision)."""
        qpos = self.init_qpos.copy()
        qpos[:7] = (0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0)
        qpos[7:] = self._nominal
        self.set_state(qpos, np.zeros(self.model.nv))
        qpos[2] = -self._lowest_sole_point()
        self.set_state(qpos, np.zeros(self.model.nv))
        self._self_clearance()  # places the robot's volumes
        batch = self._obstacle_batch
        if batch is None:
            return
        batch.vertices[: len(self._ssv_geoms)] = self._batch.vertices
        distance = batch.compute().distance
        worst = int(np.argmin(distance))
        if distance[worst] <= 0.0:
            k = int(self._pair_obstacle[worst])
            raise EnvConfigError(
                f"obstacles[{k}] overlaps the standing robot (swept-sphere distance "
                f"{distance[worst]:.3f} m): the robot stands at the origin, its toes reach x = 0.19 m "
                f"and its soles span |y| <= 0.165 m; got {self._obstacles[k]}"
            )

    # ------------------------------------------------------------------ gymnasium API
    def reset_model(self) -> NDArray[np.float64]:
        if not self._explicit and self._course == "random":
            self._set_course(
                random_course(
                    self.np_random,
                    n_obstacles=self._n_obstacles,
                    spacing=self._spacing,
                    first_obstacle_distance=self._first_distance,
                )
            )
        self._contact_steps = 0
        obs = super().reset_model()
        self._touched = self._touching_obstacle()  # the contacts of the starting state (mj_forward of set_state)
        if self._target_speed > 0.0:
            warn_if_time_limit_short(
                self,
                WALK_START_TIME + self._course_end / self._target_speed,
                f"walking this course (course_end {self._course_end:.2f} m) at target_speed",
            )
        return obs

    def _step_mujoco_simulation(self, ctrl: NDArray[np.float64], n_frames: int) -> None:
        """Step the physics as MuJoCo's ``nstep`` does, testing the contacts of every physics step: a contact
        within one control step must not go unseen because the last physics step has left it."""
        model, data = self.model, self.data
        data.ctrl[:] = ctrl
        touched = False
        for _ in range(n_frames):
            mujoco.mj_step(model, data)
            touched = touched or self._touching_obstacle()
        mujoco.mj_rnePostConstraint(model, data)
        self._touched = touched

    def _terminated(self, metrics: dict[str, Any]) -> bool:
        return super()._terminated(metrics) or bool(metrics["is_success"])

    # ------------------------------------------------------------------ task
    @property
    def obstacles(self) -> tuple[Obstacle, ...]:
        """The course's obstacles (a random course's: the one drawn at the last reset; empty before it)."""
        return self._obstacles

    @property
    def obstacle_volumes(self) -> tuple[SSV, ...]:
        """The swept-sphere volumes of all obstacles [m], world frame, in course order (each obstacle's
        :meth:`~redundancy_gym.assets.obstacle_course.Obstacle.volumes` in turn)."""
        return self._volumes

    @property
    def obstacle_geoms(self) -> NDArray[np.int64]:
        """MuJoCo geom id of each obstacle of :attr:`obstacles` (of the current ``model``)."""
        return np.arange(*self._obstacle_ids, dtype=np.int64)

    @property
    def course_end(self) -> float:
        """The pelvis x [m] that ends the course: the obstacles' largest x plus ``success_distance``."""
        return self._course_end

    def _observation_tail(self) -> NDArray[np.float64]:
        # which volumes are observed depends only on how many are left behind: one block per count, made once
        behind = bisect.bisect_left(self._max_x_sorted, float(self.data.qpos[0]) - OBSTACLE_LOOKBEHIND)
        block = self._blocks.get(behind)
        if block is None:
            rows = np.zeros((self._k, OBSTACLE_FEATURES))
            seen = np.flatnonzero(self._row_max_x >= float(self.data.qpos[0]) - OBSTACLE_LOOKBEHIND)[: self._k]
            rows[: seen.size] = self._rows[seen]
            block = self._blocks[behind] = rows.reshape(-1)
        return block

    def _get_rew(self, metrics: dict[str, Any]) -> tuple[float, dict[str, float]]:
        _, terms = super()._get_rew(metrics)
        terms["reward_obstacle"] = -self._contact_weight if metrics["obstacle_contact"] else 0.0
        return float(sum(terms.values())), terms

    # ------------------------------------------------------------------ metrics
    def _metrics(self, forward_speed: float) -> dict[str, Any]:
        metrics = super()._metrics(forward_speed)  # places the robot's volumes for the self-clearance
        clearance = self._obstacle_clearance()
        contact = bool(self._touched)
        self._contact_steps += int(contact)
        x = float(self.data.qpos[0])
        clean = not (self._fell or self._self_collided) and self._contact_steps == 0
        metrics.update(
            min_obstacle_clearance=clearance,
            min_clearance=min(metrics["min_self_clearance"], clearance),
            collision=bool(metrics["self_collision"] or contact),
            obstacle_contact=contact,
            obstacle_contacts=self._contact_steps,
            obstacles_passed=bisect.bisect_left(self._obstacle_max_x_sorted, x),
            course_end=self._course_end,
            is_success=bool(clean and x >= self._course_end),
        )
        return metrics

    def _obstacle_clearance(self) -> float:
        """Smallest swept-sphere distance [m] between the robot's volumes and the obstacles' (+inf without any).

        Exact, but only the pairs near each other are computed: a pass with a bounding-sphere margin computes the
        pairs whose spheres lie within it exactly (a sphere distance is a lower bound of the SSV distance); when its
        minimum is within the margin it is the minimum of all pairs, otherwise the margin grows and the pass repeats
        (the first margin is the last step's clearance plus 5 cm, so one pass of a few pairs usually does)."""
        batch = self._obstacle_batch
        if batch is None:
            return math.inf
        if self._backend == "compiled":  # computed with the step's other metrics, from the same first margin
            d = self._mirror_clearance
        else:  # the robot's volumes as BipedWalk placed them for this state (_self_clearance, in _metrics)
            batch.vertices[: len(self._ssv_geoms)] = self._batch.vertices
            # start from the last step's clearance: the robot moves little in a step, so one pass usually does
            d = batch.smallest(self._clearance_hint)
        if d <= 1e6:
            self._clearance_hint = self._mirror_clearance_hint = max(d, 0.0) + 0.05
        return d

    def _touching_obstacle(self) -> bool:
        """Whether MuJoCo's current contacts include an obstacle geom (obstacles only collide with the robot)."""
        low, high = self._obstacle_ids
        if self._backend == "python":
            return touches_geoms(self.data, low, high)
        return compiled_touches_geoms(self.data, low, high, self._contact_layout)


def _longest_random_course_time() -> float:
    """Time [s] to walk the longest default random course at 0.4 m/s: the start, then from the origin to the last
    obstacle's far face (5 gaps of 3.0 m after the first at 1.5 m, half the deepest obstacle) plus 1.0 m."""
    spec = default_config()
    n, gap, first = spec["n_obstacles"][1], spec["obstacle_spacing"][1], spec["first_obstacle_distance"]
    end = first + (n - 1) * gap + 0.5 * MAX_OBSTACLE_DEPTH + spec["success_distance"]
    return WALK_START_TIME + end / _WALK_SPEED


_CONTROL_RATE = 250  # [1/s] control steps per second at the default frame_skip (2 physics steps of 2 ms)
MAX_EPISODE_STEPS = int(math.ceil(_longest_random_course_time())) * _CONTROL_RATE
"""The registered time limit: 11250 steps of 4 ms (45 s), the longest default random course at 0.4 m/s (44.65 s:
0.4 s start, 17.7 m) rounded up to whole seconds."""


def _parse_obstacles(value: Any) -> tuple[Obstacle, ...]:
    """The ``obstacles`` argument as a course, each entry checked with the name of its key."""
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Sequence) or not value:
        raise EnvConfigError(
            "obstacles must be None or a non-empty list of dicts {'shape': box | prism | cylinder, "
            f"'center': [x, y, z], 'size': [...], 'yaw': 0.0}}, got {value!r}"
        )
    course = []
    for i, item in enumerate(value):
        name = f"obstacles[{i}]"
        if not isinstance(item, Mapping):
            raise EnvConfigError(
                f"{name} must be a dict with keys shape, center, size (yaw, kind optional), got {item!r}"
            )
        unknown = sorted(str(k) for k in item if k not in _OBSTACLE_KEYS)
        missing = [k for k in ("shape", "center", "size") if k not in item]
        if unknown or missing:
            raise EnvConfigError(
                f"{name} has {'unknown key(s) ' + ', '.join(unknown) if unknown else ''}"
                f"{'; ' if unknown and missing else ''}"
                f"{'missing key(s) ' + ', '.join(missing) if missing else ''}; valid: "
                f"{', '.join(_OBSTACLE_KEYS)} (yaw and kind optional)"
            )
        shape = check_choice(f"{name}['shape']", item["shape"], OBSTACLE_SHAPES)
        center = check_real_array(
            f"{name}['center']", item["center"], shape=(3,), unit="m", what="an (x, y, z) triple of finite real numbers"
        )
        n = 2 if shape == "cylinder" else 3
        size = check_real_array(
            f"{name}['size']",
            item["size"],
            shape=(n,),
            low=0.0,
            low_open=True,
            unit="m",
            what=f"a {shape}'s "
            + ("(radius, height)" if n == 2 else "(depth, width, height)")
            + " of finite real numbers",
        )
        yaw = check_real(f"{name}['yaw']", item.get("yaw", 0.0), unit="rad")
        kind = check_choice(f"{name}['kind']", item.get("kind", "custom"), OBSTACLE_KINDS)
        course.append(Obstacle(shape, tuple(center), tuple(size), yaw, kind))
    return tuple(course)
