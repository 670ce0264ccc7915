"""``redundancy-gym bench push``: the largest torso push the walking reference recovers from, per direction.

BipedWalk-v0 at ``speed`` (0.5 m/s), the ``walking`` policy. Each trial walks ``WALK_IN`` seconds, then a
push of ``duration`` (0.1 s) acts on the torso at a random gait phase (uniform over ``PHASE_WINDOW`` seconds, two
gait cycles at 0.5 m/s), and the trial is *recovered* when the biped has not fallen ``AFTER`` seconds after the
push started. Directions: ``lateral`` (+y or -y, drawn per trial) and ``forward`` (+x, along the walk).

The impulse grid (``force x duration`` [N s]) is walked upwards; at each level the same trials (phases, signs
and env seeds, drawn once from ``seed``) are run. A level *holds* when at least ``RECOVERY_TARGET`` (90 %) of its
trials recover; ``<direction>_impulse_recovered`` is the largest level up to which every level holds (a level
fails as soon as more than 10 % of its trials have fallen, and the levels above it are not run). The same
trials are run with the step adjustment off (``push_recovery=False``: ankle and hip strategy only), the peer
in the same run, reported as ``baseline_<direction>_impulse_recovered``.

The trials are held out from the tuning of the step adjuster (which used other phases and env seeds 0-9): the
phases come from ``numpy.random.default_rng([seed, 2026])`` and the env seeds are ``1000 + trial``.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, cast

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

from ..eval.machine import machine_info
from .exceptions import BenchError

if TYPE_CHECKING:
    from ..envs.biped_walk import BipedWalkEnv

__all__ = [
    "AFTER",
    "DIRECTIONS",
    "PHASE_WINDOW",
    "RECOVERY_TARGET",
    "WALK_IN",
    "format_push_bench",
    "plot_push_bench",
    "push_trial",
    "run_push_bench",
]

DIRECTIONS = ("lateral", "forward")
WALK_IN = 2.0
"""Walking time before the earliest push [s]."""
PHASE_WINDOW = 1.6
"""Pushes start uniformly in ``[WALK_IN, WALK_IN + PHASE_WINDOW)`` [s] (two gait cycles at 0.5 m/s)."""
AFTER = 3.0
"""A trial is recovered when the biped stands this long after the push started [s]."""
RECOVERY_TARGET = 0.9
"""Share of trials that must recover for an impulse level to hold."""
ENV_ID = "redundancy_gym/BipedWalk-v0"
NDArrayLike = Sequence[float] | np.ndarray


def push_trial(
    impulse: float,
    direction: NDArrayLike,
    start: float,
    env_seed: int,
    *,
    speed: float = 0.5,
    duration: float = 0.1,
    push_recovery: bool = True,
) -> tuple[bool, float]:
    """One push trial: ``(recovered, time of the fall or of the trial's end [s])``.

    Args:
        impulse: push impulse [N s] (force ``impulse / duration``).
        direction: horizontal unit vector (x, y) of the push.
        start: push start [s] after the reset.
        env_seed: the env's reset seed.
        speed: BipedWalk ``target_speed`` [m/s].
        duration: push duration [s].
        push_recovery: the walking policy's step adjustment.
    """
    from ..policies import make_policy

    unit = np.asarray(direction, dtype=np.float64)
    force = [float(unit[0] * impulse / duration), float(unit[1] * impulse / duration), 0.0]
    env = gym.make(
        ENV_ID,
        target_speed=speed,
        max_episode_steps=10**7,
        push=[{"time": float(start), "force": force, "duration": float(duration), "body": "torso"}],
    )
    try:
        policy = make_policy("walking", env, push_recovery=push_recovery)
        obs, _ = env.reset(seed=int(env_seed))
        dt = float(cast("BipedWalkEnv", env.unwrapped).dt)  # gym.make returns the base Env type
        steps = int(np.ceil((start + AFTER) / dt))
        first = np.array([True])
        for i in range(steps):
            action, _ = policy.predict(obs, episode_start=first, deterministic=True)
            first = np.array([False])
            obs, _, terminated, truncated, _ = env.step(action)
            if terminated or truncated:
                return False, (i + 1) * dt
        return True, steps * dt
    finally:
        env.close()


def _trials(seed: int, count: int, direction: str) -> list[dict[str, Any]]:
    rng = np.random.default_rng([seed, 2026, DIRECTIONS.index(direction)])
    trials = []
    for i in range(count):
        start = WALK_IN + float(rng.uniform(0.0, PHASE_WINDOW))
        if direction == "lateral":
            sign = 1.0 if rng.random() < 0.5 else -1.0
            unit = (0.0, sign)
        else:
            unit = (1.0, 0.0)
        trials.append({"start": round(start, 4), "direction": unit, "env_seed": 1000 + i})
    return trials


def run_push_bench(
    *,
    seed: int = 0,
    trials: int = 20,
    impulses: Sequence[float] = tuple(range(5, 45, 5)),
    speed: float = 0.5,
    duration: float = 0.1,
    progress: bool = True,
) -> dict[str, Any]:
    """Run the push bench (see the module docstring) and return its report (JSON-ready).

    Args:
        seed: seed of the push phases and signs.
        trials: trials per impulse level (>= 1).
        impulses: impulse grid [N s], increasing.
        speed: walking speed [m/s].
        duration: push duration [s].
        progress: show a progress bar.
    """
    if isinstance(trials, bool) or not isinstance(trials, int) or trials < 1:
        raise BenchError(f"trials must be an int >= 1, got {trials!r}")
    levels = [float(x) for x in impulses]
    if not levels or any(not np.isfinite(x) or x <= 0.0 for x in levels) or np.any(np.diff(levels) <= 0.0):
        raise BenchError(f"impulses must be positive, finite and increasing, got {list(impulses)!r}")
    allowed_failures = int(np.floor((1.0 - RECOVERY_TARGET) * trials + 1e-9))
    started = time.perf_counter()
    controllers = {"step_adjustment": True, "baseline": False}
    results: dict[str, Any] = {}
    bar = tqdm(
        total=len(controllers) * len(DIRECTIONS) * len(levels) * trials,
        desc="bench push",
        disable=not progress,
        unit="trial",
    )
    for name, on in controllers.items():
        results[name] = {}
        for direction in DIRECTIONS:
            cases = _trials(seed, trials, direction)
            rows, recovered_up_to = [], 0.0
            for impulse in levels:
                falls, outcomes = 0, []
                for case in cases:
                    ok, when = push_trial(
                        impulse,
                        case["direction"],
                        case["start"],
                        case["env_seed"],
                        speed=speed,
                        duration=duration,
                        push_recovery=on,
                    )
                    outcomes.append({**case, "recovered": ok, "end": round(when, 3)})
                    falls += not ok
                    bar.update(1)
                    if falls > allowed_failures:
                        break
                bar.update(trials - len(outcomes))
                holds = falls <= allowed_failures
                rows.append(
                    {
                        "impulse": impulse,
                        "trials_run": len(outcomes),
                        "recovered": sum(o["recovered"] for o in outcomes),
                        "holds": holds,
                        "falls": [
                            {k: o[k] for k in ("start", "direction", "env_seed", "end")}
                            for o in outcomes
                            if not o["recovered"]
                        ],
                    }
                )
                if not holds:
                    bar.update((len(levels) - len(rows)) * trials)
                    break
                recovered_up_to = impulse
            results[name][direction] = {"impulse_recovered": recovered_up_to, "levels": rows}
    bar.close()
    report: dict[str, Any] = {
        "bench": "push",
        "env_id": ENV_ID,
        "policy": "walking",
        "speed": speed,
        "push_duration": duration,
        "push_body": "torso",
        "trials_per_level": trials,
        "impulses": levels,
        "recovery_target": RECOVERY_TARGET,
        "walk_in": WALK_IN,
        "phase_window": PHASE_WINDOW,
        "after": AFTER,
        "seed": seed,
        "lateral_impulse_recovered": results["step_adjustment"]["lateral"]["impulse_recovered"],
        "forward_impulse_recovered": results["step_adjustment"]["forward"]["impulse_recovered"],
        "baseline_lateral_impulse_recovered": results["baseline"]["lateral"]["impulse_recovered"],
        "baseline_forward_impulse_recovered": results["baseline"]["forward"]["impulse_recovered"],
        "results": results,
        "wall_time_s": round(time.perf_counter() - started, 1),
        "machine": machine_info(),
    }
    return report


def format_push_bench(report: dict[str, Any]) -> str:
    """A table: per controller and direction, the recovery rate at each impulse run and the largest level held."""
    lines = [
        f"bench push: {report['env_id']} at {report['speed']} m/s, {report['push_duration']} s torso pushes, "
        f"{report['trials_per_level']} trials per level (held: >= {report['recovery_target']:.0%} recovered)"
    ]
    for name, directions in report["results"].items():
        for direction, result in directions.items():
            rates = ", ".join(f"{row['impulse']:g}: {row['recovered']}/{row['trials_run']}" for row in result["levels"])
            lines.append(f"  {name:16s} {direction:8s} recovered up to {result['impulse_recovered']:g} N s   [{rates}]")
    return "\n".join(lines)


def plot_push_bench(report: dict[str, Any], path: str) -> str:
    """Recovery rate against impulse, per direction, with and without step adjustment; saved as PNG at ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(DIRECTIONS), figsize=(10, 4), sharey=True)
    labels = {"step_adjustment": "walking (step adjustment)", "baseline": "walking, push_recovery=False"}
    for ax, direction in zip(axes, DIRECTIONS, strict=False):
        for name, style in (("step_adjustment", "o-"), ("baseline", "s--")):
            rows = report["results"][name][direction]["levels"]
            x, y = [r["impulse"] for r in rows], [r["recovered"] / r["trials_run"] for r in rows]
            (line,) = ax.plot(
                x, y, style, label=f"{labels[name]}: {report['results'][name][direction]['impulse_recovered']:g} N s"
            )
            for xi, yi, r in zip(x, y, rows, strict=False):  # recovered / run: a stopped level ran fewer trials
                ax.annotate(
                    f"{r['recovered']}/{r['trials_run']}",
                    (xi, yi),
                    textcoords="offset points",
                    xytext=(4, -12 if name == "baseline" else 5),
                    fontsize=7,
                    color=line.get_color(),
                )
        ax.axhline(report["recovery_target"], color="grey", lw=0.8, ls=":")
        lowest = min(
            r["recovered"] / r["trials_run"] for name in labels for r in report["results"][name][direction]["levels"]
        )
        ax.set_ylim(min(lowest, report["recovery_target"]) - 0.08, 1.06)  # room for the labels
        ax.set_title(f"{direction} pushes, {report['push_duration']} s on the torso")
        ax.set_xlabel("impulse [N s]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="lower left")
    axes[0].set_ylabel("share of trials recovered")
    fig.suptitle(
        f"BipedWalk-v0 at {report['speed']} m/s, {report['trials_per_level']} trials per impulse: the largest "
        f"impulse recovered in >= {report['recovery_target']:.0%} of them\n(a level stops once more than "
        f"{1.0 - report['recovery_target']:.0%} of its trials have fallen; labels: recovered / run)",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
