"""The kinematic IKD study (monograph 5.5.3): figs. 5.21, 5.23, 5.24 and 5.27 as analogues on the biped.

One walk of the walking pattern (:class:`~redundancy_gym.controllers.walking.WalkingPattern`: the plain LIPM plan,
or with ``correction`` the walking controller's plan with its multi-body ZMP correction, the analogue of the
monograph's three-mass model; ``speed`` and ``steps`` of :class:`IkdStudyConfig`, default 6 steps at 0.5 m/s, 1 ms
control period) is turned into joint motion on the kinematic model (no simulator) by

- the biped IKD (:class:`~redundancy_gym.controllers.ikd.BipedIkd`, (5.84)-(5.91)) with the pattern's ZMP as the
  prescribed contact moment, unstabilized, stabilized via the contact moment (5.97) for a sweep of the gain ``k``,
  and hybrid (the contact moment plus :class:`~redundancy_gym.controllers.ikd.PlanStabilizer`, stabilization via
  planning);
- the whole-body CLIK (:class:`~redundancy_gym.controllers.walking.WholeBodyIk`, compiled, with the walking
  controller's posture and joint-limit objectives) tracking the plan's CoM;
- the same CLIK tracking the plan's CoM plus the offset of Takenaka's dynamics error compensation
  (:class:`~redundancy_gym.controllers.ikd.error_compensation.ErrorCompensation`, fig. 5.26, (5.98)), fed with
  the moment error of the plain CLIK motion (feed-forward, as Takenaka's fig. 4).

The contact moment of a motion "by inverse dynamics" is the full model's: ``tau = M qddot + h`` through
:class:`~redundancy_gym.model.RobotModel` (:meth:`~redundancy_gym.model.RobotModel.mass_matrix`,
:meth:`~redundancy_gym.model.RobotModel.nonlinear_effects`); the floating base's six rows are the ground's wrench
(a spatial force in the base frame at its origin), moved to the world origin. The CLIK's ``qdot`` and ``qddot``
at a period are the central differences of its configurations (the Newton correction included). The ideal moment
is the plan's: ``T = m g (p_y, -p_x)`` for its ZMP ``p`` (about the world origin, the ground at z = 0, as
:class:`~redundancy_gym.controllers.ikd.BipedIkd` prescribes it). The support polygon is the bounding box of the
soles planned on the ground (sole extent as ``biped.xml``); the CoP of the inverse-dynamics wrench is checked
against it.

:func:`run_ikd_study` returns an :class:`IkdStudy` (its :meth:`IkdStudy.to_json` is the JSON report),
:func:`plot_ikd_study` writes the four figures, :func:`write_ikd_study` the JSON; ``redundancy-gym bench ikd`` and
``make demo`` run them.
"""

from __future__ import annotations

import math
import textwrap
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from numpy.typing import NDArray  # noqa: E402
from tqdm.auto import tqdm  # noqa: E402

from ..assets import BIPED_JOINTS, BIPED_SOFT_LIMIT_MARGIN, BIPED_XML  # noqa: E402
from ..controllers.ikd.biped_ikd import GRAVITY, BipedIkd, BipedIkdReference  # noqa: E402
from ..controllers.ikd.error_compensation import ErrorCompensation  # noqa: E402
from ..controllers.ikd.plan_stabilizer import PlanStabilizer  # noqa: E402
from ..controllers.objectives.actuated_objective import ActuatedObjective  # noqa: E402
from ..controllers.objectives.joint_limit_objective import JointLimitObjective  # noqa: E402
from ..controllers.objectives.posture_objective import PostureObjective  # noqa: E402
from ..controllers.walking import (  # noqa: E402
    CompiledWholeBodyIk,
    GaitConfig,
    PatternSample,
    WalkingController,
    WalkingPattern,
    WholeBodyIk,
    WholeBodyReference,
)
from ..envs.biped_walk import NOMINAL_POSTURE  # noqa: E402
from ..eval.json_writer import write_json  # noqa: E402
from ..eval.machine import machine_info  # noqa: E402
from ..eval.plots import save_figure  # noqa: E402
from ..model import RobotModel  # noqa: E402
from .exceptions import StudyError  # noqa: E402

__all__ = [
    "IkdStudy",
    "IkdStudyConfig",
    "IkdWalk",
    "contact_wrench",
    "format_ikd_study",
    "plot_ikd_study",
    "run_ikd_study",
    "write_ikd_study",
]

FEET = ("r_sole", "l_sole")
SOLE_X = (-0.095, 0.165)
"""The sole's extent behind and ahead of the sole point [m] (biped.xml: plate and toe)."""
SOLE_HALF_WIDTH = 0.075
"""The sole's half width [m]."""
COP_TOLERANCE = 1e-6
"""A CoP counts as outside the support box when it lies this far [m] beyond it (round-off of the ID's division)."""


@dataclass(frozen=True)
class IkdStudyConfig:
    """The walk and the runs of the study.

    Attributes:
        speed: commanded walking speed [m/s] (0.5: 0.4 m steps of 0.8 s).
        steps: steps walked after the 0.4 s standing start.
        period: control period [s] of every run (the monograph's 1.5 ms; the gains of (5.97) are ``K_p = k 40 /
            period``, ``K_d = 2 * 0.85 sqrt(K_p)``).
        gains: the ``k`` of the sweep (figs. 5.23, 5.24); the pendulum limit needs ``K_p > g / z_c`` (10.8 /s^2),
            ``k > 2.7e-4`` at 1 ms.
        comparison_gain: ``k`` of the hybrid IKD in the comparison (fig. 5.27; the monograph's experiments used
            2e-4).
        divergence: a run stops when its CoM is this far from the plan [m] (the legs would stretch).
        correction: plan with the walking controller's multi-body ZMP correction (its CLIK rollouts, as the
            ``walking`` policy plans; the analogue of the monograph's three-mass model): the ideal moment is then
            the reference ZMP's (:meth:`~redundancy_gym.controllers.walking.WalkingPattern.reference_zmp`), the plan's
            CoM the one the whole body needs for it. False: the plain LIPM plan.
    """

    speed: float = 0.5
    steps: int = 6
    period: float = 0.001
    gains: tuple[float, ...] = (0.0, 2e-4, 1e-3, 1e-2)
    comparison_gain: float = 2e-4
    divergence: float = 0.2
    correction: bool = False

    @property
    def plan_name(self) -> str:
        """What the plan is, for labels."""
        return "LIPM plan + ZMP correction" if self.correction else "LIPM plan"

    def __post_init__(self) -> None:
        for name in ("speed", "period", "divergence"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0.0:
                raise StudyError(f"{name} must be finite and > 0, got {value!r}")
        if not isinstance(self.steps, int) or self.steps < 1:
            raise StudyError(f"steps must be an int >= 1, got {self.steps!r}")
        for value in (*self.gains, self.comparison_gain):
            if not math.isfinite(value) or value < 0.0:
                raise StudyError(f"gains and comparison_gain must be finite and >= 0, got {value!r}")


@dataclass(frozen=True)
class IkdWalk:
    """One run of the study, per control period (``n`` periods; fewer than the walk's when it stopped).

    Attributes:
        label: what ran.
        time: the period's start [s] (n).
        moment: the contact moment ``(T_x, T_y)`` [N m] the motion needs (n, 2): the IKD's realized (prescribed)
            one, the CLIK's by inverse dynamics.
        inverse_dynamics_moment: the inverse dynamics' moment of the motion [N m] (n, 2).
        ideal_moment: the plan's (n, 2).
        com: the motion's CoM (x, y) [m] (n, 2).
        plan_com: the plan's CoM (x, y) [m] (n, 2).
        cop: the CoP of the inverse dynamics' wrench on the ground [m] (n, 2).
        support: the support box ``((x_min, y_min), (x_max, y_max))`` [m] (n, 2, 2).
        double_support: both feet planned on the ground (n).
        completed: the run walked the whole pattern (else it diverged or the IKD failed).
        gain: the IKD's ``k`` (None for the CLIK runs).
        planning: stabilization via planning on.
    """

    label: str
    time: NDArray[np.float64]
    moment: NDArray[np.float64]
    inverse_dynamics_moment: NDArray[np.float64]
    ideal_moment: NDArray[np.float64]
    com: NDArray[np.float64]
    plan_com: NDArray[np.float64]
    cop: NDArray[np.float64]
    support: NDArray[np.float64]
    double_support: NDArray[np.bool_]
    completed: bool
    gain: float | None = None
    planning: bool = False


@dataclass(frozen=True)
class IkdStudy:
    """The study's runs and their figures.

    Attributes:
        config: what was run.
        unstabilized: the IKD with ``k = 0`` and no planning (fig. 5.21).
        moment_feedback: the IKD stabilized via the contact moment, one per ``k`` of the sweep (fig. 5.23).
        hybrid: the IKD with contact moment and planning, one per ``k`` (fig. 5.24).
        clik: the plain LIPM plan tracked by the CLIK (fig. 5.27 (1)).
        error_compensation: the LIPM plan with dynamics error compensation, tracked by the CLIK (fig. 5.27 (2)).
        comparison: the hybrid IKD with ``comparison_gain`` (fig. 5.27 (3)).
        step_ends: the times [s] at which the walk's steps end.
        wall_s: the study's wall time [s].
    """

    config: IkdStudyConfig
    unstabilized: IkdWalk
    moment_feedback: tuple[IkdWalk, ...]
    hybrid: tuple[IkdWalk, ...]
    clik: IkdWalk
    error_compensation: IkdWalk
    comparison: IkdWalk
    step_ends: tuple[float, ...]
    wall_s: float
    machine: dict[str, Any] = field(default_factory=dict)

    def to_json(self) -> dict[str, Any]:
        """The figures as one JSON-able object (units in the keys)."""
        c = self.config
        sweep = []
        for feedback, hybrid in zip(self.moment_feedback, self.hybrid, strict=True):
            gain = float(feedback.gain or 0.0)
            kp = gain * 40.0 / c.period
            for name, walk in (("moment", feedback), ("hybrid", hybrid)):
                sweep.append(
                    {
                        "k": gain,
                        "kp_per_s2": kp,
                        "kd_per_s": 2.0 * 0.85 * math.sqrt(kp),
                        "stabilization": name,
                        **_summary(walk, self.step_ends),
                    }
                )
        distances = _distance_after_steps(self.unstabilized, self.step_ends)
        return {
            "config": {**asdict(c), "gains": list(c.gains)},
            "walk": {
                "duration_s": self.step_ends[-1],
                "step_ends_s": list(self.step_ends),
                "periods": int(round(self.step_ends[-1] / c.period)),
            },
            "pendulum_bound_kp_per_s2": GRAVITY / GaitConfig().com_height,
            "fig_5_21_unstabilized": {
                "com_distance_after_step_m": distances,
                **_summary(self.unstabilized, self.step_ends),
            },
            "k_sweep": sweep,
            "fig_5_27_comparison": {
                "plan_clik": _summary(self.clik, self.step_ends),
                "plan_error_compensation": _summary(self.error_compensation, self.step_ends),
                "ikd_hybrid": {"k": c.comparison_gain, **_summary(self.comparison, self.step_ends)},
            },
            "wall_s": self.wall_s,
            "machine": self.machine,
        }


# ---------------------------------------------------------------------------------------------- inverse dynamics
def contact_wrench(
    model: RobotModel, q: NDArray[np.float64], qdot: NDArray[np.float64], qddot: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The ground's wrench that the motion ``(q, qdot, qddot)`` of the floating-base ``model`` needs: ``(force [N],
    moment [N m] about the world origin)``, from the base rows of ``tau = M qddot + h`` (a spatial force in the base
    frame at its origin, pinocchio's free flyer: position ``q[:3]``, quaternion ``q[3:7]`` as x, y, z, w)."""
    model.update(q)
    tau = model.mass_matrix() @ qddot + model.nonlinear_effects(q, qdot)
    rotation = _quaternion_matrix(q[3:7])
    force = rotation @ tau[:3]
    return force, rotation @ tau[3:6] + np.cross(q[:3], force)


def _quaternion_matrix(quaternion: NDArray[np.float64]) -> NDArray[np.float64]:
    x, y, z, w = quaternion / np.linalg.norm(quaternion)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def _cop(force: NDArray[np.float64], moment: NDArray[np.float64], ground: float) -> NDArray[np.float64]:
    """The CoP [m] on the ground plane ``z = ground`` of a wrench about the origin (``n = p x f + tau_z e_z``)."""
    return np.array([ground * force[0] - moment[1], moment[0] + ground * force[1]]) / force[2]


# ---------------------------------------------------------------------------------------------- the walk
class _Walk:
    """The shared walk: the model, the standing start, the pattern sampled at every period and its references."""

    def __init__(self, config: IkdStudyConfig) -> None:
        self.config = config
        self.model = model = RobotModel.from_mjcf(BIPED_XML)
        self.period = h = config.period
        q = np.zeros(model.nq)
        q[6] = 1.0  # the identity quaternion (x, y, z, w)
        q[7:] = [NOMINAL_POSTURE.get(j, 0.0) for j in BIPED_JOINTS]
        model.update(q)
        q[2] = -min(model.frame_position(f)[2] for f in FEET)  # soles on z = 0
        self.gait = gait = GaitConfig()
        self.force = model.total_mass * GRAVITY
        lower, upper = model.lower_limits[7:], model.upper_limits[7:]
        self._posture = q[7:].copy()
        self._limits = (lower + BIPED_SOFT_LIMIT_MARGIN, upper - BIPED_SOFT_LIMIT_MARGIN)
        # the walking controller's standing start: the CLIK moves the CoM to com_height above the soles
        model.update(q)
        feet = np.array([model.frame_position(f) for f in FEET])
        rotations = np.array([model.frame_rotation(f) for f in FEET])
        com = model.com()
        stand = WholeBodyReference(
            np.array([com[0], com[1], float(feet[:, 2].mean()) + gait.com_height]),
            np.zeros(3),
            feet,
            rotations,
            np.zeros((2, 6)),
            np.eye(3),
            np.zeros(3),
        ).to_array()
        solver = self.clik()
        for _ in range(20):
            q = solver.step(q, stand, stand, h).q
        self.start = q
        model.update(q)
        feet = np.array([model.frame_position(f) for f in FEET])
        if config.correction:  # the walking controller's plan: its correction rollouts from this standing state
            controller = WalkingController(model, h, *self._limits, gait=gait, correction_iterations=3)
            controller.start(q, config.speed)
            assert controller.pattern is not None and controller.q_ref is not None
            self.start, pattern = controller.q_ref, controller.pattern
        else:
            pattern = WalkingPattern(gait, feet[0], feet[1], model.com()[:2], config.speed)
        self.pattern = pattern
        self.count = int(round(pattern.step_start(config.steps) / h))
        self.step_ends = tuple(pattern.step_start(k + 1) for k in range(config.steps))
        # each sample's ZMP is the reference ZMP that the whole body should have (the plan's own without a correction)
        self.samples: list[PatternSample] = [
            replace(sample, zmp=pattern.reference_zmp(n * h).copy())
            for n, sample in ((n, pattern.sample(n * h)) for n in range(self.count + 1))
        ]
        self.ground = pattern.ground
        self.windows = {
            k: (pattern.step_start(k) + pattern.step_single(k), pattern.step_start(k + 1))
            for k in range(config.steps + 1)
        }
        self.ideal = np.array([self.force * np.array([s.zmp[1], -s.zmp[0]]) for s in self.samples])
        self.support = np.array([_support(s) for s in self.samples])
        self.double_support = np.array([all(s.contact) for s in self.samples])
        self.references = np.array([_clik_reference(s) for s in self.samples])

    def clik(self) -> CompiledWholeBodyIk:
        """The walking controller's CLIK (its default gains, posture and joint-limit objectives; self-collision,
        which straight walking does not activate, left out), compiled."""
        model = self.model
        objectives = (
            ActuatedObjective(PostureObjective(self._posture, 1.0), model),
            ActuatedObjective(
                JointLimitObjective(*self._limits, activation_distance=0.15, slope=2.0, weight=1.0), model
            ),
        )
        return CompiledWholeBodyIk(
            WholeBodyIk(model, feet_frames=FEET, gain=100.0, gamma=0.008, beta=10.0, objectives=objectives)
        )


def _support(sample: PatternSample) -> NDArray[np.float64]:
    """The bounding box of the soles planned on the ground ``((x_min, y_min), (x_max, y_max))`` [m]."""
    feet = [f for f, on in zip(sample.feet, sample.contact, strict=True) if on]
    return np.array(
        [
            np.min([[f[0] + SOLE_X[0], f[1] - SOLE_HALF_WIDTH] for f in feet], axis=0),
            np.max([[f[0] + SOLE_X[1], f[1] + SOLE_HALF_WIDTH] for f in feet], axis=0),
        ]
    )


def _pitch(angle: float) -> NDArray[np.float64]:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _feet_twist(sample: PatternSample) -> NDArray[np.float64]:
    twist = np.zeros((2, 6))
    twist[:, :3], twist[:, 4] = sample.feet_velocity, sample.feet_pitch_rate
    return twist


def _clik_reference(sample: PatternSample) -> NDArray[np.float64]:
    """The CLIK's packed reference of a straight-walking sample: the plan's CoM, soles pitched, torso upright."""
    return WholeBodyReference(
        sample.com.copy(),
        sample.com_velocity.copy(),
        sample.feet.copy(),
        np.array([_pitch(a) for a in sample.feet_pitch]),
        _feet_twist(sample),
        np.eye(3),
        np.zeros(3),
    ).to_array()


class _Recorder:
    """Collects an :class:`IkdWalk` period by period."""

    def __init__(self, walk: _Walk) -> None:
        self.walk = walk
        self.rows: dict[str, list[Any]] = {k: [] for k in ("moment", "inverse_dynamics_moment", "com", "cop")}

    def add(
        self,
        moment: NDArray[np.float64],
        force: NDArray[np.float64],
        id_moment: NDArray[np.float64],
        com: NDArray[np.float64],
    ) -> None:
        self.rows["moment"].append(moment[:2].copy())
        self.rows["inverse_dynamics_moment"].append(id_moment[:2].copy())
        self.rows["com"].append(com[:2].copy())
        self.rows["cop"].append(_cop(force, id_moment, self.walk.ground))

    def done(self, label: str, completed: bool, gain: float | None = None, planning: bool = False) -> IkdWalk:
        w = self.walk
        n = len(self.rows["moment"])
        arrays = {k: np.array(v, dtype=np.float64).reshape(n, 2) for k, v in self.rows.items()}
        return IkdWalk(
            label,
            np.arange(n, dtype=np.float64) * w.period,
            arrays["moment"],
            arrays["inverse_dynamics_moment"],
            w.ideal[:n].copy(),
            arrays["com"],
            np.array([s.com[:2] for s in w.samples[:n]]).reshape(n, 2),
            arrays["cop"],
            w.support[:n].copy(),
            w.double_support[:n].copy(),
            completed,
            gain,
            planning,
        )


# ---------------------------------------------------------------------------------------------- the runs
def _ikd_walk(walk: _Walk, gain: float, planning: bool, bar: Any) -> IkdWalk:
    """The biped IKD along the walk with ``moment_gain`` ``gain`` (5.97), and stabilization via planning."""
    model, h, c = walk.model, walk.period, walk.config
    ikd = BipedIkd(model, feet_frames=FEET, posture=walk.start, moment_gain=gain, period=h)
    planner = PlanStabilizer(math.sqrt(GRAVITY / walk.gait.com_height)) if planning else None
    q, qdot = walk.start.copy(), np.zeros(model.nv)
    mass = model.total_mass
    recorder = _Recorder(walk)
    replanned, completed = -1, True
    for n in range(walk.count):
        sample, ahead = walk.samples[n], walk.samples[n + 1]
        t = n * h
        model.update(q)
        com, centroidal = model.com_and_centroidal_matrix()
        com_velocity = centroidal[:2] @ qdot / mass
        zmp, plan = sample.zmp.copy(), np.concatenate([sample.com[:2], sample.com_velocity[:2]])
        if planner is not None:
            k = sample.step
            # restart the plan from the IKD's CoM at the double support's start (as WalkingIkd does)
            if k >= 0 and k != replanned and t >= walk.windows[k][0] - 0.5 * h:
                replanned = k
                planner.replan(t, com[:2] - sample.com[:2], com_velocity - sample.com_velocity[:2], walk.windows[k])
            out = planner.advance(t, h)
            zmp += out.zmp_shift
            plan += np.concatenate([out.com_offset, out.com_offset_rate])
        velocity = _feet_twist(sample)
        reference = BipedIkdReference(
            sample.feet.copy(),
            np.array([_pitch(a) for a in sample.feet_pitch]),
            velocity,
            (_feet_twist(ahead) - velocity) / h,
            np.eye(3),
            np.zeros(3),
            np.zeros(3),
            np.array([sample.com[2], 0.0, 0.0]),
            walk.force * np.array([zmp[1], -zmp[0]]),
            plan if gain > 0.0 else None,
            walk.support[n],
        )
        result = ikd.step(q, qdot, reference)
        distance = float(np.linalg.norm(com[:2] - sample.com[:2]))
        if not result.success or distance > c.divergence:
            completed = False
            bar.update(walk.count - n)
            break
        force, id_moment = contact_wrench(model, q, qdot, result.qddot)
        recorder.add(result.moment, force, id_moment, com)
        qdot = qdot + h * result.qddot
        q = model.integrate(q, qdot, h)
        bar.update(1)
    stabilization = "hybrid" if planning else ("contact moment" if gain > 0.0 else "unstabilized")
    return recorder.done(f"IKD, k = {gain:g}, {stabilization}", completed, gain, planning)


def _clik_walks(walk: _Walk, bar: Any) -> tuple[IkdWalk, IkdWalk]:
    """The plain LIPM plan tracked by the CLIK, and the same plan with dynamics error compensation (the CLIK tracks
    the plan's CoM plus the compensation's offset), run side by side: the compensation at period ``n`` reads the
    plain motion's inverse-dynamics moment there (its central differences need the plain CLIK one period ahead)."""
    model, h = walk.model, walk.period
    plain_solver, compensated_solver = walk.clik(), walk.clik()
    compensation = ErrorCompensation(model.total_mass, walk.gait.com_height, h)
    plain, compensated = _Recorder(walk), _Recorder(walk)
    q_plain = [walk.start.copy(), walk.start.copy()]  # q_{n-1}, q_n (at rest before the walk)
    q_comp = [walk.start.copy(), walk.start.copy()]
    references = walk.references
    for n in range(walk.count):
        q_next = plain_solver.step(q_plain[1], references[n], references[n + 1], h).q
        q_plain.append(q_next)
        force, moment, com = _differenced_wrench(model, q_plain, h)
        plain.add(moment, force, moment, com)
        out = compensation.step(walk.ideal[n], moment[:2])
        start, end = references[n].copy(), references[n + 1].copy()
        start[0:2] += out.com_offset
        start[3:5] += out.com_offset_rate
        end[0:2] += compensation.offset
        end[3:5] += compensation.offset_rate
        q_comp.append(compensated_solver.step(q_comp[1], start, end, h).q)
        force, moment, com = _differenced_wrench(model, q_comp, h)
        compensated.add(moment, force, moment, com)
        del q_plain[0], q_comp[0]
        bar.update(1)
    name = walk.config.plan_name
    return (plain.done(f"{name}, CLIK", True), compensated.done(f"{name} + error compensation (5.98), CLIK", True))


def _differenced_wrench(
    model: RobotModel, q: list[NDArray[np.float64]], h: float
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The ground's wrench at ``q[1]`` for the motion through ``q[0], q[1], q[2]`` (central differences), and the
    CoM there."""
    before = model.difference(q[0], q[1]) / h
    after = model.difference(q[1], q[2]) / h
    force, moment = contact_wrench(model, q[1], 0.5 * (before + after), (after - before) / h)
    return force, moment, model.com().copy()


def run_ikd_study(config: IkdStudyConfig | None = None, *, progress: bool = True) -> IkdStudy:
    """Run the study (about 10 s at the defaults on one core)."""
    config = config or IkdStudyConfig()
    began = time.perf_counter()
    walk = _Walk(config)
    gains = tuple(dict.fromkeys((*config.gains, config.comparison_gain)))
    total = walk.count * (2 * len(gains) + 1)
    with tqdm(total=total, desc="ikd study", unit="period", disable=not progress, mininterval=0.5) as bar:
        feedback = {k: _ikd_walk(walk, k, False, bar) for k in gains}
        hybrid = {k: _ikd_walk(walk, k, True, bar) for k in gains}
        clik, compensated = _clik_walks(walk, bar)
    return IkdStudy(
        config,
        feedback[0.0] if 0.0 in feedback else _ikd_walk(walk, 0.0, False, _Null()),
        tuple(feedback[k] for k in config.gains),
        tuple(hybrid[k] for k in config.gains),
        clik,
        compensated,
        hybrid[config.comparison_gain],
        walk.step_ends,
        time.perf_counter() - began,
        machine_info(),
    )


class _Null:
    """A progress bar that shows nothing."""

    def update(self, n: int = 1) -> None:
        pass


# ---------------------------------------------------------------------------------------------- figures
def _rms(values: NDArray[np.float64]) -> float:
    return float(np.sqrt(np.mean(values**2))) if values.size else 0.0


def _summary(walk: IkdWalk, step_ends: tuple[float, ...]) -> dict[str, Any]:
    """A run's figures: moment error against the ideal, CoM distance from the plan, CoP against the support box,
    the inverse dynamics' agreement with the realized moment, the modification's share in double support."""
    error = walk.moment - walk.ideal_moment
    norm = np.linalg.norm(error, axis=1)
    distance = np.linalg.norm(walk.com - walk.plan_com, axis=1)
    outside = (
        np.maximum(np.maximum(walk.support[:, 0] - walk.cop, walk.cop - walk.support[:, 1]), 0.0).max(axis=1)
        if len(walk.time)
        else np.zeros(0)
    )
    scale = np.maximum(np.abs(walk.moment).max(axis=1), 1e-12) if len(walk.time) else np.zeros(0)
    id_error = np.abs(walk.inverse_dynamics_moment - walk.moment).max(axis=1) / scale if len(walk.time) else np.zeros(0)
    total = float(norm.sum())
    return {
        "label": walk.label,
        "completed": walk.completed,
        "duration_s": float(len(walk.time) * (walk.time[1] - walk.time[0])) if len(walk.time) > 1 else 0.0,
        "moment_error_rms_nm": {"x": _rms(error[:, 0]), "y": _rms(error[:, 1]), "norm": _rms(norm)},
        "moment_error_max_nm": {
            "x": float(np.abs(error[:, 0]).max(initial=0.0)),
            "y": float(np.abs(error[:, 1]).max(initial=0.0)),
            "norm": float(norm.max(initial=0.0)),
        },
        "modification_share_in_double_support": float(norm[walk.double_support].sum() / total) if total > 0.0 else 0.0,
        "com_distance_max_m": float(distance.max(initial=0.0)),
        "com_distance_final_m": float(distance[-1]) if distance.size else 0.0,
        "cop_outside_support_fraction": float(np.mean(outside > COP_TOLERANCE)) if outside.size else 0.0,
        "cop_outside_support_max_m": float(outside.max(initial=0.0)),
        "cop_margin_min_m": float(np.minimum(walk.cop - walk.support[:, 0], walk.support[:, 1] - walk.cop).min())
        if len(walk.time)
        else 0.0,
        "inverse_dynamics_relative_error_max": float(id_error.max(initial=0.0)),
    }


def _distance_after_steps(walk: IkdWalk, step_ends: tuple[float, ...]) -> list[float | None]:
    """The CoM's distance from the plan [m] at each step's end (None once the run has stopped)."""
    distance = np.linalg.norm(walk.com - walk.plan_com, axis=1)
    h = walk.time[1] - walk.time[0] if len(walk.time) > 1 else 1.0
    out: list[float | None] = []
    for end in step_ends:
        n = int(round(end / h)) - 1
        out.append(float(distance[n]) if n < distance.size else None)
    return out


def write_ikd_study(study: IkdStudy, path: str | Path) -> Path:
    """Write :meth:`IkdStudy.to_json` (parents created)."""
    return write_json(study.to_json(), path)


def format_ikd_study(report: dict[str, Any]) -> str:
    """The JSON report as text tables."""
    lines = []
    fig = report["fig_5_21_unstabilized"]
    steps = ", ".join("-" if d is None else f"{1e3 * d:.1f}" for d in fig["com_distance_after_step_m"])
    lines.append(
        f"fig. 5.21, IKD unstabilized: CoM distance from the plan after each step [mm]: {steps}"
        f" ({'walked' if fig['completed'] else 'stopped at'} {fig['duration_s']:.2f} s)"
    )
    lines.append("")
    lines.append("figs. 5.23/5.24, k sweep (moment error against the ideal [N m]; CoM distance from the plan [mm]):")
    lines.append(
        f"{'k':>8} {'K_p':>6} {'stabilization':>13} {'walked':>7} {'rms T_x':>8} {'rms T_y':>8} {'max |dT|':>9}"
        f" {'in DS':>6} {'max dist':>9} {'ID rel.':>8}"
    )
    for row in report["k_sweep"]:
        rms, peak = row["moment_error_rms_nm"], row["moment_error_max_nm"]
        lines.append(
            f"{row['k']:>8g} {row['kp_per_s2']:>6.1f} {row['stabilization']:>13} {row['duration_s']:>6.2f}s"
            f" {rms['x']:>8.2f} {rms['y']:>8.2f} {peak['norm']:>9.2f} "
            f"{100 * row['modification_share_in_double_support']:>5.0f}% "
            f"{1e3 * row['com_distance_max_m']:>9.1f} {row['inverse_dynamics_relative_error_max']:>8.1e}"
        )
    lines.append("")
    lines.append(
        "fig. 5.27, moment by inverse dynamics against the ideal [N m]; the CoP against the support box "
        "(the soles' bounding box):"
    )
    lines.append(
        f"{'method':>26} {'rms T_x':>8} {'rms T_y':>8} {'max T_x':>8} {'max T_y':>8} {'CoP out':>8}"
        f" {'by [mm]':>8} {'min margin [mm]':>16}"
    )
    for name, row in report["fig_5_27_comparison"].items():
        rms, peak = row["moment_error_rms_nm"], row["moment_error_max_nm"]
        lines.append(
            f"{name:>26} {rms['x']:>8.2f} {rms['y']:>8.2f} {peak['x']:>8.2f} {peak['y']:>8.2f} "
            f"{100 * row['cop_outside_support_fraction']:>7.1f}% {1e3 * row['cop_outside_support_max_m']:>8.1f}"
            f" {1e3 * row['cop_margin_min_m']:>16.1f}"
        )
    lines.append(
        f"({report['walk']['periods']} periods of {1e3 * report['config']['period']:g} ms, "
        f"{report['wall_s']:.1f} s wall)"
    )
    return "\n".join(lines)


def _shade_double_support(ax: Any, walk: IkdWalk, label: bool = True) -> None:
    """Yellow spans over the double-support phases (as the monograph's figs. 5.24)."""
    ds = walk.double_support
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ds.astype(int), [0]])))
    h = walk.time[1] - walk.time[0]
    for i, (a, b) in enumerate(zip(edges[::2], edges[1::2], strict=True)):
        ax.axvspan(a * h, b * h, color="gold", alpha=0.25, lw=0, label="double support" if label and i == 0 else None)


def _moment_figure(walks: tuple[IkdWalk, ...], reference: IkdWalk, title: str, path: Path) -> Path:
    """``T_x`` against the ideal, and both axes' difference from the ideal (``T_y`` about the world origin grows
    with the distance walked, so its difference is what can be read)."""
    fig, axes = plt.subplots(3, 1, figsize=(10, 8.4), sharex=True, gridspec_kw={"height_ratios": [1.3, 1, 1]})
    for row, ax in enumerate(axes):
        _shade_double_support(ax, reference, label=row == 0)
        ax.grid(alpha=0.3)
    axes[0].plot(reference.time, reference.ideal_moment[:, 0], color="k", lw=2.2, label="ideal (reference ZMP)")
    for ax in axes[1:]:
        ax.axhline(0.0, color="k", lw=1.6)
    for i, walk in enumerate(walks):
        error = walk.moment - walk.ideal_moment
        rms = np.sqrt(np.mean(error**2, axis=0)) if len(walk.time) else np.zeros(2)
        label = walk.label + ("" if walk.completed else f" (stopped at {walk.time[-1]:.2f} s)")
        axes[0].plot(walk.time, walk.moment[:, 0], lw=1.0, color=f"C{i}", label=label)
        for axis in (0, 1):
            axes[1 + axis].plot(walk.time, error[:, axis], lw=0.9, color=f"C{i}", label=f"rms {rms[axis]:.1f} N m")
    axes[0].set_ylabel("$T_x$ [N m]")
    axes[1].set_ylabel("$T_x - T_{x,ideal}$ [N m]")
    axes[2].set_ylabel("$T_y - T_{y,ideal}$ [N m]")
    axes[0].set_title(textwrap.fill(title, 100), fontsize=10)
    axes[0].legend(fontsize=7, loc="upper left", ncol=2)
    for ax in axes[1:]:
        ax.legend(fontsize=7, loc="upper left", ncol=len(walks))
    axes[2].set_xlabel("time [s]")
    return save_figure(fig, path)


def plot_ikd_study(study: IkdStudy, out_dir: str | Path, suffix: str = "") -> list[Path]:
    """Write the figures' analogues into ``out_dir``: ``ikd_fig_5_21{suffix}.png`` (unstabilized drift),
    ``ikd_fig_5_23{suffix}.png`` (k sweep, contact-moment feedback), ``ikd_fig_5_24{suffix}.png`` (k sweep, hybrid)
    and ``ikd_fig_5_27{suffix}.png`` (the plan by CLIK, with error compensation, IKD hybrid)."""
    out = Path(out_dir)
    c = study.config
    speed = f"{c.plan_name}; {c.speed:g} m/s, {c.steps} steps, {1e3 * c.period:g} ms"
    written = []
    # fig. 5.21: the lateral CoM and the distance from the plan
    walk = study.unstabilized
    reference = study.clik
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    axes[0].plot(reference.time, 1e3 * reference.plan_com[:, 1], color="k", lw=2, label=f"plan ({c.plan_name})")
    axes[0].plot(walk.time, 1e3 * walk.com[:, 1], label="IKD, no stabilization (moment tracked exactly)")
    for other in study.moment_feedback:
        if other.gain and other.completed:
            axes[0].plot(other.time, 1e3 * other.com[:, 1], lw=0.9, label=f"IKD, k = {other.gain:g} (5.97)")
            break
    axes[0].set_ylabel("lateral CoM $y_c$ [mm]")
    axes[0].legend(fontsize=8)
    axes[0].grid(alpha=0.3)
    distance = np.linalg.norm(walk.com - walk.plan_com, axis=1)
    axes[1].semilogy(walk.time, np.maximum(1e3 * distance, 1e-3), label="IKD, no stabilization")
    axes[1].set_ylim(bottom=1e-3)
    for end, d in zip(study.step_ends, _distance_after_steps(walk, study.step_ends), strict=True):
        if d is not None:
            axes[1].plot(end, 1e3 * d, "o", color="C3", ms=4)
            axes[1].annotate(f"{1e3 * d:.1f}", (end, 1e3 * d), textcoords="offset points", xytext=(3, 4), fontsize=7)
    axes[1].set_ylabel("CoM distance from the plan [mm]")
    axes[1].set_xlabel("time [s] (dots: step ends)")
    axes[1].grid(alpha=0.3, which="both")
    axes[0].set_title(
        textwrap.fill(f"Kinematic IKD without stabilization drifts off the plan (fig. 5.21 analogue; {speed})", 90),
        fontsize=10,
    )
    written.append(save_figure(fig, out / f"ikd_fig_5_21{suffix}.png"))
    written.append(
        _moment_figure(
            study.moment_feedback,
            reference,
            f"Contact moment, IKD stabilized via the contact moment (5.97) (fig. 5.23 analogue; {speed})",
            out / f"ikd_fig_5_23{suffix}.png",
        )
    )
    written.append(
        _moment_figure(
            study.hybrid,
            reference,
            f"Contact moment, IKD hybrid: planning + contact moment (fig. 5.24 analogue; {speed})",
            out / f"ikd_fig_5_24{suffix}.png",
        )
    )
    comparison = (study.clik, study.error_compensation, study.comparison)
    written.append(
        _moment_figure(
            comparison,
            reference,
            f"Contact moment by inverse dynamics against the ideal (fig. 5.27 analogue; {speed})",
            out / f"ikd_fig_5_27{suffix}.png",
        )
    )
    return written
