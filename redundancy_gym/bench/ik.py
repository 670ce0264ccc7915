"""``redundancy-gym bench ik``: one collision-aware CLIK control step on the 9-DoF AgriReach arm against mink.

Both controllers see the same states: an AgriReach-v0 episode (``medium`` by default) is run with the ``clik``
reference, and at every visited configuration

- **ours**: :class:`~redundancy_gym.controllers.GraspClikPolicy.predict` (path sample, kinematics, every
  collision pair of the arm against itself and the observed hard obstacles, DLS solve with nullspace collision
  and joint-limit avoidance), timed per call;
- **mink** (benchmark-only dependency, ``pip install -e '.[bench]'``): ``Configuration.update(q)``
  plus ``solve_ik`` with daqp on ``FrameTask`` (TCP pose towards the same path sample; the orientation target
  turns the current tool axis onto the path's axis) + ``PostureTask`` + ``ConfigurationLimit`` +
  ``CollisionAvoidanceLimit`` over the same geoms: the arm's capsules and spheres against each other and
  against the MuJoCo geoms of the same observed hard obstacles, with the same 0.1 m detection distance.

The two are timed in alternating rounds (:func:`~redundancy_gym.bench.timing.alternating_rounds`: a warm-up
round, then ``rounds`` rounds of ours, mink / mink, ours / ...), each sample one pass over all the states
(``repeats`` calls per state, the median kept). ``ratio_vs_mink`` is the median over the rounds of the ratio of the
two passes' medians over the states (ours / mink); ``ratio_vs_mink_rounds`` gives its median, min, max and spread
``(max - min) / median``. A controller's ``step_us_median`` and ``step_us_p90`` are over the states of each state's
median over the rounds. The scaling part times our control step along the same states with 10 to 1000 hard obstacle
primitives (the nearest of a long unpruned row).
"""

from __future__ import annotations

import copy
import time
from collections.abc import Sequence
from functools import partial
from typing import TYPE_CHECKING, Any, cast

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from ..eval.machine import finish_machine_info, machine_info
from ..geometry import LSS, PSS, Segment, distance
from ..policies.grasp_clik_policy import GraspClikPolicy, obstacle_volumes
from ..sb3_import import install_hint
from .exceptions import BenchError
from .timing import CLOCK, TimedPasses, alternating_rounds, check_rounds, timed_call

if TYPE_CHECKING:
    from ..envs.agri_reach import AgriReachEnv

__all__ = ["format_ik_bench", "run_ik_bench"]

ENV_ID = "redundancy_gym/AgriReach-v0"
SCALING = (10, 30, 100, 300, 1000)


def _episode(env: gym.Env, policy: GraspClikPolicy, seed: int) -> tuple[list[NDArray[np.float64]], list[float]]:
    """Run one clik episode; returns the observations it acted on and the time of each predict call [us]."""
    obs, _ = env.reset(seed=seed)
    observations, times = [], []
    for _ in range(500):
        start = time.perf_counter()
        action, _ = policy.predict(obs)
        times.append((time.perf_counter() - start) * 1e6)
        observations.append(obs)
        obs, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            break
    return observations, times


def _observed_hard_geoms(env: Any, obs: NDArray[np.float64]) -> list[int]:
    """MuJoCo geoms of the hard obstacles in the observation's obstacle block (what the clik policy avoids)."""
    u = env.unwrapped
    row = u.crop_row
    geoms = []
    for volume, hard in obstacle_volumes(obs[u.observation_layout["obstacles"]]):
        if not hard:
            continue
        match = np.flatnonzero(np.all(np.abs(row.vertices[:, 0] - volume.points[0]) < 1e-12, axis=1) & row.hard)
        geoms.append(int(u.part_geoms[match[0]]))
    return geoms


class _MinkSolver:
    """mink's ``Configuration.update`` + ``solve_ik`` (daqp) on the AgriReach arm with the same tasks, limits and
    collision geoms as our controller sees; :meth:`step` times one solve at an observation."""

    def __init__(self, env: Any, policy: GraspClikPolicy, first: NDArray[np.float64]) -> None:
        import mink  # noqa: PLC0415 - benchmark-only dependency

        from ..assets import AGRI_ARM_GEOMS, AGRI_ARM_TCP  # noqa: PLC0415

        u = env.unwrapped
        model = copy.deepcopy(u.model)
        arm = [model.geom(n).id for n in AGRI_ARM_GEOMS]
        obstacles = _observed_hard_geoms(env, first)
        model.geom_contype[arm + obstacles] = 1
        model.geom_conaffinity[arm + obstacles] = 1
        self.mink, self.tcp, self.policy = mink, AGRI_ARM_TCP, policy
        self.configuration = mink.Configuration(model)
        self.frame = mink.FrameTask(AGRI_ARM_TCP, "site", position_cost=1.0, orientation_cost=1.0, gain=1.0)
        self.posture = mink.PostureTask(model, cost=1e-2)
        self.layout = u.observation_layout
        self.posture.set_target(first[self.layout["q"]])
        self.collision = mink.CollisionAvoidanceLimit(
            model,
            [(arm, obstacles), (arm, arm)],
            collision_detection_distance=policy.config.collision_activation,
            minimum_distance_from_collisions=0.005,
        )
        self.limits = [mink.ConfigurationLimit(model), self.collision]
        self.dt = float(u.dt)

    @property
    def geom_pairs(self) -> int:
        """Collision geom pairs mink checks."""
        return len(self.collision.geom_id_pairs)

    def step(self, obs: NDArray[np.float64]) -> float:
        """Time [s] of one update + solve_ik at ``obs``."""
        mink, lay = self.mink, self.layout
        q = obs[lay["q"]]
        assert self.policy.path is not None  # planned by the episode that recorded ``obs``
        target, _ = self.policy.path(float(obs[lay["time"]][0]))

        def solve() -> None:
            self.configuration.update(q)
            current = self.configuration.get_transform_frame_to_world(self.tcp, "site")
            rotation = _turn_x_onto(current.rotation().as_matrix(), target[3:])
            self.frame.set_target(mink.SE3.from_rotation_and_translation(mink.SO3.from_matrix(rotation), target[:3]))
            mink.solve_ik(
                self.configuration, [self.frame, self.posture], self.dt, "daqp", damping=1e-6, limits=self.limits
            )

        return timed_call(solve)[1]


def _ours_step(policy: GraspClikPolicy) -> Any:
    def step(obs: NDArray[np.float64]) -> float:
        return timed_call(lambda: policy.predict(obs))[1]

    return step


def _turn_x_onto(rotation: NDArray[np.float64], axis: NDArray[np.float64]) -> NDArray[np.float64]:
    """``rotation`` turned by the shortest rotation that takes its x axis onto the unit ``axis``."""
    x = rotation[:, 0]
    k = np.cross(x, axis)
    s, c = float(np.linalg.norm(k)), float(x @ axis)
    if s < 1e-12:
        return rotation.copy()
    k /= s
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    turn = np.eye(3) + s * kx + (1.0 - c) * kx @ kx
    return turn @ rotation


def _scaling(
    policy: GraspClikPolicy,
    observations: list[NDArray[np.float64]],
    layout: dict[str, slice],
    counts: Sequence[int],
    seed: int,
    progress: bool,
) -> list[dict[str, float]]:
    """Our control step time along ``observations`` with the ``n`` hard parts of a long crop row nearest to
    the arm's workspace as obstacles, for each ``n`` in ``counts``."""
    big = gym.make(ENV_ID, prune=False, row_length=60.0)
    big.reset(seed=seed)
    row = cast("AgriReachEnv", big.unwrapped).crop_row  # gym.make returns the base Env type
    big.close()
    assert row is not None  # the reset generated it
    hard = np.flatnonzero(row.hard)
    if hard.size < max(counts):
        raise BenchError(f"the long row has only {hard.size} hard parts, fewer than {max(counts)}")
    reach = LSS([0.0, 0.0, 0.55], [0.0, 0.0, 1.35], 0.0)
    order = hard[np.argsort([distance(_volume(row, int(k)), reach).distance for k in hard])]
    out = []
    for n in tqdm(counts, desc="bench ik scaling", disable=not progress):
        environment = [Segment(f"obstacle_{i}", (_volume(row, k),)) for i, k in enumerate(order[:n])]
        controller = policy.build_controller(environment)
        times = []
        for obs in observations:
            assert policy.path is not None  # planned by the episodes that recorded the observations
            target, velocity = policy.path(float(obs[layout["time"]][0]))
            q = obs[layout["q"]]
            # partial binds this iteration's controller and state (a closure would read the loop's latest)
            times.append(timed_call(partial(controller.step, q, target, velocity))[1] * 1e6)
        out.append(
            {
                "primitives": int(n),
                "step_us_median": float(np.median(times)),
                "step_us_p90": float(np.percentile(times, 90)),
            }
        )
    return out


def _volume(row: Any, k: int) -> PSS | LSS:
    v, r = row.vertices[k], float(row.radius[k])
    return PSS(v[0], r) if row.kind[k] == 0 else LSS(v[0], v[1], r)


def run_ik_bench(
    *,
    seed: int = 0,
    difficulty: str = "medium",
    repeats: int = 3,
    rounds: int = 15,
    scaling: Sequence[int] = SCALING,
    progress: bool = True,
) -> dict[str, Any]:
    """Time our CLIK control step against mink's ``solve_ik`` on the same states in alternating rounds; returns the
    report.

    Args:
        seed: reset seed of the AgriReach episode.
        difficulty: AgriReach difficulty preset.
        repeats: timed calls per state within a pass (the median is kept).
        rounds: alternating rounds (one pass over the states by each controller) after a warm-up round.
        scaling: obstacle primitive counts of the scaling study (empty to skip it).
        progress: show progress bars.

    Raises:
        BenchError: ``repeats < 1`` or ``rounds < 1``; mink or daqp not installed.
    """
    if repeats < 1:
        raise BenchError(f"repeats must be >= 1, got {repeats}")
    check_rounds(rounds)
    machine = machine_info()
    env = gym.make(ENV_ID, difficulty=difficulty)
    try:
        policy = GraspClikPolicy(env)
        _episode(env, policy, seed)  # warm up compiled kernels and caches
        observations, first = _episode(env, policy, seed)
        # predict re-plans at time 0, so re-planning the episode's first state leaves the path as it was
        pairs = policy.collision.collision_model.num_volume_pairs if policy.collision is not None else 0
        try:
            solver = _MinkSolver(env, policy, observations[0])
        except ImportError as exc:
            raise BenchError(f"bench ik needs mink and daqp: {install_hint('bench')}") from exc
        ours, mink = (
            TimedPasses(_ours_step(policy), observations, repeats),
            TimedPasses(solver.step, observations, repeats),
        )
        timed = alternating_rounds(
            {"ours": ours, "mink": mink}, rounds=rounds, progress=progress, desc="bench ik rounds"
        )
        scale = (
            _scaling(
                policy, observations, cast("AgriReachEnv", env.unwrapped).observation_layout, scaling, seed, progress
            )
            if scaling
            else []
        )
    finally:
        env.close()
    ours_median, ours_p90 = ours.summary_us(timed.warmup)
    mink_median, mink_p90 = mink.summary_us(timed.warmup)
    stats = timed.ratio("ours", "mink")
    return {
        "benchmark": "ik",
        "env": ENV_ID,
        "difficulty": difficulty,
        "seed": seed,
        "states": len(observations),
        "repeats": repeats,
        "timing": {
            "rounds": rounds,
            "warmup": timed.warmup,
            "sample": "one pass over the states",
            "clock": CLOCK,
            "order": "ours, mink; reversed every other round",
        },
        "machine": finish_machine_info(machine),
        "ours": {
            "step_us_median": ours_median,
            "step_us_p90": ours_p90,
            "first_step_us": first[0],
            "volume_pairs": pairs,
        },
        "mink": {
            "step_us_median": mink_median,
            "step_us_p90": mink_p90,
            "geom_pairs": solver.geom_pairs,
            "solver": "daqp",
        },
        "ratio_vs_mink": stats.median,
        "ratio_vs_mink_rounds": stats.to_json(),
        "scaling": scale,
    }


def format_ik_bench(report: dict[str, Any]) -> str:
    """A plain-text summary."""
    o, m = report["ours"], report["mink"]
    lines = [
        f"{report['env']} ({report['difficulty']}, seed {report['seed']}): {report['states']} states",
        f"ours  median {o['step_us_median']:.1f} us  p90 {o['step_us_p90']:.1f} us  ({o['volume_pairs']} pairs)",
        f"mink  median {m['step_us_median']:.1f} us  p90 {m['step_us_p90']:.1f} us  ({m['geom_pairs']} pairs)",
        f"ratio_vs_mink = {report['ratio_vs_mink']:.3f}" + _rounds_text(report.get("ratio_vs_mink_rounds")),
    ]
    if report["scaling"]:
        lines.append("primitives | step median [us] | p90 [us]")
        lines += [f"{s['primitives']} | {s['step_us_median']:.1f} | {s['step_us_p90']:.1f}" for s in report["scaling"]]
    return "\n".join(lines)


def _rounds_text(stats: dict[str, Any] | None) -> str:
    """``  (rounds MIN-MAX, spread S %)`` of a ratio's round statistics, or nothing."""
    if not stats:
        return ""
    return f"  (rounds {stats['min']:.3f}-{stats['max']:.3f}, spread {100 * stats['spread']:.1f} %)"
