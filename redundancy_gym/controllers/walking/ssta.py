"""SSTA: step sequence and heuristic trajectory adaption from obstacle bounding boxes (monograph 5.4.2).

The first, planning layer of obstacle avoidance. Each obstacle's axis-aligned bounding box (from its swept-sphere
volumes) is classified against the two feet's lanes (the strips the soles sweep when walking straight):

1. no lane meets it: the feet pass beside it (``"beside"``);
2. a lane meets it: that foot steps over it (its swing's control points raised to the box's height) or swings
   around it (shifted sideways by the overlap), whichever modification is smaller and feasible
   (``"step_over"`` when a foot steps over, else ``"swing_around"``);
3. neither is feasible for a foot whose lane meets it: the walking line moves sideways so that both lanes pass
   beside it (``"sidestep"``, within ``max_line_shift``) or, failing that, too large (``"too_large"``): the walk
   stops in front of it.

The walking line's sideways offsets are planned for all boxes at once (:meth:`Ssta.plan_line`, dynamic
programming over the footholds), so that neighbouring boxes that want the line on opposite sides, or a box
beside the path, are passed together.

Footholds keep a margin to every box their sole would overlap: a foothold that falls into a box's band moves
to just in front of or just behind it, whichever changes the step length less and keeps it feasible; the later
footholds move with it, so every other step keeps its length.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, fields, replace
from typing import Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...geometry import SSV
from ...validation import check_real
from ..exceptions import ControllerError

__all__ = [
    "OBSTACLE_CLASSES",
    "STOP_CAUSES",
    "LinePlan",
    "ObstacleBox",
    "ObstacleDecision",
    "Ssta",
    "SstaConfig",
    "StopReason",
    "SwingModification",
    "bounding_boxes",
]

BLOCKED_COST = 1e6
"""The cost of a swing through a box it can neither step over nor swing around (:meth:`Ssta.plan_line`): finite,
so a plan always comes back and says where it is blocked."""

OBSTACLE_CLASSES = ("beside", "sidestep", "step_over", "swing_around", "too_large")
"""The classes of :meth:`Ssta.classify`: the monograph's (a foot next to it: ``"beside"``, or ``"sidestep"`` where
the walking line moves sideways to put the feet next to it; over it; too large), with ``"swing_around"`` for
swings shifted sideways."""

STOP_CAUSES = ("too_large", "no_foothold", "blocked_swing")
"""Why the walking pattern stops in front of a box (:class:`StopReason`): the box is ``"too_large"`` (its class, no
foot steps over it or around it and the walking line cannot move beside it), no foothold in front of or behind it
keeps the step lengths and the margins (``"no_foothold"``), or the walking line's plan found no swing past it
(``"blocked_swing"``, :meth:`Ssta.plan_line`'s ``blocked``)."""


@dataclass(frozen=True)
class ObstacleBox:
    """An axis-aligned bounding box [m] (world frame, z up).

    Attributes:
        lower: ``(x, y, z)`` of the lower corner.
        upper: ``(x, y, z)`` of the upper corner.
    """

    lower: NDArray[np.float64]
    upper: NDArray[np.float64]

    def __post_init__(self) -> None:
        lower = np.asarray(self.lower, dtype=np.float64)
        upper = np.asarray(self.upper, dtype=np.float64)
        if (
            lower.shape != (3,)
            or upper.shape != (3,)
            or not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper)))
        ):
            raise ControllerError(f"a box needs finite 3-vector corners, got {self.lower!r}, {self.upper!r}")
        if np.any(upper < lower):
            raise ControllerError(f"a box's upper corner must not lie below its lower one, got {lower}, {upper}")
        object.__setattr__(self, "lower", lower)
        object.__setattr__(self, "upper", upper)

    @classmethod
    def of_volume(cls, volume: SSV) -> ObstacleBox:
        """The bounding box of a swept-sphere volume: its vertices' box grown by its radius."""
        points = volume.points
        return cls(points.min(axis=0) - volume.radius, points.max(axis=0) + volume.radius)

    @property
    def height(self) -> float:
        """Top of the box [m] (z of the upper corner)."""
        return float(self.upper[2])

    @property
    def depth(self) -> float:
        """Extent along the walking direction x [m]."""
        return float(self.upper[0] - self.lower[0])

    def overlaps(self, other: ObstacleBox) -> bool:
        """Whether the two boxes share a point."""
        return bool(np.all(self.lower <= other.upper) and np.all(other.lower <= self.upper))

    def union(self, other: ObstacleBox) -> ObstacleBox:
        """The smallest box holding both."""
        return ObstacleBox(np.minimum(self.lower, other.lower), np.maximum(self.upper, other.upper))


def bounding_boxes(volumes: Sequence[SSV]) -> tuple[ObstacleBox, ...]:
    """The bounding boxes of obstacle volumes, overlapping ones merged (an obstacle modelled by several volumes,
    a box by the two triangles of a rectangle, gives one box), ordered by their lower x."""
    boxes = [ObstacleBox.of_volume(v) for v in volumes]
    merged = True
    while merged:  # a merge can make a box meet one it did not meet before
        merged = False
        out: list[ObstacleBox] = []
        for box in boxes:
            for i, other in enumerate(out):
                if box.overlaps(other):
                    out[i] = other.union(box)
                    merged = True
                    break
            else:
                out.append(box)
        boxes = out
    return tuple(sorted(boxes, key=lambda b: (float(b.lower[0]), float(b.lower[1]))))


@dataclass(frozen=True)
class SstaConfig:
    """Margins and limits of :class:`Ssta` (the foot's size defaults to the Lola-like biped's sole).

    Attributes:
        foothold_margin: distance [m] kept along the walking direction between a standing sole and a box in its lane.
        lateral_margin: distance [m] kept sideways between a sole's edge and a box it passes beside (also what
            makes a lane meet a box).
        clearance: height [m] of a swing sole above a box it steps over, and its distance along x from the box while
            it rises and descends.
        step_height: the nominal swing apex [m] (a foot stepping over needs ``height + clearance - step_height``
            more: the cost compared with a sideways shift).
        max_step_over_height: highest swing sole [m] above the ground (the leg's reach).
        max_step_over_depth: deepest box [m] along x a foot steps over.
        max_outward_shift: largest sideways shift [m] of a swing foot away from the other foot (the hip's roll
            range: with the nominal 0.18 m between the feet, the swing foot passes 0.32 m beside the stance foot).
        max_inward_shift: largest sideways shift [m] towards the other foot (the stance leg stands there).
        toe_length: sole point to toe tip [m].
        heel_length: sole point to heel [m].
        foot_half_width: half the sole's width [m].
        max_line_shift: largest sideways move [m] of the walking line around a box neither foot can step over or
            swing around by ``quick_shift``.
        quick_shift: the largest swing shift [m] chosen before moving the walking line: the real swing foot
            follows a sideways shift by about half within a step (the hip's roll servo), so longer shifts are
            taken only where the line cannot move (the monograph's triangle, in both feet's paths).
        lateral_cost: weight of a sideways shift against a raise of the same length when the smaller
            modification is chosen: the swing foot follows a quick sideways shift less closely than a raise
            (on the random courses it lagged by up to 0.15 m), and a box low enough is safer stepped over.
        max_step_length: longest step [m] between the two feet's footholds that a moved foothold may make.
        min_step_length: shortest (most negative) step [m]: a moved foothold never lands behind the other foot by
            more than this.
        step_over_single: single-support duration [s] of a step over a box (None: the nominal one); a slower swing
            lifts the foot to the box's height with smaller accelerations (Lola stepped over with 1 s steps).
        long_swing: the longest swing [m] of a foot (between its footholds) at the nominal single-support duration;
            a longer one is slowed to the same mean speed (None: never).
        raise_pitch: toe-down pitch [rad/m] added to a swing over a box per metre of its toe tip's height: with the
            knee bent that far the ankle meets its dorsiflexion limit (a swing 0.26 m high, planned at 0.25 rad,
            pitched 0.57 rad and its toe caught the box's edge); planned, the foot turns about its toe tip, which
            keeps to the path.
        stuck_cost: cost of a walking-line offset that leaves a foothold in a box's band (its lane meeting the box
            with the full margin) where no move along x fits (:meth:`foothold_shift`): the walk would stop there.
        max_line_move: largest sideways move [m] of one foot's foothold by the walking line's offset in one step
            (:meth:`Ssta.plan_line`; a larger one ran the legs into each other).
        max_widening: largest widening [m] of the stance by the line's offsets (the foot on the side of a move goes
            first; the stance never narrows).
        line_offset_cost: cost per metre of line offset per foothold (the line comes back when nothing holds it).
        line_move_cost: cost per metre a foot moves sideways in a step (a few large moves rather than many).
        long_shift_cost: cost added to a swing shifted sideways by more than ``quick_shift``.
        move_clearance: distance [m] along x kept between the sole of a swing that moves sideways (along the
            straight line between its footholds) and every box it does not pass beside.
        straddle_height: the highest box [m] (its swept-sphere bounding box) that a swing shifted outwards around
            it keeps between the legs: the legs slant inwards from the feet to the hips, and above it the shank or
            knee passes over the box's top (the triangle, 0.345 m with its radius, is passed so; posts of 0.39 to
            0.45 m touched a shank or knee on the random courses). A higher box blocks such a swing: the walking line
            moves, or the walk stops in front of it.
        line_tolerance: how much [m] less than ``lateral_margin`` a sideways-moving swing may keep to a box (the
            boxes move by a few millimetres each time the robot's drift maps them again).
    """

    foothold_margin: float = 0.07
    lateral_margin: float = 0.035
    clearance: float = 0.05
    step_height: float = 0.07
    max_step_over_height: float = 0.3
    max_step_over_depth: float = 0.3
    max_outward_shift: float = 0.14
    max_inward_shift: float = 0.0
    toe_length: float = 0.165
    heel_length: float = 0.095
    foot_half_width: float = 0.075
    max_line_shift: float = 0.3
    quick_shift: float = 0.05
    lateral_cost: float = 2.0
    max_step_length: float = 0.6
    min_step_length: float = 0.0
    step_over_single: float | None = None
    long_swing: float | None = 0.7
    raise_pitch: float = 1.5
    stuck_cost: float = 1.0
    max_line_move: float = 0.3
    max_widening: float = 0.3
    line_offset_cost: float = 0.05
    line_move_cost: float = 1.0
    long_shift_cost: float = 3.0
    move_clearance: float = 0.15
    line_tolerance: float = 0.01
    straddle_height: float = 0.35

    def __post_init__(self) -> None:
        positive = ("max_step_over_height", "max_step_length", "toe_length", "heel_length", "foot_half_width")
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in ("step_over_single", "long_swing"):
                unit = "s" if f.name == "step_over_single" else "m"
                check_real(f.name, value, low=0.0, low_open=True, optional=True, unit=unit, error=ControllerError)
            elif f.name == "min_step_length":  # may be negative: a step back
                check_real(f.name, value, unit="m", error=ControllerError)
            else:
                check_real(f.name, value, low=0.0, low_open=f.name in positive, error=ControllerError)
        if self.min_step_length >= self.max_step_length:
            raise ControllerError("min_step_length must be below max_step_length")


class StopReason(NamedTuple):
    """Why a walk stops in front of an obstacle (:attr:`WalkingPattern.stop_reason
    <redundancy_gym.controllers.walking.WalkingPattern.stop_reason>`).

    Attributes:
        foothold: the first foothold that stays in front of the box (the feet step in place from it on).
        cause: one of :data:`STOP_CAUSES`.
        box: the box the walk stops in front of.
        classification: the box's class (:meth:`Ssta.classify`, one of :data:`OBSTACLE_CLASSES`); only
            ``"too_large"`` is impassable for this robot.
        limits: the limits that decide the class, in words (:meth:`Ssta.limits`).
    """

    foothold: int
    cause: str
    box: ObstacleBox
    classification: str
    limits: str

    @property
    def impassable(self) -> bool:
        """Whether the box is too large to pass for this robot (a stop that the monograph's classification allows)."""
        return self.classification == "too_large"

    def describe(self) -> str:
        """One line: the cause, the box [m] and its class with its limits."""
        lo, hi = self.box.lower, self.box.upper
        return (
            f"{self.cause} before foothold {self.foothold}: box x [{lo[0]:.3f}, {hi[0]:.3f}] y [{lo[1]:.3f}, "
            f"{hi[1]:.3f}] height {self.box.height:.3f} m, class {self.classification} ({self.limits})"
        )


class SwingModification(NamedTuple):
    """How :class:`Ssta` changes one swing.

    Attributes:
        kind: ``"over"`` (control points raised) or ``"around"`` (shifted sideways).
        height: the sole's height [m] above the ground while it passes the box (``"over"``; else the step height).
        lateral: sideways shift [m] of the swing path while it passes the box (``"around"``; else 0); positive +y.
        band: ``(start, end)`` x [m] of the sole point between which the modification holds (the box grown by the
            toe, the heel and the clearance).
    """

    kind: Literal["over", "around"]
    height: float
    lateral: float
    band: tuple[float, float]


class LinePlan(NamedTuple):
    """The walking line's sideways offsets of :meth:`Ssta.plan_line`.

    Attributes:
        offsets: per foothold from the first one planned, the offset [m] added to its y.
        cost: the plan's cost (:class:`SstaConfig`'s line, shift and raise costs); at least
            :data:`BLOCKED_COST` when some swing is blocked.
        blocked: index (into ``offsets``) of the first foothold whose swing is blocked (None: none is).
    """

    offsets: NDArray[np.float64]
    cost: float
    blocked: int | None


class ObstacleDecision(NamedTuple):
    """The class of one obstacle box and what each foot does about it.

    Attributes:
        box: the bounding box.
        classification: one of :data:`OBSTACLE_CLASSES`.
        feet: per foot (right, left): ``"over"``, ``"around"``, ``"beside"`` or ``"blocked"``.
        lateral: per foot, the sideways shift [m] ``"around"`` needs (0 otherwise).
        line_shift: the walking line's sideways move [m] of a ``"sidestep"`` (0 otherwise).
    """

    box: ObstacleBox
    classification: str
    feet: tuple[str, str]
    lateral: tuple[float, float]
    line_shift: float = 0.0


class Ssta:
    """Step sequence and heuristic trajectory adaption (monograph 5.4.2), as pure functions of the footholds
    and the obstacle boxes (the walking pattern applies them).

    Args:
        config: margins and limits.
        lanes: the nominal lateral positions [m] of the right and left soles' centres (walking along +x).
    """

    def __init__(self, config: SstaConfig | None = None, lanes: ArrayLike = (-0.09, 0.09)) -> None:
        self.config = config or SstaConfig()
        lanes_a = np.asarray(lanes, dtype=np.float64)
        if lanes_a.shape != (2,) or not np.all(np.isfinite(lanes_a)) or not lanes_a[0] < lanes_a[1]:
            raise ControllerError(f"lanes must be finite (right, left) with right < left, got {lanes!r}")
        self.lanes = lanes_a
        self._without_margin: Ssta | None = None

    def _marginless(self) -> Ssta:
        """This SSTA without the lateral margin (built once)."""
        if self._without_margin is None:
            self._without_margin = Ssta(replace(self.config, lateral_margin=0.0), self.lanes)
        return self._without_margin

    # ------------------------------------------------------------------ classification
    def _lateral_options(
        self, box: ObstacleBox, y: float, side: int, outward: float | None = None
    ) -> tuple[bool, float]:
        """Whether a sole centred at ``y`` meets ``box`` sideways, and the shift [m] that clears it (signed; NaN
        when no shift within the limits does; ``outward`` overrides ``max_outward_shift``)."""
        c = self.config
        half = c.foot_half_width + c.lateral_margin
        low, high = y - half, y + half
        if high <= box.lower[1] or low >= box.upper[1]:
            return False, 0.0
        # clear it on the side of the box's centre away from the box: up moves the sole's lower edge above the box
        up, down = float(box.upper[1]) - low, float(box.lower[1]) - high
        outward_up = side == 1  # the left foot's outside is +y
        outward = c.max_outward_shift if outward is None else min(outward, c.max_outward_shift)
        limit_up = outward if outward_up else c.max_inward_shift
        limit_down = c.max_inward_shift if outward_up else outward
        candidates = [s for s, limit in ((up, limit_up), (down, limit_down)) if abs(s) <= limit + 1e-12]
        if not candidates:
            return True, float("nan")
        return True, min(candidates, key=abs)

    def _can_step_over(self, box: ObstacleBox) -> bool:
        c = self.config
        return box.height + c.clearance <= c.max_step_over_height and box.depth <= c.max_step_over_depth

    def foot_decision(self, box: ObstacleBox, y: float, side: int, outward: float | None = None) -> tuple[str, float]:
        """What a foot with its sole centred at ``y`` [m] does about ``box``: ``("beside", 0)``, ``("over", 0)``,
        ``("around", shift)`` or ``("blocked", 0)``; the smaller modification wins (the raise of the swing
        above its step height against ``lateral_cost`` times the sideways shift; ``outward`` [m] limits the
        shift away from the other foot below ``max_outward_shift``)."""
        meets, shift = self._lateral_options(box, y, side, outward)
        if not meets:
            return "beside", 0.0
        c = self.config
        raise_ = box.height + c.clearance - c.step_height if self._can_step_over(box) else float("inf")
        around = c.lateral_cost * abs(shift) if np.isfinite(shift) else float("inf")
        if raise_ == around == float("inf"):
            return "blocked", 0.0
        if around <= raise_:
            return "around", float(shift)
        return "over", 0.0

    def classify(self, box: ObstacleBox) -> ObstacleDecision:
        """The class of ``box`` for feet walking in :attr:`lanes`."""
        # a short shift, a raise, or else the walking line moved beside the box; a long shift only where that is
        # not possible (the swing foot follows a quick sideways shift by about half: it is the last resort)
        feet, lateral = self._feet(box, self.config.quick_shift)
        if "blocked" in feet:
            shift = self.line_shift(box)
            if shift is not None:
                return ObstacleDecision(box, "sidestep", ("beside", "beside"), (0.0, 0.0), shift)
            feet, lateral = self._feet(box, None)
        if "blocked" in feet:
            classification = "too_large"
        elif "over" in feet:
            classification = "step_over"
        elif "around" in feet:
            classification = "swing_around"
        else:
            classification = "beside"
        return ObstacleDecision(box, classification, feet, lateral)

    def limits(self, box: ObstacleBox) -> str:
        """The limits that decide the class of ``box``, in words: stepping over it (its height and depth against
        ``max_step_over_height`` and ``max_step_over_depth``), swinging around it (each lane's sideways shift
        against ``max_outward_shift`` / ``max_inward_shift``) and the sidestep (``line_shift`` against
        ``max_line_shift``)."""
        c = self.config
        over_height, depth = box.height + c.clearance, box.depth
        high = "<=" if over_height <= c.max_step_over_height else ">"
        deep = "<=" if depth <= c.max_step_over_depth else ">"
        over = (
            f"step over: height {box.height:.3f} + clearance {c.clearance:.3f} = {over_height:.3f} m {high} "
            f"max_step_over_height {c.max_step_over_height:.3f}, depth {depth:.3f} m {deep} max_step_over_depth "
            f"{c.max_step_over_depth:.3f}"
        )
        shifts = []
        for side, name in ((0, "right"), (1, "left")):
            meets, shift = self._lateral_options(box, float(self.lanes[side]), side)
            if not meets:
                shifts.append(f"{name} beside")
            elif math.isnan(shift):
                shifts.append(f"{name} beyond the shift limits")
            else:
                shifts.append(f"{name} {shift:+.3f} m")
        around = (
            f"swing around (max_outward_shift {c.max_outward_shift:.3f}, max_inward_shift {c.max_inward_shift:.3f} m):"
            f" {', '.join(shifts)}"
        )
        line = self.line_shift(box)
        sidestep = (
            f"sidestep: {line:+.3f} m within max_line_shift {c.max_line_shift:.3f}"
            if line is not None
            else f"sidestep: beyond max_line_shift {c.max_line_shift:.3f} m"
        )
        return f"{over}; {around}; {sidestep}"

    def _feet(self, box: ObstacleBox, outward: float | None) -> tuple[tuple[str, str], tuple[float, float]]:
        """Both feet's :meth:`foot_decision` in their lanes: (decisions, shifts), right then left."""
        right = self.foot_decision(box, float(self.lanes[0]), 0, outward)
        left = self.foot_decision(box, float(self.lanes[1]), 1, outward)
        return (right[0], left[0]), (right[1], left[1])

    def line_shift(self, box: ObstacleBox, side: float = 0.0) -> float | None:
        """The smallest sideways move [m] of both lanes that puts ``box`` beside them (None: beyond
        ``max_line_shift``); ``side`` > 0 asks for a move to +y, < 0 to -y (0: either)."""
        half = self.config.foot_half_width + self.config.lateral_margin
        right, left = float(self.lanes[0]), float(self.lanes[1])
        # the lanes pass on the box's -y side (the left lane's upper edge below it) or its +y side
        down, up = float(box.lower[1]) - (left + half), float(box.upper[1]) - (right - half)
        # to one side, a box already clear of the lanes needs no move (not one back towards it)
        candidates = [min(down, 0.0)] if side < 0.0 else [max(up, 0.0)] if side > 0.0 else [down, up]
        shift = min(candidates, key=abs)
        return shift if abs(shift) <= self.config.max_line_shift else None

    # ------------------------------------------------------------------ footholds
    def foothold_band(self, box: ObstacleBox) -> tuple[float, float]:
        """The x range [m] in which a sole point standing in the box's lane would overlap it (with the margin)."""
        c = self.config
        return (
            float(box.lower[0]) - c.foothold_margin - c.toe_length,
            float(box.upper[0]) + c.foothold_margin + c.heel_length,
        )

    def in_lane(self, box: ObstacleBox, y: float) -> bool:
        """Whether a sole centred at ``y`` [m] meets ``box`` sideways (with the lateral margin)."""
        half = self.config.foot_half_width + self.config.lateral_margin
        return bool(y + half > box.lower[1] and y - half < box.upper[1])

    def in_band(self, x: float, y: float, boxes: Sequence[ObstacleBox]) -> bool:
        """Whether a sole point at ``(x, y)`` [m] stands in the band (:meth:`foothold_band`) of a box in its lane."""
        return any(self.in_lane(b, y) and self.foothold_band(b)[0] < x < self.foothold_band(b)[1] for b in boxes)

    def foothold_shift(
        self, foothold: ArrayLike, previous: ArrayLike, boxes: Sequence[ObstacleBox], behind: float = -np.inf
    ) -> float | None:
        """The move along x [m] that takes a foothold out of every box's band, changing the step from
        ``previous`` (the other foot's foothold) least within the step-length limits: 0 when it stands clear,
        None when no move does (a box the step cannot clear: too deep or too close to the previous foothold).

        Moves are tried in growing size; a move that lands in another box's band is not taken, nor one that does
        not land ahead of ``behind`` (the same foot's previous foothold [m]: every swing moves forward, so the
        planning cannot step in place before a box forever).
        """
        h = np.asarray(foothold, dtype=np.float64)
        p = np.asarray(previous, dtype=np.float64)
        c = self.config
        bands = [self.foothold_band(b) for b in boxes if self.in_lane(b, float(h[1]))]
        if not any(low < h[0] < high for low, high in bands):
            return 0.0
        candidates = sorted({band[0] - h[0] for band in bands} | {band[1] - h[0] for band in bands}, key=abs)
        for move in candidates:
            x = h[0] + move
            step = x - p[0]
            if not c.min_step_length - 1e-12 <= step <= c.max_step_length + 1e-9 or x <= behind + 1e-9:
                continue
            if any(band[0] + 1e-9 < x < band[1] - 1e-9 for band in bands):
                continue
            return float(move)
        return None

    # ------------------------------------------------------------------ swing
    def _swing_decision(self, box: ObstacleBox, y: float, side: int) -> tuple[str, float, bool]:
        """:meth:`foot_decision` of a swing: a shift of at most ``quick_shift`` or a raise, else a longer shift
        (the swing foot follows a quick sideways shift by about half: a long one is the last resort); and whether
        the shift is a long one."""
        decision, shift = self.foot_decision(box, y, side, self.config.quick_shift)
        if decision != "blocked":
            return decision, shift, False
        decision, shift = self.foot_decision(box, y, side)
        return decision, shift, True

    def swing(
        self, start: ArrayLike, end: ArrayLike, side: int, boxes: Sequence[ObstacleBox]
    ) -> SwingModification | None:
        """The modification of a swing of foot ``side`` (0 right, 1 left) from foothold ``start`` to ``end``
        [m], or None when its path passes no box in its lane.

        A swing that passes several boxes takes the largest height or shift over the band that holds them all.
        """
        a, b = np.asarray(start, dtype=np.float64), np.asarray(end, dtype=np.float64)
        c = self.config
        y = 0.5 * float(a[1] + b[1])
        low, high = min(a[0], b[0]), max(a[0], b[0])
        kind: Literal["over", "around"] | None = None
        height, lateral = c.step_height, 0.0
        band = (np.inf, -np.inf)
        for box in boxes:
            reach = (
                float(box.lower[0]) - c.toe_length - c.clearance,
                float(box.upper[0]) + c.heel_length + c.clearance,
            )
            if reach[1] <= low or reach[0] >= high:
                continue  # the swing's sole does not pass over the box along x
            decision, shift, _ = self._swing_decision(box, y, side)
            if decision == "blocked" and c.lateral_margin > 0.0:
                # the walking line was planned with less margin (the drift relaxation of plan_line): pass the box
                # by the smallest shift that clears it rather than through it
                decision, shift, _ = self._marginless()._swing_decision(box, y, side)
            if decision in ("beside", "blocked"):
                continue
            band = (min(band[0], reach[0]), max(band[1], reach[1]))
            if decision == "over":
                kind = "over"
                height = max(height, box.height + c.clearance)
            else:
                kind = kind or "around"
                if abs(shift) > abs(lateral):
                    lateral = shift
        if kind is None:
            return None
        if kind == "over":
            lateral = 0.0
        return SwingModification(kind, float(height), float(lateral), (float(band[0]), float(band[1])))

    # ------------------------------------------------------------------ the walking line
    def swing_cost(self, box: ObstacleBox, y: float, side: int) -> float:
        """The cost of a swing of foot ``side`` (0 right, 1 left) with its sole at ``y`` [m] past ``box`` (whose band
        along x it crosses): 0 beside it; a raise above the step height [m] over it; ``lateral_cost`` times a
        sideways shift around it (plus ``long_shift_cost`` beyond ``quick_shift``); :data:`BLOCKED_COST` when none of
        these passes, or when the shift is outwards around a box higher than ``straddle_height`` (kept between the
        legs)."""
        c = self.config
        decision, shift, long = self._swing_decision(box, y, side)
        extra = c.long_shift_cost if long else 0.0
        if decision == "blocked":
            return BLOCKED_COST
        if decision == "beside":
            return 0.0
        if decision == "over":
            return max(box.height + c.clearance - c.step_height, 0.0)
        if box.height > c.straddle_height and (shift > 0.0) == (side == 1):
            return BLOCKED_COST  # shifted outwards, the box stays between the legs: the knee passes over its top
        return extra + c.lateral_cost * abs(shift)

    def _passing_cost(
        self, start: tuple[float, float], end: tuple[float, float], side: int, boxes: Sequence[ObstacleBox]
    ) -> float:
        """The cost of a swing from ``start`` to ``end`` (x, y) [m] past ``boxes`` (all of which its sole passes along
        x) as :meth:`swing` plans it, the boxes taken together: :data:`BLOCKED_COST` where a box blocks it, where
        the shift it takes around one box leaves its sole in another's lane (without margin), or where it steps
        over one box but not over another in its lane."""
        if not boxes:
            return 0.0
        y = 0.5 * (start[1] + end[1])
        costs = [self.swing_cost(box, y, side) for box in boxes]
        if max(costs) >= BLOCKED_COST:
            return BLOCKED_COST
        modification = self.swing((start[0], start[1]), (end[0], end[1]), side, boxes)
        if modification is None:
            return 0.0
        free = self._marginless()
        for box in boxes:
            if modification.kind == "over":
                if free.in_lane(box, y) and box.height + self.config.clearance > modification.height + 1e-9:
                    return BLOCKED_COST
            elif free.in_lane(box, y + modification.lateral):
                return BLOCKED_COST
        return float(sum(costs))

    def plan_line(
        self,
        footholds: ArrayLike,
        first_side: int,
        fixed: tuple[float, float],
        boxes: Sequence[ObstacleBox],
        free_end: bool = False,
    ) -> LinePlan:
        """Sideways offsets of the walking line per foothold that pass ``boxes`` at least cost (dynamic
        programming over the footholds, each offset from the box sides' :meth:`line_shift` and 0).

        A foothold's offset moves it sideways; a swing from the same foot's previous foothold costs
        :meth:`swing_cost` for every box its sole passes along x (a swing that moves sideways, for every box within
        ``move_clearance`` of it). Constraints: a foot moves by at most ``max_line_move`` per step; the stance (the
        left offset minus the right one of consecutive footholds) widens by 0 to ``max_widening``.

        Args:
            footholds: ``(n, 2)`` footholds [m] (x, y) before the offsets; the first two are fixed (their swings
                began) and keep the offsets ``fixed``.
            first_side: the side (0 right, 1 left) of ``footholds[0]``; they alternate.
            fixed: the offsets [m] of the first two footholds.
            boxes: the obstacle boxes.
            free_end: whether the line may end offset (else the last two footholds come back to offset 0).

        Returns:
            the offsets of ``footholds[2:]``, the plan's cost and the first blocked foothold.
        """
        h = np.asarray(footholds, dtype=np.float64)
        if h.ndim != 2 or h.shape[0] < 2 or h.shape[1] < 2:
            raise ControllerError(f"footholds must be (n >= 2, 2), got shape {h.shape}")
        # the footholds whose swings began were planned around the boxes where they were mapped then: when the
        # robot's drift moved them by more than the tolerance, plan with less margin rather than stop. The last
        # rungs shorten the distance along x kept by sideways-moving swings, then let such a swing pass a box
        # around it (its sideways shift made before the box, as Ssta.swing plans it): a stop in front of the box
        # never passes it, these swings usually do
        c = self.config
        margin, clearance = c.lateral_margin, c.move_clearance
        ladder = (
            (c.line_tolerance, clearance, False),
            (2.0 * c.line_tolerance, clearance, False),
            (margin, clearance, False),
            (margin, 0.5 * clearance, False),
            (margin, 0.0, False),
            (margin, 0.0, True),
        )
        plan = LinePlan(np.zeros(0), 0.0, None)
        for tolerance, move_clearance, moving_around in ladder:
            plan = self._plan_line(
                h, first_side, fixed, boxes, free_end, min(tolerance, margin), move_clearance, moving_around
            )
            if plan.blocked is None:
                break
        return plan

    def _plan_line(
        self,
        h: NDArray[np.float64],
        first_side: int,
        fixed: tuple[float, float],
        boxes: Sequence[ObstacleBox],
        free_end: bool,
        tolerance: float,
        move_clearance: float | None = None,
        moving_around: bool = False,
    ) -> LinePlan:
        """:meth:`plan_line` with the margin to the boxes less ``tolerance`` [m] and sideways-moving swings kept
        ``move_clearance`` [m] along x from the boxes (None: the configured one), or (``moving_around``) costed
        like the other swings where they pass a box."""
        c = self.config
        if h.shape[0] == 2:
            return LinePlan(np.zeros(0), 0.0, None)
        clearance = c.move_clearance if move_clearance is None else move_clearance
        values = {0.0, round(float(fixed[0]), 6), round(float(fixed[1]), 6)}
        for box in boxes:
            for side in (-1.0, 1.0):
                shift = self.line_shift(box, side)
                if shift is not None:  # rounded away from the box to 5 mm: the same values when it is mapped again
                    values.add(round(float(np.sign(shift)) * math.ceil(abs(shift) / 0.005 - 1e-6) * 0.005, 6))
        offsets = np.array(sorted(values))
        n = len(offsets)
        a_index, b_index = int(np.argmin(np.abs(offsets - fixed[0]))), int(np.argmin(np.abs(offsets - fixed[1])))
        value = np.full((n, n), np.inf)
        value[a_index, b_index] = 0.0
        move = np.abs(offsets[None, :] - offsets[:, None])  # [a, c]: the foot's move from o_a to o_c
        step = c.line_move_cost * move + c.line_offset_cost * np.abs(offsets)[None, :]
        step[move > c.max_line_move + 1e-9] = np.inf
        # a moving swing's sweep is checked with the margin less the tolerance: the boxes move by a few millimetres
        # each time the robot's drift maps them again, and the offsets planned before must stay feasible
        half = c.foot_half_width + c.lateral_margin - tolerance
        tolerant = Ssta(replace(c, lateral_margin=c.lateral_margin - tolerance), self.lanes)
        reaches = [
            (float(b.lower[0]) - c.toe_length - c.clearance, float(b.upper[0]) + c.heel_length + c.clearance)
            for b in boxes
        ]
        bands = [self.foothold_band(b) for b in boxes]
        parents: list[NDArray[np.intp]] = []
        swings: list[NDArray[np.float64]] = []
        straddles: list[NDArray[np.float64]] = []
        for m in range(2, h.shape[0]):
            side = (first_side + m) % 2
            x0, x1 = float(h[m - 2, 0]), float(h[m, 0])
            y0, y1 = float(h[m - 2, 1]), float(h[m, 1])
            swing = np.zeros((n, n))
            ya, yc = y0 + offsets[:, None], y1 + offsets[None, :]
            moving = np.abs(yc - ya) > 1e-3
            for box, (low, high) in zip(boxes, reaches, strict=True):
                u0, u1 = max(min(x0, x1), low - clearance), min(max(x0, x1), high + clearance)
                if u0 >= u1:
                    continue
                # the sole moves along the straight line between the footholds: its y where it is near the box
                f0, f1 = ((u0 - x0) / (x1 - x0), (u1 - x0) / (x1 - x0)) if x1 != x0 else (0.0, 1.0)
                y_u0, y_u1 = ya + (yc - ya) * f0, ya + (yc - ya) * f1
                sweep = (np.minimum(y_u0, y_u1) - half < box.upper[1]) & (np.maximum(y_u0, y_u1) + half > box.lower[1])
                passes = high > min(x0, x1) and low < max(x0, x1)
                # a moving swing may step over a box low enough (its path is raised above it wherever it moves)
                over = passes and self._can_step_over(box)
                if not moving_around:
                    swing[moving & sweep] += (
                        max(box.height + c.clearance - c.step_height, 0.0) if over else BLOCKED_COST
                    )
                if passes:  # its sole passes the box along x: over, around or beside
                    for i, k in zip(*np.nonzero(~moving), strict=True):
                        swing[i, k] += tolerant.swing_cost(box, 0.5 * float(ya[i, 0] + yc[0, k]), side)
            if moving_around:
                passed = [
                    b for b, (low, high) in zip(boxes, reaches, strict=True) if high > min(x0, x1) and low < max(x0, x1)
                ]
                for i, k in zip(*np.nonzero(moving), strict=True):
                    swing[i, k] += tolerant._passing_cost((x0, float(ya[i, 0])), (x1, float(yc[0, k])), side, passed)
            # a foothold left in a box's band in its lane (full margin) moves along x; where no move fits, the walk
            # stops in front of the box (a line barely 1 cm off the box would have passed it)
            stand = np.zeros(n)
            if any(low < x1 < high for low, high in bands):  # in some box's band along x (whatever the lane)
                previous, behind = h[m - 1], float(h[m - 2, 0])
                for i, o in enumerate(offsets):
                    if self.foothold_shift((x1, y1 + o), previous, boxes, behind=behind) is None:
                        stand[i] = c.stuck_cost
            # the stance from o_b (foothold m-1, the other foot) to o_c: never narrower, widened at most so much
            widening = (offsets[:, None] - offsets[None, :]) if side == 0 else (offsets[None, :] - offsets[:, None])
            width = np.where((widening >= -1e-9) & (widening <= c.max_widening + 1e-9), 0.0, np.inf)  # [b, c]
            # a swing past a box higher than straddle_height with the box between the soles (the stance foot on its
            # other side): the legs slant inwards, and the shank or knee passes over its top
            straddle = np.zeros((n, n))  # [b, c]
            stance_y = float(h[m - 1, 1]) + offsets[:, None]
            swing_y = y1 + offsets[None, :]
            right_y, left_y = (swing_y, stance_y) if side == 0 else (stance_y, swing_y)
            for box, (low, high) in zip(boxes, reaches, strict=True):
                if box.height > c.straddle_height and high > min(x0, x1) and low < max(x0, x1):
                    between = (right_y + c.foot_half_width <= box.lower[1]) & (
                        left_y - c.foot_half_width >= box.upper[1]
                    )
                    straddle[between] = BLOCKED_COST
            total = value[:, :, None] + (step + swing + stand[None, :])[:, None, :] + (width + straddle)[None, :, :]
            parent = np.argmin(total, axis=0)  # over a, for each (b, c)
            value = np.take_along_axis(total, parent[None], axis=0)[0]
            parents.append(parent)
            swings.append(swing)
            straddles.append(straddle)
        zero = int(np.argmin(np.abs(offsets)))
        if free_end or not np.isfinite(value[zero, zero]):
            b, cc = (int(i) for i in np.unravel_index(int(np.argmin(value)), value.shape))
        else:
            b, cc = zero, zero
        cost = float(value[b, cc])
        chosen = [int(cc), int(b)]
        for parent in reversed(parents[1:]):
            chosen.append(int(parent[chosen[-1], chosen[-2]]))
        chosen = chosen[::-1]  # offsets of footholds 1 .. n-1 (index into offsets)
        path = [a_index, *chosen]
        blocked = next(
            (
                m
                for m in range(len(swings))
                if swings[m][path[m], path[m + 2]] + straddles[m][path[m + 1], path[m + 2]] >= BLOCKED_COST
            ),
            None,
        )
        if not np.isfinite(cost) and blocked is None:  # no stance from the fixed footholds keeps the limits
            blocked = 0
        return LinePlan(offsets[path[2:]], cost, blocked)
