"""``redundancy-gym bench walk``: the walking reference's control step on BipedWalk-v0, and its whole-body IK
compiled against the same IK on pinocchio, on the same states.

One walk of the ``walking`` policy (``target_speed`` 0.7 m/s by default) is timed per ``predict`` call (the
whole controller: pattern sample, contact ZMP, stabilizer, IK). A second, identical walk records the IK's
inputs at every period (the kinematic configuration and the start and end references); on those inputs

- **compiled**: :class:`~redundancy_gym.controllers.walking.CompiledWholeBodyIk` (one kernel call),
- **python**: :class:`~redundancy_gym.controllers.walking.WholeBodyIk` (pinocchio kinematics and Jacobians,
  the same objectives and solve),

are timed and compared in alternating rounds (:func:`~redundancy_gym.bench.timing.alternating_rounds`: a
warm-up round, then ``rounds`` rounds of compiled, python / python, compiled / ..., each sample one pass over the
recorded states): ``ik_compiled_vs_python`` is the median over the rounds of the ratio of the two passes' medians
(``ik_compiled_vs_python_rounds``: median, min, max and spread ``(max - min) / median``), ``ik_max_difference`` the
largest difference of their configurations [rad or m].

``ikd``: the controller step with the joint trajectory from Inverse Kineto-Dynamics (the policy's ``ik="ikd"``,
:class:`~redundancy_gym.controllers.ikd.WalkingIkd`) on the same walk, timed in alternating rounds with the CLIK
controller (one walk each per round, the order reversed every other round, after a warm-up round):
``ikd_vs_clik`` is the median over rounds of the ratio of the two walks' median steps (``ikd_vs_clik_rounds``; Lola:
823 / 548 us = 1.50 on a Core2 Duo; published). The CLIK walks of these rounds also give the controller step
(``controller``: median and p99 over their steps, and the start); ``controller_vs_lola`` relates its median to the
548 us per cycle that Lola's whole controller took (a 2.33 GHz Core2 Duo; a published figure, not measured here;
``controller_vs_lola_rounds``: the same per round). ``zmp_rms_mm``: in those walks, the rms distance of the
measured ZMP (the env's contact pressure, in the plan's frame) from the pattern's reference ZMP, per controller;
``zmp_rms_by_phase_mm`` the same per gait phase (single and double support, and the 20 ms around each touchdown and
lift-off; with each phase's share of the periods and of the squared error). ``zmp_plan_margin_mm``: the smallest
signed distance [mm] of the planned ZMP inside the planned support polygon (the soles on the ground; negative:
outside), the planned ZMP being the one the plan's whole-body motion demands of the ground (a kinematic rollout of the
IK on the pattern without feedback, from the model's CoM and centroidal momentum rate,
:meth:`WalkingController.plan_zmp`) over the first four steps at the bench's speed; ``zmp_whole_body_plan`` gives it
per step, after the first step, and its rms distance from the reference [mm]. ``zmp_reference_margin_mm`` and
``zmp_lipm_margin_mm``: the same margin of the reference ZMP and of the LIPM's ZMP (the reduced model's planning
variable, the reference less the multi-body correction: not a ZMP the robot is to have) over the periods of those
walks, per controller.

``obstacles``: the same controller step on BipedObstacles-v0 (the monograph's beam and triangle courses at
0.4 m/s, walked to the end of the course): with SSTA's planning (at the start and once a step) and RCA's swing-leg
distances and (5.80) while an obstacle is within its gate. ``obstacles_vs_lola_cycle`` relates its median to the
2 ms cycle in which Lola ran its whole controller with collision avoidance (a Xeon at 2.3 GHz; published).

``terrain``: the same controller step on BipedTerrain-v0 (:data:`TERRAIN_COURSES`: stairs of 15 cm rises and 30 cm
treads, a platform; 0.4 m/s, walked to the end): the height scan read into the terrain map, footholds placed on the
map once a step, the CoM height and the swings over the terrain. ``terrain.step_us_median`` is the median over both
walks' steps (target :data:`TERRAIN_TARGET_US`), ``terrain_vs_flat`` its ratio to the flat walk's median step.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import partial
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from ..controllers import CollisionObjective
from ..controllers.walking import (
    CompiledWholeBodyIk,
    PlanZmp,
    WalkingPattern,
    WholeBodyIkResult,
    support_margin,
    support_polygon,
)
from ..eval.evaluate import make_env
from ..eval.machine import finish_machine_info, machine_info
from ..policies.walking_policy import WalkingPolicy
from .exceptions import BenchError
from .timing import CLOCK, RatioStats, TimedPasses, alternating_rounds, check_rounds, timed_call

__all__ = [
    "EVENT_WINDOW",
    "LOLA_CYCLE_US",
    "LOLA_IKD_CYCLE_US",
    "LOLA_OBSTACLE_CYCLE_US",
    "OBSTACLE_COURSES",
    "TERRAIN_COURSES",
    "TERRAIN_TARGET_US",
    "ZMP_PHASES",
    "format_walk_bench",
    "run_walk_bench",
]

ENV_ID = "redundancy_gym/BipedWalk-v0"
LOLA_CYCLE_US = 548.0
"""Lola's whole controller per cycle [us] on a 2.33 GHz Core2 Duo (the issue's reference figure)."""
LOLA_IKD_CYCLE_US = 823.0
"""Lola's IKD-based walking controller per cycle [us] on the same Core2 Duo (monograph 5.5.3; published)."""
LOLA_OBSTACLE_CYCLE_US = 2000.0
"""Lola's control cycle with obstacle avoidance [us] (monograph 5.4.2: all planning, collision avoidance,
redundancy resolution, force and position control in one 2 ms cycle)."""
OBSTACLE_ENV_ID = "redundancy_gym/BipedObstacles-v0"
OBSTACLE_COURSES = ("beam", "triangle")
TERRAIN_ENV_ID = "redundancy_gym/BipedTerrain-v0"
TERRAIN_COURSES: dict[str, dict[str, Any]] = {
    "stairs": {"terrain": "stairs", "terrain_ranges": {"stairs": {"rise": (0.15, 0.15), "tread": (0.3, 0.3)}}},
    "platform": {"terrain": "platform"},
}
"""``terrain``'s walks: name -> BipedTerrain-v0 keyword arguments (the issue's stairs: 15 cm rises, 30 cm treads)."""
TERRAIN_TARGET_US = 150.0
"""The terrain controller step's target median [us]."""
PLAN_STEPS = 4
"""Steps of the plan's kinematic rollout in ``zmp_whole_body_plan`` (the first from standing, then steady ones)."""

_Call = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]


class _Recorder:
    """Stands in for the controller's IK and keeps each call's inputs."""

    def __init__(self, solver: Any) -> None:
        self.solver = solver
        self.calls: list[_Call] = []

    def step(self, q: NDArray[np.float64], start: Any, end: Any, dt: float) -> WholeBodyIkResult:
        self.calls.append((np.array(q), np.array(start), np.array(end), float(dt)))
        return self.solver.step(q, start, end, dt)


def _timed_walk(
    env_id: str, kwargs: dict[str, Any], seed: int, each: Callable[[WalkingPolicy, dict[str, Any]], None] | None = None
) -> tuple[list[float], bool]:
    """One walk of the ``walking`` policy to the episode's end; returns its predict times [us] and whether it
    succeeded. ``each(policy, info)`` runs after every step."""
    env = make_env(env_id, kwargs)
    policy = WalkingPolicy(env)
    times: list[float] = []
    success = False
    try:
        obs, _ = env.reset(seed=seed)
        while True:
            # a partial, not a lambda over the loop's variables (ruff B023); timed_call calls it at once
            (action, _), seconds = timed_call(partial(policy.predict, obs, episode_start=np.array([not times])))
            times.append(seconds * 1e6)
            obs, _, terminated, truncated, info = env.step(action)
            if each is not None:
                each(policy, info)
            if terminated or truncated:
                success = bool(info["is_success"])
                break
    finally:
        env.close()
    return times, success


def _obstacle_walk(course: str, seed: int) -> tuple[list[float], list[bool], bool, int]:
    """One walk over an obstacle course to its end; returns the predict times [us], whether RCA evaluated
    distances in each period, whether it succeeded, and its obstacle contacts."""
    active: list[bool] = []
    contacts: list[bool] = []

    def record(policy: WalkingPolicy, info: dict[str, Any]) -> None:
        avoidance = policy.last_command.avoidance if policy.last_command is not None else None
        active.append(bool(avoidance is not None and np.isfinite(avoidance.distance)))
        contacts.append(bool(info["obstacle_contact"]))

    times, success = _timed_walk(OBSTACLE_ENV_ID, {"course": course}, seed, record)
    return times, active, success, sum(contacts)


def _terrain_walk(kwargs: dict[str, Any], seed: int) -> tuple[list[float], bool]:
    """One walk over a terrain to its end; returns the predict times [us] (the height scan read into the terrain
    map, the footholds placed once a step, the pattern, stabilizer and IK) and whether it succeeded."""
    return _timed_walk(TERRAIN_ENV_ID, kwargs, seed)


ZMP_PHASES = ("single", "double", "touchdown", "liftoff")
"""The gait phases of ``zmp_rms_by_phase_mm``: single and double support, and the ``EVENT_WINDOW`` around each
touchdown and lift-off (taken out of the support phases)."""
EVENT_WINDOW = 0.020  # [s] centred on a touchdown or a lift-off


class _ZmpSample(NamedTuple):
    """One control period of a walk: the measured ZMP's distance [m] from the reference and its gait phase, and the
    LIPM's ZMP's and the reference ZMP's signed distances [m] inside the planned support polygon."""

    distance: float | None  # None where the feet carry no load (no measured ZMP)
    error: tuple[float, float] | None  # measured - reference (x, y) [m], plan frame
    phase: str
    lipm_margin: float
    reference_margin: float


def _phase(pattern: WalkingPattern, t: float) -> str:
    """The gait phase (:data:`ZMP_PHASES`) of the walk at ``t`` [s], after the start."""
    k, s, remaining = pattern.swing_state(t)
    half = 0.5 * EVENT_WINDOW
    if s < half or pattern.step_start(k + 1) - t <= half:
        return "liftoff"
    if abs(remaining) <= half:
        return "touchdown"
    return "single" if remaining > 0.0 else "double"


def _walk(
    speed: float, steps: int, seed: int, record: bool, ik: str = "clik", zmp: list[_ZmpSample] | None = None
) -> tuple[list[float], list[_Call], WalkingPolicy, bool]:
    """One walk; returns the predict times [us], the IK calls (when recording), the policy and whether it fell.
    With a list ``zmp``, appends a :class:`_ZmpSample` per period once the first step has begun: the measured ZMP
    (the env's contact pressure, mapped into the plan's frame) against the pattern's reference ZMP at the period's
    end, and the margins of the period's pattern sample (its planned ZMP, and the reference ZMP at its time, inside
    the support polygon of its feet on the ground)."""
    env = make_env(ENV_ID, {"target_speed": speed})
    policy = WalkingPolicy(env, ik=ik)
    times: list[float] = []
    recorder: _Recorder | None = None
    fell = False
    try:
        obs, _ = env.reset(seed=seed)
        for k in range(steps):
            if k == 1 and record:  # after start(), which builds the IK
                recorder = _Recorder(policy.controller.solver)
                policy.controller.solver = recorder  # type: ignore[assignment]
            # a partial, not a lambda over the loop's variables (ruff B023); timed_call calls it at once
            (action, _), seconds = timed_call(partial(policy.predict, obs, episode_start=np.array([k == 0])))
            times.append(seconds * 1e6)
            obs, _, terminated, truncated, info = env.step(action)
            controller = policy.controller
            pattern = controller.pattern
            command = policy.last_command
            if (
                zmp is not None
                and pattern is not None
                and command is not None
                and pattern.step_at(controller.time) >= 0
            ):
                distance = error = None
                if info["zmp_valid"]:
                    rotation, translation = controller._world_to_plan
                    measured = (rotation @ np.array([*info["zmp"], 0.0]) + translation)[:2]
                    offset = measured - pattern.reference_zmp(controller.time)
                    distance, error = float(np.linalg.norm(offset)), (float(offset[0]), float(offset[1]))
                sample = command.pattern
                polygon = support_polygon(sample.feet, sample.contact, sample.feet_yaw)
                zmp.append(
                    _ZmpSample(
                        distance,
                        error,
                        _phase(pattern, controller.time),
                        support_margin(sample.zmp, polygon),
                        support_margin(pattern.reference_zmp(sample.time), polygon),
                    )
                )
            if terminated or truncated:
                fell = bool(info["fell"])
                break
    finally:
        env.close()
    if recorder is not None:
        policy.controller.solver = recorder.solver
    return times, recorder.calls if recorder is not None else [], policy, fell


class _Walks:
    """A sampler: one walk of the walking policy (``ik`` "clik" or "ikd") per call; keeps each walk's predict times
    [us], ZMP distances [m] and whether it fell, and returns the walk's median step after the first (which plans
    the walk) [s]."""

    def __init__(self, speed: float, steps: int, seed: int, ik: str) -> None:
        self.speed, self.steps, self.seed, self.ik = speed, steps, seed, ik
        self.times: list[list[float]] = []
        self.zmp: list[list[_ZmpSample]] = []
        self.fell: list[bool] = []

    def __call__(self) -> float:
        zmp: list[_ZmpSample] = []
        times, _, _, fell = _walk(self.speed, self.steps, self.seed, record=False, ik=self.ik, zmp=zmp)
        self.times.append(times)
        self.zmp.append(zmp)
        self.fell.append(fell)
        return float(np.median(times[1:])) * 1e-6


def _timed_solve(solver: Any) -> Any:
    """``call -> seconds`` of one ``solver.step`` on a recorded IK call."""

    def timed(call: _Call) -> float:
        q, start, end, dt = call
        return timed_call(lambda: solver.step(q, start, end, dt))[1]

    return timed


def run_walk_bench(
    *,
    speed: float = 0.7,
    duration: float = 4.0,
    seed: int = 0,
    repeats: int = 1,
    rounds: int = 7,
    progress: bool = True,
) -> dict[str, Any]:
    """Time the walking controller step (CLIK and IKD walks in alternating rounds), then its compiled IK against the
    pinocchio IK (alternating passes over the recorded states), then the obstacle courses; returns the report.

    Args:
        speed: commanded walking speed [m/s].
        duration: walk length [s].
        seed: reset seed.
        repeats: timed repetitions per IK state within a pass (the median is kept).
        rounds: alternating rounds of the CLIK and IKD walks and of the compiled and python IK passes (after a
            warm-up round each).
        progress: show progress bars.

    Raises:
        BenchError: ``repeats < 1``, ``rounds < 1``, a duration not finite and > 0, or a policy without the compiled IK.
    """
    if repeats < 1:
        raise BenchError(f"repeats must be >= 1, got {repeats}")
    check_rounds(rounds)
    if not np.isfinite(duration) or duration <= 0.0:
        raise BenchError(f"duration must be finite and > 0, got {duration!r}")
    machine = machine_info()
    steps = int(round(duration / 0.004))
    walks = {"clik": _Walks(speed, steps, seed, "clik"), "ikd": _Walks(speed, steps, seed, "ikd")}
    walk_rounds = alternating_rounds(walks, rounds=rounds, progress=progress, desc="bench walk clik/ikd rounds")
    skip = walk_rounds.warmup
    clik, ikd = walks["clik"], walks["ikd"]
    controller = [t for times in clik.times[skip:] for t in times[1:]]  # the first call of a walk plans it
    ikd_times = [t for times in ikd.times[skip:] for t in times[1:]]
    zmp = {name: [z for walk in w.zmp[skip:] for z in walk] for name, w in walks.items()}
    fell, ikd_fell = any(clik.fell[skip:]), any(ikd.fell[skip:])
    ikd_stats = walk_rounds.ratio("ikd", "clik")
    lola_stats = RatioStats.of([t * 1e6 / LOLA_CYCLE_US for t in walk_rounds.samples["clik"]])

    _, calls, policy, _ = _walk(speed, steps, seed, record=True)
    plan = policy.controller.plan_zmp(speed, steps=PLAN_STEPS)
    ik = policy.controller.ik
    compiled = policy.controller.solver
    if not isinstance(compiled, CompiledWholeBodyIk) or ik is None:
        raise BenchError("bench walk needs the compiled IK backend (the policy default)")
    difference = max(float(np.max(np.abs(compiled.step(*c).q - ik.step(*c).q))) for c in calls)
    passes = {
        "compiled": TimedPasses(_timed_solve(compiled), calls, repeats),
        "python": TimedPasses(_timed_solve(ik), calls, repeats),
    }
    ik_rounds = alternating_rounds(passes, rounds=rounds, progress=progress, desc="bench walk IK rounds")
    compiled_median, compiled_p90 = passes["compiled"].summary_us(ik_rounds.warmup)
    python_median, python_p90 = passes["python"].summary_us(ik_rounds.warmup)
    ik_stats = ik_rounds.ratio("compiled", "python")

    obstacles: dict[str, Any] = {}
    all_times: list[float] = []
    for course in tqdm(OBSTACLE_COURSES, desc="bench walk obstacles", disable=not progress):
        times, active, success, contacts = _obstacle_walk(course, seed)
        times, active = times[1:], active[1:]  # the first call plans the walk
        near = [t for t, a in zip(times, active, strict=False) if a]
        obstacles[course] = {
            "step_us_median": float(np.median(times)),
            "step_us_p99": float(np.percentile(times, 99)),
            "rca_share": float(np.mean(active)),
            "step_us_median_rca": float(np.median(near)) if near else float("nan"),
            "steps": len(times),
            "success": success,
            "obstacle_contacts": contacts,
        }
        all_times += times
    obstacle_median = float(np.median(all_times))
    terrain: dict[str, Any] = {}
    terrain_times: list[float] = []
    for name, kwargs in tqdm(TERRAIN_COURSES.items(), desc="bench walk terrain", disable=not progress):
        times, success = _terrain_walk(kwargs, seed)
        times = times[1:]  # the first call plans the walk
        terrain[name] = {
            "env_kwargs": kwargs,
            "step_us_median": float(np.median(times)),
            "step_us_p99": float(np.percentile(times, 99)),
            "steps": len(times),
            "success": success,
        }
        terrain_times += times
    terrain_median = float(np.median(terrain_times))
    controller_median = walk_rounds.median("clik") * 1e6
    ikd_median = walk_rounds.median("ikd") * 1e6
    return {
        "benchmark": "walk",
        "env": ENV_ID,
        "target_speed": speed,
        "duration": duration,
        "seed": seed,
        "states": len(calls),
        "repeats": repeats,
        "fell": fell,
        "timing": {
            "rounds": rounds,
            "warmup": skip,
            "clock": CLOCK,
            "walk_orders": walk_rounds.orders,
            "ik_orders": ik_rounds.orders,
            "sample": "clik/ikd: one walk's median step; compiled/python: one pass over the recorded states",
        },
        "machine": finish_machine_info(machine),
        "controller": {
            "step_us_median": controller_median,
            "step_us_p99": float(np.percentile(controller, 99)),
            "start_ms": float(np.median([w[0] for w in clik.times[skip:]])) * 1e-3,
        },
        "ik_compiled": {"step_us_median": compiled_median, "step_us_p90": compiled_p90},
        "ik_python": {"step_us_median": python_median, "step_us_p90": python_p90},
        "ik_compiled_vs_python": ik_stats.median,
        "ik_compiled_vs_python_rounds": ik_stats.to_json(),
        "ikd": {
            "step_us_median": ikd_median,
            "step_us_p99": float(np.percentile(ikd_times, 99)),
            "fell": ikd_fell,
            "rounds": rounds,
        },
        "ikd_vs_clik": ikd_stats.median,
        "ikd_vs_clik_rounds": ikd_stats.to_json(),
        "zmp_rms_mm": {name: _rms_mm([z.distance for z in z_]) for name, z_ in zmp.items()},
        "zmp_rms_by_phase_mm": {name: _by_phase(z_) for name, z_ in zmp.items()},
        "zmp_plan_margin_mm": float(plan.margin.min()) * 1e3,
        "zmp_reference_margin_mm": {name: _smallest_mm([z.reference_margin for z in z_]) for name, z_ in zmp.items()},
        "zmp_lipm_margin_mm": {name: _smallest_mm([z.lipm_margin for z in z_]) for name, z_ in zmp.items()},
        "zmp_whole_body_plan": _plan_report(plan),
        "ikd_vs_clik_spread": [ikd_stats.min, ikd_stats.max],
        "ikd_vs_lola_ikd": ikd_median / LOLA_IKD_CYCLE_US,
        "ik_max_difference": difference,
        "controller_vs_lola": controller_median / LOLA_CYCLE_US,
        "controller_vs_lola_rounds": lola_stats.to_json(),
        "obstacles": {
            "env": OBSTACLE_ENV_ID,
            "target_speed": 0.4,
            "courses": obstacles,
            "step_us_median": obstacle_median,
            "step_us_p99": float(np.percentile(all_times, 99)),
        },
        "obstacles_vs_lola_cycle": obstacle_median / LOLA_OBSTACLE_CYCLE_US,
        "terrain": {
            "env": TERRAIN_ENV_ID,
            "target_speed": 0.4,
            "courses": terrain,
            "step_us_median": terrain_median,
            "step_us_p99": float(np.percentile(terrain_times, 99)),
            "within_target": terrain_median <= TERRAIN_TARGET_US,
        },
        "terrain_vs_flat": terrain_median / controller_median,
        "self_collision_pairs": sum(
            len(o.collision_model.layout().segment_pairs) for o in ik.objectives if isinstance(o, CollisionObjective)
        ),
    }


def format_walk_bench(report: dict[str, Any]) -> str:
    """A plain-text summary."""
    c, k, p = report["controller"], report["ik_compiled"], report["ik_python"]
    return "\n".join(
        [
            f"{report['env']} at {report['target_speed']} m/s, {report['duration']} s, seed {report['seed']}: "
            f"{report['states']} IK states" + (" (fell)" if report["fell"] else ""),
            f"controller step  median {c['step_us_median']:.1f} us  p99 {c['step_us_p99']:.1f} us  "
            f"(start {c['start_ms']:.1f} ms)",
            f"IK compiled      median {k['step_us_median']:.1f} us  p90 {k['step_us_p90']:.1f} us",
            f"IK python        median {p['step_us_median']:.1f} us  p90 {p['step_us_p90']:.1f} us",
            f"ik_compiled_vs_python = {report['ik_compiled_vs_python']:.3f}  "
            f"(largest difference {report['ik_max_difference']:.1e})"
            + _rounds_text(report.get("ik_compiled_vs_python_rounds")),
            f"controller_vs_lola = {report['controller_vs_lola']:.3f}  (Lola: {LOLA_CYCLE_US:.0f} us per cycle)"
            + _rounds_text(report.get("controller_vs_lola_rounds")),
            f"IKD controller   median {report['ikd']['step_us_median']:.1f} us  "
            f"p99 {report['ikd']['step_us_p99']:.1f} us" + ("  (fell)" if report["ikd"]["fell"] else ""),
            "measured ZMP from the reference, rms: "
            + ", ".join(
                f"{ik.upper()} " + ("(no step walked)" if v is None else f"{v:.1f} mm")
                for ik, v in report["zmp_rms_mm"].items()
            ),
            *[
                f"  {ik.upper()} by phase: "
                + ", ".join(
                    f"{phase} {_mm(v['rms_mm'])} ({100 * (v['error_share'] or 0.0):.0f} % of the error"
                    + (
                        ""
                        if v["mean_offset_mm"] is None
                        else ", mean offset ({:.0f}, {:.0f}) mm".format(*v["mean_offset_mm"])
                    )
                    + ")"
                    for phase, v in phases.items()
                )
                for ik, phases in report.get("zmp_rms_by_phase_mm", {}).items()
            ],
            "zmp_plan_margin_mm = "
            + _mm(report["zmp_plan_margin_mm"])
            + ": the planned ZMP's smallest margin inside the support polygon (the whole-body motion of the plan, a "
            "kinematic rollout without feedback; per step: "
            + ", ".join(_mm(row["margin_mm"]) for row in report["zmp_whole_body_plan"]["by_step"])
            + f"), rms {report['zmp_whole_body_plan']['rms_mm']:.1f} mm from the reference",
            "smallest margin in the walks: "
            + ", ".join(
                f"{ik.upper()} reference ZMP {_mm(v)}, LIPM ZMP {_mm(report['zmp_lipm_margin_mm'][ik])}"
                for ik, v in report.get("zmp_reference_margin_mm", {}).items()
            ),
            f"ikd_vs_clik = {report['ikd_vs_clik']:.3f}  (rounds {report['ikd_vs_clik_spread'][0]:.3f}-"
            f"{report['ikd_vs_clik_spread'][1]:.3f}; Lola: {LOLA_IKD_CYCLE_US:.0f} / {LOLA_CYCLE_US:.0f} us = "
            f"{LOLA_IKD_CYCLE_US / LOLA_CYCLE_US:.2f})",
            *[
                f"with obstacles ({course}): median {r['step_us_median']:.1f} us  p99 {r['step_us_p99']:.1f} us  "
                f"RCA evaluating {100 * r['rca_share']:.0f} % of periods (median then {r['step_us_median_rca']:.1f} us)"
                f"{'' if r['success'] else '  (course not passed)'}"
                for course, r in report["obstacles"]["courses"].items()
            ],
            f"obstacles_vs_lola_cycle = {report['obstacles_vs_lola_cycle']:.3f}  (median "
            f"{report['obstacles']['step_us_median']:.1f} us against Lola's {LOLA_OBSTACLE_CYCLE_US:.0f} us cycle with "
            "collision avoidance)",
            *[
                f"on terrain ({name}): median {r['step_us_median']:.1f} us  p99 {r['step_us_p99']:.1f} us"
                f"{'' if r['success'] else '  (terrain not passed)'}"
                for name, r in report["terrain"]["courses"].items()
            ],
            f"terrain controller step median {report['terrain']['step_us_median']:.1f} us (target "
            f"<= {TERRAIN_TARGET_US:.0f} us: {'met' if report['terrain']['within_target'] else 'NOT met'}); "
            f"terrain_vs_flat = {report['terrain_vs_flat']:.3f}",
        ]
    )


def _plan_report(plan: PlanZmp) -> dict[str, Any]:
    """``zmp_whole_body_plan``: the plan's whole-body ZMP (:meth:`WalkingController.plan_zmp`) against the
    reference, overall and per step: smallest margin inside the support polygon, rms and largest distance [mm]."""
    distance = np.linalg.norm(plan.zmp - plan.reference, axis=1)
    by_step = []
    for k in range(PLAN_STEPS):
        m = (plan.times >= plan.step_starts[k]) & (plan.times < plan.step_starts[k + 1])
        by_step.append(
            {
                "step": k,
                "margin_mm": float(plan.margin[m].min()) * 1e3,
                "rms_mm": float(np.sqrt(np.mean(distance[m] ** 2))) * 1e3,
                "max_mm": float(distance[m].max()) * 1e3,
            }
        )
    return {
        "steps": PLAN_STEPS,
        "margin_mm": float(plan.margin.min()) * 1e3,
        "margin_after_first_step_mm": min(row["margin_mm"] for row in by_step[1:]),
        "rms_mm": float(np.sqrt(np.mean(distance**2))) * 1e3,
        "by_step": by_step,
    }


def _mm(value: float | None) -> str:
    """``value`` [mm] as text (``-`` for None)."""
    return "-" if value is None else f"{value:.1f} mm"


def _rms_mm(distances: Sequence[float | None]) -> float | None:
    """The rms [mm] of the measured distances [m] (None where nothing was measured)."""
    d = [x for x in distances if x is not None]
    return 1e3 * float(np.sqrt(np.mean(np.square(d)))) if d else None


def _smallest_mm(margins: list[float]) -> float | None:
    """The smallest margin [mm] of margins [m] (None without any)."""
    return 1e3 * min(margins) if margins else None


def _by_phase(samples: list[_ZmpSample]) -> dict[str, dict[str, Any]]:
    """Per gait phase: the measured ZMP's rms distance from the reference [mm], its mean offset (x, y) [mm] in the
    plan's frame (a bias, where the rms is not scatter), the phase's share of the periods, its share of the squared
    error (how much of ``zmp_rms_mm``'s square it carries), and the periods without a measured ZMP."""
    total = sum(z.distance**2 for z in samples if z.distance is not None)
    out: dict[str, dict[str, Any]] = {}
    for phase in ZMP_PHASES:
        own = [z for z in samples if z.phase == phase]
        measured = [z.distance for z in own if z.distance is not None]
        errors = [z.error for z in own if z.error is not None]
        out[phase] = {
            "rms_mm": _rms_mm(measured),
            "mean_offset_mm": [1e3 * float(v) for v in np.mean(errors, axis=0)] if errors else None,
            "period_share": len(own) / len(samples) if samples else None,
            "error_share": sum(d**2 for d in measured) / total if total > 0.0 else None,
            "unloaded": len(own) - len(measured),
        }
    return out


def _rounds_text(stats: dict[str, Any] | None) -> str:
    """``  rounds MIN-MAX, spread S %`` of a ratio's round statistics, or nothing."""
    if not stats:
        return ""
    return f"  rounds {stats['min']:.3f}-{stats['max']:.3f}, spread {100 * stats['spread']:.1f} %"
