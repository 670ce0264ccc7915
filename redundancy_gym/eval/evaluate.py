"""The evaluation harness: run a policy for N seeded episodes and report the evaluation contract
(docs/evaluation.md)."""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, cast

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from .. import ENV_IDS, make_policy
from ..wrappers.action_check import CONTROLLER_TIME_ATTRIBUTE
from .compile_clock import COMPILE_CLOCK
from .exceptions import EvalError
from .json_writer import write_json
from .parallel import run_parallel

__all__ = ["EpisodeTrace", "EvalReport", "controller_clock", "evaluate", "format_report", "make_env", "run_episode"]


@dataclass
class EpisodeTrace:
    """Per-step record of one episode (arrays over steps; NaN where the env does not report the quantity).

    Attributes:
        time: env time after the step [s].
        tracking_error: TCP distance to the env's reference path [m] (``info["tracking_error"]``).
        goal_error: TCP distance to the goal [m] (``info["goal_error"]``).
        speed_error: ``|v_x - target_speed|`` of the biped [m/s] (``info["speed_error"]``).
        joint_speed: largest joint speed of the step [rad/s]; min_clearance: [m]; pseudoenergy: ``qdot^T qdot dt``.
        step_time_us: the policy's compute time for the step [us] (an action wrapper's controller included).
    """

    time: NDArray[np.float64]
    tracking_error: NDArray[np.float64]
    goal_error: NDArray[np.float64]
    speed_error: NDArray[np.float64]
    joint_speed: NDArray[np.float64]
    min_clearance: NDArray[np.float64]
    pseudoenergy: NDArray[np.float64]
    step_time_us: NDArray[np.float64]


@dataclass
class EpisodeSummary:
    """Metrics of one episode (``None`` where the env does not define the quantity).

    Attributes:
        tracking_error_max, tracking_error_sq_sum: largest and summed squared tracking error [m, m^2].
        goal_error: TCP distance to the goal at the last step [m].
        time_to_goal: first time ``info["goal_reached"]`` held [s] (``None``: never).
        speed_error_sq_sum: summed squared instantaneous speed error [m^2/s^2] (biped).
        mean_speed_error: ``|distance / time - target_speed|`` at the end [m/s] (biped).
        first_step_us: the policy's compute time for the first step [us] (where a plan-once policy solves).
        min_obstacle_clearance, min_self_clearance: the smallest of ``info``'s values over the episode [m].
        leaf_contacts: leaf contacts of the episode, summed over steps (``info["leaf_contacts_total"]`` at the
            end; a leaf touched for 10 steps counts 10).
        obstacle_contact: whether ``info["obstacle_contact"]`` held at any step (BipedObstacles: a MuJoCo contact of
            the robot with an obstacle).
        stop_reason: for a policy with a ``stop_reason`` attribute (the ``walking`` policy), its value at the
            episode's end: why the walk stopped in front of an obstacle (None: it did not stop).
        terrain_kind: BipedTerrain: where a failed walk failed: the class of the last terrain segment the pelvis
            reached before its first unsupported touchdown, or before it fell or ended (``"flat"``: none).
        unsupported_steps: BipedTerrain: touchdowns with less than the env's ``min_support`` of the sole supported.
        min_support_fraction: BipedTerrain: the episode's smallest touchdown support fraction.
        sb3_predict_us: for an SB3 policy on its fast path (``Sb3Policy.fast_path``), the step time SB3's own
            ``predict`` would have given, per step [us]: ``sb3_predict`` timed on the step's observation right after
            the policy's ``predict`` (its action unused), plus the step's action-wrapper controller time as in
            ``step_time_us``; ``None`` for every other policy.
        compile_time_s: numba kernel preparation [s] inside the episode's timed calls (a kernel's first call in a
            process compiles it, or loads its machine code from the cache), taken out of their step times
            (:mod:`~redundancy_gym.eval.compile_clock`).
    """

    seed: int
    length: int
    episode_return: float
    success: bool
    collision: bool
    pseudoenergy: float
    peak_joint_speed: float
    min_clearance: float
    first_step_us: float
    tracking_error_max: float | None = None
    tracking_error_sq_sum: float | None = None
    goal_error: float | None = None
    goal_reached: bool | None = None
    time_to_goal: float | None = None
    speed_error_sq_sum: float | None = None
    mean_speed_error: float | None = None
    fell: bool | None = None
    forward_speed: float | None = None
    min_obstacle_clearance: float | None = None
    min_self_clearance: float | None = None
    leaf_contacts: int | None = None
    obstacle_contact: bool | None = None
    stop_reason: str | None = None
    terrain_kind: str | None = None
    unsupported_steps: int | None = None
    min_support_fraction: float | None = None
    sb3_predict_us: NDArray[np.float64] | None = None
    compile_time_s: float = 0.0


@dataclass
class EvalReport:
    """Everything an evaluation measured; :meth:`to_json` gives the evaluation contract of docs/evaluation.md."""

    env: str
    policy: str
    episodes: int
    seed: int
    env_kwargs: dict[str, Any]
    summaries: list[EpisodeSummary]
    step_times_us: NDArray[np.float64]
    traces: list[EpisodeTrace] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        """The evaluation-contract object (finite numbers or ``null``; the README lists every field's unit)."""
        s = self.summaries
        steps = sum(e.length for e in s)
        returns = np.array([e.episode_return for e in s])
        times = self.step_times_us
        first = np.array([e.first_step_us for e in s])
        return {
            "env": self.env,
            "policy": self.policy,
            "episodes": self.episodes,
            "seed": self.seed,
            "env_kwargs": self.env_kwargs,
            "success_rate": float(np.mean([e.success for e in s])),
            "collision_rate": float(np.mean([e.collision for e in s])),
            **self._task_metrics(steps),
            "pseudoenergy": float(np.mean([e.pseudoenergy for e in s])),
            "peak_joint_speed": max(e.peak_joint_speed for e in s),
            "min_clearance": _finite_or_none(min(e.min_clearance for e in s)),
            **self._clearance_metrics(),
            "step_time_us": _time_stats(times, first),
            **self._sb3_metrics(),
            "compile_time_s": float(sum(e.compile_time_s for e in s)),
            "compute_time_per_episode_ms": float(times.sum()) * 1e-3 / len(s),
            "episode_return": float(returns.mean()),
            "episode_return_std": float(returns.std()),
            "episode_length": float(np.mean([e.length for e in s])),
            **self._walking_metrics(),
            **self._terrain_metrics(),
            "per_episode": [_episode_row(e) for e in s],
        }

    def _sb3_metrics(self) -> dict[str, dict[str, float | int]]:
        """``sb3_predict_us``: the statistics of ``step_time_us`` over the step times SB3's own ``predict`` gave on
        the same observations (:attr:`EpisodeSummary.sb3_predict_us`), for an SB3 policy on its fast path; nothing
        for other policies, whose contract stays as it was."""
        timed = [e.sb3_predict_us for e in self.summaries]
        if not timed or any(t is None or t.size == 0 for t in timed):
            return {}
        arrays = cast(list[NDArray[np.float64]], timed)
        return {"sb3_predict_us": _time_stats(np.concatenate(arrays), np.array([t[0] for t in arrays]))}

    def _task_metrics(self, steps: int) -> dict[str, float | None]:
        """Tracking error (against the env's reference path), goal error and time to the goal; each ``None``
        where the env does not define it."""
        s = self.summaries
        tracked = [e for e in s if e.tracking_error_max is not None]
        goals = [e for e in s if e.goal_error is not None]
        reached = [e.time_to_goal for e in goals if e.time_to_goal is not None]
        return {
            "tracking_error_rms": (
                math.sqrt(sum(e.tracking_error_sq_sum or 0.0 for e in tracked) / max(sum(e.length for e in tracked), 1))
                if tracked
                else None
            ),
            "tracking_error_max": max(e.tracking_error_max or 0.0 for e in tracked) if tracked else None,
            "goal_error": float(np.mean([e.goal_error for e in goals])) if goals else None,
            "goal_error_max": max(e.goal_error or 0.0 for e in goals) if goals else None,
            "goal_reached_rate": float(np.mean([bool(e.goal_reached) for e in goals])) if goals else None,
            "time_to_goal": float(np.mean(reached)) if reached else None,
        }

    def _clearance_metrics(self) -> dict[str, float | None]:
        """``min_obstacle_clearance`` and ``min_self_clearance`` [m] (smallest over all steps and episodes),
        ``leaf_contacts`` (mean per episode of the leaf contacts summed over steps) and ``obstacle_contact_rate``
        (share of episodes with an obstacle contact), for envs that report them."""
        s = self.summaries
        out: dict[str, float | None] = {}
        for key in ("min_obstacle_clearance", "min_self_clearance"):
            values = [getattr(e, key) for e in s if getattr(e, key) is not None]
            if values:
                out[key] = _finite_or_none(min(values))
        leaves = [e.leaf_contacts for e in s if e.leaf_contacts is not None]
        if leaves:
            out["leaf_contacts"] = float(np.mean(leaves))
        touched = [e.obstacle_contact for e in s if e.obstacle_contact is not None]
        if touched:
            out["obstacle_contact_rate"] = float(np.mean(touched))
        return out

    def _walking_metrics(self) -> dict[str, float]:
        """``fall_rate``, ``forward_speed`` (mean of distance / time), ``speed_error`` (mean over episodes of
        ``|distance / time - target_speed|``) and ``speed_error_rms`` (instantaneous ``|v_x - target|``) [m/s]
        for envs that report falls (the biped)."""
        s = self.summaries
        if any(e.fell is None for e in s):
            return {}
        out = {
            "fall_rate": float(np.mean([bool(e.fell) for e in s])),
            "forward_speed": float(np.mean([e.forward_speed for e in s])),
        }
        if all(e.mean_speed_error is not None for e in s):
            out["speed_error"] = float(np.mean([e.mean_speed_error for e in s]))
            out["speed_error_rms"] = math.sqrt(
                sum(e.speed_error_sq_sum or 0.0 for e in s) / max(sum(e.length for e in s), 1)
            )
        return out

    def _terrain_metrics(self) -> dict[str, Any]:
        """``unsupported_rate`` (share of episodes with a touchdown on less than the env's ``min_support`` of the
        sole), ``min_support_fraction`` (the smallest over all episodes) and ``failures_by_terrain`` (failed episodes
        per class of the segment where they failed, :attr:`EpisodeSummary.terrain_kind`), for BipedTerrain."""
        s = self.summaries
        if any(e.terrain_kind is None for e in s):
            return {}
        failures: dict[str, int] = {}
        for e in s:
            if not e.success:
                kind = str(e.terrain_kind)
                failures[kind] = failures.get(kind, 0) + 1
        return {
            "unsupported_rate": float(np.mean([bool(e.unsupported_steps) for e in s])),
            "min_support_fraction": float(min(e.min_support_fraction or 0.0 for e in s)),
            "failures_by_terrain": dict(sorted(failures.items())),
        }

    def write_json(self, path: str | Path) -> Path:
        """Write :meth:`to_json` to ``path`` (parents created)."""
        return write_json(self.to_json(), path)


def _time_stats(times: NDArray[np.float64], first: NDArray[np.float64]) -> dict[str, float | int]:
    """Median, p99 and mean of per-step times [us], the mean of the episodes' first steps and the step count."""
    return {
        "median": float(np.median(times)),
        "p99": float(np.percentile(times, 99)),
        "mean": float(np.mean(times)),
        "first_step_mean": float(first.mean()),
        "steps": int(times.size),
    }


def make_env(env_id: str, env_kwargs: dict[str, Any] | None = None, **make_kwargs: Any) -> gym.Env:
    """``gym.make`` with a clear error for an unknown id."""
    if env_id not in gym.registry:
        raise EvalError(f"unknown env id {env_id!r}; registered by redundancy_gym: {', '.join(ENV_IDS)}")
    return gym.make(env_id, **(env_kwargs or {}), **make_kwargs)


def reseed_policy(policy: Any, seed: int) -> None:
    """Restart a stochastic policy's generator from the episode's seed (its ``reseed`` method, where it has one), so
    that the episode depends on its seed only: the same serially and on parallel workers."""
    reseed = getattr(policy, "reseed", None)
    if callable(reseed):
        reseed(seed)


def controller_clock(env: gym.Env) -> Any:
    """The wrapper in ``env``'s chain that times its controller (``controller_time_us``), or None."""
    layer: gym.Env | None = env
    while layer is not None:
        if CONTROLLER_TIME_ATTRIBUTE in vars(layer):
            return layer
        layer = getattr(layer, "env", None)
    return None


def _frame(env: gym.Env) -> NDArray[np.uint8]:
    """``env.render()``: one RGB frame, as the ``rgb_array`` render mode that a caller asking for frames sets
    gives (gymnasium types ``render`` for every mode)."""
    return cast(NDArray[np.uint8], env.render())


def run_episode(
    env: gym.Env, policy: Any, seed: int, *, frames: list[NDArray[np.uint8]] | None = None
) -> tuple[EpisodeSummary, EpisodeTrace]:
    """Run one episode from ``env.reset(seed=seed)``, timing only the policy: ``policy.predict`` plus, in an action
    wrapper, the wrapper's controller (its ``controller_time_us`` attribute); the simulation is not counted.

    An SB3 policy on its fast path is timed a second time per step through SB3's own ``predict`` on the same
    observation (its action unused: the episode is the fast path's), for
    :attr:`EpisodeSummary.sb3_predict_us`.

    ``frames``: when given, ``env.render()`` output is appended after the reset and after every step.
    """
    obs, info = env.reset(seed=seed)
    controller = controller_clock(env)
    sb3_predict = policy.sb3_predict if getattr(policy, "fast_path", False) else None
    sb3_times: list[float] = []
    if frames is not None:
        frames.append(_frame(env))
    rows: list[tuple[float, ...]] = []
    ret = 0.0
    collision = False
    time_to_goal: float | None = None
    clearances = {"min_obstacle_clearance": math.inf, "min_self_clearance": math.inf}
    obstacle_contact = False
    terrain_kind = "flat"
    failed_on_terrain = False
    state = None
    episode_start = np.array([True])
    compiled_s = 0.0
    while True:
        compiling = COMPILE_CLOCK.seconds
        t0 = time.perf_counter_ns()
        action, state = policy.predict(obs, state=state, episode_start=episode_start, deterministic=True)
        elapsed_us = (time.perf_counter_ns() - t0) * 1e-3
        # a kernel compiled inside the call is the compiler's time, not the step's (compile_time_s)
        compiled = COMPILE_CLOCK.seconds - compiling
        if compiled > 0.0:
            compiled_s += compiled
            elapsed_us = max(elapsed_us - compiled * 1e6, 0.0)
        sb3_us = 0.0
        if sb3_predict is not None:  # after the policy's own timing, which it leaves as it was
            t0 = time.perf_counter_ns()
            sb3_predict(obs, state=None, episode_start=episode_start, deterministic=True)
            sb3_us = (time.perf_counter_ns() - t0) * 1e-3
        episode_start = np.array([False])
        compiling = COMPILE_CLOCK.seconds
        obs, reward, terminated, truncated, info = env.step(action)
        if controller is not None:  # an action wrapper's controller is part of the policy: its time counts too
            controller_us = float(getattr(controller, CONTROLLER_TIME_ATTRIBUTE))
            compiled = COMPILE_CLOCK.seconds - compiling  # the controller's or the env's: bounded by the former
            if compiled > 0.0:
                taken = min(compiled * 1e6, controller_us)
                compiled_s += taken * 1e-6
                controller_us -= taken
            elapsed_us += controller_us
            sb3_us += controller_us
        if sb3_predict is not None:
            sb3_times.append(sb3_us)
        if frames is not None:
            frames.append(_frame(env))
        ret += float(reward)
        collision = collision or bool(info.get("collision", False))
        obstacle_contact = obstacle_contact or bool(info.get("obstacle_contact", False))
        kind = info.get("terrain_kind")
        if kind is not None and kind != "flat" and not failed_on_terrain:
            terrain_kind = str(kind)
        # a walk that lands a foot unsupported has failed there, though it may walk on to the course's end
        failed_on_terrain = failed_on_terrain or bool(info.get("unsupported_steps", 0))
        now = float(info.get("time", len(rows) + 1))
        if time_to_goal is None and info.get("goal_reached", False):
            time_to_goal = now
        for key, low in clearances.items():
            if key in info:
                clearances[key] = min(low, float(info[key]))
        rows.append(
            (
                now,
                float(info.get("tracking_error", np.nan)),
                float(info.get("goal_error", np.nan)),
                float(info.get("speed_error", np.nan)),
                float(info.get("peak_joint_speed", 0.0)),
                float(info.get("min_clearance", np.inf)),
                float(info.get("pseudoenergy", 0.0)),
                elapsed_us,
            )
        )
        if terminated or truncated:
            break
    data = np.asarray(rows, dtype=np.float64)
    trace = EpisodeTrace(*(data[:, k].copy() for k in range(8)))
    summary = EpisodeSummary(
        seed=seed,
        length=len(rows),
        episode_return=ret,
        success=bool(info.get("is_success", False)),
        collision=collision,
        pseudoenergy=float(np.sum(trace.pseudoenergy)),
        peak_joint_speed=float(np.max(trace.joint_speed)),
        min_clearance=float(np.min(trace.min_clearance)),
        first_step_us=float(trace.step_time_us[0]),
        sb3_predict_us=np.asarray(sb3_times, dtype=np.float64) if sb3_predict is not None else None,
        compile_time_s=compiled_s,
    )
    if "tracking_error" in info:
        summary.tracking_error_max = float(np.max(trace.tracking_error))
        summary.tracking_error_sq_sum = float(np.sum(trace.tracking_error**2))
    if "goal_error" in info:
        summary.goal_error = float(info["goal_error"])
        summary.goal_reached = time_to_goal is not None
        summary.time_to_goal = time_to_goal
    if "speed_error" in info:
        summary.speed_error_sq_sum = float(np.sum(trace.speed_error**2))
        summary.mean_speed_error = float(info.get("mean_speed_error", np.nan))
    for key, low in clearances.items():
        if key in info:
            setattr(summary, key, low)
    if "leaf_contacts_total" in info:
        summary.leaf_contacts = int(info["leaf_contacts_total"])
    if "obstacle_contact" in info:
        summary.obstacle_contact = obstacle_contact
    if hasattr(policy, "stop_reason"):
        summary.stop_reason = policy.stop_reason
    if "terrain_kind" in info:
        summary.terrain_kind = terrain_kind
        summary.unsupported_steps = int(info["unsupported_steps"])
        summary.min_support_fraction = float(info["min_support_fraction"])
    if "fell" in info and "distance" in info:
        elapsed = float(info.get("time", 0.0))
        summary.fell = bool(info["fell"])
        summary.forward_speed = float(info["distance"]) / elapsed if elapsed > 0.0 else 0.0
    return summary, trace


def evaluate(
    env_id: str,
    policy: str,
    *,
    episodes: int = 10,
    seed: int = 0,
    env_kwargs: dict[str, Any] | None = None,
    policy_kwargs: dict[str, Any] | None = None,
    keep_traces: bool = False,
    progress: bool = True,
    warmup: int = 0,
    workers: int = 1,
    retries: int = 0,
    ray_address: str | None = None,
) -> EvalReport:
    """Evaluate a policy (name or SB3 ``.zip``) on ``episodes`` episodes with seeds ``seed, seed + 1, ...``.

    Args:
        env_id: a registered env id.
        policy: ``clik``, ``zero``, ``random`` or a ``.zip`` path (see :func:`redundancy_gym.make_policy`).
        episodes: number of episodes (>= 1).
        seed: first episode seed; the random policy is seeded with it too.
        env_kwargs: keyword arguments for ``gym.make``.
        policy_kwargs: options of the policy.
        keep_traces: keep per-step traces in the report (for plots).
        progress: show a progress bar.
        warmup: untimed episodes (seed ``seed``) run first with the same policy object and env, so that one-time
            costs (JIT compilation, lazily built models) are not counted in the step times or as a plan-once
            policy's per-episode solve. With ``workers`` > 1 or Ray, any ``warmup`` > 0 is one warm-up call instead
            (a reset with seed ``seed`` and one policy step and env step), made once before the workers fork or
            once per spawned worker: it loads the compiled kernels (numba's cache) that the episodes use.
        workers: processes the episodes are split across (:mod:`redundancy_gym.eval.parallel`); each episode
            keeps its seed, so the report is the serial one's, timings excepted.
        retries: with ``workers`` > 1 or Ray, how many times episodes whose worker failed or died run again.
        ray_address: run the episodes on ``workers`` Ray actors: a cluster's address or ``"local"`` (a local
            instance); the ``ray`` extra.

    A stochastic policy (``random``) is reseeded with each episode's seed before it (:func:`reseed_policy`).

    Raises:
        ParallelEvalError: with ``workers`` > 1, episodes that failed on every attempt (named by seed).
    """
    if episodes < 1:
        raise EvalError(f"episodes must be >= 1, got {episodes}")
    if isinstance(warmup, bool) or not isinstance(warmup, int) or warmup < 0:
        raise EvalError(f"warmup must be an int >= 0, got {warmup!r}")
    env_kwargs = dict(env_kwargs or {})
    policy_kwargs = dict(policy_kwargs or {})
    if policy == "random":
        policy_kwargs.setdefault("seed", seed)
    if workers != 1 or retries or ray_address is not None:
        return _evaluate_parallel(
            env_id,
            policy,
            episodes,
            seed,
            env_kwargs,
            policy_kwargs,
            keep_traces,
            progress,
            warmup,
            workers,
            retries,
            ray_address,
        )
    runner = _EpisodeRunner(env_id, policy, env_kwargs, policy_kwargs, warmup, seed)
    try:
        summaries: list[EpisodeSummary] = []
        traces: list[EpisodeTrace] = []
        step_times: list[NDArray[np.float64]] = []
        for k in tqdm(range(episodes), desc=f"eval {policy} on {env_id}", disable=not progress, leave=False):
            summary, trace = runner.episode(seed + k)
            summaries.append(summary)
            step_times.append(trace.step_time_us)
            if keep_traces:
                traces.append(trace)
    finally:
        runner.close()
    return EvalReport(env_id, policy, episodes, seed, env_kwargs, summaries, np.concatenate(step_times), traces)


class _EpisodeRunner:
    """The env and the policy of an evaluation, after its warm-up; :meth:`episode` runs a seed's episode (the policy
    reseeded first). The serial loop uses one; a parallel run builds one before its workers fork (or one per spawned
    worker), and the workers call it (:meth:`__call__`) for compact results.

    Args:
        warmup: warm-up episodes of seed ``warmup_seed`` (``warmup_call``: one warm-up call instead, if > 0).
        keep_traces: whether :meth:`__call__` sends every trace field back or only the step times.
        warmup_call: warm up with one reset and one step rather than whole episodes (what loads the compiled
            kernels: numba's cache is on disk, so a worker needs each kernel run once, not a whole episode).
    """

    def __init__(
        self,
        env_id: str,
        policy: str,
        env_kwargs: dict[str, Any],
        policy_kwargs: dict[str, Any],
        warmup: int,
        warmup_seed: int,
        *,
        keep_traces: bool = True,
        warmup_call: bool = False,
    ) -> None:
        self.keep_traces = keep_traces
        self.env = make_env(env_id, env_kwargs)
        try:
            self.agent = make_policy(policy, self.env, **policy_kwargs)
            if warmup_call and warmup:
                obs, _ = self.env.reset(seed=warmup_seed)
                start = np.array([True])
                action, _ = self.agent.predict(obs, state=None, episode_start=start, deterministic=True)
                if getattr(self.agent, "fast_path", False):  # run_episode times SB3's own predict too: warm it
                    self.agent.sb3_predict(obs, state=None, episode_start=start, deterministic=True)
                self.env.step(action)
            else:
                for _ in range(warmup):
                    run_episode(self.env, self.agent, warmup_seed)
        except BaseException:
            self.env.close()
            raise

    def episode(self, seed: int) -> tuple[EpisodeSummary, EpisodeTrace]:
        """The episode of ``seed``: its summary and its trace."""
        reseed_policy(self.agent, seed)
        return run_episode(self.env, self.agent, seed)

    def __call__(self, seed: int) -> tuple[EpisodeSummary, NDArray[np.float64]]:
        """The episode of ``seed`` as a worker sends it back: the summary and the trace as one array (one row per
        :class:`EpisodeTrace` field, or only ``step_time_us`` without ``keep_traces``), one buffer to pickle."""
        summary, trace = self.episode(seed)
        if not self.keep_traces:
            return summary, trace.step_time_us[np.newaxis]
        return summary, np.stack([getattr(trace, f.name) for f in dataclasses.fields(EpisodeTrace)])

    @staticmethod
    def unpack(packed: NDArray[np.float64]) -> EpisodeTrace:
        """The trace of a :meth:`__call__` array with every field (its rows, as views)."""
        return EpisodeTrace(**{f.name: row for f, row in zip(dataclasses.fields(EpisodeTrace), packed, strict=True)})

    def close(self) -> None:
        """Close the env."""
        self.env.close()


def _evaluate_parallel(
    env_id: str,
    policy: str,
    episodes: int,
    seed: int,
    env_kwargs: dict[str, Any],
    policy_kwargs: dict[str, Any],
    keep_traces: bool,
    progress: bool,
    warmup: int,
    workers: int,
    retries: int,
    ray_address: str | None,
) -> EvalReport:
    """:func:`evaluate` on worker processes."""
    seeds = [seed + k for k in range(episodes)]
    where = "Ray actors" if ray_address is not None else "workers"
    setup = functools.partial(
        _EpisodeRunner,
        env_id,
        policy,
        env_kwargs,
        policy_kwargs,
        warmup,
        seed,
        keep_traces=keep_traces,
        warmup_call=True,
    )
    with tqdm(
        total=episodes, desc=f"eval {policy} on {env_id} ({workers} {where})", disable=not progress, leave=False
    ) as bar:
        outcomes = run_parallel(
            setup,
            seeds,
            workers=workers,
            retries=retries,
            progress=bar.update,
            ray_address=ray_address,
            # where the setup does not run here first (spawn, Ray): a clear error for a bad id or kwargs
            validate=lambda: make_env(env_id, env_kwargs).close(),
        )
    summaries = [summary for summary, _ in outcomes]
    step_row = [f.name for f in dataclasses.fields(EpisodeTrace)].index("step_time_us") if keep_traces else 0
    return EvalReport(
        env_id,
        policy,
        episodes,
        seed,
        env_kwargs,
        summaries,
        np.concatenate([packed[step_row] for _, packed in outcomes]),
        [_EpisodeRunner.unpack(packed) for _, packed in outcomes] if keep_traces else [],
    )


def format_report(report: dict[str, Any]) -> str:
    """A readable table of an evaluation-contract object."""
    step = report["step_time_us"]
    rows = [
        ("env", report["env"]),
        ("policy", report["policy"]),
        ("episodes (seed)", f"{report['episodes']} ({report['seed']})"),
        ("success rate", f"{report['success_rate']:.3f}"),
        ("collision rate", f"{report['collision_rate']:.3f}"),
    ]
    if report.get("tracking_error_rms") is not None:
        rows.append(
            (
                "tracking error rms / max [mm]",
                f"{1e3 * report['tracking_error_rms']:.2f} / {1e3 * report['tracking_error_max']:.2f}",
            )
        )
    if report.get("goal_error") is not None:
        reached = report["time_to_goal"]
        rows.append(
            (
                "goal error at end mean / max [mm]",
                f"{1e3 * report['goal_error']:.2f} / {1e3 * report['goal_error_max']:.2f}",
            )
        )
        rows.append(
            (
                "goal reached rate, time to goal [s]",
                f"{report['goal_reached_rate']:.3f}, " + ("n/a" if reached is None else f"{reached:.2f}"),
            )
        )
    if "speed_error" in report:
        rows.append(("speed error mean / rms [m/s]", f"{report['speed_error']:.3f} / {report['speed_error_rms']:.3f}"))
    rows += [
        ("pseudoenergy [rad^2/s]", f"{report['pseudoenergy']:.4f}"),
        ("peak joint speed [rad/s]", f"{report['peak_joint_speed']:.3f}"),
        ("min clearance [mm]", "n/a" if report["min_clearance"] is None else f"{1e3 * report['min_clearance']:.1f}"),
        *(
            (f"  {label} [mm]", "n/a" if report[key] is None else f"{1e3 * report[key]:.1f}")
            for key, label in (("min_obstacle_clearance", "to obstacles"), ("min_self_clearance", "between own links"))
            if key in report
        ),
        *(
            (("leaf contacts per episode [leaf-steps]", f"{report['leaf_contacts']:.1f}"),)
            if "leaf_contacts" in report
            else ()
        ),
        *(
            (("obstacle contact rate", f"{report['obstacle_contact_rate']:.3f}"),)
            if "obstacle_contact_rate" in report
            else ()
        ),
        ("step time median / p99 / mean [us]", f"{step['median']:.1f} / {step['p99']:.1f} / {step['mean']:.1f}"),
        *(
            (
                (
                    "  with SB3's predict instead [us]",
                    "{median:.1f} / {p99:.1f} / {mean:.1f}".format(**report["sb3_predict_us"]),
                ),
            )
            if "sb3_predict_us" in report
            else ()
        ),
        ("first step of an episode, mean [us]", f"{step['first_step_mean']:.1f} (plans, builds models)"),
        (
            "numba compiling or cache loading [s]",
            f"{report.get('compile_time_s', 0.0):.2f} (out of the step times; compiling only on a first run)",
        ),
        ("episode return", f"{report['episode_return']:.3f} +- {report['episode_return_std']:.3f}"),
        ("episode length [steps]", f"{report['episode_length']:.1f}"),
    ]
    if "fall_rate" in report:
        rows.append(("fall rate", f"{report['fall_rate']:.3f}"))
        rows.append(("forward speed [m/s]", f"{report['forward_speed']:.3f}"))
    if "failures_by_terrain" in report:
        rows.append(("unsupported touchdown rate", f"{report['unsupported_rate']:.3f}"))
        rows.append(("min support fraction", f"{report['min_support_fraction']:.2f}"))
        failures = ", ".join(f"{k} {v}" for k, v in report["failures_by_terrain"].items()) or "none"
        rows.append(("failures by terrain class", failures))
    for e in report.get("per_episode", []):  # a failed walk that stopped in front of an obstacle: why
        if not e["success"] and e.get("stop_reason"):
            rows.append((f"stopped, seed {e['seed']}", e["stop_reason"]))
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def _episode_row(e: EpisodeSummary) -> dict[str, Any]:
    """One episode's entry of ``per_episode`` (fields the env does not define are left out)."""
    row: dict[str, Any] = {
        "seed": e.seed,
        "length": e.length,
        "return": e.episode_return,
        "success": e.success,
        "collision": e.collision,
        "pseudoenergy": e.pseudoenergy,
        "peak_joint_speed": e.peak_joint_speed,
        "min_clearance": _finite_or_none(e.min_clearance),
        "first_step_us": e.first_step_us,
    }
    if e.tracking_error_max is not None:
        row["tracking_error_max"] = e.tracking_error_max
    if e.goal_error is not None:
        row.update(goal_error=e.goal_error, time_to_goal=e.time_to_goal)
    if e.fell is not None:
        row.update(fell=e.fell, forward_speed=e.forward_speed)
    if e.mean_speed_error is not None:
        row["speed_error"] = e.mean_speed_error
    if e.min_obstacle_clearance is not None:
        row["min_obstacle_clearance"] = _finite_or_none(e.min_obstacle_clearance)
    if e.obstacle_contact is not None:
        row["obstacle_contact"] = e.obstacle_contact
    if e.stop_reason is not None:
        row["stop_reason"] = e.stop_reason
    if e.terrain_kind is not None:
        row.update(
            terrain_kind=e.terrain_kind,
            unsupported_steps=e.unsupported_steps,
            min_support_fraction=e.min_support_fraction,
        )
    return row


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None
