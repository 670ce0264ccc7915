"""Monograph fig. 5.10: a point-to-point motion of the 9-DoF agricultural arm that self-collides without
nullspace collision avoidance and not with it.

The TCP moves on a straight quintic path (tool axis turned on the great circle) from the pose of ``q_start``
to the pose of ``q_goal``, tracked by the grasp CLIK (5-D task: TCP position and tool axis) in a kinematic
rollout (``q += qdot dt``, clamped to the joint limits). Without the collision objective the minimum-velocity
solution (5.14 with ``W = I``) swings the gripper into the distal forearm; with it, the nullspace motion keeps
every non-adjacent link pair apart while the task is tracked the same.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..assets import AGRI_ARM_TCP, AGRI_ARM_XML
from ..eval.plots import save_figure
from ..model import RobotModel, collision_model_from_mjcf
from ..policies.grasp_clik_policy import GraspClikPolicy, GraspPath
from .exceptions import StudyError

__all__ = [
    "plot_point_to_point",
    "FIG_5_10",
    "PointToPointScenario",
    "PointToPointSetup",
    "PointToPointTrace",
    "prepare_point_to_point",
    "rollout_point_to_point",
]


@dataclass(frozen=True)
class PointToPointScenario:
    """A point-to-point TCP motion of the agricultural arm.

    Attributes:
        q_start: start configuration [m, rad] (lift first); q_goal: the configuration whose TCP pose is the goal.
        duration: of the quintic move [s]; hold: time at the goal afterwards [s]; dt: control period [s].
    """

    q_start: tuple[float, ...]
    q_goal: tuple[float, ...]
    duration: float = 2.0
    hold: float = 0.5
    dt: float = 0.01


FIG_5_10 = PointToPointScenario(
    q_start=(0.48, -1.9504, -0.9831, -1.5625, -0.1266, -0.4956, -0.5295, 0.2427, 1.5273),
    q_goal=(0.53, 0.69, -1.0106, -1.0123, 0.0982, 0.9143, 0.4037, -1.2321, -1.2936),
)
"""Found by a seeded random search over start/goal configurations (both at least 5 cm clear of self-collision,
within 70 % of the joint ranges) for a move that collides without avoidance, stays clear with it, and is
tracked to within 1 cm in both runs."""


@dataclass(frozen=True)
class PointToPointTrace:
    """One rollout.

    Attributes:
        time: (T,) [s]; q: (T, 9) configurations after each step.
        self_clearance: (T,) smallest distance between non-adjacent links (and the lift column) [m].
        closest_pair: (T,) names ``"a/b"`` of the pair realizing it.
        task_error: (T,) norm of the 5-D task error before each step [m, rad].
        collision_avoidance: whether the nullspace collision objective was on.
        final_position_error: distance of the final TCP position from the goal [m].
    """

    time: NDArray[np.float64]
    q: NDArray[np.float64]
    self_clearance: NDArray[np.float64]
    closest_pair: tuple[str, ...]
    task_error: NDArray[np.float64]
    collision_avoidance: bool
    final_position_error: float


class _Robot:
    """What :class:`GraspClikPolicy` reads from an env, for a rollout without one."""

    observation_layout = {"q": slice(0, 9)}
    ROBOT_XML = AGRI_ARM_XML
    TCP_FRAME = AGRI_ARM_TCP
    max_joint_speeds = np.array([0.4] + [1.5] * 8)


class PointToPointSetup(NamedTuple):
    """What a rollout of a :class:`PointToPointScenario` starts from.

    Attributes:
        policy: the grasp CLIK reference (its model, task, joint limits and collision objective).
        controller: its controller, built with no plant obstacles.
        monitor: collision model of the arm's own non-adjacent segments, for the clearance.
        path: the TCP reference ``path(t) -> (target, velocity)``.
        q_start: start configuration; goal_position: TCP goal [m]; steps: control steps of move and hold.
    """

    policy: GraspClikPolicy
    controller: Any
    monitor: Any
    path: GraspPath
    q_start: NDArray[np.float64]
    goal_position: NDArray[np.float64]
    steps: int


def prepare_point_to_point(
    scenario: PointToPointScenario = FIG_5_10, *, collision_avoidance: bool = True, **policy_options: float | str
) -> PointToPointSetup:
    """The grasp CLIK reference (``policy_options``: fields of
    :class:`~redundancy_gym.policies.grasp_clik_policy.GraspClikConfig`), its controller, the self-clearance
    monitor and the TCP path of ``scenario``."""
    policy = GraspClikPolicy(_Robot(), collision_avoidance="on" if collision_avoidance else "off", **policy_options)
    model: RobotModel = policy.model
    q = np.asarray(scenario.q_start, dtype=np.float64)
    goal = np.asarray(scenario.q_goal, dtype=np.float64)
    if q.shape != (model.nq,) or goal.shape != (model.nq,):
        raise StudyError(f"q_start and q_goal need {model.nq} entries")
    controller = policy.build_controller([])
    monitor = collision_model_from_mjcf(model, [])
    model.update(goal)
    goal_position = model.frame_position(AGRI_ARM_TCP).copy()
    goal_axis = model.frame_rotation(AGRI_ARM_TCP)[:, 0].copy()
    model.update(q)
    path = GraspPath(
        model.frame_position(AGRI_ARM_TCP).copy(),
        model.frame_rotation(AGRI_ARM_TCP)[:, 0].copy(),
        goal_position,
        goal_position,
        goal_axis,
        scenario.duration,
        scenario.hold,
    )
    steps = int(round((scenario.duration + scenario.hold) / scenario.dt))
    return PointToPointSetup(policy, controller, monitor, path, q, goal_position, steps)


def rollout_point_to_point(
    scenario: PointToPointScenario = FIG_5_10, *, collision_avoidance: bool = True, **policy_options: float | str
) -> PointToPointTrace:
    """Kinematic CLIK rollout of ``scenario``; ``policy_options`` are fields of
    :class:`~redundancy_gym.policies.grasp_clik_policy.GraspClikConfig` (defaults otherwise)."""
    setup = prepare_point_to_point(scenario, collision_avoidance=collision_avoidance, **policy_options)
    model: RobotModel = setup.policy.model
    q = setup.q_start.copy()
    times, qs, clearance, pairs, errors = [], [], [], [], []
    for k in range(setup.steps):
        target, velocity = setup.path(k * scenario.dt)
        result = setup.controller.step(q, target, velocity)
        q = model.clamp(model.integrate(q, result.qdot, scenario.dt))
        model.update(q)
        state = setup.monitor.evaluate(model)
        i = int(np.argmin(state.distance))
        times.append((k + 1) * scenario.dt)
        qs.append(q.copy())
        clearance.append(float(state.distance[i]))
        pairs.append("/".join(state.pairs[i]))
        errors.append(result.error_norm)
    final = float(np.linalg.norm(model.frame_position(AGRI_ARM_TCP) - setup.goal_position))
    return PointToPointTrace(
        np.array(times), np.array(qs), np.array(clearance), tuple(pairs), np.array(errors), collision_avoidance, final
    )


def plot_point_to_point(traces: Mapping[str, PointToPointTrace], path: str | Path, title: str) -> Path:
    """Fig. 5.10 analogue: self-clearance (top) and task error (bottom) over time, one line per rollout; the
    closest pair at each run's minimum is named in the legend."""
    import matplotlib.pyplot as plt  # noqa: PLC0415 - eval.plots has chosen the Agg backend

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7.5, 5.2), sharex=True, height_ratios=(2, 1))
    for label, trace in traces.items():
        k = int(np.argmin(trace.self_clearance))
        (line,) = top.plot(
            trace.time,
            1e3 * trace.self_clearance,
            label=f"{label}: min {1e3 * trace.self_clearance[k]:.1f} mm ({trace.closest_pair[k]})",
        )
        top.plot(trace.time[k], 1e3 * trace.self_clearance[k], "o", color=line.get_color())
        bottom.plot(trace.time, 1e3 * trace.task_error, color=line.get_color())
    top.axhline(0.0, color="k", lw=0.8, ls="--", label="self-collision")
    top.set_ylabel("min self-clearance [mm]")
    top.set_title(title)
    top.grid(alpha=0.3)
    top.legend(loc="best", fontsize=8)
    bottom.set_xlabel("time [s]")
    bottom.set_ylabel("task error [mm, mrad]")
    bottom.grid(alpha=0.3)
    return save_figure(fig, path)
