"""``redundancy-gym bench startup``: what a new process pays before its first step, with an empty numba cache
(cold: a first run, a fresh machine, a new cluster worker) and with the cache that run filled (warm).

Every probe runs in its own fresh Python process (``sys.executable``): first with ``NUMBA_CACHE_DIR`` set to a
new empty folder, then ``rounds`` times again with the same folder; the warm result is the run with the median
``process_s`` (a single warm run varies by about 0.1 s, as much as a target's margin), with every run's
``process_s`` beside it (``process_s_runs``). ``process_s`` is the parent's wall clock around the process
(interpreter start, imports, everything a user waits for); inside, each probe times its stages with
``time.perf_counter`` and reads numba's time compiling kernels (``compile_s``) and compiling or loading them from
the cache (``kernels_s``, :data:`~redundancy_gym.eval.compile_clock.COMPILE_CLOCK`).

The probes: ``import`` (``import redundancy_gym``), ``list`` (``redundancy-gym list``), ``quick_start`` (the README's
quick start: PlanarReach, ``clik``, one episode), every registered env id (``gym.make``, ``reset``, the first
``step`` of a zero action) and every analytic reference policy on the first env it supports (its construction and
first ``predict``). The targets (:data:`STARTUP_TARGETS`) are absolute wall times on the machine the JSON records.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ..eval.machine import machine_info
from .exceptions import BenchError
from .timing import check_rounds

__all__ = [
    "STARTUP_TARGETS",
    "StartupProbe",
    "format_startup_bench",
    "run_startup_bench",
    "startup_probes",
]

STARTUP_TARGETS: dict[str, tuple[str, str, float]] = {
    "quick_start_cold": ("quick_start", "cold", 8.0),
    "quick_start_warm": ("quick_start", "warm", 1.5),
    "list_cold": ("list", "cold", 2.0),
}
"""target name -> (probe, cold or warm, the largest process wall time [s] it meets)."""

_HEADER = """\
import json, time
_t0 = time.perf_counter()
import gymnasium as gym
import numpy as np
import redundancy_gym
from redundancy_gym.eval.compile_clock import COMPILE_CLOCK
_t = {"import_s": time.perf_counter() - _t0}
COMPILE_CLOCK.install()
def _lap(name, start):
    now = time.perf_counter()
    _t[name] = now - start
    return now
"""
_FOOTER = """
_t["compile_s"] = COMPILE_CLOCK.compiling_seconds
_t["kernels_s"] = COMPILE_CLOCK.seconds
_t["total_s"] = time.perf_counter() - _t0
print("STARTUP " + json.dumps(_t))
"""


@dataclass(frozen=True)
class StartupProbe:
    """One probe: its name (the ``--envs`` choice and the JSON key), what it does, and its Python source (printing
    one ``STARTUP {json}`` line of stage times [s])."""

    name: str
    summary: str
    code: str


def _env_probe(env_id: str) -> StartupProbe:
    code = f"""{_HEADER}
s = time.perf_counter()
env = gym.make({env_id!r})
s = _lap("make_s", s)
env.reset(seed=0)
s = _lap("reset_s", s)
env.step(np.zeros(env.action_space.shape, dtype=env.action_space.dtype))
_lap("first_step_s", s)
{_FOOTER}"""
    return StartupProbe(env_id.split("/")[-1], f"gym.make, reset and the first step of {env_id}", code)


def _policy_probe(policy: str, env_id: str) -> StartupProbe:
    code = f"""{_HEADER}
env = gym.make({env_id!r})
obs, _ = env.reset(seed=0)
s = time.perf_counter()
policy = redundancy_gym.make_policy({policy!r}, env)
s = _lap("policy_s", s)
action, _ = policy.predict(obs, deterministic=True)
s = _lap("first_predict_s", s)
env.step(action)
_lap("first_step_s", s)
{_FOOTER}"""
    return StartupProbe(f"policy:{policy}", f"make_policy({policy!r}) on {env_id} and its first predict", code)


_QUICK_START = StartupProbe(
    "quick_start",
    "the README's quick start: PlanarReach-v0, clik, one episode",
    f"""{_HEADER}
s = time.perf_counter()
env = gym.make("redundancy_gym/PlanarReach-v0")
s = _lap("make_s", s)
policy = redundancy_gym.make_policy("clik", env)
s = _lap("policy_s", s)
obs, info = env.reset(seed=0)
s = _lap("reset_s", s)
action, _ = policy.predict(obs, deterministic=True)
obs, reward, terminated, truncated, info = env.step(action)
s = _lap("first_step_s", s)
while not (terminated or truncated):
    action, _ = policy.predict(obs, deterministic=True)
    obs, reward, terminated, truncated, info = env.step(action)
_lap("rest_of_episode_s", s)
{_FOOTER}""",
)

_IMPORT = StartupProbe(
    "import",
    "import redundancy_gym",
    """import json, time
_t0 = time.perf_counter()
import redundancy_gym
print("STARTUP " + json.dumps({"import_s": time.perf_counter() - _t0, "total_s": time.perf_counter() - _t0}))
""",
)

_LIST = StartupProbe(
    "list",
    "redundancy-gym list",
    """import contextlib, io, json, time
_t0 = time.perf_counter()
from redundancy_gym.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    code = main(["list"])
print("STARTUP " + json.dumps({"exit_code": code, "total_s": time.perf_counter() - _t0}))
""",
)


def startup_probes(names: Sequence[str] | None = None, quick: bool = False) -> list[StartupProbe]:
    """The probes by name (default: all; ``quick``: ``import`` and PlanarReach-v0's first step); unknown names
    raise :class:`BenchError` naming the valid ones."""
    from ..policies import GENERIC_POLICIES, registered, supported_env_ids
    from ..registration import ENV_IDS

    everything = [_IMPORT, _LIST, _QUICK_START, *(_env_probe(env_id) for env_id in ENV_IDS)]
    for entry in registered("policy"):
        if entry.name in GENERIC_POLICIES:
            continue
        supported = supported_env_ids(entry.name)
        if supported:
            everything.append(_policy_probe(entry.name, supported[0]))
    if names is None:
        return [p for p in everything if p.name in ("import", "PlanarReach-v0")] if quick else everything
    by_name = {p.name: p for p in everything}
    unknown = [n for n in names if n not in by_name]
    if unknown:
        raise BenchError(f"unknown startup probe {', '.join(unknown)}; valid: {', '.join(by_name)}")
    return [by_name[n] for n in names]


def _run(probe: StartupProbe, cache: str, timeout: float, extra_env: dict[str, str] | None = None) -> dict[str, Any]:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache, "PYTHONHASHSEED": "0", **(extra_env or {})}
    start = time.perf_counter()
    try:
        done = subprocess.run(
            [sys.executable, "-c", probe.code], env=env, capture_output=True, text=True, timeout=timeout, check=False
        )
    except subprocess.TimeoutExpired:
        return {"error": f"timed out after {timeout:g} s"}
    wall = time.perf_counter() - start
    lines = [line for line in done.stdout.splitlines() if line.startswith("STARTUP ")]
    if done.returncode != 0 or not lines:
        return {"error": f"exit {done.returncode}: {done.stderr.strip()[-500:]}"}
    stages: dict[str, Any] = json.loads(lines[-1][len("STARTUP ") :])
    return {"process_s": wall, **stages}


def _median_run(runs: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The run with the median ``process_s`` (the lower one of an even count), every run's ``process_s`` beside
    it; the first failed run if any failed."""
    failed = [run for run in runs if "error" in run]
    if failed:
        return failed[0]
    ordered = sorted(runs, key=lambda run: run["process_s"])
    return {**ordered[(len(ordered) - 1) // 2], "process_s_runs": [run["process_s"] for run in runs]}


def run_startup_bench(
    *,
    names: Sequence[str] | None = None,
    quick: bool = False,
    rounds: int = 5,
    timeout: float = 1800.0,
    progress: bool = True,
) -> dict[str, Any]:
    """Every probe cold, then warm ``rounds`` times (module docstring): ``{"machine", "rounds", "probes": {name:
    {"summary", "cold", "warm"}}, "targets": {name: {"probe", "run", "limit_s", "measured_s", "met"}}}``.

    Raises:
        BenchError: ``rounds < 1`` or an unknown probe name.
    """
    check_rounds(rounds)
    probes = startup_probes(names, quick)
    from tqdm.auto import tqdm

    from ..kernel_pack import seeding_state

    pack = seeding_state()
    results: dict[str, Any] = {}
    for probe in tqdm(probes, desc="bench startup", unit="probe", disable=not progress):
        with tempfile.TemporaryDirectory(prefix="numba-cold-") as cache:
            cold = _run(probe, cache, timeout)
            warm = _median_run([_run(probe, cache, timeout) for _ in range(int(rounds))])
        results[probe.name] = {"summary": probe.summary, "cold": cold, "warm": warm}
        if pack.pack is not None:  # the same cold process compiling every kernel, as without a pack
            with tempfile.TemporaryDirectory(prefix="numba-cold-") as cache, tempfile.TemporaryDirectory() as none:
                results[probe.name]["cold_unpacked"] = _run(probe, cache, timeout, {"REDUNDANCY_GYM_KERNEL_PACK": none})
    targets = {}
    for name, (probe_name, run, limit) in STARTUP_TARGETS.items():
        measured = results.get(probe_name, {}).get(run, {}).get("process_s")
        targets[name] = {
            "probe": probe_name,
            "run": run,
            "limit_s": limit,
            "measured_s": measured,
            "met": None if measured is None else bool(measured <= limit),
        }
    return {
        "machine": machine_info(),
        "method": "each probe in a fresh process: cold with an empty NUMBA_CACHE_DIR, then warm with the cache "
        "that run filled, the run with the median of `rounds` warm runs; process_s is the wall time around the "
        "process; where a kernel pack fits (kernel_pack), cold copies its kernels into the empty cache and "
        "cold_unpacked is a cold run with the pack switched off",
        "kernel_pack": {"folder": None if pack.pack is None else str(pack.pack), "reason": pack.reason},
        "rounds": rounds,
        "probes": results,
        "targets": targets,
    }


def format_startup_bench(report: dict[str, Any]) -> str:
    """The report as a text table: per probe the process wall time cold and warm, the compile time and first step
    cold; then the targets."""

    def cell(run: dict[str, Any], key: str) -> str:
        if "error" in run:
            return "error"
        value = run.get(key)
        return "-" if value is None else f"{value:.2f}"

    unpacked = any("cold_unpacked" in r for r in report["probes"].values())
    rows: list[tuple[str, ...]] = [
        ("probe", "cold process [s]", "warm process [s]", "cold compile [s]", "cold first step [s]")
    ]
    if unpacked:
        rows[0] += ("cold without the pack [s]",)
    for name, result in report["probes"].items():
        cold, warm = result["cold"], result["warm"]
        first = "first_predict_s" if "first_predict_s" in cold else "first_step_s"
        row = (name, cell(cold, "process_s"), cell(warm, "process_s"), cell(cold, "compile_s"), cell(cold, first))
        rows.append(row + ((cell(result.get("cold_unpacked", {}), "process_s"),) if unpacked else ()))
    widths = [max(len(r[k]) for r in rows) for k in range(len(rows[0]))]
    lines = ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in rows]
    errors = [
        f"{n} {run}: {r[run]['error']}"
        for n, r in report["probes"].items()
        for run in ("cold", "warm")
        if "error" in r[run]
    ]
    pack = report.get("kernel_pack", {})
    lines += ["", f"kernel pack: {pack.get('folder') or 'none (' + str(pack.get('reason')) + ')'}"]
    lines += [f"error: {e}" for e in errors]
    for name, t in report["targets"].items():
        measured = "not measured" if t["measured_s"] is None else f"{t['measured_s']:.2f} s"
        verdict = "" if t["met"] is None else (" met" if t["met"] else " NOT met")
        lines.append(f"target {name}: <= {t['limit_s']:g} s, {measured}{verdict}")
    return "\n".join(lines)
