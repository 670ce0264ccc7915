"""BipedTerrain-v0: the Lola-like biped walks forward over stairs, platforms, stepping stones, slopes and rough
ground, seeing the terrain through a height scan."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from gymnasium import utils
from numpy.typing import NDArray

from ..assets import BIPED_SOLE_GEOMS
from ..assets.biped_scene import TERRAIN_GEOM_PREFIX, terrain_scene_xml
from ..assets.terrain import (
    SEGMENT_KEYS,
    TERRAIN_KINDS,
    TERRAIN_RANGES,
    Terrain,
    explicit_terrain,
    random_terrain,
    segment_length_bound,
)
from .biped_walk import BipedWalkEnv
from .exceptions import EnvConfigError
from .terrain_kernels import pack_terrain, terrain_heights_kernel
from .validation import (
    check_choice,
    check_known_arguments,
    check_range_pair,
    check_real,
    check_real_array,
    constructor_arguments,
    constructor_defaults,
    warn_if_time_limit_short,
)

__all__ = [
    "EDGE_DISTANCE_CAP",
    "MAX_EPISODE_STEPS",
    "TERRAINS",
    "BipedTerrainEnv",
    "default_config",
]

TERRAINS = (*TERRAIN_KINDS, "random")
"""Values of ``terrain``: one segment of a class per reset, or a seeded sequence of classes."""
EDGE_DISTANCE_CAP = 1.0
"""``edge_distance`` [m] is capped here: a sole farther from any edge reports this."""
_WALK_SPEED = 0.4  # [m/s] default target speed: the monograph's experiments
_START_TIME = 0.4  # [s] the walking reference's weight shift before its first step
_MIN_FIRST_DISTANCE = 0.5  # [m] the standing toes reach x = 0.19 m
_CONTACT_FORCE = 1.0  # [N] a foot with more normal force touches the ground
_MIN_SWING = 0.05  # [s] a foot off the ground this long lands at its next contact (shorter: a flicker of contact)
_SOLE_GRID = {"plate": (10, 8), "toe": (4, 8)}  # sample points (along, across) of each sole box's bottom face


def default_config() -> dict[str, Any]:
    """Default keyword arguments of :class:`BipedTerrainEnv`, the rendering ones left out (a fresh dict each call),
    read from its signature: the one place they are written."""
    return constructor_defaults(BipedTerrainEnv.__init__)


class BipedTerrainEnv(BipedWalkEnv):
    r"""## Description
    The Lola-like biped of :class:`~redundancy_gym.envs.BipedWalkEnv` (same robot, servos, sensors) walks forward
    (+x) at ``target_speed`` (0.4 m/s by default) over terrain: stairs up and down, a platform to step onto and off,
    stepping stones, ramps, rough ground, or a seeded sequence of them
    (:mod:`redundancy_gym.assets.terrain`), then ``success_distance`` on past the terrain's end. It sees the terrain
    only through a height scan ahead of it, the convention of legged RL. The terrain's parameters are drawn from
    their ranges (:data:`~redundancy_gym.assets.terrain.TERRAIN_RANGES`, overridable per class) at every reset from
    the env's generator; the ranges are the target, not a filter.

    The terrain is MuJoCo geoms of the world body (boxes, convex ramp meshes, heightfields) that collide like the
    floor, with consecutive geom ids after it: a sole's contact with any of them is ground contact (``cop``,
    ``zmp``, ``normal_force``). A changed terrain recompiles the scene at the reset (about 10 ms); ``model``,
    ``data`` and the renderer are then new objects.

    ## Action Space
    As BipedWalk: ``Box(-1, 1, (22,), float32)``, joint position targets normalized around the standing posture.

    ## Observation Space
    ``Box(-inf, inf, (81 + N,), float64)`` with ``N = nx * ny`` scan points (119 at the defaults: 17 x 7); the
    slices are in :attr:`OBSERVATION_LAYOUT` (the class attribute holds the defaults', an instance its own):

    | name | size | unit |
    |------|------|------|
    | BipedWalk's entries (``base_position`` ... ``time``) | 81 | as BipedWalk |
    | ``height_scan``: terrain height minus the pelvis height at each scan point | N | m |

    The scan points form a grid in the pelvis's heading frame (its yaw only): ``nx = round(scan_size[0] /
    scan_spacing) + 1`` rows from ``scan_offset`` to ``scan_offset + scan_size[0]`` ahead of the pelvis, ``ny =
    round(scan_size[1] / scan_spacing) + 1`` columns from ``-scan_size[1] / 2`` to ``+scan_size[1] / 2`` to its left;
    entry ``i * ny + j`` is row ``i`` (back to front), column ``j`` (right to left) (:attr:`scan_points` gives the
    offsets). On flat ground every entry is minus the pelvis height (about -0.92 m). ``sensor_noise`` does not
    apply to it.

    ## Rewards
    BipedWalk's terms (``reward_speed``, ``reward_lateral``, ``reward_healthy``, ``reward_energy``, ``reward_fall``;
    ``speed_scale`` 0.15 m/s here: standing still through a 52 s episode must not pay a third of a walk's return,
    and at 0.25 m/s it earned 44 %) plus ``reward_unsupported = -unsupported_weight`` on the step that lands a foot
    with less than ``min_support`` of its sole supported.

    ``info`` holds every BipedWalk metric, plus the touchdown metrics of the last foot that landed (a foot lands
    when its normal force exceeds 1 N after at least 50 ms without; its touchdown is measured when it first carries
    half the robot's weight; a contact that ends before that is a scuff, counted in ``scuffs``, not a landing):
    ``support_fraction`` (share of the sole's bottom area with the terrain within ``support_tolerance`` [m] below
    it: how much of the sole stands on the tread or stone; 1 before the first touchdown), ``edge_distance`` [m] (the
    signed distance of the sole's footprint from the nearest edge of the box top it stands on, or of any box when it
    stands on the ground: negative when the sole overhangs an edge or stands against a riser; capped at
    :data:`EDGE_DISTANCE_CAP`), ``touchdown_slip`` [m] (horizontal motion of the sole from its first contact to the
    measurement), ``touchdowns`` and ``unsupported_steps`` (counts in the episode), ``min_support_fraction`` (the
    episode's smallest), ``terrain_height`` [m] (under the pelvis), ``terrain_kind`` (the class of the segment under
    the pelvis, ``"flat"`` between segments), ``terrain_end`` [m] (x of the terrain's end) and ``course_end``
    (``terrain_end + success_distance``). Changed: ``is_success`` is the pelvis past ``course_end`` with no fall, no
    self-collision and no unsupported touchdown in the episode (the mean speed does not count); a fall is the pelvis
    less than ``min_base_height`` above the terrain under it, or the torso tilted past ``max_torso_tilt``.

    ## Starting State
    As BipedWalk: the standing posture with the soles on the ground at the origin, upper-body noise. The terrain is
    drawn first (``reset(seed=...)`` reproduces terrain and posture).

    ## Episode End
    - Termination: BipedWalk's (a fall or a self-collision), and success.
    - Truncation: the time limit of the registration, :data:`MAX_EPISODE_STEPS` = 13000 steps of 4 ms (52 s): the
      longest default ``"random"`` terrain (three segments of 5 m, 1.5 m apart, the first at 1.5 m, then 1 m) at
      0.4 m/s. A reset warns once when a terrain needs longer at ``target_speed`` and names the
      ``max_episode_steps`` to pass to ``gym.make``.

    ## Arguments
    Every argument of BipedWalk (``target_speed`` defaults to 0.4 m/s here, ``speed_scale`` to 0.15 m/s), and:

    - ``terrain`` (``"stairs" | "platform" | "stepping_stones" | "slope" | "rough" | "random"``, default
      ``"random"``): one segment of the class, or ``n_segments`` of classes drawn uniformly.
    - ``segments`` (default None): an explicit terrain overriding ``terrain``, a non-empty list of dicts ``{"kind":
      class, "gap": flat ground before it [m] (optional), parameter: value, ...}``; a parameter not given is drawn
      from its range. Example: ``[{"kind": "stairs", "rise": 0.15, "tread": 0.3}]``.
    - ``terrain_ranges`` (default None): ``{class: {parameter: (low, high)}}`` replacing ranges of
      :data:`~redundancy_gym.assets.terrain.TERRAIN_RANGES` (a fixed value: ``(v, v)``).
    - ``n_segments`` (ints (low, high) >= 1; default (2, 3)), ``segment_spacing`` ((low, high) [m] of flat ground
      between segments; default (1.0, 1.5)), ``first_segment_distance`` ([m] >= 0.5, x of the first segment's
      start; default 1.5).
    - ``scan_size`` ((length, width) [m], default (1.6, 0.6)), ``scan_spacing`` ([m] > 0, default 0.1),
      ``scan_offset`` ([m], x of the scan's back row relative to the pelvis, default -0.2).
    - ``support_tolerance`` ([m] >= 0, default 0.04), ``min_support`` (in [0, 1], default 0.5): the touchdown rule.
    - ``unsupported_weight`` (>= 0, default 1.0), ``success_distance`` ([m] >= 0, default 1.0).

    ## Version History
    - v0: initial release (unreleased)
    """

    OBSERVATION_LAYOUT: dict[str, slice] = {  # noqa: RUF012 - the defaults'; an instance holds its own
        **BipedWalkEnv.OBSERVATION_LAYOUT,
        "height_scan": slice(BipedWalkEnv.OBSERVATION_SIZE, BipedWalkEnv.OBSERVATION_SIZE + 17 * 7),
    }
    OBSERVATION_SIZE = BipedWalkEnv.OBSERVATION_SIZE + 17 * 7
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
        terrain: str = "random",
        segments: Sequence[Mapping[str, Any]] | None = None,
        terrain_ranges: Mapping[str, Mapping[str, Sequence[float]]] | None = None,
        n_segments: Sequence[int] = (2, 3),
        segment_spacing: Sequence[float] = (1.0, 1.5),
        first_segment_distance: float = 1.5,
        scan_size: Sequence[float] = (1.6, 0.6),
        scan_spacing: float = 0.1,
        scan_offset: float = -0.2,
        support_tolerance: float = 0.04,
        min_support: float = 0.5,
        unsupported_weight: float = 1.0,
        success_distance: float = 1.0,
        speed_scale: float = 0.15,
        backend: str = "compiled",
        dynamics: float | dict[str, Any] | None = None,
        **kwargs: Any,
    ) -> None:
        check_known_arguments(kwargs, BipedTerrainEnv.__init__)
        arguments = constructor_arguments(BipedTerrainEnv.__init__, locals())
        self._terrain_choice = check_choice("terrain", terrain, TERRAINS)
        self._ranges = _parse_ranges(terrain_ranges)
        self._segments = None if segments is None else _parse_segments(segments)
        fewest, most = check_range_pair("n_segments", n_segments, low=1, integer=True)
        self._n_segments = (int(fewest), int(most))
        self._spacing = check_range_pair("segment_spacing", segment_spacing, low=0.0, unit="m")
        self._first_distance = check_real(
            "first_segment_distance",
            first_segment_distance,
            low=_MIN_FIRST_DISTANCE,
            unit="m",
            note="the standing toes reach x = 0.19 m",
        )
        length, breadth = check_real_array(
            "scan_size", scan_size, shape=(2,), low=0.0, unit="m", what="a (length, width) pair of finite numbers"
        )
        self._scan_spacing = check_real("scan_spacing", scan_spacing, low=0.0, low_open=True, unit="m")
        self._scan_offset = check_real("scan_offset", scan_offset, unit="m")
        self._scan = _scan_grid(float(length), float(breadth), self._scan_spacing, self._scan_offset)
        self._support_tolerance = check_real("support_tolerance", support_tolerance, low=0.0, unit="m")
        self._min_support = check_real("min_support", min_support, low=0.0, high=1.0)
        self._unsupported_weight = check_real("unsupported_weight", unsupported_weight, low=0.0)
        self._success_distance = check_real("success_distance", success_distance, low=0.0, unit="m")
        start = BipedWalkEnv.OBSERVATION_SIZE
        self.OBSERVATION_LAYOUT = {
            **BipedWalkEnv.OBSERVATION_LAYOUT,
            "height_scan": slice(start, start + len(self._scan)),
        }
        self.OBSERVATION_SIZE = start + len(self._scan)
        self._terrain = Terrain(())
        self._packed = pack_terrain(self._terrain)
        self._base_xml: str | None = None
        self._scan_x = np.empty(len(self._scan))
        self._scan_y = np.empty(len(self._scan))
        self._scan_out = np.empty(len(self._scan))
        self._point = (np.empty(1), np.empty(1), np.empty(1))
        self._base_ground = 0.0
        self._reset_touchdowns()
        super().__init__(**constructor_arguments(BipedWalkEnv.__init__, arguments))  # every BipedWalk argument
        utils.EzPickle.__init__(self, **arguments)

    # ------------------------------------------------------------------ scene
    def _scene_xml(self) -> str:
        if self._base_xml is None:  # composing the robot file costs about 27 ms: once per env
            self._base_xml = super()._scene_xml()
        return terrain_scene_xml(self._base_xml, self._terrain)

    def _draw_terrain(self) -> Terrain:
        """The terrain of the coming episode, drawn from the env's generator."""
        rng = self.np_random
        if self._segments is not None:
            return explicit_terrain(
                self._segments,
                rng,
                first_distance=self._first_distance,
                default_gap=0.5 * (self._spacing[0] + self._spacing[1]),
                ranges=self._ranges,
            )
        kinds: tuple[str, ...] = TERRAIN_KINDS
        count = self._n_segments
        if self._terrain_choice != "random":
            kinds, count = (self._terrain_choice,), (1, 1)
        return random_terrain(
            rng,
            kinds=kinds,
            n_segments=count,
            spacing=self._spacing,
            first_distance=self._first_distance,
            ranges=self._ranges,
        )

    def _resolve_names(self) -> None:
        super()._resolve_names()
        m = self.model
        count = self._terrain.geom_count
        ids = [m.geom(f"{TERRAIN_GEOM_PREFIX}_{k}").id for k in range(count)]
        floor = self._ground[0]
        if ids != list(range(floor + 1, floor + 1 + count)):
            raise EnvConfigError("the terrain geoms must follow the floor's with consecutive ids")
        self._ground = (floor, floor + 1 + count)
        # each sole box's bottom-face sample points (local frame) and their area weights, per foot
        samples: list[list[tuple[int, NDArray[np.float64], float]]] = [[], []]
        for name in BIPED_SOLE_GEOMS:
            g = m.geom(name).id
            hx, hy, hz = m.geom_size[g]
            nx, ny = _SOLE_GRID["toe" if "toe" in name else "plate"]
            xs = (np.arange(nx) + 0.5) / nx * 2.0 * hx - hx
            ys = (np.arange(ny) + 0.5) / ny * 2.0 * hy - hy
            local = np.array([[x, y, -hz] for x in xs for y in ys])
            samples[0 if name.startswith("r_") else 1].append((g, local, 4.0 * hx * hy / (nx * ny)))
        self._sole_samples = samples
        self._plate_geoms = (m.geom("r_sole_geom").id, m.geom("l_sole_geom").id)

    # ------------------------------------------------------------------ gymnasium API
    def reset_model(self) -> NDArray[np.float64]:
        terrain = self._draw_terrain()
        if terrain != self._terrain:
            self._terrain = terrain
            self._packed = pack_terrain(terrain)
            self._recompile()
        self._reset_touchdowns()
        self._weight = float(self.model.body_subtreemass[0]) * float(np.linalg.norm(self.model.opt.gravity))
        obs = super().reset_model()
        if self._target_speed > 0.0:
            warn_if_time_limit_short(
                self,
                _START_TIME + self.course_end / self._target_speed,
                f"walking this terrain (course_end {self.course_end:.2f} m) at target_speed",
            )
        return obs

    def _terminated(self, metrics: dict[str, Any]) -> bool:
        return super()._terminated(metrics) or bool(metrics["is_success"])

    def _reset_touchdowns(self) -> None:
        self._airborne = [0.0, 0.0]  # [s] each foot's time without ground contact (0: it touches)
        self._pending: list[tuple[NDArray[np.float64], tuple[float, float, float]] | None] = [None, None]
        self._last = (1.0, EDGE_DISTANCE_CAP, 0.0)  # support fraction, edge distance [m], slip [m]
        self._touchdowns = 0
        self._scuffs = 0
        self._unsupported = 0
        self._min_fraction = 1.0
        self._landed_unsupported = False

    # ------------------------------------------------------------------ task
    @property
    def terrain(self) -> Terrain:
        """The terrain of the current episode (empty before the first reset)."""
        return self._terrain

    @property
    def course_end(self) -> float:
        """The pelvis x [m] that ends the walk: the terrain's end plus ``success_distance``."""
        return self._terrain.end + self._success_distance

    @property
    def scan_points(self) -> NDArray[np.float64]:
        """(N, 2) the scan points' offsets (forward, left) [m] in the pelvis's heading frame, in observation order."""
        return self._scan.copy()

    def terrain_heights(self, points: NDArray[np.float64]) -> NDArray[np.float64]:
        """Terrain height [m] at world points (..., 2) (``backend``: the compiled kernel or the readable
        :meth:`Terrain.heights`; the same bits)."""
        p = np.asarray(points, dtype=np.float64)
        if self._backend == "python":
            return self._terrain.heights(p)
        flat = p.reshape(-1, 2)
        out = np.empty(len(flat))
        terrain_heights_kernel(np.ascontiguousarray(flat[:, 0]), np.ascontiguousarray(flat[:, 1]), *self._packed, out)
        return out.reshape(p.shape[:-1])

    def _heading(self) -> tuple[float, float]:
        """cos and sin of the pelvis's yaw."""
        w, x, y, z = self.data.qpos[3:7]
        yaw = math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
        return math.cos(yaw), math.sin(yaw)

    def _observation_tail(self) -> NDArray[np.float64]:
        qpos = self.data.qpos
        c, s = self._heading()
        forward, left = self._scan[:, 0], self._scan[:, 1]
        if self._backend == "python":
            points = np.column_stack((qpos[0] + c * forward - s * left, qpos[1] + s * forward + c * left))
            return self._terrain.heights(points) - qpos[2]
        np.multiply(forward, c, out=self._scan_x)
        self._scan_x -= s * left
        self._scan_x += qpos[0]
        np.multiply(forward, s, out=self._scan_y)
        self._scan_y += c * left
        self._scan_y += qpos[1]
        out = terrain_heights_kernel(self._scan_x, self._scan_y, *self._packed, self._scan_out)
        return out - qpos[2]

    def _ground_under_base(self) -> float:
        x, y, out = self._point
        x[0], y[0] = self.data.qpos[0], self.data.qpos[1]
        if self._backend == "python":
            self._base_ground = float(self._terrain.heights(np.array([[x[0], y[0]]]))[0])
        else:
            self._base_ground = float(terrain_heights_kernel(x, y, *self._packed, out)[0])
        return self._base_ground

    def _get_rew(self, metrics: dict[str, Any]) -> tuple[float, dict[str, float]]:
        _, terms = super()._get_rew(metrics)
        terms["reward_unsupported"] = -self._unsupported_weight if self._landed_unsupported else 0.0
        return float(sum(terms.values())), terms

    # ------------------------------------------------------------------ metrics
    def _metrics(self, forward_speed: float) -> dict[str, Any]:
        metrics = super()._metrics(forward_speed)
        self._track_touchdowns(metrics["normal_force"])
        fraction, edge, slip = self._last
        x = float(self.data.qpos[0])
        clean = not (self._fell or self._self_collided) and self._unsupported == 0
        metrics.update(
            support_fraction=fraction,
            edge_distance=edge,
            touchdown_slip=slip,
            touchdowns=self._touchdowns,
            scuffs=self._scuffs,
            unsupported_steps=self._unsupported,
            min_support_fraction=self._min_fraction,
            terrain_height=self._base_ground,
            terrain_kind=self._terrain.kind_at(x),
            terrain_end=self._terrain.end,
            course_end=self.course_end,
            is_success=bool(clean and x >= self.course_end),
        )
        return metrics

    def _track_touchdowns(self, normal: NDArray[np.float64]) -> None:
        """Advance each foot's touchdown state by the step's normal forces [N] and measure touchdowns."""
        self._landed_unsupported = False
        for foot in (0, 1):
            touching = bool(normal[foot] > _CONTACT_FORCE)
            if touching and self._airborne[foot] >= _MIN_SWING:  # a landing: measure it until it carries weight
                start = self.data.geom_xpos[self._plate_geoms[foot], :2].copy()
                self._pending[foot] = (start, self._touchdown(foot, start))
            pending = self._pending[foot]
            if pending is not None:
                if touching:
                    pending = (pending[0], self._touchdown(foot, pending[0]))
                    self._pending[foot] = pending
                if normal[foot] >= 0.5 * self._weight:
                    self._finish_touchdown(pending[1])
                    self._pending[foot] = None
                elif not touching:  # lifted before it carried weight: a swing that caught the terrain, no landing
                    self._scuffs += 1
                    self._pending[foot] = None
            self._airborne[foot] = 0.0 if touching else self._airborne[foot] + self._dt

    def _finish_touchdown(self, values: tuple[float, float, float]) -> None:
        self._last = values
        self._touchdowns += 1
        self._min_fraction = min(self._min_fraction, values[0])
        if values[0] < self._min_support:
            self._unsupported += 1
            self._landed_unsupported = True

    def _touchdown(self, foot: int, start: NDArray[np.float64]) -> tuple[float, float, float]:
        """``(support fraction, edge distance [m], slip [m])`` of ``foot``'s sole now (``start``: its plate's
        horizontal position at the first contact)."""
        d = self.data
        points, weights, corners = [], [], []
        for g, local, weight in self._sole_samples[foot]:
            frame = d.geom_xmat[g].reshape(3, 3)
            world = d.geom_xpos[g] + local @ frame.T
            points.append(world)
            weights.append(np.full(len(local), weight))
            hx, hy, hz = self.model.geom_size[g]
            box = np.array([[sx * hx, sy * hy, -hz] for sx in (-1, 1) for sy in (-1, 1)])
            corners.append((d.geom_xpos[g] + box @ frame.T)[:, :2])
        p = np.concatenate(points)
        w = np.concatenate(weights)
        gap = p[:, 2] - self.terrain_heights(p[:, :2])
        fraction = float(w[gap <= self._support_tolerance].sum() / w.sum())
        plate = d.geom_xpos[self._plate_geoms[foot], :2]
        edge = self._terrain.edge_distance(np.concatenate(corners), plate, cap=EDGE_DISTANCE_CAP)
        slip = float(np.hypot(*(plate - start)))
        return fraction, edge, slip


def _scan_grid(length: float, width: float, spacing: float, offset: float) -> NDArray[np.float64]:
    """(N, 2) the scan offsets (forward, left) [m]: rows back to front, columns right to left."""
    nx = int(round(length / spacing)) + 1
    ny = int(round(width / spacing)) + 1
    xs = offset + spacing * np.arange(nx)
    ys = -0.5 * (ny - 1) * spacing + spacing * np.arange(ny)
    return np.array([[x, y] for x in xs for y in ys])


def _parse_ranges(value: Any) -> dict[str, dict[str, tuple[float, float]]] | None:
    """``terrain_ranges`` checked: known classes and parameters, (low, high) pairs."""
    if value is None:
        return None
    if not isinstance(value, Mapping):
        raise EnvConfigError(
            f"terrain_ranges must be None or a dict {{class: {{parameter: (low, high)}}}} with classes "
            f"{', '.join(TERRAIN_KINDS)}, got {value!r}"
        )
    ranges: dict[str, dict[str, tuple[float, float]]] = {}
    for kind, entries in value.items():
        check_choice("terrain_ranges class", kind, TERRAIN_KINDS)
        if not isinstance(entries, Mapping):
            raise EnvConfigError(f"terrain_ranges[{kind!r}] must be a dict {{parameter: (low, high)}}, got {entries!r}")
        ranges[kind] = {}
        for name, pair in entries.items():
            check_choice(f"terrain_ranges[{kind!r}] parameter", name, SEGMENT_KEYS[kind])
            integer = name in ("steps", "stones")
            ranges[kind][name] = check_range_pair(f"terrain_ranges[{kind!r}][{name!r}]", pair, low=0.0, integer=integer)
    return ranges


def _parse_segments(value: Any) -> tuple[dict[str, Any], ...]:
    """``segments`` checked: a non-empty list of dicts with a known ``kind`` and its parameters."""
    if isinstance(value, (str, bytes, Mapping)) or not isinstance(value, Sequence) or not value:
        raise EnvConfigError(
            "segments must be None or a non-empty list of dicts {'kind': class, 'gap': m, parameter: value}, "
            f"got {value!r}"
        )
    parsed = []
    for i, item in enumerate(value):
        if not isinstance(item, Mapping) or "kind" not in item:
            raise EnvConfigError(
                f"segments[{i}] must be a dict with a 'kind' ({', '.join(TERRAIN_KINDS)}), got {item!r}"
            )
        kind = check_choice(f"segments[{i}]['kind']", item["kind"], TERRAIN_KINDS)
        entry: dict[str, Any] = {"kind": kind}
        for name, v in item.items():
            if name == "kind":
                continue
            check_choice(f"segments[{i}] parameter", name, ("gap", *SEGMENT_KEYS[kind]))
            entry[name] = check_real(f"segments[{i}][{name!r}]", v, low=0.0)
        parsed.append(entry)
    return tuple(parsed)


def _longest_terrain_time() -> float:
    """Time [s] to walk the longest default ``"random"`` terrain at 0.4 m/s: the start, the first segment's
    distance, the most segments at the longest class's greatest length with the widest spacing, then 1 m."""
    spec = default_config()
    count = spec["n_segments"][1]
    end = (
        spec["first_segment_distance"]
        + count * segment_length_bound(TERRAIN_RANGES)
        + (count - 1) * spec["segment_spacing"][1]
        + spec["success_distance"]
    )
    return _START_TIME + end / _WALK_SPEED


_CONTROL_RATE = 250  # [1/s] control steps per second at the default frame_skip (2 physics steps of 2 ms)
MAX_EPISODE_STEPS = int(math.ceil(_longest_terrain_time())) * _CONTROL_RATE
"""The registered time limit: 13000 steps of 4 ms (52 s), the longest default random terrain at 0.4 m/s."""
