"""``redundancy-gym bench envs``: env steps per second with a zero policy, ours against Gymnasium's MuJoCo envs.

Every env of ours and the peers (Gymnasium's ``Pusher-v5`` and ``Humanoid-v5``) is made with ``gym.make`` (so
the same wrappers apply) and stepped with the zero action (for BipedWalk-v0: stand in the nominal posture),
resetting when an episode ends (resets count: they are part of what a training loop pays). All of them are open
at once and stepped in alternating rounds (:func:`~redundancy_gym.bench.timing.alternating_rounds`: one
warm-up round, then ``rounds`` rounds in which every env runs one window of ``seconds / rounds``, in the list's
order and reversed every other round), so that a slow moment of the machine hits ours and the peer alike. An env's
``steps_per_second`` is the median over the rounds; a ratio ``<ours>_vs_<peer>`` is the median over the rounds of
the two rates measured in the same round (``ratio_rounds``: its median, min, max and spread ``(max - min) /
median``). ``agri_vs_pusher`` is AgriReach-v0 over Pusher-v5, ``biped_vs_humanoid`` BipedWalk-v0 over
Humanoid-v5, ``biped_obstacles_vs_humanoid`` BipedObstacles-v0 (a random course per reset) and
``biped_terrain_vs_humanoid`` BipedTerrain-v0 (random terrain, its height scan in every observation) over Humanoid-v5
(per env step; ``sim_seconds_per_second`` also compares simulated time, since the two step
different periods: 4 ms and 15 ms). Variants of our envs (by default
AgriReach with ``prune=False``, the whole crop row in the scene and the collision model) are measured in the same
rounds, and ``agri_prune_speedup`` is the pruned rate over the unpruned one. Every wrapped id
(``<Env>-<Wrapper>-v0``) is measured against its raw env in alternating rounds too (``wrapped``: the ratio
wrapped / raw, median and range over the rounds): what an action wrapper's controller costs per step.

**Env step against its physics.** Every env (ours and the peers) is also timed as bare physics: ``mujoco.mj_step``
with ``nstep=frame_skip`` on the env's own model and data, in a window of its own in the same alternating rounds
(the label ``<id> physics``). ``physics`` in the report gives, per env, ``env_step_us`` and ``physics_us`` (medians
over the rounds [us]), ``env_vs_physics`` (the median of the per-round ratio env step / physics step) and
``overhead_us`` (the median of the per-round difference [us]: what the env spends outside MuJoCo, resets
included). For each of our envs ``bound_us`` is the larger of 1.5 x its physics and its physics plus Pusher-v5's
overhead measured in the same run, and ``within_bound`` whether its env step is at most that. For every wrapped id,
``glue_us`` is what the wrapper adds beyond its controller: the wrapped step less the steps of the env inside it
(each timed in the window) less the wrapper's own ``controller_time_us``, per round, by its median [us]. The inner
env's steps are timed on the wrapped episode itself: the raw env's zero-action episode is another trajectory (an
arm at rest among the plants computes fewer near pairs than one reaching), so its step is not the one the wrapper
calls. The wrapped ids' windows are timed without their resets (a wrapped episode ends at other times than the raw
env's, and a reset rebuilds the controller's plan): ``step_us``, ``raw_step_us``, the ratio and ``glue_us`` are
per step.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from functools import partial
from typing import Any, Protocol, cast

import gymnasium as gym
import mujoco
import numpy as np
from gymnasium import spaces
from tqdm.auto import tqdm

from ..eval.evaluate import controller_clock
from ..eval.machine import finish_machine_info, machine_info
from ..registration import BASE_ENV_IDS, WRAPPED_ENV_IDS
from .exceptions import BenchError
from .timing import CLOCK, alternating_rounds, check_rounds

__all__ = ["PEERS", "VARIANTS", "format_envs_bench", "run_envs_bench"]

PEERS = ("Pusher-v5", "Ant-v5", "Humanoid-v5")
OVERHEAD_PEER = "Pusher-v5"
"""The peer whose overhead (env step - physics step) bounds ours in ``physics``: Gymnasium's leanest MuJoCo env."""
PHYSICS_FACTOR = 1.5
"""``bound_us`` is at least this times the env's bare physics step."""
VARIANTS = {
    "redundancy_gym/AgriReach-v0 (prune=False)": ("redundancy_gym/AgriReach-v0", {"prune": False}, "agri_prune_speedup")
}
"""label -> (env id, gym.make kwargs, name of the ratio base rate / variant rate)."""
_SHORT = {
    "redundancy_gym/PlanarReach-v0": "planar",
    "redundancy_gym/AgriReach-v0": "agri",
    "redundancy_gym/BipedWalk-v0": "biped",
    "redundancy_gym/BipedObstacles-v0": "biped_obstacles",
    "redundancy_gym/BipedTerrain-v0": "biped_terrain",
    "Pusher-v5": "pusher",
    "Ant-v5": "ant",
    "Humanoid-v5": "humanoid",
}


class _ControlPeriod(Protocol):
    """What :class:`_Stepper` reads of a base env beside gymnasium's ``Env``: every env benchmarked here (ours and
    gymnasium's MuJoCo envs) has a control period."""

    @property
    def dt(self) -> float:
        """Seconds of simulated time per step [s]."""


class _Stepper:
    """One env stepped with the zero action in timed windows, resetting when an episode ends; keeps each window's
    steps, resets and duration."""

    def __init__(self, env_id: str, seed: int, env_kwargs: dict[str, Any] | None = None) -> None:
        self.env = gym.make(env_id, **(env_kwargs or {}))
        self.env.reset(seed=seed)
        space = self.env.action_space
        assert isinstance(space, spaces.Box)  # every env benchmarked here takes a Box action
        self.action = np.zeros(space.shape, dtype=space.dtype)
        base = self.env.unwrapped
        self.dt = float(cast(_ControlPeriod, base).dt)
        self._physics = (base.model, base.data, int(base.frame_skip))  # type: ignore[attr-defined]
        self._clock = controller_clock(self.env)
        self.windows: list[tuple[int, int, float]] = []
        self.controller_us: list[float] = []
        self.step_only_s: list[float] = []
        self.glue_us: list[float] = []
        self._inner_ns = 0
        if self._clock is not None:
            self._time_inner_steps(self._clock.env)
        self._run(0.0, warmup=50)  # compiled kernels and caches
        self.env.reset(seed=seed)

    def window(self, seconds: float) -> float:
        """One window of about ``seconds`` [s]; returns its time per step [s] (resets included)."""
        steps, resets, elapsed = self._run(seconds)
        self.windows.append((steps, resets, elapsed))
        return elapsed / steps

    def _time_inner_steps(self, inner: gym.Env) -> None:
        """Time every ``step`` of the env inside the action wrapper (on this instance only), so that a window
        knows its wrapper's own time: its step less the inner env's steps less its controller."""
        step = inner.step

        def timed(action: Any) -> Any:
            began = time.perf_counter_ns()
            result = step(action)
            self._inner_ns += time.perf_counter_ns() - began
            return result

        inner.step = timed  # type: ignore[method-assign]

    def step_window(self, seconds: float) -> float:
        """:meth:`window`, returning its time per step without the resets [s] (each reset timed by the wall clock
        and taken out): the wrapped ids' comparison, whose episodes end at other times than the raw env's."""
        self.window(seconds)
        return self.step_only_s[-1]

    def physics_window(self, seconds: float) -> float:
        """One window of about ``seconds`` [s] of bare physics, ``mj_step`` with ``nstep=frame_skip`` on the env's
        own model and data; returns its time per step [s]."""
        model, data, substeps = self._physics
        steps = 0
        cpu = time.process_time()
        start = time.perf_counter()
        while True:
            for _ in range(16):
                mujoco.mj_step(model, data, nstep=substeps)
            steps += 16
            if time.perf_counter() - start >= seconds:
                break
        wall = time.perf_counter() - start
        return min(wall, time.process_time() - cpu) / steps

    def totals(self, skip: int) -> tuple[int, int, float]:
        """Steps, resets and seconds of the windows after the first ``skip`` (the warm-up)."""
        kept = self.windows[skip:]
        return sum(w[0] for w in kept), sum(w[1] for w in kept), sum(w[2] for w in kept)

    def _run(self, seconds: float, warmup: int = 0) -> tuple[int, int, float]:
        """Steps, resets and time [s] (the smaller of wall-clock and process CPU time, as
        :func:`~redundancy_gym.bench.timing.timed_call`) of one window of about ``seconds`` wall time."""
        steps = resets = 0
        clock = self._clock
        controller = resetting = 0.0
        self._inner_ns = 0
        cpu = time.process_time()
        start = time.perf_counter()
        while True:
            _, _, terminated, truncated, _ = self.env.step(self.action)
            steps += 1
            if clock is not None:
                controller += clock.controller_time_us
            if terminated or truncated:
                began = time.perf_counter()
                self.env.reset()
                resetting += time.perf_counter() - began
                resets += 1
            if warmup and steps >= warmup:
                break
            if not warmup and steps % 16 == 0 and time.perf_counter() - start >= seconds:
                break
        wall = time.perf_counter() - start
        elapsed = min(wall, time.process_time() - cpu)
        if not warmup:
            self.controller_us.append(controller / steps)
            self.step_only_s.append(max(elapsed - resetting, 1e-9) / steps)
            if clock is not None:
                self.glue_us.append(self.step_only_s[-1] * 1e6 - self._inner_ns * 1e-3 / steps - controller / steps)
        return steps, resets, elapsed

    def close(self) -> None:
        """Close the env."""
        self.env.close()


def wrapped_rates(
    wrapped: Sequence[str], *, seconds: float, rounds: int, seed: int, progress: bool = False
) -> dict[str, dict[str, Any]]:
    """Steps/s of every wrapped id against its raw env, measured in alternating windows (raw, wrapped / wrapped,
    raw / ...; a warm-up pair, then ``rounds`` pairs of ``seconds / rounds`` each): the ratio wrapped / raw per
    round, its median, range and spread, so that a slow moment of the machine hits both alike."""
    out = {}
    for wrapped_id in tqdm(wrapped, desc="bench envs (wrapped)", disable=not progress):
        raw_id = gym.spec(wrapped_id).kwargs["env_id"]
        raw, inner = _Stepper(raw_id, seed), _Stepper(wrapped_id, seed)
        try:
            timed = alternating_rounds(
                # partial binds this iteration's steppers (a closure would read the loop's latest)
                {
                    "raw": partial(raw.step_window, seconds / rounds),
                    "wrapped": partial(inner.step_window, seconds / rounds),
                },
                rounds=rounds,
            )
        finally:
            raw.close()
            inner.close()
        stats = timed.ratio("raw", "wrapped")  # time per step raw / wrapped = rate wrapped / raw
        skip = timed.warmup
        glue = inner.glue_us[skip:]
        out[wrapped_id] = {
            "raw": raw_id,
            "raw_steps_per_second": 1.0 / timed.median("raw"),
            "steps_per_second": 1.0 / timed.median("wrapped"),
            "ratio": stats.median,
            "ratio_min": stats.min,
            "ratio_max": stats.max,
            "ratio_spread": stats.spread,
            "step_us": timed.median("wrapped") * 1e6,
            "raw_step_us": timed.median("raw") * 1e6,
            "controller_time_us": float(np.median(inner.controller_us[skip:])),
            "glue_us": float(np.median(glue)),
            "glue_us_min": float(np.min(glue)),
            "glue_us_max": float(np.max(glue)),
            "glue_us_rounds": glue,
            "rounds": rounds,
        }
    return out


def run_envs_bench(
    *,
    seconds: float = 3.0,
    seed: int = 0,
    envs: Sequence[str] = BASE_ENV_IDS,
    peers: Sequence[str] = PEERS,
    env_kwargs: dict[str, dict[str, Any]] | None = None,
    variants: dict[str, tuple[str, dict[str, Any], str]] | None = None,
    wrapped: Sequence[str] = WRAPPED_ENV_IDS,
    rounds: int = 7,
    progress: bool = True,
) -> dict[str, Any]:
    """Steps per second of ``envs``, ``peers`` and ``variants`` (zero policy, ``seconds`` each, in ``rounds``
    alternating windows), and of every ``wrapped`` id against its raw env (:func:`wrapped_rates`); returns the report.

    Args:
        seconds: wall time per env over all rounds [s] (per wrapped id and per its raw env too).
        seed: reset seed.
        envs: our env ids; peers: Gymnasium ids measured in the same rounds.
        env_kwargs: optional ``gym.make`` kwargs per id.
        variants: extra measurements ``label -> (id, kwargs, ratio name)`` (default :data:`VARIANTS`, those
            whose id is in ``envs``); the ratio is the id's rate over the variant's.
        wrapped: wrapped env ids (``<Env>-<Wrapper>-v0``) measured against their raw env.
        rounds: alternating rounds (one window per env each) after a warm-up round.
        progress: show a progress bar.

    Raises:
        BenchError: ``seconds <= 0`` or ``rounds < 1``.
    """
    if not np.isfinite(seconds) or seconds <= 0:
        raise BenchError(f"seconds must be finite and > 0, got {seconds}")
    check_rounds(rounds)
    machine = machine_info()
    env_kwargs = env_kwargs or {}
    variants = {k: v for k, v in (VARIANTS if variants is None else variants).items() if v[0] in envs}
    runs = [(i, i, env_kwargs.get(i, {})) for i in (*envs, *peers)]
    runs += [(label, i, {**env_kwargs.get(i, {}), **kw}) for label, (i, kw, _) in variants.items()]
    steppers: dict[str, _Stepper] = {}
    try:
        for label, env_id, kwargs in runs:
            steppers[label] = _Stepper(env_id, seed, kwargs)
        window = seconds / rounds
        samplers = {}
        for label, stepper in steppers.items():
            samplers[label] = partial(stepper.window, window)
            samplers[f"{label} physics"] = partial(stepper.physics_window, window)
        timed = alternating_rounds(
            samplers,
            rounds=rounds,
            progress=progress,
            desc="bench envs rounds",
        )
    finally:
        for stepper in steppers.values():
            stepper.close()
    rates: dict[str, dict[str, float]] = {}
    for label, stepper in steppers.items():
        steps, resets, elapsed = stepper.totals(timed.warmup)
        rate = 1.0 / timed.median(label)
        rates[label] = {
            "steps_per_second": rate,
            "steps": steps,
            "resets": resets,
            "seconds": elapsed,
            "control_period": stepper.dt,
            "sim_seconds_per_second": rate * stepper.dt,
        }
    stats = {}
    for ours in envs:
        for peer in peers:
            stats[f"{_SHORT.get(ours, ours)}_vs_{_SHORT.get(peer, peer)}"] = timed.ratio(peer, ours)
    for label, (env_id, _, name) in variants.items():
        stats[name] = timed.ratio(label, env_id)
    ratios = {name: s.median for name, s in stats.items()}
    physics = _physics_report(timed, steppers, envs, peers)
    wrapped_report = wrapped_rates(wrapped, seconds=seconds, rounds=rounds, seed=seed, progress=progress)
    return {
        "benchmark": "envs",
        "seed": seed,
        "seconds_per_env": seconds,
        "policy": "zero",
        "timing": {
            "rounds": rounds,
            "warmup": timed.warmup,
            "window_s": window,
            "clock": CLOCK,
            "orders": timed.orders,
        },
        "machine": finish_machine_info(machine),
        "envs": rates,
        "physics": physics,
        "ratios": ratios,
        "ratio_rounds": {name: s.to_json() for name, s in stats.items()},
        "wrapped": wrapped_report,
        **ratios,
    }


def _physics_report(
    timed: Any, steppers: dict[str, _Stepper], envs: Sequence[str], peers: Sequence[str]
) -> dict[str, dict[str, Any]]:
    """Per env: its step and its bare physics step [us], their ratio and difference per round by the median, and
    for ours the bound of the module's docstring (when :data:`OVERHEAD_PEER` was measured)."""
    out: dict[str, dict[str, Any]] = {}
    for label, stepper in steppers.items():
        env_s = np.asarray(timed.samples[label])
        physics_s = np.asarray(timed.samples[f"{label} physics"])
        ratio = timed.ratio(label, f"{label} physics")
        out[label] = {
            "substeps": stepper._physics[2],
            "env_step_us": float(np.median(env_s)) * 1e6,
            "physics_us": float(np.median(physics_s)) * 1e6,
            "env_vs_physics": ratio.median,
            "env_vs_physics_rounds": ratio.to_json(),
            "overhead_us": float(np.median(env_s - physics_s)) * 1e6,
        }
    peer = out.get(OVERHEAD_PEER)
    if peer is not None:
        for label in envs:
            row = out[label]
            row["bound_us"] = max(PHYSICS_FACTOR * row["physics_us"], row["physics_us"] + peer["overhead_us"])
            row["within_bound"] = bool(row["env_step_us"] <= row["bound_us"])
    return out


def format_envs_bench(report: dict[str, Any]) -> str:
    """A plain-text table of steps/s and ratios."""
    lines = ["env | steps/s | resets", "-" * 40]
    for env_id, r in report["envs"].items():
        lines.append(f"{env_id} | {r['steps_per_second']:.0f} | {r['resets']}")
    spread = report.get("ratio_rounds", {})
    lines += [
        f"{name} = {value:.2f}"
        + (f"  (rounds {spread[name]['min']:.2f}-{spread[name]['max']:.2f})" if name in spread else "")
        for name, value in report["ratios"].items()
    ]
    if report.get("physics"):
        lines += ["", "env | step [us] | physics [us] | env / physics | overhead [us] | bound [us]", "-" * 72]
        for env_id, r in report["physics"].items():
            bound = f"{r['bound_us']:.1f} ({'met' if r['within_bound'] else 'NOT met'})" if "bound_us" in r else "-"
            lines.append(
                f"{env_id} | {r['env_step_us']:.1f} | {r['physics_us']:.1f} ({r['substeps']} substeps) | "
                f"{r['env_vs_physics']:.2f} | {r['overhead_us']:.1f} | {bound}"
            )
    if report.get("wrapped"):
        lines += [
            "",
            "wrapped env | steps/s | raw steps/s | wrapped / raw (median, range) | controller [us] | glue [us]",
            "-" * 96,
        ]
        for env_id, r in report["wrapped"].items():
            lines.append(
                f"{env_id} | {r['steps_per_second']:.0f} | {r['raw_steps_per_second']:.0f} | "
                f"{r['ratio']:.2f} ({r['ratio_min']:.2f}-{r['ratio_max']:.2f}) | {r['controller_time_us']:.1f} | "
                f"{r['glue_us']:.1f}"
            )
    return "\n".join(lines)
