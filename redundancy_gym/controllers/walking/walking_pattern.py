"""The walking pattern: footholds from the command, the ZMP reference, the LIPM/DCM CoM and the swing feet.

Timeline: a double support of ``start_duration`` moves the weight onto the first stance foot (the left: the
right foot swings first); then step ``k`` starts at ``t_k = start_duration + k T``. In step ``k`` foothold
``h_k`` swings to ``h_{k+2}`` over the single support ``[t_k, t_k + (1 - ratio) T]`` while the robot stands on
``h_{k+1}``; the double support that follows moves the ZMP from ``h_{k+1}`` to ``h_{k+2}``. ``h_0`` and ``h_1``
are the starting right and left feet; the first swing is one step length, later ones two.

The CoM is replanned at every step start over ``preview_steps`` steps ahead (the DCM of (4.5.1) backward from
a stop), starting from the CoM of the previous plan, so the reference is continuous; the preview error
decays as ``e^(-omega T)`` per step (about 5e-5 of a step after four 0.8 s steps).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import Any, SupportsFloat, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import ControllerError
from .dcm_planner import DcmPlan, DcmPlanner, horizontal_point
from .gait_config import GaitConfig
from .quintic import PiecewiseQuintic, Quintic
from .ssta import ObstacleBox, Ssta, StopReason, SwingModification
from .terrain_map import Foothold, TerrainMap

__all__ = ["PatternSample", "WalkingPattern", "ZmpCorrection"]

RIGHT, LEFT = 0, 1
MIN_ADJUSTED_SWING = 0.01
"""Shortest swing left [s] that :meth:`WalkingPattern.adjust_step` replans."""
MAX_SHIFT = 2.0
"""Largest foothold move [m] of one :meth:`WalkingPattern.adjust_step` (twice a leg's length)."""
MIN_STEP_WIDTH, MAX_STEP_WIDTH = 0.16, 0.30
"""The distance [m] across between a foothold moved onto its lane in the world (:meth:`WalkingPattern.set_terrain`)
and the foothold before it stays within these (or the nominal step's, where that is outside): a robot drifted a
stride's width across returns to its lanes over a few steps instead of setting a foot onto the other's (soles
0.15 m wide; :class:`StepAdjusterConfig`'s nearest landing beside the stance foot)."""
_R = TypeVar("_R")
_M = TypeVar("_M", bound=Callable[..., Any])


ADJUSTED_RISE = 0.35
"""Share of the remaining single support in which an adjusted swing rises to the step height."""
ADJUSTED_OVER = 0.7
"""Share of the remaining single support after which an adjusted swing is above its landing (then only descends)."""
TURN_WIDENING = 1.0
"""Outward shift of a turned foothold [m] per radian of heading change from the previous foothold, in toe lengths."""
MAX_STEP_TURN = 0.4
"""Largest heading change [rad] per step of a yaw-rate command (:meth:`WalkingPattern.set_velocity`): 0.5 rad/s at
0.8 s steps."""


@dataclass(frozen=True)
class PatternSample:
    """Task-space references of the walking pattern at one instant (world frame, z up).

    Attributes:
        time: [s] since the start of the walk.
        com: CoM position [m] (height ``com_height`` above the ground).
        com_velocity: [m/s].
        zmp: ZMP reference (x, y) [m].
        dcm: DCM reference (x, y) [m].
        feet: sole positions [m], rows right and left.
        feet_velocity: [m/s], rows right and left.
        feet_pitch: sole pitch about the lateral axis [rad] (positive: toes down), rows right and left.
        feet_pitch_rate: [rad/s].
        feet_yaw: sole heading about the vertical [rad] (0: the starting heading, +x), rows right and left; zeros
            while no yaw rate has been commanded (:meth:`WalkingPattern.set_velocity`).
        feet_yaw_rate: [rad/s].
        contact: which feet are planned on the ground (right, left).
        right_load: share of the weight the right foot carries [0, 1] (the ZMP's place between the feet).
        step: index of the current step (-1 during the start).
    """

    time: float
    com: NDArray[np.float64]
    com_velocity: NDArray[np.float64]
    zmp: NDArray[np.float64]
    dcm: NDArray[np.float64]
    feet: NDArray[np.float64]
    feet_velocity: NDArray[np.float64]
    feet_pitch: NDArray[np.float64]
    feet_pitch_rate: NDArray[np.float64]
    feet_yaw: NDArray[np.float64]
    feet_yaw_rate: NDArray[np.float64]
    contact: tuple[bool, bool]
    right_load: float
    step: int


@dataclass(frozen=True)
class ZmpCorrection:
    """The multi-body ZMP shift of one step, by step phase, that the LIPM leaves out.

    The LIPM puts all mass in the CoM; a swinging leg adds the rate of angular momentum about the CoM, which
    moves the ZMP by ``delta = (-Ldot_y, Ldot_x) / (m g)``. Planning the LIPM on ``r_ref - delta`` instead of
    ``r_ref`` puts the whole-body ZMP back on ``r_ref`` (the second stage of a two-stage pattern generator).

    Attributes:
        phases: step phases in [0, 1) at which the shift is given, increasing, shape (n,).
        offsets: ZMP shifts [m], shape (2, n, 2): for steps swinging the right foot, then the left.
        first: ZMP shifts [m] of the first steps of a walk, shape (m, n, 2): step ``k < m`` takes ``first[k]``
            instead of ``offsets[k % 2]`` (the first steps start from standing, with another momentum profile
            than the steady steps; ``None``: every step takes ``offsets``).
    """

    phases: NDArray[np.float64]
    offsets: NDArray[np.float64]
    first: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        phases, offsets = np.asarray(self.phases), np.asarray(self.offsets)
        if phases.ndim != 1 or offsets.shape != (2, phases.size, 2):
            raise ControllerError(f"need phases (n,) and offsets (2, n, 2), got {phases.shape} and {offsets.shape}")
        if not (np.all(np.isfinite(phases)) and np.all(np.isfinite(offsets))):
            raise ControllerError("ZMP correction must be finite")
        if phases.size and (phases[0] < 0.0 or phases[-1] >= 1.0 or np.any(np.diff(phases) <= 0.0)):
            raise ControllerError("phases must increase within [0, 1)")
        if self.first is not None:
            first = np.asarray(self.first)
            if first.ndim != 3 or first.shape[1:] != (phases.size, 2):
                raise ControllerError(f"need first (m, {phases.size}, 2), got {first.shape}")
            if not np.all(np.isfinite(first)):
                raise ControllerError("ZMP correction must be finite")

    def table(self, k: int) -> NDArray[np.float64]:
        """The shifts [m] (n, 2) of step ``k`` (>= 0): its own first-step table, else its foot's steady one."""
        first = self.first
        if first is not None and k < len(first):
            return first[k]
        return self.offsets[k % 2]


@dataclass(frozen=True)
class _RetimedSwing:
    """A swing replanned mid-way by :meth:`WalkingPattern.adjust_step`.

    Attributes:
        since: swing time of the adjustment [s].
        nominal_since: the nominal swing time it stood at [s] (height and pitch profiles).
        rate: nominal swing time per swing time from then on (> 1: a shortened single support) for the pitch.
        horizontal: the new horizontal path from ``since`` to touchdown (its time starts at 0).
        vertical: the new height from ``since`` to touchdown (its time starts at 0).
    """

    since: float
    nominal_since: float
    rate: float
    horizontal: PiecewiseQuintic
    vertical: PiecewiseQuintic


def _moves_footholds(method: _M) -> _M:
    """Marks a :class:`WalkingPattern` method that changes what the footholds depend on (step adjustments, velocity
    commands, obstacles, the terrain map): the footholds kept between calls are dropped, and within the method they
    are computed afresh (memoized only where :meth:`WalkingPattern._memoized` says so)."""

    @functools.wraps(method)
    def changing(self: WalkingPattern, *args: Any, **kwargs: Any) -> Any:
        self._keep(False)
        self._changing += 1
        try:
            return method(self, *args, **kwargs)
        finally:
            self._changing -= 1
            if self._changing == 0:
                self._keep(True)

    return changing  # type: ignore[return-value]


def _kept(kept: dict[int, _R] | None, k: int, compute: Callable[[], _R]) -> _R:
    """Step ``k``'s value from ``kept`` (a :class:`WalkingPattern` cache of :func:`_moves_footholds`), computed and
    kept there if missing; computed afresh where nothing is kept (None)."""
    if kept is None:
        return compute()
    value = kept.get(k)
    if value is None:
        value = kept[k] = compute()
    return value


class WalkingPattern:
    """Walking from a standing start along the starting heading (+x) at a commanded speed; later commands
    (:meth:`set_velocity`) change the velocity and turn the heading.

    Args:
        config: gait parameters.
        right_foot, left_foot: starting sole positions [m] (x, y, z); the ground is at their height.
        com: starting CoM (x, y) [m], at rest.
        speed: commanded forward speed [m/s] (the step length and duration follow from :meth:`GaitConfig.timing`).
        correction: the multi-body ZMP shift per step (None: the plain LIPM).
    """

    def __init__(
        self,
        config: GaitConfig,
        right_foot: ArrayLike,
        left_foot: ArrayLike,
        com: ArrayLike,
        speed: float,
        correction: ZmpCorrection | None = None,
    ) -> None:
        self.config = config
        self.correction = correction
        try:
            start = np.array([right_foot, left_foot], dtype=np.float64)
        except (TypeError, ValueError):
            start = np.zeros(0)
        if start.shape != (2, 3) or not np.all(np.isfinite(start)):
            raise ControllerError(
                f"right_foot and left_foot must be finite 3-vectors, got {right_foot!r}, {left_foot!r}"
            )
        com = horizontal_point("com", com)
        self.step_length, self.step_duration = config.timing(speed)
        self.speed = self.step_length / self.step_duration
        self.ground = float(start[:, 2].mean())
        self._start_feet = start
        self._center = start[:, :2].mean(axis=0)
        self._single = (1.0 - config.double_support_ratio) * self.step_duration
        self.planner = DcmPlanner(config.com_height)
        self._swing_cache: dict[int, tuple[PiecewiseQuintic, Quintic | PiecewiseQuintic]] = {}
        # step adjustments (push recovery, :meth:`adjust_step`): foothold shifts from a foothold index on, the
        # single supports that were shortened, and the re-timed swings
        self._shifts: list[tuple[int, NDArray[np.float64]]] = []
        # velocity commands (:meth:`set_velocity`): from foothold index ``first`` on, each foothold moves by
        # ``(j - first + 1) * delta`` (the step displacement the command adds); merged per first index
        self._velocity = np.array([self.speed, 0.0])
        self._velocity_changes: dict[int, NDArray[np.float64]] = {}
        # yaw-rate commands: from foothold index ``first`` on, each foothold's heading turns by
        # ``(j - first + 1) * delta``; until the first one (``_turned`` False) the footholds are computed as for
        # straight walking (bit for bit), after it along the turned headings (``_path``, cached per foothold)
        self._yaw_rate = 0.0
        self._heading_changes: dict[int, float] = {}
        self._turned = False
        self._path_cache: dict[int, tuple[float, float, float]] = {}
        self._yaw_cache: dict[int, tuple[float, float, Quintic]] = {}
        self._stale = False  # footholds changed since the CoM plan was made
        self._singles: dict[int, float] = {}
        self._retimed: dict[int, _RetimedSwing] = {}
        # obstacles (:meth:`set_obstacles`): the SSTA, the boxes it plans around, the swings it changed, and the
        # first foothold that would have to pass a box too large to pass (the walk stops in front of it)
        self._ssta: Ssta | None = None
        self._boxes: tuple[ObstacleBox, ...] = ()
        self._modifications: dict[int, SwingModification] = {}
        self._stop: int | None = None
        self._stop_cause: tuple[int, str, ObstacleBox] | None = None  # (foothold, cause, box) of the last stop set
        # earlier stops in front of passable boxes that the walk resumed from: footholds [stop, resume) in place,
        # and the moves along x that bring the footholds from each resume on back to the feet (not to steps in place)
        self._paused: list[tuple[int, int]] = []
        self._resumes: list[tuple[int, float]] = []
        # the walking line's sideways offsets [m] per foothold (sidesteps, :meth:`set_obstacles`)
        self._line: dict[int, float] = {}
        # terrain (:meth:`set_terrain`): the map, the plan-minus-world shift along x [m], each foothold placed on it
        # (keyed by what it was placed from), and the first foothold that may still move
        self._terrain: TerrainMap | None = None
        self._terrain_shift = 0.0
        self._terrain_lateral = (0.0, 1.0, 0.0)  # world (x, y) -> plan y: r10 x + r11 y + t_y
        # per foothold placed on the terrain: its nominal (x, y, the previous foothold's x, y), the placement and the
        # lateral shift
        self._holds: dict[int, tuple[tuple[float, float, float, float], Foothold, float]] = {}
        # what is computed from the footholds and the step timing, kept until a method that moves them
        # (:func:`_moves_footholds`) runs: the footholds (the terrain's placement, the CoM height and the step's
        # levels read the same few a dozen times a period), each step's CoM height ramps, whether it is level and
        # its swing foot's pitch blend; None within such a method, where only a :meth:`_memoized` scope keeps
        # footholds (``_memo``)
        self._footholds: dict[int, NDArray[np.float64]] | None = None
        self._ramps: dict[int, tuple[float, list[tuple[float, float, float, Quintic]]]] | None = None
        self._level_steps: dict[int, bool] | None = None
        self._pitch_blends: dict[int, Quintic] | None = None
        self._changing = 0
        self._memo: dict[int, NDArray[np.float64]] | None = None
        self._terrain_open = 2
        self._over_terrain: set[int] = set()  # steps whose swings pass terrain (held over it)
        self._height_steps: dict[float, Quintic] = {}  # the CoM height's unit step per duration [s]
        # toes down early in the swing, flat again well before touchdown: the trailing foot leaves the ground
        # without the ankle bending past its dorsiflexion limit
        peak, flat = config.swing_pitch_peak * self._single, config.swing_pitch_flat * self._single
        self._swing_pitch = PiecewiseQuintic(
            [
                Quintic.from_boundary(peak, 0.0, config.swing_pitch),
                Quintic.from_boundary(flat - peak, config.swing_pitch, 0.0),
                Quintic.from_boundary(self._single - flat, 0.0, 0.0),
            ]
        )
        times, zmp = self._knots(-1)
        zmp = self.planner.start_zmp(times, zmp, com)
        self._start_zmp = zmp[0].copy()  # the first knot of the standing start, for a replan within it
        self._plan: DcmPlan = self.planner.plan(times, zmp, com)
        self._plan_step = -1
        self._keep(True)

    def _keep(self, on: bool) -> None:
        """Keep what is computed from the footholds (``on``), or drop it and keep nothing (:func:`_moves_footholds`)."""
        self._footholds = {} if on else None
        self._ramps = {} if on else None
        self._level_steps = {} if on else None
        self._pitch_blends = {} if on else None

    # ------------------------------------------------------------------ footholds and timing
    def foothold(self, j: int) -> NDArray[np.float64]:
        """Sole position of foothold ``h_j`` [m]: ``h_0``/``h_1`` the starting right/left feet, then alternating
        (moved by the step adjustments made so far)."""
        memo = self._footholds
        if memo is None:
            memo = self._memo
            if memo is None:
                return self._foothold(j)
        h = memo.get(j)
        if h is None:
            h = memo[j] = self._foothold(j)
        return h.copy()

    def _foothold(self, j: int) -> NDArray[np.float64]:
        if j < 2:
            return self._start_feet[j].copy()
        side = RIGHT if j % 2 == 0 else LEFT
        if self._stop is not None and j >= self._stop:
            return self._in_place(j, self._stop)
        for stop, resume in self._paused:
            if stop <= j < resume:
                return self._in_place(j, stop)
        if self._turned:
            x, y, heading = self._path(j)
            # a turned foot is set wider by its heading change times the toe length: the feet of a turn would
            # otherwise come closer (the chord of the arc, the outer foot's toes turned in); without it the thighs
            # touched under random commands of 0.3 rad/s
            widen = TURN_WIDENING * self.config.toe_length * abs(heading - self.heading(j - 1))
            offset = (-1.0 if side == RIGHT else 1.0) * (0.5 * self.config.step_width + widen)
            h = np.array([x - math.sin(heading) * offset, y + math.cos(heading) * offset, self.ground])
            for first, shift in self._shifts:
                if j >= first:
                    h[:2] += shift
            for first, dx in self._resumes:
                if j >= first:
                    h[0] += dx
            h[1] += self._line.get(j, 0.0)
            return h
        # in Python floats, one array at the end (runs several times per control period): the array form's
        # elementwise additions in the same order, the same floats
        center_x, center_y = self._center.tolist()
        x = center_x + (j - 1) * self.step_length
        y = center_y + (-0.5 if side == RIGHT else 0.5) * self.config.step_width
        for first, shift in self._shifts:
            if j >= first:
                dx, dy = shift.tolist()
                x, y = x + dx, y + dy
        for first, delta in self._velocity_changes.items():
            if j >= first:
                dx, dy = ((j - first + 1) * delta).tolist()
                x, y = x + dx, y + dy
        for first, dx in self._resumes:
            if j >= first:
                x += dx
        if self._terrain is not None:
            return self._on_terrain(j, x, y + self._line.get(j, 0.0))
        return np.array((x, y + self._line.get(j, 0.0), self.ground))

    def _on_terrain(self, j: int, x: float, y: float) -> NDArray[np.float64]:
        """Foothold ``j`` (nominally at ``(x, y)`` [m] in the plan's frame) placed on the terrain map: within reach
        of the foothold before it, where the sole rests best on one plane (:meth:`TerrainMap.place`)."""
        terrain = self._terrain
        assert terrain is not None
        cached = self._holds.get(j)
        if cached is not None and j < self._terrain_open:
            # placed when its swing began (kept without looking back at the footholds before it: this runs many
            # times a period); a step adjustment (push recovery) moves it with the nominal foothold
            hold = cached[1]
            return np.array((hold.x + (x - cached[0][0]), y + cached[2], hold.z))
        before_hold = self.foothold(j - 1)
        previous, other = float(before_hold[0]), float(before_hold[1])
        key = (x, y, previous, other)
        if cached is not None and cached[0] == key:
            hold, lateral = cached[1], cached[2]
        else:
            shift = self._terrain_shift
            # the nominal step from the foothold before, as placed: an absolute schedule would make up for a short
            # step with a long one (a stone skipped, the next 0.6 m on)
            before = self._holds.get(j - 1)
            x = previous + (x - (before[0][0] if before is not None else previous)) if j >= 3 else x
            behind = float(self.foothold(j - 2)[0]) if j >= 2 else previous
            # ahead of the foot's own last foothold and of the other foot less a little, within a step's reach
            low = max(previous - 0.1, behind + 0.05) - shift
            lane = RIGHT if j % 2 == 0 else LEFT
            hold = terrain.place(lane, x - shift, low, previous + self.config.max_step_length - shift)
            stance_z = float(self.foothold(j - 1)[2])
            if abs(hold.z - stance_z) > terrain.config.height_step:
                # a step up or down: no longer than nominal, or the leg stretches past its length; placed again
                # within that reach, it may land before the edge (the next step then takes the height)
                reach = previous + self.step_length + terrain.config.step_reach - shift
                if hold.x > reach:
                    hold = terrain.place(lane, min(x - shift, reach), low, reach)
            hold = replace(hold, x=hold.x + shift)
            # the nominal y is the lane's in the world: mapped into the plan's frame at the landing
            r10, r11, t_y = self._terrain_lateral
            lateral = r10 * (hold.x - shift) + r11 * y + t_y - y
            # the step's width within [MIN_STEP_WIDTH, MAX_STEP_WIDTH]: a plan drifted 0.18 m across from the world
            # had put a foot onto the other foot's lane, into the stance foot
            side = 1.0 if j % 2 else -1.0  # the left foot's footholds are the odd ones
            nominal = side * (y - other)
            width = min(max(side * (y + lateral - other), min(MIN_STEP_WIDTH, nominal)), max(MAX_STEP_WIDTH, nominal))
            lateral = other + side * width - y
            self._holds[j] = (key, hold, lateral)
        return np.array((hold.x, y + lateral, hold.z))

    def foothold_pitch(self, j: int) -> float:
        """Pitch [rad] of the sole on foothold ``j`` (positive: toes down): along the terrain's surface there, 0 on
        flat ground or without a terrain map."""
        if self._terrain is None or j < 2 or self._turned:  # a turned walk plans over flat ground
            return 0.0
        cached = self._placed(j)
        return 0.0 if cached is None else cached.pitch

    def foothold_roughness(self, j: int) -> float:
        """Peak-to-peak [m] of the terrain under the sole on foothold ``j`` about its surface
        (:attr:`Foothold.roughness`): 0 on flat ground, treads, stones, ramps or without a terrain map."""
        if self._terrain is None or j < 2 or self._turned:
            return 0.0
        cached = self._placed(j)
        return 0.0 if cached is None else cached.roughness

    def _placed(self, j: int) -> Foothold | None:
        """Foothold ``j`` as placed on the terrain map (placed now if not yet; None where it is not on the map)."""
        cached = self._holds.get(j)
        if cached is None or j >= self._terrain_open:
            # placed, or placed again where what it depends on moved (a foothold whose swing has begun keeps its
            # placement: read without computing its position, several times a period)
            self.foothold(j)
            cached = self._holds.get(j)
        return None if cached is None else cached[1]

    @_moves_footholds
    def set_terrain(
        self, t: float, terrain: TerrainMap, shift: float, lateral: tuple[float, float, float] = (0.0, 1.0, 0.0)
    ) -> None:
        """Place the footholds not yet begun at ``t`` [s] on ``terrain`` (:class:`TerrainMap`, world frame), whose
        x is the plan's less ``shift`` [m] (the drift of the real stance foot from the plan), and plan the swings and
        the CoM's height over them; the landing of the swing under way is kept. Walking straight along +x only.
        ``lateral`` is the plan's y of a world point, ``(r10, r11, t_y)``: ``y_plan = r10 x + r11 y + t_y`` (the
        second row of the world-to-plan map): the footholds not yet begun are placed across as their nominal y taken
        in the world (the map's lanes, the stones' lanes), not where the drifted, turned plan would put them.

        Raises:
            ControllerError: the walk was turned by a yaw-rate command (:meth:`set_velocity`).
        """
        if self._turned:
            raise ControllerError("terrain planning plans for walking straight; a yaw rate was commanded")
        k = self.step_at(t)
        if k > self._plan_step:
            self._replan(k)
        self._terrain, self._terrain_shift = terrain, float(shift)
        self._terrain_lateral = (float(lateral[0]), float(lateral[1]), float(lateral[2]))
        self._terrain_open = k + 3 if k >= 0 else 2
        # the footholds not yet begun are placed again on the map as it is now
        self._holds = {j: v for j, v in self._holds.items() if j < self._terrain_open}
        kept = k if k >= 0 and t - self.step_start(k) > 0.01 * self.step_single(k) else k - 1
        self._swing_cache = {i: v for i, v in self._swing_cache.items() if i <= kept}
        self._stale = True
        self._replan_from(t)

    def level_step(self, t: float) -> bool:
        """Whether the step under way at ``t`` [s] swings over level ground: no terrain map, or lift-off, stance and
        landing within the map's ``height_step`` of each other and nothing to pass between them (a step the push
        recovery may move and re-time over flat ground; the standing start counts as level). On rough ground (a
        foothold's roughness above the map's ``rough_ground``) the bumps the swing passes over do not count: they
        are no edge for a moved landing to meet, and push recovery is what rough walks need most (development
        walks: 14 of 32 with it there, 9 without)."""
        terrain = self._terrain
        k = self.step_at(t)
        if terrain is None or k < 0 or self._turned:
            return True
        return _kept(self._level_steps, k, lambda: self._level(k, terrain))

    def _level(self, k: int, terrain: TerrainMap) -> bool:
        """:meth:`level_step` of step ``k`` on ``terrain``."""
        heights = self._memoized(self._step_heights, k)
        if max(heights) - min(heights) > terrain.config.height_step:
            return False
        if k not in self._over_terrain:
            return True
        rough = terrain.config.rough_ground
        return any(self.foothold_roughness(j) > rough for j in (k, k + 1, k + 2))

    def _step_heights(self, k: int) -> list[float]:
        """The heights [m] of step ``k``'s lift-off, stance and landing footholds, its swing planned (so that
        ``_over_terrain`` knows it)."""
        self._nominal_swing(k)
        return [float(self.foothold(j)[2]) for j in (k, k + 1, k + 2)]

    def _memoized(self, compute: Callable[..., _R], *args: Any) -> _R:
        """``compute(*args)`` with each foothold computed once within it (:meth:`foothold`): for calls that change
        nothing a foothold depends on, which read the same few footholds many times (the outer scope kept)."""
        saved = self._memo
        self._memo = {}
        try:
            return compute(*args)
        finally:
            self._memo = saved

    def _com_height(self, t: float, k: int) -> tuple[float, float]:
        """The CoM's height [m] and vertical velocity [m/s] at ``t`` in step ``k``.

        Step ``i`` has a level: ``com_height`` above the lower of its stance foothold and landing. The height moves
        from each level to the next by a quintic step (C2, at rest at both ends) over one step duration, delayed
        from the step's start by the map's ``rise_delay`` or ``descent_delay`` [s]; the steps add up where they
        overlap. A step down is taken low; a step up is risen to while the foot that landed higher takes the
        weight."""
        if self._terrain is None:
            return self.ground + self.config.com_height, 0.0
        terrain = self._terrain
        z, ramp_list = _kept(self._ramps, k, lambda: self._height_ramps(k, terrain))
        vz = 0.0
        for begin, duration, change, step in ramp_list:
            if t <= begin:
                continue
            values = step.values(min(t - begin, duration))
            assert values is not None  # a scalar profile
            (share,), (rate,), _ = values
            z += change * share
            vz += change * rate
        return z, vz

    def _height_ramps(self, k: int, terrain: TerrainMap) -> tuple[float, list[tuple[float, float, float, Quintic]]]:
        """Step ``k``'s CoM height before its ramps [m] (:meth:`_com_height`), and the ramps from each step's level to
        the next that may act in it: their begin [s], duration [s], height change [m] and unit step."""
        config = terrain.config
        height = self.config.com_height

        def level(i: int) -> float:
            if i < 0:
                return self.ground + height
            stance, landing = float(self.foothold(i + 1)[2]), float(self.foothold(i + 2)[2])
            return min(stance, landing) + height

        ramps = []
        for i in (k - 1, k):
            if i < 0:
                continue
            change = level(i) - level(i - 1)
            if change == 0.0:
                continue
            begin = self.step_start(i) + (config.rise_delay if change > 0.0 else config.descent_delay)
            duration = self.step_start(i + 1) - self.step_start(i)
            step = self._height_steps.get(duration)
            if step is None:  # one unit step per step duration, made once
                step = self._height_steps[duration] = Quintic.from_boundary(duration, 0.0, 1.0)
            ramps.append((begin, duration, change, step))
        return level(k - 2), ramps

    def _in_place(self, j: int, stop: int) -> NDArray[np.float64]:
        """Foothold ``j`` of a walk stopped in front of a box from foothold ``stop`` on: the feet step in place
        beside the last foothold before it."""
        last = self.foothold(stop - 1)
        own = self.foothold(stop - 1 if (stop - 1) % 2 == j % 2 else stop - 2)
        # beside the other foot, unless a box stands there in this foot's lane (a post the other foot passed)
        x = last[0]
        if self._ssta is not None and self._ssta.in_band(float(x), float(own[1]), self._boxes):
            x = own[0]
        h = np.array([x, own[1], own[2]])
        for first, shift in self._shifts:  # push recovery still moves the steps in place
            if stop <= first <= j:
                h[:2] += shift
        return h

    def heading(self, j: int) -> float:
        """Heading [rad] of foothold ``h_j`` about the vertical (0: the starting heading, +x; positive: to the
        left), turned by the yaw-rate commands so far (:meth:`set_velocity`)."""
        if j < 2 or not self._turned:
            return 0.0
        return sum((j - first + 1) * delta for first, delta in self._heading_changes.items() if j >= first)

    def _path(self, j: int) -> tuple[float, float, float]:
        """The walking line's point (x, y) [m] of foothold ``h_j`` (``j >= 1``, before step adjustments) and its
        heading [rad]: each step moves it by the step displacement (the velocity times the step duration) turned
        by the mean heading of the step's two footholds; the foothold lies half the step width beside it,
        perpendicular to its heading."""
        cached = self._path_cache.get(j)
        if cached is not None:
            return cached
        i = j - 1
        while i > 1 and i not in self._path_cache:
            i -= 1
        x, y, previous = self._path_cache[i] if i > 1 else (float(self._center[0]), float(self._center[1]), 0.0)
        for n in range(i + 1, j + 1):
            dx, dy = self.step_length, 0.0
            for first, delta in self._velocity_changes.items():
                if n >= first:  # each step from ``first`` on is longer by ``delta``
                    dx += float(delta[0])
                    dy += float(delta[1])
            heading = self.heading(n)
            mean = 0.5 * (previous + heading)
            c, s = math.cos(mean), math.sin(mean)
            x, y, previous = x + c * dx - s * dy, y + s * dx + c * dy, heading
            self._path_cache[n] = (x, y, heading)
        return self._path_cache[j]

    @property
    def velocity(self) -> NDArray[np.float64]:
        """The commanded walking velocity (forward, lateral) [m/s] (:meth:`set_velocity`)."""
        return self._velocity.copy()

    @property
    def yaw_rate(self) -> float:
        """The commanded yaw rate [rad/s] (:meth:`set_velocity`)."""
        return self._yaw_rate

    @_moves_footholds
    def set_velocity(
        self, t: float, forward: float, lateral: float = 0.0, replan: bool = True, yaw_rate: float = 0.0
    ) -> bool:
        """Walk at ``forward`` and ``lateral`` [m/s], turning at ``yaw_rate`` [rad/s] (positive: to the left), from
        the next step that has not begun: the footholds after the landing of the step under way at ``t`` (after
        the first landing during the standing start) move so that each step covers ``(forward, lateral) *
        step_duration`` in the frame of its heading, and each turns the heading by ``yaw_rate * step_duration``;
        with ``replan`` the CoM plan is replanned from ``t`` on (its CoM continues, its DCM follows from the new
        footholds, as after :meth:`adjust_step`), otherwise at the next step's start or the next call with
        ``replan``. Returns whether the command changed.

        Raises:
            ControllerError: a speed that is not finite, ``forward`` outside ``[0, max_step_length /
                step_duration]``, ``lateral`` so large that the feet would come closer than half the step
                width (``|lateral| step_duration > step_width / 2``), or ``|yaw_rate| step_duration`` above
                :data:`MAX_STEP_TURN`.
        """
        if not (np.isfinite(t) and t >= 0.0):
            raise ControllerError(f"time must be finite and >= 0, got {t!r}")
        fastest = self.config.max_step_length / self.step_duration
        if not (np.isfinite(forward) and 0.0 <= forward <= fastest + 1e-12):
            raise ControllerError(f"forward must lie in [0, {fastest:g}] m/s, got {forward!r}")
        widest = 0.5 * self.config.step_width / self.step_duration
        if not (np.isfinite(lateral) and abs(lateral) <= widest + 1e-12):
            raise ControllerError(f"lateral must lie in [-{widest:g}, {widest:g}] m/s, got {lateral!r}")
        sharpest = MAX_STEP_TURN / self.step_duration
        if not (np.isfinite(yaw_rate) and abs(yaw_rate) <= sharpest + 1e-12):
            raise ControllerError(f"yaw_rate must lie in [-{sharpest:g}, {sharpest:g}] rad/s, got {yaw_rate!r}")
        velocity = np.array([float(forward), float(lateral)])
        yaw_rate = float(yaw_rate)
        if np.array_equal(velocity, self._velocity) and yaw_rate == self._yaw_rate:
            if replan and self._stale:
                self._replan_from(t)
            return False
        k = self.step_at(t)
        if k > self._plan_step:
            self._replan(k)
        first = k + 3 if k >= 0 else 2
        if not np.array_equal(velocity, self._velocity):
            delta = (velocity - self._velocity) * self.step_duration
            self._velocity_changes[first] = self._velocity_changes.get(first, np.zeros(2)) + delta
            self._velocity = velocity
        if yaw_rate != self._yaw_rate:
            turn = (yaw_rate - self._yaw_rate) * self.step_duration
            self._heading_changes[first] = self._heading_changes.get(first, 0.0) + turn
            self._yaw_rate = yaw_rate
            self._turned = True
        self._path_cache = {}
        self._swing_cache = {i: v for i, v in self._swing_cache.items() if i <= k}  # later swings land elsewhere
        self._stale = True
        if replan:
            self._replan_from(t)
        return True

    # ------------------------------------------------------------------ obstacles (SSTA)
    @property
    def turned(self) -> bool:
        """Whether a yaw rate was commanded (:meth:`set_velocity`): the walk no longer goes along +x."""
        return self._turned

    @property
    def obstacle_boxes(self) -> tuple[ObstacleBox, ...]:
        """The obstacle bounding boxes the footholds and swings are planned around (:meth:`set_obstacles`)."""
        return self._boxes

    @property
    def stop_index(self) -> int | None:
        """The first foothold that stays in front of a box too large to pass (None: no such box)."""
        return self._stop

    @property
    def stop_reason(self) -> StopReason | None:
        """Why the walk stops at :attr:`stop_index`: the cause, the box and its class with the limits that decide
        it (None: the walk does not stop)."""
        cause = self._active_stop_cause()
        if cause is None or self._ssta is None:
            return None
        j, why, box = cause
        return StopReason(j, why, box, self._ssta.classify(box).classification, self._ssta.limits(box))

    def resumable(self, t: float) -> bool:
        """Whether the walk steps in place at ``t`` [s] in front of a box that is not too large to pass: the next
        :meth:`set_obstacles` then plans the walk on from the feet where they stand (a stop only stays where the
        box is impassable for this robot)."""
        cause = self._active_stop_cause()
        if cause is None or self._ssta is None:
            return False
        k = self.step_at(t)
        # the class alone (stop_reason would also write out the limits)
        return cause[0] < (k + 3 if k >= 0 else 2) and self._ssta.classify(cause[2]).classification != "too_large"

    def _resume(self, first: int) -> None:
        """Walk on from foothold ``first`` after the stop before it: the footholds from the stop to ``first`` stay
        in place, and ``first`` is a step ahead of the foothold before it, the later ones following."""
        assert self._stop is not None
        behind = self.foothold(first - 1)
        self._paused.append((self._stop, first))
        self._stop, self._stop_cause = None, None
        nominal = self.foothold(first)
        self._resumes.append((first, float(behind[0]) + self.step_length - float(nominal[0])))

    def _active_stop_cause(self) -> tuple[int, str, ObstacleBox] | None:
        """``(foothold, cause, box)`` of the stop in force (None: none, or one set without a box)."""
        cause = self._stop_cause
        return cause if self._stop is not None and cause is not None and cause[0] == self._stop else None

    def _set_stop(self, j: int, cause: str, box: ObstacleBox) -> None:
        self._stop = j
        self._stop_cause = (j, cause, box)

    def swing_modification(self, k: int) -> SwingModification | None:
        """How SSTA changed step ``k``'s swing (None: the nominal swing); for a step already over, the
        modification it was walked with (planning it again would use the boxes where the drift has mapped them
        since)."""
        if self._ssta is None or k < 0:
            return None
        if k < self._plan_step:
            return self._modifications.get(k)
        self._nominal_swing(k)
        return self._modifications.get(k)

    @_moves_footholds
    def set_obstacles(self, t: float, boxes: tuple[ObstacleBox, ...], ssta: Ssta) -> bool:
        """Plan the footholds and swings not yet begun at ``t`` [s] around obstacle ``boxes`` with ``ssta``
        (monograph 5.4.2): the walking line moves sideways where boxes are passed best beside the feet
        (:meth:`Ssta.plan_line`); a foothold whose sole would overlap a box moves along the walking direction to
        just in front of or behind it (the later footholds with it); a swing that passes a box in its lane steps
        over it or around it (:meth:`Ssta.swing`); a box too large to pass stops the walk in front of it. The CoM plan
        is replanned from ``t`` when a foothold moved. Planning is for walking straight along +x.

        The landing of the swing under way at ``t`` (and during the standing start, the first landing) is kept:
        it was planned when its swing began. Returns whether a foothold or a step timing changed.

        Raises:
            ControllerError: the walk was turned by a yaw-rate command (:meth:`set_velocity`).
        """
        if self._turned:
            raise ControllerError("obstacle planning (SSTA) plans for walking straight; a yaw rate was commanded")
        if not (np.isfinite(t) and t >= 0.0):
            raise ControllerError(f"time must be finite and >= 0, got {t!r}")
        k = self.step_at(t)
        if k > self._plan_step:
            self._replan(k)
        self._ssta, self._boxes = ssta, tuple(boxes)
        first = k + 3 if k >= 0 else 2
        changed = False
        if self._stop is not None and self._stop >= first:
            self._stop = None
            changed = True
        elif self.resumable(t):
            self._resume(first)
            changed = True
        walls = [(ssta.foothold_band(b)[0], b) for b in self._boxes if ssta.classify(b).classification == "too_large"]
        wall, wall_box = min(walls, key=lambda w: w[0], default=(np.inf, None))
        passable = tuple(b for b in self._boxes if float(b.lower[0]) < wall)
        reach = max((float(b.upper[0]) for b in self._boxes), default=-np.inf) + 2.0 * self.config.max_step_length
        # the line's offsets decide which lanes meet a box, the footholds' moves where the swings pass it: the
        # line is planned once more after footholds moved
        for _ in range(2):
            if self._stop is not None and self._stop >= first:
                self._stop = None
            changed |= self._plan_line(first, passable, ssta, min(reach, wall), free_end=bool(np.isfinite(wall)))
            moved = False
            j = first
            while (self._stop is None or j < self._stop) and self.foothold(j)[0] <= reach:
                h, previous = self.foothold(j), self.foothold(j - 1)
                move = ssta.foothold_shift(h, previous, self._boxes, behind=float(self.foothold(j - 2)[0]))
                if move is None or h[0] + (move or 0.0) > wall:
                    if wall_box is not None and h[0] + (move or 0.0) > wall:
                        self._set_stop(j, "too_large", wall_box)
                    else:
                        self._set_stop(j, "no_foothold", _box_at(ssta, h, self._boxes))
                    changed = True
                    break
                if move != 0.0:
                    self._shifts.append((j, np.array([move, 0.0])))
                    changed = moved = True
                j += 1
            if not moved:
                break
        # the swings from the first step not yet begun: their modification and (stepping over) their timing; a swing
        # only just begun (the controller samples the new step before it maps the obstacles again) is replanned too:
        # in its first 1 % it has not moved (a quintic covers 1e-5 of its path), and its old path passed boxes
        # where they were mapped a step ago
        kept = k if k >= 0 and t - self.step_start(k) > 0.01 * self.step_single(k) else k - 1
        self._swing_cache = {i: v for i, v in self._swing_cache.items() if i <= kept}
        self._modifications = {i: v for i, v in self._modifications.items() if i <= kept}
        over_single, long_swing = ssta.config.step_over_single, ssta.config.long_swing
        if over_single is not None or long_swing is not None:
            for i in range(max(k + 1, 0), j):
                single = self._ssta_single(i, ssta)
                if single is not None and self._singles.get(i) != single:
                    self._singles[i] = single
                    changed = True
                elif single is None and i in self._singles:
                    del self._singles[i]
                    changed = True
        if changed:
            self._path_cache = {}
            self._stale = True
            self._replan_from(t)
        return changed

    def _ssta_single(self, i: int, ssta: Ssta) -> float | None:
        """The single support [s] SSTA gives step ``i``'s swing (None: the nominal one): ``step_over_single`` over a
        box, and a swing longer than ``long_swing`` (a foothold moved back before a box makes the next swing of
        that foot long) slowed to the nominal swing's speed over ``long_swing``: the swing foot lags a fast swing
        and lands short of its foothold, hard enough to kick the stance foot back onto the box."""
        c = ssta.config
        start, end = self.foothold(i), self.foothold(i + 2)
        modification = ssta.swing(start, end, RIGHT if i % 2 == 0 else LEFT, self._boxes)
        if modification is not None and modification.kind == "over":
            # (slowed, a swing over a box pitched its toe into the box's edge on the random courses)
            return None if c.step_over_single is None else float(c.step_over_single)
        travel = float(np.hypot(end[0] - start[0], end[1] - start[1]))
        if c.long_swing is not None and travel > c.long_swing:
            return self._single * travel / c.long_swing
        return None

    def _plan_line(self, first: int, boxes: tuple[ObstacleBox, ...], ssta: Ssta, reach: float, free_end: bool) -> bool:
        """Offset the walking line sideways from foothold ``first`` on (:meth:`Ssta.plan_line`): the footholds up
        to ``reach`` [m] along x and two more, which come back to the line unless ``free_end``. A blocked swing
        stops the walk in front of it. Returns whether an offset changed."""
        line = self._line
        old = {j: line.pop(j) for j in [j for j in line if j >= first]}
        fixed = (line.get(first - 2, 0.0), line.get(first - 1, 0.0))
        bases = [self.foothold(first - 2)[:2] - (0.0, fixed[0]), self.foothold(first - 1)[:2] - (0.0, fixed[1])]
        if boxes and (self._stop is None or self._stop > first):
            # (a walk stopped in front of a box steps in place: its footholds never pass the reach)
            j, past = first, 0
            while past < 2 and (self._stop is None or j < self._stop):
                bases.append(self.foothold(j)[:2])
                past += int(bases[-1][0] > reach)
                j += 1
        plan = ssta.plan_line(np.array(bases), first % 2, fixed, boxes, free_end)
        for j, offset in enumerate(plan.offsets, start=first):
            if offset != 0.0:
                line[j] = float(offset)
        if plan.blocked is not None:
            self._stop = first + plan.blocked
            if boxes:  # (the plan meets no box without one; a blocked plan then only lacks a stance)
                swing = (bases[plan.blocked], bases[min(plan.blocked + 2, len(bases) - 1)])
                self._set_stop(self._stop, "blocked_swing", _box_passed(ssta, swing, boxes))
            for j in [j for j in line if j >= self._stop]:
                del line[j]
        return (
            any(abs(line.get(j, 0.0) - old.get(j, 0.0)) > 1e-6 for j in set(line) | set(old))
            or plan.blocked is not None
        )

    def _replan_from(self, t: float) -> None:
        """The CoM plan from ``t`` on, with the footholds as they are now."""
        k = self.step_at(t)
        com = self._plan.sample(t).position
        times, zmp = self._knots_from(t, k)
        self._plan = self.planner.plan(times, zmp, com)
        self._stale = False

    @property
    def single_support(self) -> float:
        """Planned single-support duration [s] of every step."""
        return self._single

    def step_single(self, k: int) -> float:
        """Single-support duration [s] of step ``k`` (other than nominal after a re-timing by :meth:`adjust_step`)."""
        return self._singles.get(k, self._single)

    def step_start(self, k: int) -> float:
        """Start time [s] of step ``k`` (its swing foot lifts off)."""
        start = self.config.start_duration + k * self.step_duration
        for i, single in self._singles.items():
            if i < k:
                start -= self._single - single
        return start

    def step_at(self, t: float) -> int:
        """Index of the step under way at ``t`` (-1 during the starting double support)."""
        if t < self.config.start_duration:
            return -1
        k = int((t - self.config.start_duration) // self.step_duration)
        if not self._singles:
            return k
        while k > 0 and self.step_start(k) > t:
            k -= 1
        while self.step_start(k + 1) <= t:
            k += 1
        return k

    def _zmp_point(self, j: int, along: float) -> NDArray[np.float64]:
        x, y, _ = self.foothold(j).tolist()
        inward = 1.0 if j % 2 == 0 else -1.0  # right feet (even) shift towards +y
        if self._turned:  # along and across the foot's heading
            heading = self.heading(j)
            c, s = math.cos(heading), math.sin(heading)
            across = inward * self.config.zmp_inset
            return np.array((x + c * along - s * across, y + s * along + c * across))
        return np.array((x + along, y + inward * self.config.zmp_inset))

    def _knots(self, first_step: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """ZMP knots from the start of ``first_step`` (-1: the standing start) to ``preview_steps`` steps ahead."""
        # the knots read each foothold several times (push recovery previews them a dozen times a period)
        return self._memoized(self._knots_uncached, first_step)

    def _knots_uncached(self, first_step: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        a = self.config.heel_toe_shift
        times, points = [], []
        if first_step < 0:
            times.append(0.0)
            points.append(self._center.copy())  # replaced by DcmPlanner.start_zmp
            first_step = 0
        last = first_step + self.config.preview_steps
        correction = self.correction
        for k in range(first_step, last + 1):
            t = self.step_start(k)
            single = self.step_single(k)
            if correction is None:
                times += [t, t + single]
                points += [self._zmp_point(k + 1, -a), self._zmp_point(k + 1, a)]
                continue
            stance, swing_to = self._zmp_point(k + 1, -a), self._zmp_point(k + 1, a)
            landing = self._zmp_point(k + 2, -a)
            ratio = self._single / self.step_duration
            offsets = correction.table(k)
            if self._turned:  # the tables are in the stance foot's frame (estimated walking along +x)
                heading = self.heading(k + 1)
                c, s = math.cos(heading), math.sin(heading)
                offsets = offsets @ np.array([[c, s], [-s, c]])
            for phase, offset in zip(correction.phases, offsets, strict=False):
                if phase < ratio:
                    base = stance + (swing_to - stance) * (phase / ratio)
                else:
                    base = swing_to + (landing - swing_to) * ((phase - ratio) / (1.0 - ratio))
                if single == self._single:
                    times.append(t + phase * self.step_duration)
                elif phase < ratio:  # a re-timed step: its single support is shorter, its double support is not
                    times.append(t + phase / ratio * single)
                else:
                    times.append(t + single + (phase - ratio) * self.step_duration)
                points.append(base - offset)
        times.append(self.step_start(last + 1))
        points.append(self._zmp_point(last + 2, -a))
        return np.array(times), np.array(points)

    # ------------------------------------------------------------------ sampling
    def sample(self, t: float) -> PatternSample:
        """The references at time ``t`` [s] (non-decreasing between calls, except after :meth:`restart`)."""
        if not t >= 0.0 or t == np.inf:
            raise ControllerError(f"time must be finite and >= 0, got {t!r}")
        k = self.step_at(t)
        if k > self._plan_step:
            self._replan(k)
        return self._memoized(self._sample, t, k)

    def _sample(self, t: float, k: int) -> PatternSample:
        # the plan's values and the swing as Python floats, the arrays built once each: this runs every control
        # period, where numpy's per-call overhead on 2- and 3-vectors cost several times the arithmetic (the
        # operations are the array form's, elementwise: the same floats)
        px, py, vx, vy, _, _, dcm_x, dcm_y, rx, ry = self._plan.values(t)
        feet_velocity = np.zeros((2, 3))
        pitch, pitch_rate = np.zeros(2), np.zeros(2)
        yaw, yaw_rate = np.zeros(2), np.zeros(2)
        contact = [True, True]
        if k < 0:
            feet = np.array([self.foothold(0), self.foothold(1)])
        else:
            feet = np.empty((2, 3))  # both rows set here
            swing_side = RIGHT if k % 2 == 0 else LEFT
            feet[swing_side] = self.foothold(k + 2)
            feet[1 - swing_side] = self.foothold(k + 1)
            if self._turned:
                yaw[swing_side], yaw[1 - swing_side] = self.heading(k + 2), self.heading(k + 1)
            s = t - self.step_start(k)
            if s < self.step_single(k):
                x, y, z, x_rate, y_rate, z_rate = self._swing_values(k, s)
                nominal, scale = self._nominal_swing_time(k, s)
                pitch_values = self._swing_pitch.values(nominal)
                assert pitch_values is not None  # a scalar profile
                (angle,), (rate,), _ = pitch_values
                rate = rate * scale
                modification = self._modifications.get(k)
                if modification is not None and modification.kind == "over" and self._ssta is not None:
                    # high over a box the knee bends so far that the ankle meets its dorsiflexion limit and the
                    # real foot pitches toes-down anyway; planned, its toe tip still follows the path
                    gain = self._ssta.config.raise_pitch
                    angle += gain * (z - self.ground)
                    rate += gain * z_rate
                # the pitched foot turns about its toe tip, which follows the swing path: no toe scuffing
                toe = self.config.toe_length
                if self._turned:  # the toe tip ahead along the foot's heading, which turns over the single support
                    heading, heading_rate = self._swing_yaw(k, nominal)
                    heading_rate *= scale
                    c, s_ = math.cos(heading), math.sin(heading)
                    ahead = toe * (1.0 - math.cos(angle))
                    ahead_rate = toe * rate * math.sin(angle)
                    feet[swing_side] = (x + c * ahead, y + s_ * ahead, z + toe * math.sin(angle))
                    feet_velocity[swing_side] = (
                        x_rate + (c * ahead_rate - s_ * ahead * heading_rate),
                        y_rate + (s_ * ahead_rate + c * ahead * heading_rate),
                        z_rate + toe * rate * math.cos(angle),
                    )
                    yaw[swing_side], yaw_rate[swing_side] = heading, heading_rate
                else:
                    # np.cos and np.sin as before (their last bit may differ from math's)
                    cos, sin = float(np.cos(angle)), float(np.sin(angle))
                    feet[swing_side] = (x + toe * (1.0 - cos), y + toe * 0.0, z + toe * sin)
                    toe_rate = toe * rate
                    feet_velocity[swing_side] = (
                        x_rate + toe_rate * sin,
                        y_rate + toe_rate * 0.0,
                        z_rate + toe_rate * cos,
                    )
                pitch[swing_side], pitch_rate[swing_side] = angle, rate
                contact[swing_side] = False
        zmp = np.array((rx, ry))
        com_z, com_vz = self._com_height(t, k)
        if self._terrain is not None and k >= 0:
            self._terrain_pitch(k, t - self.step_start(k), pitch, pitch_rate, contact)
        return PatternSample(
            time=float(t),
            com=np.array((px, py, com_z)),
            com_velocity=np.array((vx, vy, com_vz)),
            zmp=zmp,
            dcm=np.array((dcm_x, dcm_y)),
            feet=feet,
            feet_velocity=feet_velocity,
            feet_pitch=pitch,
            feet_pitch_rate=pitch_rate,
            feet_yaw=yaw,
            feet_yaw_rate=yaw_rate,
            contact=(contact[0], contact[1]),
            right_load=self._right_load(zmp, feet, contact),
            step=k,
        )

    def reference_zmp(self, t: float) -> NDArray[np.float64]:
        """The ZMP [m] (x, y) the whole body should have at ``t`` [s]: the piecewise-linear reference under the
        footholds (heel to toe in single support, foot to foot in double support). Without a :attr:`correction`
        it is the LIPM plan's ZMP; with one, the plan's ZMP is this minus the multi-body shift (the plan's CoM is
        the one the whole body needs for this ZMP)."""
        k = self.step_at(t)
        if self.correction is None or k < 0:
            return self._plan.sample(t).zmp
        a = self.config.heel_toe_shift
        start, single, end = self.step_start(k), self.step_single(k), self.step_start(k + 1)
        # in Python floats (the IKD reads it every period): the array form's elementwise operations, the same floats
        (stance_x, stance_y), (to_x, to_y) = self._zmp_point(k + 1, -a).tolist(), self._zmp_point(k + 1, a).tolist()
        s = t - start
        if s < single:
            w = s / single
            return np.array((stance_x + (to_x - stance_x) * w, stance_y + (to_y - stance_y) * w))
        landing_x, landing_y = self._zmp_point(k + 2, -a).tolist()
        w = (s - single) / (end - start - single)
        return np.array((to_x + (landing_x - to_x) * w, to_y + (landing_y - to_y) * w))

    def _terrain_pitch(
        self, k: int, s: float, pitch: NDArray[np.float64], rate: NDArray[np.float64], contact: list[bool]
    ) -> None:
        """Add the terrain's pitch to step ``k``'s feet at swing time ``s`` [s]: the stance foot's surface pitch; the
        swing foot's blends from its lift-off surface to its landing surface over the single support (a quintic, at
        rest at both ends), on top of its swing profile."""
        swing_side = RIGHT if k % 2 == 0 else LEFT
        pitch[1 - swing_side] += self.foothold_pitch(k + 1)
        landing = self.foothold_pitch(k + 2)
        if contact[swing_side]:
            pitch[swing_side] += landing
            return
        lift_off = self.foothold_pitch(k)
        if lift_off == landing:
            pitch[swing_side] += landing
            return
        single = self.step_single(k)
        blend = _kept(self._pitch_blends, k, lambda: Quintic.from_boundary(single, lift_off, landing))
        values = blend.values(min(s, single))
        assert values is not None  # a scalar profile
        (angle,), (angle_rate,), _ = values
        pitch[swing_side] += angle
        rate[swing_side] += angle_rate

    def _swing_yaw(self, k: int, nominal: float) -> tuple[float, float]:
        """Heading [rad] and its rate [rad/s] of step ``k``'s swing foot at nominal swing time ``nominal`` [s]: a
        quintic (C2, at rest at both ends) from the lift-off foothold's heading to the landing's over the single
        support."""
        start, end = self.heading(k), self.heading(k + 2)
        cached = self._yaw_cache.get(k)
        if cached is None or cached[0] != start or cached[1] != end:
            cached = (start, end, Quintic.from_boundary(self._single, start, end))
            self._yaw_cache = {i: v for i, v in self._yaw_cache.items() if i >= k - 1}
            self._yaw_cache[k] = cached
        if start == end:
            return start, 0.0
        angle, rate, _ = cached[2].evaluate(min(nominal, self._single))
        return float(angle), float(rate)

    def _replan(self, k: int) -> None:
        start = self.step_start(k)
        com = self._plan.sample(start).position
        times, zmp = self._knots(k)
        self._plan = self.planner.plan(times, zmp, com)
        self._plan_step = k
        self._stale = False
        self._swing_cache = {i: v for i, v in self._swing_cache.items() if i >= k}
        self._retimed = {i: v for i, v in self._retimed.items() if i >= k}

    def _swing_values(self, k: int, s: float) -> tuple[float, float, float, float, float, float]:
        """Step ``k``'s swing path at swing time ``s`` [s]: position (x, y, z) [m] and velocity [m/s] as floats."""
        retimed = self._retimed.get(k)
        if retimed is None:
            vertical, horizontal = self._nominal_swing(k)
        else:
            vertical, horizontal, s = retimed.vertical, retimed.horizontal, s - retimed.since
        height, path = vertical.values(s), horizontal.values(s)
        if height is None or path is None:  # not the scalar height and 2-D path of the pattern's swings
            z_array, vz_array, _ = vertical.evaluate(s)
            xy, vxy, _ = horizontal.evaluate(s)
            (x, y), (vx, vy) = xy.tolist(), vxy.tolist()
            return x, y, float(z_array), vx, vy, float(vz_array)
        ((z,), (vz,), _), ((x, y), (vx, vy), _) = height, path
        return x, y, z, vx, vy, vz

    def _swing_kinematics(
        self, k: int, s: float
    ) -> tuple[tuple[NDArray[np.float64], ...], tuple[NDArray[np.float64], ...]]:
        """Horizontal and vertical (position, velocity, acceleration) of step ``k``'s swing at ``s`` [s]."""
        retimed = self._retimed.get(k)
        if retimed is None:
            vertical, horizontal = self._nominal_swing(k)
            return horizontal.evaluate(s), vertical.evaluate(s)
        return retimed.horizontal.evaluate(s - retimed.since), retimed.vertical.evaluate(s - retimed.since)

    def _nominal_swing(self, k: int) -> tuple[PiecewiseQuintic, Quintic | PiecewiseQuintic]:
        """Step ``k``'s planned swing: height over the nominal single support, and the horizontal path (changed by
        SSTA where it passes an obstacle box)."""
        if k not in self._swing_cache:
            start, end = self.foothold(k), self.foothold(k + 2)
            if self._ssta is not None and self._boxes:
                side = RIGHT if k % 2 == 0 else LEFT
                modification = self._ssta.swing(start, end, side, self._boxes)
                if modification is not None:
                    self._modifications[k] = modification
                    self._swing_cache[k] = self._modified_swing(start, end, self.step_single(k), modification)
                    return self._swing_cache[k]
                self._modifications.pop(k, None)
            single = self.step_single(k)
            if self._terrain is not None and not self._turned:
                side = RIGHT if k % 2 == 0 else LEFT
                shift = self._terrain_shift
                envelope = self._terrain.envelope(side, float(start[0]) - shift, float(end[0]) - shift)
                b0, b1 = envelope.band
                self._over_terrain.discard(k)
                if b1 > b0:  # something to pass between lift-off and landing: held over, as over an obstacle box
                    self._over_terrain.add(k)
                    # above both ends as planned (a foothold placed on an older map may stand above its profile)
                    top = max(envelope.top, max(float(start[2]), float(end[2])) + self._terrain.config.min_rise)
                    over = SwingModification("over", top - self.ground, 0.0, (b0 + shift, b1 + shift))
                    self._swing_cache[k] = self._modified_swing(start, end, single, over)
                    return self._swing_cache[k]
            self._swing_cache[k] = (
                self._nominal_vertical(start, end, single),
                Quintic.from_boundary(single * (1.0 - self.config.swing_settle), start[:2], end[:2]),
            )
        return self._swing_cache[k]

    def _modified_swing(
        self,
        start: NDArray[np.float64],
        end: NDArray[np.float64],
        single: float,
        modification: SwingModification,
    ) -> tuple[PiecewiseQuintic, PiecewiseQuintic]:
        """An SSTA swing (monograph 5.4.2): its control points at the ends of the band where it passes the box,
        raised to the box's height (``"over"``) or shifted sideways by the overlap (``"around"``); C2 throughout.

        Over a box, three pieces: lift-off to the band's start, across the band, down to the landing; their
        durations share ``single`` in proportion to the distance each covers (at least a fifth each). Along x the
        sole moves forward only: at the band's ends its speed is the crossing speed, at most twice the mean speed of
        the outer pieces. Around a box: :meth:`_around`, at the nominal height.
        """
        a, e = float(start[0]), float(end[0])
        if e < a:  # a swing back (a foothold moved behind): the band is passed standing still along x
            a = e = 0.5 * (a + e)
        b0 = min(max(modification.band[0], a), e)
        b1 = min(max(modification.band[1], b0), e)
        top = self.ground + modification.height
        if modification.kind == "around":
            return self._nominal_vertical(start, end, single), self._around(start, end, single, modification, b0, b1)
        # each piece's share of the time follows the distance it covers: the rise happens before the band, the
        # descent after it
        shift = abs(modification.lateral)
        lift = (b0 - a) + (top - float(start[2]) if modification.kind == "over" else shift)
        cross = b1 - b0
        land = (e - b1) + (top - float(end[2]) if modification.kind == "over" else shift)
        total = lift + cross + land
        weights = np.array([lift, cross, land]) + 0.25 * total + 1e-9
        t1, t2, t3 = single * weights / weights.sum()
        # the horizontal motion ends before the landing (GaitConfig.swing_settle), by at most half the last piece
        t3_horizontal = max(t3 - self.config.swing_settle * single, 0.5 * t3)
        speed = (b1 - b0) / t2
        v1, v2 = min(speed, 2.0 * (b0 - a) / t1), min(speed, 2.0 * (e - b1) / t3_horizontal)
        # the nominal lateral path (start to end) plus the shift, which holds across the band
        lateral = Quintic.from_boundary(single * (1.0 - self.config.swing_settle), start[1], end[1])
        y1, vy1, ay1 = (float(x) for x in lateral.evaluate(t1))
        y2, vy2, ay2 = (float(x) for x in lateral.evaluate(t1 + t2))
        d = modification.lateral
        horizontal = PiecewiseQuintic(
            [
                Quintic.from_boundary(t1, start[:2], [b0, y1 + d], 0.0, [v1, vy1], 0.0, [0.0, ay1]),
                Quintic.from_boundary(t2, [b0, y1 + d], [b1, y2 + d], [v1, vy1], [v2, vy2], [0.0, ay1], [0.0, ay2]),
                Quintic.from_boundary(t3_horizontal, [b1, y2 + d], end[:2], [v2, vy2], 0.0, [0.0, ay2], 0.0),
            ]
        )
        vertical = PiecewiseQuintic(
            [
                Quintic.from_boundary(t1, start[2], top),
                Quintic.from_boundary(t2, top, top),
                Quintic.from_boundary(t3, top, end[2]),
            ]
        )
        return vertical, horizontal

    def _nominal_vertical(
        self, start: NDArray[np.float64], end: NDArray[np.float64], single: float
    ) -> PiecewiseQuintic:
        """The nominal swing height over ``single`` [s]: up to ``step_height`` above the landing and down, C2 at the
        apex (both pieces share the parabola's apex acceleration)."""
        half = 0.5 * single
        height = self.config.step_height
        apex_acceleration = -8.0 * height / single**2
        return PiecewiseQuintic(
            [
                Quintic.from_boundary(half, start[2], end[2] + height, end_acceleration=apex_acceleration),
                Quintic.from_boundary(half, end[2] + height, end[2], start_acceleration=apex_acceleration),
            ]
        )

    def _around(
        self,
        start: NDArray[np.float64],
        end: NDArray[np.float64],
        single: float,
        modification: SwingModification,
        b0: float,
        b1: float,
    ) -> PiecewiseQuintic:
        """The horizontal path of a swing around a box: the nominal one (settled before the landing) plus a sideways
        shift by ``modification.lateral``, made before the sole reaches the band ``[b0, b1]`` along x and taken back
        after it, each in at least ``0.3 * single`` [s] times the shift over ``quick_shift`` (at most 1).

        Along x the sole keeps the nominal quintic: the three pieces of a swing over a box, stalled along x while the
        shift was made, left a landing piece 0.36 m in 0.18 s, and the foot, 18 cm behind, touched down short and
        hard. A short shift needs little time; where the band begins at the lift-off the shift is under way while
        the sole starts forward (slowly: a quintic covers 3 % of its path in the first 15 % of its time)."""
        settled = single * (1.0 - self.config.swing_settle)
        base = Quintic.from_boundary(settled, start[:2], end[:2])
        a, e = float(start[0]), float(end[0])

        def reaches(x: float) -> float:
            """When the nominal sole reaches ``x`` along x [s] (bisection: the quintic is monotonic)."""
            if e <= a or x <= a:
                return 0.0
            if x >= e:
                return settled
            low, high = 0.0, settled
            for _ in range(40):
                mid = 0.5 * (low + high)
                low, high = (mid, high) if float(base.evaluate(mid)[0][0]) < x else (low, mid)
            return 0.5 * (low + high)

        d = float(modification.lateral)
        quick = self._ssta.config.quick_shift if self._ssta is not None else 0.05
        shortest = 0.3 * single * (min(abs(d) / quick, 1.0) if quick > 0.0 else 1.0)
        t_in, t_out = max(reaches(b0), shortest), min(reaches(b1), settled - shortest)
        if t_out < t_in:  # a short band: the shift is held for an instant between going out and back
            t_in = t_out = min(max(0.5 * (t_in + t_out), shortest), settled - shortest)
        shift_in, shift_out = Quintic.from_boundary(t_in, 0.0, d), Quintic.from_boundary(settled - t_out, d, 0.0)

        def state(t: float) -> tuple[NDArray[np.float64], ...]:
            """The path's position, velocity and acceleration at ``t`` [s]: the nominal plus the shift."""
            p, v, acc = (np.array(x, dtype=np.float64) for x in base.evaluate(t))
            w: Sequence[SupportsFloat]  # the shift's (position, velocity, acceleration) [m, m/s, m/s^2]
            if t <= t_in:
                w = shift_in.evaluate(t)
            elif t >= t_out:
                w = shift_out.evaluate(t - t_out)
            else:
                w = (d, 0.0, 0.0)
            for target, value in zip((p, v, acc), map(float, w), strict=True):
                target[1] += value
            return p, v, acc

        knots = [t for t in dict.fromkeys([0.0, t_in, t_out, settled])]
        pieces = []
        for t0, t1 in zip(knots[:-1], knots[1:], strict=True):
            if t1 - t0 <= 1e-12:
                continue
            (p0, v0, a0), (p1, v1, a1) = state(t0), state(t1)
            pieces.append(Quintic.from_boundary(t1 - t0, p0, p1, v0, v1, a0, a1))
        return PiecewiseQuintic(pieces)

    def _nominal_swing_time(self, k: int, s: float) -> tuple[float, float]:
        """The nominal swing time [s] at swing time ``s`` of step ``k``, and its rate (1 unless re-timed)."""
        retimed = self._retimed.get(k)
        if retimed is None:
            single = self._singles.get(k)
            if single is not None and single != self._single:  # a longer (or shorter) swing: the same profile
                rate = self._single / single
                return min(s * rate, self._single), rate
            return s, 1.0
        return min(retimed.nominal_since + (s - retimed.since) * retimed.rate, self._single), retimed.rate

    # ------------------------------------------------------------------ step adjustment
    def swing_state(self, t: float) -> tuple[int, float, float]:
        """``(step, swing time [s], remaining single support [s])`` at ``t``; remaining <= 0 outside a swing."""
        k = self.step_at(t)
        if k < 0:
            return k, 0.0, 0.0
        s = t - self.step_start(k)
        return k, s, self.step_single(k) - s

    def swing_foot(self, t: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Planned horizontal position [m] and velocity [m/s] of the swing foot's path at ``t`` (in single support)."""
        k, s, remaining = self.swing_state(t)
        if remaining <= 0.0:
            raise ControllerError(f"no foot swings at t={t!r}")
        (xy, vxy, _), _ = self._swing_kinematics(k, s)
        return np.asarray(xy, dtype=np.float64).copy(), np.asarray(vxy, dtype=np.float64).copy()

    def dcm(self, t: float) -> NDArray[np.float64]:
        """The planned DCM (x, y) [m] at ``t`` (replanned at a step start, as :meth:`sample` does)."""
        k = self.step_at(t)
        if k > self._plan_step:
            self._replan(k)
        return self._plan.sample(t).dcm

    @_moves_footholds
    def preview_dcm(self, t: float, shift: ArrayLike, single: float) -> NDArray[np.float64]:
        """The planned DCM at ``t`` [m] that :meth:`adjust_step` ``(t, shift, single)`` would give (nothing changes).

        The DCM is affine in ``shift``, with the same gain on x and y, which :class:`StepAdjuster` uses.
        """
        k, _, _ = self._check_adjustable(t, single)
        shifts, singles = self._shifts, self._singles
        try:
            self._shifts = [*shifts, (k + 2, np.asarray(shift, dtype=np.float64))]
            self._singles = {**singles, k: float(single)}
            times, zmp = self._knots_from(t, k)
        finally:
            self._shifts, self._singles = shifts, singles
        return self.planner.first_dcm(times, zmp)

    @_moves_footholds
    def adjust_step(self, t: float, shift: ArrayLike, single: float) -> None:
        """Move the swing foot's landing and every later foothold by ``shift`` (x, y) [m] and end the current single
        support ``single`` [s] after the step's start (sooner or later than planned, at most twice the nominal
        single support); the swing and the CoM plan are replanned from ``t`` on.

        The swing foot continues from its state at ``t`` (position, velocity and acceleration: the reference
        stays C2): it rises to the step height, is above its landing at ``ADJUSTED_OVER`` of the time left and
        then comes straight down; its toes-down pitch follows the planned profile, time-scaled. The CoM plan
        restarts at ``t`` from the current plan's CoM; its DCM at ``t`` follows from the new footholds and
        timing (:meth:`preview_dcm`).

        Raises:
            ControllerError: ``t`` is not inside a single support or ``single`` ends before ``t``.
        """
        k, s, _ = self._check_adjustable(t, single)
        shift = horizontal_point("shift", shift)
        if float(np.max(np.abs(shift))) > MAX_SHIFT:
            raise ControllerError(f"shift must be a finite (x, y) within +-{MAX_SHIFT} m, got {shift!r}")
        (xy, vxy, axy), (z, vz, az) = self._swing_kinematics(k, s)
        nominal, _ = self._nominal_swing_time(k, s)
        com = self._plan.sample(t).position
        if np.any(shift != 0.0):
            if self._shifts and self._shifts[-1][0] == k + 2:
                # the same step adjusted again (every period while the DCM error stays beyond the margin): one
                # entry per step, or every foothold would loop over hundreds of them
                self._shifts[-1] = (k + 2, self._shifts[-1][1] + shift)
            else:
                self._shifts.append((k + 2, shift))
        self._singles[k] = float(single)
        remaining = float(single) - s
        # the foot rises to the step height (or holds a higher one) and reaches the landing above it, then
        # comes straight down: a foot moving sideways close to the ground of a tilted robot would catch it
        rise, over = ADJUSTED_RISE * remaining, ADJUSTED_OVER * remaining
        top = max(float(z), self.ground + self.config.step_height)
        landing = self.foothold(k + 2)
        if self._terrain is None:
            vertical = PiecewiseQuintic(
                [
                    Quintic.from_boundary(rise, z, top, vz, 0.0, az, 0.0),
                    Quintic.from_boundary(remaining - rise, top, landing[2]),
                ]
            )
        else:  # over the terrain between here and the landing, held until above the landing, then down onto it
            shift = self._terrain_shift
            envelope = self._terrain.envelope(k % 2, float(xy[0]) - shift, float(landing[0]) - shift)
            top = max(float(z), envelope.top, float(landing[2]) + self._terrain.config.min_rise)
            vertical = PiecewiseQuintic(
                [
                    Quintic.from_boundary(rise, z, top, vz, 0.0, az, 0.0),
                    Quintic.from_boundary(over - rise, top, top),
                    Quintic.from_boundary(remaining - over, top, landing[2]),
                ]
            )
        horizontal = PiecewiseQuintic(
            [
                Quintic.from_boundary(over, xy, landing[:2], vxy, 0.0, axy, 0.0),
                Quintic.from_boundary(remaining - over, landing[:2], landing[:2]),
            ]
        )
        self._retimed[k] = _RetimedSwing(
            since=s,
            nominal_since=nominal,
            rate=(self._single - nominal) / remaining,
            horizontal=horizontal,
            vertical=vertical,
        )
        times, zmp = self._knots_from(t, k)
        self._plan = self.planner.plan(times, zmp, com)

    def _check_adjustable(self, t: float, single: float) -> tuple[int, float, float]:
        k, s, remaining = self.swing_state(t)
        if k > self._plan_step:
            self._replan(k)
        if remaining <= 0.0:
            raise ControllerError(f"a step can be adjusted in single support only; t={t!r} is not in one")
        if not np.isfinite(single) or single < s + MIN_ADJUSTED_SWING or single > 2.0 * self._single:
            raise ControllerError(
                f"single must lie in [{s + MIN_ADJUSTED_SWING!r}, {2.0 * self._single!r}] s (at "
                f"least {MIN_ADJUSTED_SWING} s of swing left), got {single!r}"
            )
        return k, s, remaining

    def _knots_from(self, t: float, k: int) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The ZMP knots of step ``k`` on (the standing start for ``k = -1``), cut at ``t`` (its ZMP
        interpolated)."""
        times, zmp = self._knots(k)
        if k < 0:
            zmp[0] = self._start_zmp
        i = int(np.searchsorted(times, t, side="right"))
        if i >= times.size:
            raise ControllerError(f"t={t!r} lies past the preview")
        if i == 0:
            return times, zmp
        w = (t - times[i - 1]) / (times[i] - times[i - 1])
        first = zmp[i - 1] + w * (zmp[i] - zmp[i - 1])
        if times[i] - t < 1e-9:  # on a knot: no zero-length segment
            return times[i:], zmp[i:]
        return np.concatenate([[t], times[i:]]), np.concatenate([first[None], zmp[i:]])

    @staticmethod
    def _right_load(zmp: NDArray[np.float64], feet: NDArray[np.float64], contact: list[bool]) -> float:
        if not contact[LEFT]:
            return 1.0
        if not contact[RIGHT]:
            return 0.0
        axis = feet[LEFT, :2] - feet[RIGHT, :2]
        share = float(np.dot(zmp - feet[RIGHT, :2], axis) / np.dot(axis, axis))
        load = 1.0 - share
        # np.clip(load, 0, 1) without its dispatch: NaN and -0.0 pass as there
        return load if load != load else 0.0 if load < 0.0 else 1.0 if load > 1.0 else load


def _box_at(ssta: Ssta, foothold: NDArray[np.float64], boxes: Sequence[ObstacleBox]) -> ObstacleBox:
    """The box in whose band (its lane, :meth:`Ssta.foothold_band`) ``foothold`` stands, else the nearest along x."""
    x, y = float(foothold[0]), float(foothold[1])
    for box in boxes:
        low, high = ssta.foothold_band(box)
        if ssta.in_lane(box, y) and low < x < high:
            return box
    return min(boxes, key=lambda b: abs(0.5 * float(b.lower[0] + b.upper[0]) - x))


def _box_passed(
    ssta: Ssta, swing: tuple[NDArray[np.float64], NDArray[np.float64]], boxes: Sequence[ObstacleBox]
) -> ObstacleBox:
    """The first box along x that a swing from ``swing[0]`` to ``swing[1]`` passes (its band), else the nearest."""
    x0, x1 = sorted((float(swing[0][0]), float(swing[1][0])))
    passed = [b for b in boxes if ssta.foothold_band(b)[1] > x0 and ssta.foothold_band(b)[0] < x1]
    if passed:
        return min(passed, key=lambda b: float(b.lower[0]))
    return min(boxes, key=lambda b: abs(0.5 * float(b.lower[0] + b.upper[0]) - x1))
