"""The evaluation harness: run a policy for N seeded episodes and report the evaluation contract of DESIGN.md."""

from __future__ import annotations

import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from .. import ENV_IDS, make_policy
from .exceptions import EvalError

__all__ = ["EpisodeTrace", "EvalReport", "evaluate", "format_report", "make_env", "run_episode"]


@dataclass
class EpisodeTrace:
    """Per-step record of one episode (arrays over steps)."""

    time: NDArray[np.float64]
    task_error: NDArray[np.float64]
    joint_speed: NDArray[np.float64]
    min_clearance: NDArray[np.float64]
    pseudoenergy: NDArray[np.float64]
    step_time_us: NDArray[np.float64]


@dataclass
class EpisodeSummary:
    """Metrics of one episode."""

    seed: int
    length: int
    episode_return: float
    success: bool
    collision: bool
    task_error_max: float
    task_error_sq_sum: float
    pseudoenergy: float
    peak_joint_speed: float
    min_clearance: float
    fell: bool | None = None
    forward_speed: float | None = None


@dataclass
class EvalReport:
    """Everything an evaluation measured; :meth:`to_json` gives the DESIGN.md contract."""

    env: str
    policy: str
    episodes: int
    seed: int
    env_kwargs: dict[str, Any]
    summaries: list[EpisodeSummary]
    step_times_us: NDArray[np.float64]
    traces: list[EpisodeTrace] = field(default_factory=list)

    def to_json(self) -> dict[str, Any]:
        """The evaluation-contract object (finite numbers or ``null``)."""
        s = self.summaries
        steps = sum(e.length for e in s)
        returns = np.array([e.episode_return for e in s])
        return {
            "env": self.env,
            "policy": self.policy,
            "episodes": self.episodes,
            "seed": self.seed,
            "env_kwargs": self.env_kwargs,
            "success_rate": float(np.mean([e.success for e in s])),
            "collision_rate": float(np.mean([e.collision for e in s])),
            "task_error_rms": math.sqrt(sum(e.task_error_sq_sum for e in s) / max(steps, 1)),
            "task_error_max": max(e.task_error_max for e in s),
            "pseudoenergy": float(np.mean([e.pseudoenergy for e in s])),
            "peak_joint_speed": max(e.peak_joint_speed for e in s),
            "min_clearance": _finite_or_none(min(e.min_clearance for e in s)),
            "step_time_us": {
                "median": float(np.median(self.step_times_us)),
                "p99": float(np.percentile(self.step_times_us, 99)),
                "mean": float(np.mean(self.step_times_us)),
                "steps": int(self.step_times_us.size),
            },
            "episode_return": float(returns.mean()),
            "episode_return_std": float(returns.std()),
            "episode_length": float(np.mean([e.length for e in s])),
            **self._walking_metrics(),
            "per_episode": [
                {"seed": e.seed, "length": e.length, "return": e.episode_return, "success": e.success,
                 "collision": e.collision, "task_error_max": e.task_error_max, "pseudoenergy": e.pseudoenergy,
                 "peak_joint_speed": e.peak_joint_speed, "min_clearance": _finite_or_none(e.min_clearance),
                 **({} if e.fell is None else {"fell": e.fell, "forward_speed": e.forward_speed})}
                for e in s
            ],
        }

    def _walking_metrics(self) -> dict[str, float]:
        """``fall_rate`` and ``forward_speed`` (mean of distance / time) for envs that report falls (the biped)."""
        if any(e.fell is None for e in self.summaries):
            return {}
        return {"fall_rate": float(np.mean([bool(e.fell) for e in self.summaries])),
                "forward_speed": float(np.mean([e.forward_speed for e in self.summaries]))}

    def write_json(self, path: str | Path) -> Path:
        """Write :meth:`to_json` to ``path`` (parents created)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(self.to_json(), indent=2) + "\n")
        return path


def make_env(env_id: str, env_kwargs: dict[str, Any] | None = None, **make_kwargs: Any) -> gym.Env:
    """``gym.make`` with a clear error for an unknown id."""
    if env_id not in gym.registry:
        raise EvalError(f"unknown env id {env_id!r}; registered by redundancy_gym: {', '.join(ENV_IDS)}")
    return gym.make(env_id, **(env_kwargs or {}), **make_kwargs)


def run_episode(env: gym.Env, policy: Any, seed: int, *,
                frames: list[NDArray[np.uint8]] | None = None) -> tuple[EpisodeSummary, EpisodeTrace]:
    """Run one episode from ``env.reset(seed=seed)``, timing only ``policy.predict``.

    ``frames``: when given, ``env.render()`` output is appended after the reset and after every step.
    """
    obs, info = env.reset(seed=seed)
    if frames is not None:
        frames.append(env.render())
    rows: list[tuple[float, ...]] = []
    ret = 0.0
    collision = False
    state = None
    episode_start = np.array([True])
    while True:
        t0 = time.perf_counter_ns()
        action, state = policy.predict(obs, state=state, episode_start=episode_start, deterministic=True)
        elapsed_us = (time.perf_counter_ns() - t0) * 1e-3
        episode_start = np.array([False])
        obs, reward, terminated, truncated, info = env.step(action)
        if frames is not None:
            frames.append(env.render())
        ret += float(reward)
        collision = collision or bool(info.get("collision", False))
        rows.append((float(info.get("time", len(rows) + 1)), float(info.get("task_error", np.nan)),
                     float(info.get("peak_joint_speed", 0.0)), float(info.get("min_clearance", np.inf)),
                     float(info.get("pseudoenergy", 0.0)), elapsed_us))
        if terminated or truncated:
            break
    data = np.asarray(rows, dtype=np.float64)
    trace = EpisodeTrace(*(data[:, k].copy() for k in range(6)))
    summary = EpisodeSummary(
        seed=seed, length=len(rows), episode_return=ret, success=bool(info.get("is_success", False)),
        collision=collision, task_error_max=float(np.max(trace.task_error)),
        task_error_sq_sum=float(np.sum(trace.task_error**2)), pseudoenergy=float(np.sum(trace.pseudoenergy)),
        peak_joint_speed=float(np.max(trace.joint_speed)), min_clearance=float(np.min(trace.min_clearance)))
    if "fell" in info and "distance" in info:
        elapsed = float(info.get("time", 0.0))
        summary.fell = bool(info["fell"])
        summary.forward_speed = float(info["distance"]) / elapsed if elapsed > 0.0 else 0.0
    return summary, trace


def evaluate(env_id: str, policy: str, *, episodes: int = 10, seed: int = 0, env_kwargs: dict[str, Any] | None = None,
             policy_kwargs: dict[str, Any] | None = None, keep_traces: bool = False,
             progress: bool = True) -> EvalReport:
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
    """
    if episodes < 1:
        raise EvalError(f"episodes must be >= 1, got {episodes}")
    env_kwargs = dict(env_kwargs or {})
    policy_kwargs = dict(policy_kwargs or {})
    env = make_env(env_id, env_kwargs)
    try:
        if policy == "random":
            policy_kwargs.setdefault("seed", seed)
        agent = make_policy(policy, env, **policy_kwargs)
        summaries: list[EpisodeSummary] = []
        traces: list[EpisodeTrace] = []
        step_times: list[NDArray[np.float64]] = []
        for k in tqdm(range(episodes), desc=f"eval {policy} on {env_id}", disable=not progress, leave=False):
            summary, trace = run_episode(env, agent, seed + k)
            summaries.append(summary)
            step_times.append(trace.step_time_us)
            if keep_traces:
                traces.append(trace)
    finally:
        env.close()
    return EvalReport(env_id, policy, episodes, seed, env_kwargs, summaries, np.concatenate(step_times), traces)


def format_report(report: dict[str, Any]) -> str:
    """A readable table of an evaluation-contract object."""
    step = report["step_time_us"]
    rows = [
        ("env", report["env"]),
        ("policy", report["policy"]),
        ("episodes (seed)", f"{report['episodes']} ({report['seed']})"),
        ("success rate", f"{report['success_rate']:.3f}"),
        ("collision rate", f"{report['collision_rate']:.3f}"),
        ("task error rms / max [m]", f"{report['task_error_rms']:.3e} / {report['task_error_max']:.3e}"),
        ("pseudoenergy [rad^2/s]", f"{report['pseudoenergy']:.4f}"),
        ("peak joint speed [rad/s]", f"{report['peak_joint_speed']:.3f}"),
        ("min clearance [m]", "n/a" if report["min_clearance"] is None else f"{report['min_clearance']:.4f}"),
        ("step time median / p99 [us]", f"{step['median']:.1f} / {step['p99']:.1f}"),
        ("episode return", f"{report['episode_return']:.3f} +- {report['episode_return_std']:.3f}"),
    ]
    if "fall_rate" in report:
        rows.append(("fall rate", f"{report['fall_rate']:.3f}"))
        rows.append(("forward speed [m/s]", f"{report['forward_speed']:.3f}"))
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None
