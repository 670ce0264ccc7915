"""The table of benchmarks that ``redundancy-gym bench`` reads: name -> what it measures, the options it takes and
how it runs (prints its table, writes its JSON and figures).

A new benchmark is one file in this package and one :class:`Bench` row in :data:`BENCHES`; the CLI builds its
choices, its help and its option checks from the rows.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TypedDict

from ..eval.json_writer import write_json
from .exceptions import BenchError

__all__ = ["BENCHES", "OPTIONS", "Bench", "BenchArgs", "RoundsKwargs", "bench", "check_bench_args", "run_bench"]

OPTIONS: tuple[str, ...] = ("rounds", "seconds", "steps", "trials", "episodes", "workers", "ray", "envs")
"""The options that only some benches take (``--seed``, ``--quick``, ``--json`` and ``--no-progress`` apply to all)."""


class RoundsKwargs(TypedDict, total=False):
    """The ``rounds`` keyword of a bench's run function, or nothing (the bench's default); typed so that a call
    unpacking it passes an int to ``rounds`` and nothing else."""

    rounds: int


@dataclass(frozen=True)
class BenchArgs:
    """What ``redundancy-gym bench`` passes to a bench; ``None`` means the bench's default."""

    json_path: str
    seed: int | None = None
    quick: bool = False
    progress: bool = True
    rounds: int | None = None
    seconds: float | None = None
    steps: int | None = None
    trials: int | None = None
    episodes: int | None = None
    workers: int | None = None
    ray: str | None = None
    envs: tuple[str, ...] | None = None

    def seed_or(self, default: int = 0) -> int:
        """``--seed``, or ``default``."""
        return default if self.seed is None else self.seed

    def rounds_kwargs(self) -> RoundsKwargs:
        """``{"rounds": N}`` from ``--rounds``, or 3 with ``--quick``; empty: the bench's default."""
        if self.rounds is not None:
            return {"rounds": self.rounds}
        return {"rounds": 3} if self.quick else {}


@dataclass(frozen=True)
class Bench:
    """One benchmark: ``name`` (the CLI's choice), ``summary`` (its help), ``options`` (of :data:`OPTIONS`, those it
    takes) and ``run`` (runs it with the given arguments, prints and writes; returns the exit status)."""

    name: str
    summary: str
    options: frozenset[str]
    run: Callable[[BenchArgs], int]


def _wrote(path: Path | str) -> None:
    print(f"wrote {path}")


def _ssv(a: BenchArgs) -> int:
    from .ssv import format_ssv_bench, run_ssv_bench

    timing: dict[str, Any] = {"min_time": 0.002} if a.quick else {}
    report = run_ssv_bench(seed=a.seed_or(), progress=a.progress, **timing, **a.rounds_kwargs())
    print(format_ssv_bench(report))
    _wrote(write_json(report, a.json_path))
    return 0


def _ik(a: BenchArgs) -> int:
    from .ik import format_ik_bench, run_ik_bench

    kwargs: dict[str, Any] = {"repeats": 1, "scaling": (10, 100)} if a.quick else {}
    report = run_ik_bench(seed=a.seed_or(), progress=a.progress, **kwargs, **a.rounds_kwargs())
    print(format_ik_bench(report))
    _wrote(write_json(report, a.json_path))
    return 0


def _pik(a: BenchArgs) -> int:
    from .pik import format_pik_bench, run_pik_bench

    report = run_pik_bench(
        seed=a.seed_or(), episodes=2 if a.quick else 10, quick=a.quick, progress=a.progress, **a.rounds_kwargs()
    )
    print(format_pik_bench(report))
    _wrote(write_json(report, a.json_path))
    return 0


def _soak(a: BenchArgs) -> int:
    from .soak import format_soak_bench, run_soak_bench

    seconds = a.seconds if a.seconds is not None else (1.0 if a.quick else 10.0)
    report = run_soak_bench(
        seconds=None if a.steps is not None else seconds, steps=a.steps, seed=a.seed_or(), progress=a.progress
    )
    print(format_soak_bench(report))
    _wrote(write_json(report, a.json_path))
    return 0 if report["ok"] else 1


def _push(a: BenchArgs) -> int:
    from .push import format_push_bench, plot_push_bench, run_push_bench

    trials = a.trials if a.trials is not None else (5 if a.quick else 20)
    report = run_push_bench(seed=a.seed_or(), trials=trials, progress=a.progress)
    print(format_push_bench(report))
    _wrote(write_json(report, a.json_path))
    _wrote(plot_push_bench(report, str(Path(a.json_path).with_suffix(".png"))))
    return 0


def _ikd(a: BenchArgs) -> int:
    from ..studies.ikd_study import IkdStudyConfig, format_ikd_study, plot_ikd_study, run_ikd_study, write_ikd_study

    # the plain LIPM plan, then the walking controller's plan with its multi-body ZMP correction
    for correction, suffix in ((False, ""), (True, "_corrected")):
        config = IkdStudyConfig(steps=2 if a.quick else 6, correction=correction)
        study = run_ikd_study(config, progress=a.progress)
        print(f"\n{config.plan_name}:")
        print(format_ikd_study(study.to_json()))
        path = Path(a.json_path)
        _wrote(write_ikd_study(study, path.with_name(path.stem + suffix + path.suffix)))
        for written in plot_ikd_study(study, path.parent, suffix):
            _wrote(written)
    return 0


def _write_table(
    a: BenchArgs,
    table: dict[str, Any],
    title: str,
    markdown: Callable[[dict[str, Any]], str],
    plot: Callable[..., list[Path]],
) -> None:
    """Print a table's markdown; write its JSON (``--json``), the markdown beside it (``.md``, under ``title``) and
    its figures (``<stem>_<env>.png``). With ``--envs``, the other envs' sections of an existing JSON of the same seed
    and episodes are kept (a table updated env by env)."""
    if a.envs is not None:
        table = _merged(table, a.json_path)
    text = markdown(table)
    print(text)
    path = write_json(table, a.json_path)
    _wrote(path)
    md = path.with_suffix(".md")
    md.write_text(f"# {title}\n\n" + text)
    _wrote(md)
    for written in plot(table, path.parent, prefix=path.stem + "_"):
        _wrote(written)


def _merged(table: dict[str, Any], path: str) -> dict[str, Any]:
    """``table`` with the sections of the envs it lacks taken from the JSON at ``path``, in that file's order, when
    the file holds a table of the same seed and episodes; ``table`` itself otherwise."""
    try:
        old = json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return table
    if not isinstance(old, dict) or (old.get("seed"), old.get("episodes")) != (table["seed"], table["episodes"]):
        return table
    envs = {key: table["envs"].get(key, section) for key, section in old.get("envs", {}).items()}
    envs.update({key: section for key, section in table["envs"].items() if key not in envs})
    return {**table, "envs": envs}


def _learned(a: BenchArgs) -> int:
    from ..eval.parallel import ray_cpus
    from .learned import HELD_OUT_SEED, learned_markdown, plot_learned_bench, run_learned_bench

    episodes = a.episodes if a.episodes is not None else (2 if a.quick else 20)
    workers = a.workers if a.workers is not None else (1 if a.ray is None else ray_cpus(a.ray))
    table = run_learned_bench(
        episodes=episodes,
        seed=a.seed_or(HELD_OUT_SEED),
        envs=None if a.envs is None else list(a.envs),
        progress=a.progress,
        workers=workers,
        ray_address=a.ray,
    )
    _write_table(a, table, "Learned baselines against the analytic references", learned_markdown, plot_learned_bench)
    return 0


def _robustness(a: BenchArgs) -> int:
    from .robustness import HELD_OUT_SEED, plot_robustness_bench, robustness_markdown, run_robustness_bench

    episodes = a.episodes if a.episodes is not None else (2 if a.quick else 10)
    table = run_robustness_bench(
        episodes=episodes,
        seed=a.seed_or(HELD_OUT_SEED),
        envs=None if a.envs is None else list(a.envs),
        progress=a.progress,
        workers=a.workers if a.workers is not None else 1,
    )
    _write_table(
        a, table, "The references on plants that differ from their model", robustness_markdown, plot_robustness_bench
    )
    return 0


def _curves(a: BenchArgs) -> int:
    from .curves import curves_markdown, plot_curves_bench, run_curves_bench

    table = run_curves_bench(
        a.json_path,
        seeds=a.trials if a.trials is not None else (1 if a.quick else 3),
        episodes=a.episodes if a.episodes is not None else (1 if a.quick else 10),
        envs=a.envs,
        steps=a.steps,
        workers=a.workers if a.workers is not None else 1,
        quick=a.quick,
        progress=a.progress,
    )
    command = "redundancy-gym bench curves" + (" --quick" if a.quick else "")
    command += f" --envs {' '.join(a.envs)}" if a.envs else ""
    command += f" --steps {a.steps}" if a.steps is not None else ""
    command += f" --trials {a.trials}" if a.trials is not None else ""
    command += f" --workers {a.workers}" if a.workers is not None else ""
    command += f" --json {a.json_path}"
    _write_table(
        a,
        table,
        "Learning curves against the analytic references",
        lambda t: curves_markdown(t, command=command),
        plot_curves_bench,
    )
    # the study is written either way; a script or Makefile still learns that what it asked for was not trained
    for name, why in table["notes"].items():
        print(f"not extended: {name}: {why}", file=sys.stderr)
    return 1 if table["notes"] else 0


def _startup(a: BenchArgs) -> int:
    from .startup import format_startup_bench, run_startup_bench

    report = run_startup_bench(names=a.envs, quick=a.quick, progress=a.progress, **a.rounds_kwargs())
    command = "redundancy-gym bench startup" + (" --quick" if a.quick else "")
    command += f" --rounds {a.rounds}" if a.rounds is not None else ""
    command += f" --envs {' '.join(a.envs)}" if a.envs else ""
    report["command"] = command + f" --json {a.json_path}"
    print(format_startup_bench(report))
    _wrote(write_json(report, a.json_path))
    return 0


def _scale(a: BenchArgs) -> int:
    from .scale import format_scale_bench, run_scale_bench

    episodes = a.episodes if a.episodes is not None else (4 if a.quick else None)
    try:
        import ray  # noqa: F401  (the Ray rows need the ray extra)

        ray_workers: tuple[int, ...] = () if a.quick else (4, 8)
    except ImportError:
        ray_workers = ()
        print("Ray is not installed: the Ray rows are left out (pip install -e '.[ray]')")
    report = run_scale_bench(
        workers=(a.workers or 2,),
        episodes=episodes,
        ray_workers=ray_workers,
        rounds=a.rounds or (1 if a.quick else 3),
        vec_steps=30 if a.quick else 300,
        seed=a.seed_or(),
        progress=a.progress,
    )
    print(format_scale_bench(report))
    _wrote(write_json(report, a.json_path))
    return 0


def _walk(a: BenchArgs) -> int:
    from .walk import format_walk_bench, run_walk_bench

    kwargs: dict[str, Any] = {"duration": 1.0, "repeats": 1} if a.quick else {}
    report = run_walk_bench(seed=a.seed_or(), progress=a.progress, **kwargs, **a.rounds_kwargs())
    print(format_walk_bench(report))
    _wrote(write_json(report, a.json_path))
    return 0


def _envs(a: BenchArgs) -> int:
    from .envs import format_envs_bench, run_envs_bench

    report = run_envs_bench(seconds=0.3 if a.quick else 3.0, seed=a.seed_or(), progress=a.progress, **a.rounds_kwargs())
    print(format_envs_bench(report))
    _wrote(write_json(report, a.json_path))
    return 0


_ROUNDS = frozenset({"rounds"})
BENCHES: Mapping[str, Bench] = {
    b.name: b
    for b in (
        Bench("ssv", "swept-sphere distances against coal", _ROUNDS, _ssv),
        Bench(
            "envs",
            "steps/s against Gymnasium's Pusher/Humanoid, and every wrapped id against its raw env",
            _ROUNDS,
            _envs,
        ),
        Bench("ik", "the AgriReach CLIK control step against mink's solve_ik (needs the 'bench' extra)", _ROUNDS, _ik),
        Bench(
            "walk", "the BipedWalk controller step, and its compiled whole-body IK against pinocchio's", _ROUNDS, _walk
        ),
        Bench("pik", "predictive IK against local CLIK and the global optimum", _ROUNDS, _pik),
        Bench(
            "soak",
            "random, bang-bang and reference-policy actions on every env, counting exceptions and non-finite "
            "values (exit status 1 when any)",
            frozenset({"seconds", "steps"}),
            _soak,
        ),
        Bench(
            "push",
            "the largest torso push the walking reference recovers from, with and without step adjustment "
            "(also writes a PNG beside the JSON)",
            frozenset({"trials"}),
            _push,
        ),
        Bench(
            "ikd",
            "the kinematic IKD study of monograph 5.5.3 (figs. 5.21, 5.23, 5.24, 5.27 analogues: unstabilized "
            "drift, k sweep, LIPM vs error compensation vs IKD hybrid; PNGs beside the JSON)",
            frozenset(),
            _ikd,
        ),
        Bench(
            "learned",
            "every analytic reference and shipped learned baseline per env on held-out seeds (success, "
            "failures, errors, pseudoenergy, step time, training cost; markdown and one time-vs-error PNG per env "
            "beside the JSON)",
            frozenset({"episodes", "workers", "ray", "envs"}),
            _learned,
        ),
        Bench(
            "robustness",
            "every env's references under dynamics randomization: success, failures and errors against the "
            "model-error level and the actuation latency on held-out seeds (markdown and one PNG per env beside "
            "the JSON)",
            frozenset({"episodes", "workers", "envs"}),
            _robustness,
        ),
        Bench(
            "curves",
            "learning curves: every learner per env at logarithmically spaced budgets, 3 training seeds "
            "(--trials), held-out evaluations, the references as lines; resumable; --steps caps the budgets, "
            "--envs picks envs or env-learner pairs (markdown and one PNG per env beside the JSON; exit status 1 "
            "when a run could not be trained on)",
            frozenset({"episodes", "workers", "envs", "steps", "trials"}),
            _curves,
        ),
        Bench(
            "startup",
            "what a new process pays before its first step: import, list, the quick start, every env's first step "
            "and every reference's first predict, each in a fresh process with an empty numba cache and again "
            "warm (the median of --rounds warm runs, default 5); --envs picks probes",
            frozenset({"envs", "rounds"}),
            _startup,
        ),
        Bench(
            "scale",
            "eval's episodes/s with --workers against the serial loop (alternating rounds, Amdahl's serial "
            "fraction and its 64-core prediction) and make_vec's steps/s by num_envs, sync and async",
            frozenset({"rounds", "episodes", "workers"}),
            _scale,
        ),
    )
}
"""Every benchmark, by name, in the order ``redundancy-gym bench --help`` lists them."""


def bench(name: str) -> Bench:
    """The row of :data:`BENCHES` named ``name``."""
    if name not in BENCHES:
        raise BenchError(f"unknown bench {name!r}; valid: {', '.join(BENCHES)}")
    return BENCHES[name]


def check_bench_args(name: str, args: BenchArgs) -> Bench:
    """The row of ``name`` after checking that it takes every option given in ``args``.

    Raises:
        BenchError: unknown bench, an option it does not take (naming the benches that take it), or ``rounds < 1``.
    """
    entry = bench(name)
    given = [option for option in OPTIONS if getattr(args, option) is not None]
    extra = [option for option in given if option not in entry.options]
    if extra:
        takers = {option: [b.name for b in BENCHES.values() if option in b.options] for option in extra}
        raise BenchError(
            "; ".join(f"--{option} applies to bench {', '.join(names)} only" for option, names in takers.items())
        )
    if args.rounds is not None and args.rounds < 1:
        raise BenchError(f"--rounds must be >= 1, got {args.rounds}")
    return entry


def run_bench(name: str, args: BenchArgs) -> int:
    """Run the bench ``name`` with ``args`` after :func:`check_bench_args`; the exit status."""
    return check_bench_args(name, args).run(args)
