"""``redundancy-gym bench soak``: drive every env for a long time and count what goes wrong.

Each env is stepped by three action sources, one after the other, for a share of a wall-time budget
(``seconds``) or of a step budget (``steps``) per env:

- ``random``: actions uniform in the action box, from a generator seeded with ``seed``;
- ``bang_bang``: each action entry at the low or the high bound of the box (-1 or +1 here), each entry
  switching with probability :data:`BANG_BANG_SWITCH` per step, from a seeded generator;
- ``reference``: the env's model-based reference policy (``walking`` where the env supports it, else ``clik``;
  :func:`redundancy_gym.make_policy`), given ``episode_start`` after every reset; on a wrapped env
  (``<Env>-<Wrapper>-v0``) the zero action, which leaves the wrapper's own controller in charge.

Episodes end on termination or truncation and the env is reset with consecutive seeds ``seed``, ``seed + 1``,
... An exception (from ``reset``, ``step`` or the policy) is caught and counted with its type and message, the
env is reset and the run goes on. Every step's observation, reward, numeric ``info`` values (and the reference
policy's action) are checked for non-finite values (NaN or +-inf), counted per step and key; NaN in the
``info`` keys that are NaN by design (:data:`DOCUMENTED_NAN`) is counted apart, as ``documented_nan``. Steps/s include
resets and the policy's compute time: what a training or evaluation loop pays.

The BipedWalk reference (the whole-body walking controller, about 170 us per step) gets a smaller share than
the random and bang-bang sources there (:data:`DEFAULT_SHARES`), so that a step budget takes about as long as
on the arms. The issue's acceptance is ``--steps 1000000`` with no exception and no non-finite value.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from tqdm.auto import tqdm

from .. import ENV_IDS
from ..eval.machine import machine_info
from .exceptions import BenchError

__all__ = [
    "BANG_BANG_SWITCH",
    "DEFAULT_SHARES",
    "SOURCES",
    "format_soak_bench",
    "machine_info",
    "run_soak_bench",
    "soak_ok",
]

SOURCES = ("random", "bang_bang", "reference")
BANG_BANG_SWITCH = 0.1
"""Probability per step and action entry that a bang-bang entry switches to the other bound."""
DEFAULT_SHARES: dict[str, dict[str, float]] = {
    "redundancy_gym/BipedWalk-v0": {"random": 0.4, "bang_bang": 0.4, "reference": 0.2},
}
"""Shares of the per-env budget by source, where they are not equal (they are normalized over the sources run)."""
DOCUMENTED_NAN: dict[str, tuple[str, ...]] = {}
"""``info`` keys that an env documents as NaN by design, per env id (none today: BipedWalk's centre of pressure and
ZMP are 0 with validity flags where undefined): NaN there is counted as ``documented_nan``, not as non-finite; an
infinite value still is."""
MAX_MESSAGES = 5
"""How many exception messages and non-finite keys each source keeps."""
MAX_CONSECUTIVE_FAILURES = 20
"""A source whose reset fails this many times in a row is stopped (the env cannot be driven any further)."""
_CHECK_EVERY = 64  # steps between clock reads and progress-bar updates


def _reference_name(env: gym.Env) -> str | None:
    """``walking`` or ``clik``, whichever the env supports; ``zero`` for an env in one of our action wrappers
    (the wrapper's own controller acting alone); None: neither, or the env is not ours."""
    try:
        from ..policies import supported_policies

        supported = supported_policies(env)
    except Exception:  # noqa: BLE001 - an env the policy layer does not know has no reference
        return None
    for name in ("walking", "clik"):
        if name in supported:
            return name
    from ..policies.registry import action_wrapper

    return "zero" if action_wrapper(env) is not None else None


class _Counter:
    """Steps, episodes, exceptions and non-finite values of one (env, source) run."""

    def __init__(self) -> None:
        self.steps = 0
        self.episodes = 0
        self.exceptions = 0
        self.exception_messages: list[dict[str, Any]] = []
        self.non_finite = 0
        self.non_finite_keys: list[dict[str, Any]] = []
        self.documented_nan = 0
        self.nan_ok: frozenset[str] = frozenset()
        self.stopped: str | None = None

    def exception(self, where: str, exc: BaseException) -> None:
        self.exceptions += 1
        if len(self.exception_messages) < MAX_MESSAGES:
            self.exception_messages.append(
                {"where": where, "type": type(exc).__name__, "message": str(exc)[:500], "step": self.steps}
            )

    def bad(self, key: str) -> None:
        self.non_finite += 1
        if len(self.non_finite_keys) < MAX_MESSAGES:
            self.non_finite_keys.append({"key": key, "step": self.steps})


def _finite_array(value: Any) -> bool:
    try:
        return bool(np.isfinite(value).all())
    except TypeError:  # a non-numeric array (strings, objects) has nothing to check
        return True


def _check(counter: _Counter, obs: Any, reward: Any, info: Mapping[str, Any]) -> None:
    """Count the non-finite values of one step (one per key)."""
    if isinstance(obs, np.ndarray):
        if not _finite_array(obs):
            counter.bad("observation")
    elif isinstance(obs, Mapping):
        _check_mapping(counter, obs, "observation.")
    if not _finite_array(reward):
        counter.bad("reward")
    _check_mapping(counter, info, "info.")


def _check_mapping(counter: _Counter, values: Mapping[str, Any], prefix: str) -> None:
    for key, value in values.items():
        if isinstance(value, float):
            if not math.isfinite(value):
                if key in counter.nan_ok and math.isnan(value):
                    counter.documented_nan += 1
                else:
                    counter.bad(f"{prefix}{key}")
        elif isinstance(value, np.ndarray | np.floating):
            if value.dtype.kind in "fc" and not _finite_array(value):
                if key in counter.nan_ok and not np.isinf(value).any():
                    counter.documented_nan += 1
                else:
                    counter.bad(f"{prefix}{key}")
        elif isinstance(value, Mapping):
            _check_mapping(counter, value, f"{prefix}{key}.")
        elif isinstance(value, list | tuple) and value and isinstance(value[0], float | np.floating):
            if not _finite_array(np.asarray(value, dtype=float)):
                counter.bad(f"{prefix}{key}")


def _action_source(
    source: str, env: gym.Env, seed: int, policy_name: str | None, policy_kwargs: dict[str, Any]
) -> Callable[[Any, bool], Any]:
    """A function ``(observation, episode_start) -> action`` for ``source``."""
    space = env.action_space
    if source == "random":
        if not isinstance(space, gym.spaces.Box):
            space.seed(seed)
            return lambda obs, start: space.sample()
        rng = np.random.default_rng(seed)
        low, high = space.low.astype(np.float64), space.high.astype(np.float64)
        dtype = space.dtype
        return lambda obs, start: rng.uniform(low, high).astype(dtype)
    if source == "bang_bang":
        if not isinstance(space, gym.spaces.Box):
            raise BenchError(f"bang_bang needs a Box action space, got {space}")
        rng = np.random.default_rng(seed + 1_000_003)
        low, high = space.low, space.high
        signs = rng.random(space.shape) < 0.5

        def bang_bang(obs: Any, start: bool) -> Any:
            nonlocal signs
            signs = signs ^ (rng.random(space.shape) < BANG_BANG_SWITCH)
            return np.where(signs, high, low).astype(space.dtype)

        return bang_bang
    if source == "reference":
        if policy_name is None:
            raise BenchError("the env has no reference policy (walking or clik)")
        from .. import make_policy

        policy = make_policy(policy_name, env, **policy_kwargs)
        flag_true, flag_false = np.ones(1, dtype=bool), np.zeros(1, dtype=bool)
        state: list[Any] = [None]

        def reference(obs: Any, start: bool) -> Any:
            action, state[0] = policy.predict(obs, state[0], flag_true if start else flag_false, deterministic=True)
            return action

        return reference
    raise BenchError(f"unknown action source {source!r}; expected one of {SOURCES}")


def _soak_source(
    env_id: str,
    source: str,
    *,
    seconds: float | None,
    steps: int | None,
    seed: int,
    env_kwargs: dict[str, Any],
    policy_name: str | None,
    policy_kwargs: dict[str, Any],
    nan_ok: Sequence[str],
    bar: Any,
) -> dict[str, Any]:
    """One (env, source) run: a fresh env driven for ``seconds`` or ``steps``."""
    counter = _Counter()
    counter.nan_ok = frozenset(nan_ok)
    start_time = time.perf_counter()
    env = None
    try:
        env = gym.make(env_id, **env_kwargs)
        act = _action_source(source, env, seed, policy_name, policy_kwargs)
    except Exception as exc:  # noqa: BLE001 - an env or policy that cannot be built is a finding, not a crash
        counter.exception("make", exc)
        counter.stopped = f"could not build the env or the policy: {type(exc).__name__}: {exc}"
        if env is not None:
            env.close()
        return _source_report(counter, source, policy_name, time.perf_counter() - start_time)
    next_seed = seed
    attempts = 0  # steps tried, raised or not: ends a step budget even when every step raises
    reported: float = 0  # progress shown so far: steps, or seconds of a time budget
    time_limit = math.inf if seconds is None else seconds  # [s]; read only without a step budget

    def reset() -> Any:
        nonlocal next_seed
        failures = 0
        while True:
            try:
                obs, info = env.reset(seed=next_seed)
                next_seed += 1
                if isinstance(obs, np.ndarray) and not _finite_array(obs):
                    counter.bad("reset.observation")
                _check_mapping(counter, info, "reset.info.")
                return obs
            except Exception as exc:  # noqa: BLE001
                next_seed += 1
                counter.exception("reset", exc)
                failures += 1
                if failures >= MAX_CONSECUTIVE_FAILURES:
                    return None

    try:
        obs = reset()
        start = True
        while obs is not None:
            if steps is not None:
                if attempts >= steps:
                    break
            elif attempts and attempts % _CHECK_EVERY == 0 and time.perf_counter() - start_time >= time_limit:
                break
            attempts += 1
            try:
                action = act(obs, start)
                if source == "reference" and not _finite_array(action):
                    counter.bad("action")
                obs, reward, terminated, truncated, info = env.step(action)
            except Exception as exc:  # noqa: BLE001 - counted; the run goes on from a reset
                counter.exception("step", exc)
                obs, start = reset(), True
                continue
            counter.steps += 1
            start = False
            _check(counter, obs, reward, info)
            if terminated or truncated:
                counter.episodes += 1
                obs, start = reset(), True
            if bar is not None and attempts % _CHECK_EVERY == 0:
                now = attempts if steps is not None else min(time.perf_counter() - start_time, time_limit)
                bar.update(now - reported)
                reported = now
        if obs is None:
            counter.stopped = f"reset failed {MAX_CONSECUTIVE_FAILURES} times in a row"
    finally:
        env.close()
    elapsed = time.perf_counter() - start_time
    if bar is not None:
        bar.update((steps if steps is not None else time_limit) - reported)
    return _source_report(counter, source, policy_name, elapsed)


def _source_report(counter: _Counter, source: str, policy_name: str | None, elapsed: float) -> dict[str, Any]:
    report = {
        "policy": policy_name if source == "reference" else source,
        "steps": counter.steps,
        "episodes": counter.episodes,
        "seconds": elapsed,
        "steps_per_second": counter.steps / elapsed if elapsed > 0 else 0.0,
        "exceptions": {"count": counter.exceptions, "first": counter.exception_messages},
        "non_finite": {"count": counter.non_finite, "first": counter.non_finite_keys},
        "documented_nan": counter.documented_nan,
    }
    if counter.stopped:
        report["stopped"] = counter.stopped
    return report


def _split(total: float, shares: Mapping[str, float], sources: Sequence[str]) -> dict[str, float]:
    weights = {s: float(shares.get(s, 1.0)) for s in sources}
    norm = sum(weights.values())
    return {s: total * w / norm for s, w in weights.items()}


def run_soak_bench(
    *,
    seconds: float | None = None,
    steps: int | None = None,
    seed: int = 0,
    envs: Sequence[str] = ENV_IDS,
    sources: Sequence[str] = SOURCES,
    shares: Mapping[str, Mapping[str, float]] | None = None,
    env_kwargs: Mapping[str, dict[str, Any]] | None = None,
    policy_kwargs: Mapping[str, dict[str, Any]] | None = None,
    documented_nan: Mapping[str, Sequence[str]] | None = None,
    progress: bool = True,
) -> dict[str, Any]:
    """Soak every env of ``envs`` with every action source; returns the report (see :func:`format_soak_bench`).

    Args:
        seconds: wall time per env, split over the sources by ``shares``; or
        steps: steps per env (attempts: a step that raises counts), split likewise. Give exactly one.
        seed: seed of the action generators and of the first reset (then seed + 1, ...), for every source.
        envs: env ids (any registered Gymnasium id with a Box action space).
        sources: a subset of :data:`SOURCES`; an env without a reference policy reports ``reference`` as
            stopped, with the reason.
        shares: per env id, the weight of each source (default :data:`DEFAULT_SHARES`, else equal).
        env_kwargs: optional ``gym.make`` kwargs per env id; policy_kwargs: reference-policy options per id.
        documented_nan: per env id, ``info`` keys whose NaN is by design (default :data:`DOCUMENTED_NAN`).
        progress: show a progress bar.
    """
    if (seconds is None) == (steps is None):
        raise BenchError("give exactly one of seconds and steps")
    if seconds is not None and not (isinstance(seconds, int | float) and math.isfinite(seconds) and seconds > 0):
        raise BenchError(f"seconds must be a finite number > 0, got {seconds!r}")
    if steps is not None and (isinstance(steps, bool) or not isinstance(steps, int | np.integer) or steps <= 0):
        raise BenchError(f"steps must be an integer > 0, got {steps!r}")
    unknown = [s for s in sources if s not in SOURCES]
    if unknown or not sources:
        raise BenchError(f"sources must be a non-empty subset of {SOURCES}, got {tuple(sources)}")
    shares = DEFAULT_SHARES if shares is None else shares
    documented_nan = DOCUMENTED_NAN if documented_nan is None else documented_nan
    env_kwargs = env_kwargs or {}
    policy_kwargs = policy_kwargs or {}
    if seconds is not None:
        budget: float = float(seconds)
    else:
        assert steps is not None  # exactly one of the two, checked above
        budget = int(steps)
    plan = []
    for env_id in envs:
        split = _split(budget, shares.get(env_id, {}), sources)
        if steps is not None:  # whole steps that add up to the budget (the rounding remainder to the first source)
            split = {s: max(1, int(v)) for s, v in split.items()}
            split[sources[0]] += max(0, int(steps) - sum(split.values()))
        for source in sources:
            plan.append((env_id, source, split[source]))
    total = sum(p[2] for p in plan)
    bar = tqdm(
        total=total,
        desc="bench soak",
        unit="step" if steps is not None else "s",
        disable=not progress,
        dynamic_ncols=True,
    )
    report_envs: dict[str, Any] = {}
    try:
        for env_id, source, amount in plan:
            if env_id not in report_envs:
                policy_name = None
                if "reference" in sources:
                    try:
                        probe = gym.make(env_id, **env_kwargs.get(env_id, {}))
                        try:
                            policy_name = _reference_name(probe)
                        finally:
                            probe.close()
                    except Exception:  # noqa: BLE001 - the sources report the failure to build
                        policy_name = None
                report_envs[env_id] = {"reference_policy": policy_name, "sources": {}}
            bar.set_postfix_str(f"{env_id.split('/')[-1]} {source}")
            report_envs[env_id]["sources"][source] = _soak_source(
                env_id,
                source,
                seconds=None if steps is not None else amount,
                steps=int(amount) if steps is not None else None,  # an int already: whole steps
                seed=seed,
                env_kwargs=env_kwargs.get(env_id, {}),
                policy_name=report_envs[env_id]["reference_policy"],
                policy_kwargs=policy_kwargs.get(env_id, {}),
                nan_ok=documented_nan.get(env_id, ()),
                bar=bar if progress else None,
            )
    finally:
        bar.close()
    for entry in report_envs.values():
        entry.update(_totals(entry["sources"].values()))
    totals = _totals([s for e in report_envs.values() for s in e["sources"].values()])
    report = {
        "benchmark": "soak",
        "seed": seed,
        "budget": {"seconds_per_env": seconds} if seconds is not None else {"steps_per_env": steps},
        "sources": list(sources),
        "bang_bang_switch_probability": BANG_BANG_SWITCH,
        "shares": {e: _split(1.0, shares.get(e, {}), sources) for e in envs},
        "documented_nan_keys": {e: list(documented_nan.get(e, ())) for e in envs},
        "machine": machine_info(),
        "envs": report_envs,
        "totals": totals,
    }
    report["ok"] = soak_ok(report)
    return report


def _totals(runs: Any) -> dict[str, Any]:
    runs = list(runs)
    steps = sum(r["steps"] for r in runs)
    seconds = sum(r["seconds"] for r in runs)
    return {
        "steps": steps,
        "episodes": sum(r["episodes"] for r in runs),
        "seconds": seconds,
        "steps_per_second": steps / seconds if seconds > 0 else 0.0,
        "exceptions": sum(r["exceptions"]["count"] for r in runs),
        "non_finite": sum(r["non_finite"]["count"] for r in runs),
        "documented_nan": sum(r["documented_nan"] for r in runs),
        "stopped": sum(1 for r in runs if "stopped" in r),
    }


def soak_ok(report: Mapping[str, Any]) -> bool:
    """True when no source raised, saw a non-finite value or was stopped."""
    t = report["totals"]
    return t["exceptions"] == 0 and t["non_finite"] == 0 and t["stopped"] == 0


def format_soak_bench(report: Mapping[str, Any]) -> str:
    """A plain-text table: per env and source, steps, episodes, steps/s, exceptions and non-finite values."""
    header = ("env", "source", "steps", "episodes", "steps/s", "exceptions", "non-finite")
    rows = [header]
    notes = []
    for env_id, entry in report["envs"].items():
        name = env_id.split("/")[-1]
        for source, r in entry["sources"].items():
            label = source if source != "reference" else f"reference ({r['policy']})"
            rows.append(
                (
                    name,
                    label,
                    f"{r['steps']:,}",
                    f"{r['episodes']:,}",
                    f"{r['steps_per_second']:,.0f}",
                    str(r["exceptions"]["count"]),
                    str(r["non_finite"]["count"]),
                )
            )
            for e in r["exceptions"]["first"]:
                notes.append(f"  {name} {source}: {e['where']} at step {e['step']}: {e['type']}: {e['message']}")
            for k in r["non_finite"]["first"]:
                notes.append(f"  {name} {source}: non-finite {k['key']} at step {k['step']}")
            if "stopped" in r:
                notes.append(f"  {name} {source}: stopped: {r['stopped']}")
        rows.append(
            (
                name,
                "all",
                f"{entry['steps']:,}",
                f"{entry['episodes']:,}",
                f"{entry['steps_per_second']:,.0f}",
                str(entry["exceptions"]),
                str(entry["non_finite"]),
            )
        )
    t = report["totals"]
    rows.append(
        (
            "total",
            "",
            f"{t['steps']:,}",
            f"{t['episodes']:,}",
            f"{t['steps_per_second']:,.0f}",
            str(t["exceptions"]),
            str(t["non_finite"]),
        )
    )
    widths = [max(len(r[i]) for r in rows) for i in range(len(header))]
    lines = [
        "  ".join(c.rjust(w) if i >= 2 else c.ljust(w) for i, (c, w) in enumerate(zip(r, widths, strict=False)))
        for r in rows
    ]
    lines.insert(1, "-" * len(lines[0]))
    verdict = "OK: no exception, no non-finite value" if report["ok"] else "FAILED: see below"
    if t.get("documented_nan"):
        verdict += f" ({t['documented_nan']:,} documented NaN values, e.g. BipedWalk's cop/zmp without contact)"
    return "\n".join([*lines, verdict, *notes])
