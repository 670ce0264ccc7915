"""``redundancy-gym bench curves``: learning curves of every learner per env, over logarithmically spaced budgets
with 3 training seeds, evaluated on held-out seeds, against the analytic references (horizontal lines).

Each (env, learner, seed) is one :class:`~redundancy_gym.learning.learning_curve.CurveRun`: its points are kept in
``<json stem>/<run>.json`` beside the study's JSON (committed), its agent and replay buffer in ``runs/curves/`` (not
committed; shared by every ``--json``, so a run with no points refuses to start over a same-named agent there).
Running the bench again trains every run on from its last point to its last budget (raise a budget, or ``--steps``,
to extend); a run whose points exist but whose agent is gone (a fresh clone) keeps its points and is not extended.
``--envs`` picks envs (``planar_reach``) or single learners (``planar_reach-ppo``); ``--workers`` runs that many
runs at once (one process each, torch on one thread).

Budgets, per learner as the study ran them (``docs/learned_baselines.md`` says why each stops where it does): PPO to
3M environment steps on the arms, its variants to 1M (rl-zoo3's Reacher settings to 300k); SAC and TQC to 300k on
PlanarReach and AgriReach easy, to 100k on AgriReach medium and hard (300k there would take about 34 more CPU-hours
on this 2-core machine); on the bipeds the residual and walking-command learners to 100k-300k. ``--steps`` above a
learner's last budget extends it.

Hyperparameters: PPO with stable-baselines3's defaults, plain (``ppo``) and behind SB3's ``VecNormalize``
(``ppo-norm``: rl-zoo3's PPO ``mujoco-defaults`` are SB3's defaults with ``normalize: true``; the agent's statistics
are saved beside its ``.zip`` and read by its policy); SAC and TQC with rl-zoo3's MuJoCo settings
(``learning_starts`` 10000, SB3's defaults otherwise; the replay buffer held at 300 000 transitions, the largest
budget). On the bipeds, the residual on the walking reference with SB3's defaults (``ppo-residual``: its exploration
noise starts at a standard deviation of 1, the residual's full bound) and with the noise started at exp(-2) = 0.14 of
it (``ppo-residual-quiet``: ``log_std_init`` -2, as rl-zoo3's tuned PPO settings of the PyBullet walkers), so
that the first rollouts walk as the reference does; and with that noise and rl-zoo3's learning rate for those
walkers, 3e-5, a tenth of SB3's default (``ppo-residual-slow``), so that each update moves the policy less far from
the reference it starts at. On AgriReach easy, PPO trained with ``energy_weight`` 0 (``ppo-no-energy``; evaluated
with the env's own weights like every learner) asks whether the energy term is why PPO learns to hold still
instead of reaching; PPO observing none of the plant parts (``ppo-no-obstacles``: ``observed_obstacles`` 0 in
training and evaluation; easy's approach corridors are clear by construction) whether the obstacle rows are why it
does not reach; on that observation, PPO with rl-zoo3's tuned Reacher settings (``ppo-reacher-no-obstacles``) and
TQC (``tqc-no-obstacles``) whether the learner is; and PPO and TQC commanding the TCP's velocity through
``AgriReach-TaskSpace-v0`` on that observation (``ppo-task_space-no-obstacles``, ``tqc-task_space-no-obstacles``)
whether the action space is: through it a proportional law on the observation grasps. CrossQ (sb3-contrib) is left
out of the default study: rl-zoo3's MuJoCo CrossQ has 2048-unit critics, far beyond this 2-core machine's budget.
"""

from __future__ import annotations

import json
import logging
import math
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field, replace
from multiprocessing import get_context
from pathlib import Path
from typing import Any

import numpy as np

from ..eval.evaluate import evaluate
from ..eval.machine import machine_info
from ..learning.learning_curve import CurveRun, budgets_between, train_learning_curve
from .exceptions import BenchError

__all__ = [
    "CURVE_ENVS",
    "CURVE_EVAL_SEED",
    "CurveEnv",
    "CurveLearner",
    "budget_table",
    "curves_markdown",
    "plot_curves_bench",
    "run_curves_bench",
]

CURVE_EVAL_SEED = 40000
"""First held-out seed of every point's evaluation (apart from the training seeds, the evaluation callback's 30000
and the learned table's 20000)."""

ON_POLICY_LAST, OFF_POLICY_LAST = 3_000_000, 300_000
_OFF_POLICY = {"learning_starts": 10_000, "buffer_size": 300_000}


@dataclass(frozen=True)
class CurveLearner:
    """One learner of an env: ``name`` (``ppo``, ``ppo-residual``), its algorithm, the env id it trains on (a
    wrapped id for a wrapper's action), its budgets and hyperparameters; ``env_kwargs`` change the env it trains
    and is evaluated on (what its agent observes, such as ``observed_obstacles``: the task, its reward and its
    success stay the study's), ``train_env_kwargs`` the training env only (a reward variant: its points are
    evaluated on the env as the study defines it)."""

    name: str
    algo: str
    env_id: str
    budgets: tuple[int, ...]
    hyperparameters: dict[str, Any] = field(default_factory=dict)
    normalize: bool = False
    env_kwargs: dict[str, Any] = field(default_factory=dict)
    train_env_kwargs: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class CurveEnv:
    """One env of the study: its key, title, env kwargs, error measure (a contract field, its label, unit and scale
    from SI), failure rate field, references (label -> policy name) and learners."""

    key: str
    title: str
    env_id: str
    env_kwargs: dict[str, Any]
    error: tuple[str, str, str, float]
    rate: str
    references: dict[str, str]
    learners: tuple[CurveLearner, ...]


def _arm_learners(
    env_id: str, *, off_policy_last: int = OFF_POLICY_LAST, norm: bool = True
) -> tuple[CurveLearner, ...]:
    return (
        CurveLearner("ppo", "ppo", env_id, budgets_between(10_000, ON_POLICY_LAST)),
        *(
            (CurveLearner("ppo-norm", "ppo", env_id, budgets_between(10_000, 1_000_000), normalize=True),)
            if norm
            else ()
        ),
        CurveLearner("sac", "sac", env_id, budgets_between(10_000, off_policy_last), dict(_OFF_POLICY)),
        CurveLearner("tqc", "tqc", env_id, budgets_between(10_000, off_policy_last), dict(_OFF_POLICY)),
    )


def _biped_learners(name: str, *, obstacles: bool) -> tuple[CurveLearner, ...]:
    residual = f"redundancy_gym/{name}-Residual-v0"
    quiet = {"log_std_init": -2.0}  # a standard deviation of 0.14 of the action bound
    slow = CurveLearner(
        "ppo-residual-slow",
        "ppo",
        residual,
        budgets_between(10_000, 100_000 if obstacles else 300_000),
        {"learning_rate": 3e-5, "policy_kwargs": dict(quiet)},
    )
    command = CurveLearner(
        "ppo-walking_command", "ppo", f"redundancy_gym/{name}-WalkingCommand-v0", budgets_between(10_000, 100_000)
    )
    if obstacles:  # the residual learner that kept the reference's success longest on the walk, and the command's
        return (slow, command)
    return (
        CurveLearner("ppo-residual", "ppo", residual, budgets_between(10_000, 300_000)),
        CurveLearner("ppo-residual-quiet", "ppo", residual, budgets_between(10_000, 100_000), {"policy_kwargs": quiet}),
        slow,
        command,
    )


_ZOO_REACHER: dict[str, Any] = {  # rl-zoo3's ppo.yml, Reacher (normalize: true)
    "n_steps": 512,
    "batch_size": 32,
    "gamma": 0.9,
    "learning_rate": 1.04019e-4,
    "ent_coef": 7.52585e-8,
    "clip_range": 0.3,
    "n_epochs": 5,
    "gae_lambda": 1.0,
    "max_grad_norm": 0.9,
    "vf_coef": 0.950368,
    "policy_kwargs": {"log_std_init": -2.0, "ortho_init": False, "net_arch": {"pi": [256, 256], "vf": [256, 256]}},
}
_PLANAR, _AGRI = "redundancy_gym/PlanarReach-v0", "redundancy_gym/AgriReach-v0"
_AGRI_TASK_SPACE = "redundancy_gym/AgriReach-TaskSpace-v0"
# the ladder's questions on easy: is the energy term why PPO holds still (trained without it, evaluated with it)?
# Are the obstacle rows (480 of the 528 observation entries) why it does not reach (observing none of them)?
_EASY_VARIANTS = (
    CurveLearner(
        "ppo-no-energy", "ppo", _AGRI, budgets_between(10_000, 1_000_000), train_env_kwargs={"energy_weight": 0.0}
    ),
    CurveLearner(
        "ppo-no-obstacles", "ppo", _AGRI, budgets_between(10_000, 1_000_000), env_kwargs={"observed_obstacles": 0}
    ),
    # rl-zoo3's tuned PPO for Reacher, the closest MuJoCo task (its activation left at SB3's tanh: a JSON setting)
    CurveLearner(
        "ppo-reacher-no-obstacles",
        "ppo",
        _AGRI,
        budgets_between(10_000, 300_000),
        dict(_ZOO_REACHER),
        normalize=True,
        env_kwargs={"observed_obstacles": 0},
    ),
    # does an off-policy learner, which reuses every transition, reach where PPO observing the same only approaches?
    CurveLearner(
        "tqc-no-obstacles",
        "tqc",
        _AGRI,
        budgets_between(10_000, OFF_POLICY_LAST),
        dict(_OFF_POLICY),
        env_kwargs={"observed_obstacles": 0},
    ),
    # does the action space decide it? Commanding the TCP's velocity (CLIK with avoidance moves the joints), the
    # grasp is a nearly linear function of the observation (a proportional law on it succeeds), not one of joints
    CurveLearner(
        "ppo-task_space-no-obstacles",
        "ppo",
        _AGRI_TASK_SPACE,
        budgets_between(10_000, 1_000_000),
        env_kwargs={"observed_obstacles": 0},
    ),
    CurveLearner(
        "tqc-task_space-no-obstacles",
        "tqc",
        _AGRI_TASK_SPACE,
        budgets_between(10_000, OFF_POLICY_LAST),
        dict(_OFF_POLICY),
        env_kwargs={"observed_obstacles": 0},
    ),
)
_RETURN = ("episode_return", "episode_length")
# what a learner that learned nothing earns: the arms hold still, the bipeds hold the standing posture
_ARM_REFERENCES = {"clik": "clik", "zero action": "zero"}
_BIPED_REFERENCES = {"walking": "walking", "zero action": "zero"}
_TRACKING = ("tracking_error_max", "tracking error max", "mm", 1e3)
_GOAL = ("goal_error", "goal error at the end", "mm", 1e3)
_SPEED = ("speed_error", "speed error (mean speed vs command)", "m/s", 1.0)
CURVE_ENVS: tuple[CurveEnv, ...] = (
    CurveEnv(
        "planar_reach",
        "PlanarReach-v0 with obstacle",
        _PLANAR,
        {"obstacle": True},
        _TRACKING,
        "collision_rate",
        _ARM_REFERENCES,
        _arm_learners(_PLANAR),
    ),
    *(
        CurveEnv(
            f"agri_reach_{d}",
            f"AgriReach-v0 ({d})",
            _AGRI,
            {"difficulty": d},
            _GOAL,
            "collision_rate",
            _ARM_REFERENCES,
            # medium and hard: SAC and TQC to 100k, PPO with VecNormalize not run (docs/learned_baselines.md)
            _arm_learners(_AGRI) + _EASY_VARIANTS
            if d == "easy"
            else _arm_learners(_AGRI, off_policy_last=100_000, norm=False),
        )
        for d in ("easy", "medium", "hard")
    ),
    CurveEnv(
        "biped_walk",
        "BipedWalk-v0 at 0.5 m/s",
        "redundancy_gym/BipedWalk-v0",
        {"target_speed": 0.5},
        _SPEED,
        "fall_rate",
        _BIPED_REFERENCES,
        _biped_learners("BipedWalk", obstacles=False),
    ),
    CurveEnv(
        "biped_obstacles",
        "BipedObstacles-v0, random courses",
        "redundancy_gym/BipedObstacles-v0",
        {"course": "random"},
        _SPEED,
        "fall_rate",
        _BIPED_REFERENCES,
        _biped_learners("BipedObstacles", obstacles=True),
    ),
)
"""The study's envs, in its order."""

QUICK = replace(
    CURVE_ENVS[0], learners=(CurveLearner("ppo", "ppo", _PLANAR, (64, 128), {"n_steps": 64, "batch_size": 32}),)
)
"""``--quick``: a 2-point PPO curve on PlanarReach (seconds; CI)."""


def _select(envs: Sequence[str] | None, quick: bool) -> list[tuple[CurveEnv, CurveLearner]]:
    table = (QUICK,) if quick else CURVE_ENVS
    pairs = [(env, learner) for env in table for learner in env.learners]
    if envs is None:
        return pairs
    valid = [env.key for env in table] + [f"{env.key}-{learner.name}" for env, learner in pairs]
    unknown = [name for name in envs if name not in valid]
    if unknown:
        raise BenchError(f"unknown curve env or learner {', '.join(unknown)}; valid: {', '.join(valid)}")
    return [(e, learner) for e, learner in pairs if e.key in envs or f"{e.key}-{learner.name}" in envs]


def _run(env: CurveEnv, learner: CurveLearner, seed: int, steps: int | None, episodes: int) -> CurveRun:
    budgets = learner.budgets if steps is None else tuple(b for b in learner.budgets if b < steps) + (steps,)
    return CurveRun(
        name=f"{env.key}-{learner.name}-s{seed}",
        env_id=learner.env_id,
        env_kwargs={**env.env_kwargs, **learner.env_kwargs},
        algo=learner.algo,
        seed=seed,
        budgets=budgets,
        hyperparameters=dict(learner.hyperparameters),
        eval_episodes=episodes,
        eval_seed=CURVE_EVAL_SEED,
        normalize=learner.normalize,
        train_env_kwargs=dict(learner.train_env_kwargs),
    )


def _train_one(run: CurveRun, folder: str, agents: str) -> tuple[str, dict[str, Any] | str]:
    """One run in a worker: its state, or why it was not extended."""
    logging.getLogger("redundancy_gym.policies.sb3_policy").setLevel(logging.ERROR)  # its own agents, announced
    try:
        return run.name, train_learning_curve(run, folder, agents=agents)
    except Exception as exc:  # a run that fails is a row that says so; the others go on
        return run.name, f"{type(exc).__name__}: {exc}"


def _references(env: CurveEnv, folder: Path, episodes: int, progress: bool) -> dict[str, dict[str, Any]]:
    path = folder / f"references-{env.key}.json"
    cached = json.loads(path.read_text()) if path.is_file() else {}
    same = cached.get("episodes") == episodes and cached.get("seed") == CURVE_EVAL_SEED
    if same and list(cached.get("references", {})) == list(env.references):
        return dict(cached["references"])
    out = {}
    for label, policy in env.references.items():
        report = evaluate(
            env.env_id, policy, episodes=episodes, seed=CURVE_EVAL_SEED, env_kwargs=env.env_kwargs, progress=progress
        ).to_json()
        out[label] = {k: report.get(k) for k in ("success_rate", env.rate, env.error[0], *_RETURN)}
    folder.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"episodes": episodes, "seed": CURVE_EVAL_SEED, "references": out}, indent=1) + "\n")
    return out


def _summary(points_by_seed: dict[str, list[dict[str, Any]]], error_key: str) -> dict[str, Any]:
    """Per budget reached by every seed: success and the error, each with its mean, min and max over seeds; the
    return's and CPU time's means; and the first budget whose mean success reaches 0.5 and 0.9 (None: not within the
    largest)."""
    runs = [p for p in points_by_seed.values() if p]
    rows = []
    if runs:
        common = sorted(set.intersection(*({q["budget"] for q in p} for p in runs)))
        for budget in common:
            at = [next(q for q in p if q["budget"] == budget) for p in runs]
            success = [q.get("success_rate", 0.0) for q in at]
            errors = [q[error_key] for q in at if error_key in q]
            returns = [q["episode_return"] for q in at if "episode_return" in q]
            rows.append(
                {
                    "budget": budget,
                    "steps_mean": float(np.mean([q["steps"] for q in at])),
                    "success_mean": float(np.mean(success)),
                    "success_min": float(min(success)),
                    "success_max": float(max(success)),
                    "error_mean": float(np.mean(errors)) if errors else None,
                    "error_min": float(min(errors)) if errors else None,
                    "error_max": float(max(errors)) if errors else None,
                    "return_mean": float(np.mean(returns)) if returns else None,
                    "cpu_s_mean": float(np.mean([q["cpu_s"] for q in at])),
                }
            )
    first = {}
    for threshold in (0.5, 0.9):
        hit = next((r["budget"] for r in rows if r["success_mean"] >= threshold), None)
        first[f"first_{threshold}"] = hit
    return {"by_budget": rows, "largest_budget": rows[-1]["budget"] if rows else None, **first}


def run_curves_bench(
    json_path: str | Path,
    *,
    seeds: int = 3,
    episodes: int = 10,
    envs: Sequence[str] | None = None,
    steps: int | None = None,
    workers: int = 1,
    quick: bool = False,
    agents: str | Path = "runs/curves",
    progress: bool = True,
) -> dict[str, Any]:
    """Train every selected run on to its last budget (module docstring) and gather the study: per env its
    references, per learner the command, hyperparameters, every seed's points and the summary over seeds. With
    ``envs``, the study's other envs and learners are read from their state files as they stand."""
    if seeds < 1 or episodes < 1 or workers < 1:
        raise BenchError(f"seeds, episodes and workers must be >= 1, got {seeds}, {episodes}, {workers}")
    if steps is not None and steps < 1:
        raise BenchError(f"--steps must be >= 1, got {steps}")
    folder = Path(json_path).with_suffix("")
    chosen = _select(envs, quick)
    runs = [_run(env, learner, seed, steps, episodes) for env, learner in chosen for seed in range(seeds)]
    notes: dict[str, str] = {}
    from tqdm.auto import tqdm

    with tqdm(total=len(runs), desc="bench curves", unit="run", disable=not progress) as bar:
        if workers == 1:
            results = []
            for run in runs:
                results.append(_train_one(run, str(folder), str(agents)))
                bar.update(1)
        else:
            with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as pool:
                futures = [pool.submit(_train_one, run, str(folder), str(agents)) for run in runs]
                results = []
                for future in futures:
                    results.append(future.result())
                    bar.update(1)
    for name, result in results:
        if isinstance(result, str):
            notes[name] = result
    table_envs: dict[str, Any] = {}
    for env in (QUICK,) if quick else CURVE_ENVS:
        learners: dict[str, Any] = {}
        for learner in env.learners:
            points = {}
            for seed in range(seeds):
                path = folder / f"{env.key}-{learner.name}-s{seed}.json"
                if path.is_file():
                    points[str(seed)] = json.loads(path.read_text())["points"]
            if not points:
                continue
            summary = _summary(points, env.error[0])
            # the command that gives these points: capped at the largest budget reached where that is short of
            # the learner's last (running it without --steps extends the curve)
            reached = summary["largest_budget"]
            cap = f" --steps {reached}" if reached is not None and reached < learner.budgets[-1] else ""
            pick = "--quick" if quick else f"--envs {env.key}-{learner.name}{cap} --trials {seeds}"
            learners[learner.name] = {
                **asdict(learner),
                "command": f"redundancy-gym bench curves {pick} --json {json_path}",
                "seeds": points,
                **summary,
            }
        if not learners:
            continue
        table_envs[env.key] = {
            "title": env.title,
            "env_id": env.env_id,
            "env_kwargs": env.env_kwargs,
            "error": {"key": env.error[0], "label": env.error[1], "unit": env.error[2], "scale": env.error[3]},
            "rate": env.rate,
            "references": _references(env, folder, episodes, progress),
            "learners": learners,
        }
    return {
        "seed": CURVE_EVAL_SEED,
        "eval_seed": CURVE_EVAL_SEED,
        "episodes": episodes,
        "seeds": seeds,
        "machine": machine_info(),
        "notes": notes,
        "envs": table_envs,
    }


def _steps(value: int) -> str:
    """A budget as the tables write it: ``3M``, ``300k``, or with separators where it is not round."""
    if value and value % 1_000_000 == 0:
        return f"{value // 1_000_000}M"
    if value and value % 1_000 == 0:
        return f"{value // 1_000}k"
    return f"{value:,}"


def _budget(value: int | None, largest: int | None) -> str:
    if value is None:
        return f"not within {_steps(largest)}" if largest else "-"
    return _steps(value)


def budget_table(table: dict[str, Any]) -> list[str]:
    """The study in one markdown table: per env and learner the largest budget every seed reached, the mean success
    and the mean of the env's error measure there, the best mean success and the lowest mean error over the budgets
    and where (a learner can peak and unlearn), and the first budgets at which the mean success reaches 0.5 and
    0.9. Budgets are written short (``300k``, ``3M``) to keep the table narrow."""
    lines = [
        "| env | learner | seeds | largest budget [steps] | success there | error there | best success; lowest error "
        "(at [steps]) | first >= 0.5 | first >= 0.9 |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for env in table["envs"].values():
        for name, learner in env["learners"].items():
            rows = learner["by_budget"]
            if not rows:
                continue
            last = rows[-1]
            best = max(rows, key=lambda row: row["success_mean"])
            peak = f"{best['success_mean']:.2f}" + (f" ({_steps(best['budget'])})" if best["success_mean"] > 0 else "")
            measured = [row for row in rows if row.get("error_mean") is not None]
            lowest = min(measured, key=lambda row: row["error_mean"]) if measured else None
            nearest = "-" if lowest is None else f"{_error(env, lowest)} ({_steps(lowest['budget'])})"
            lines.append(
                f"| {env['title']} | {name} | {len(learner['seeds'])} | {_steps(last['budget'])} | "
                f"{last['success_mean']:.2f} | {_error(env, last)} | {peak}; {nearest} | "
                f"{_firsts(learner, last['budget'])} |"
            )
    return [*lines, ""]


def _error(env: dict[str, Any], row: dict[str, Any], *, unit: bool = True, spread: bool = False) -> str:
    """A table cell: the mean of the env's error measure at one budget, in the env's unit (named unless the column
    header names it); with ``spread``, followed by its min-max over seeds where the row has them."""
    if row.get("error_mean") is None:
        return "-"

    def scaled(value: float) -> str:
        value *= env["error"]["scale"]
        return f"{value:.3g}" if abs(value) < 1000 else f"{value:.0f}"  # 1004, not 1e+03

    cell = scaled(row["error_mean"])
    if spread and row.get("error_min") is not None and row.get("error_max") is not None:
        cell += f" ({scaled(row['error_min'])}-{scaled(row['error_max'])})"
    return f"{cell} {env['error']['unit']}" if unit else cell


def _firsts(learner: dict[str, Any], largest: int) -> str:
    """The two table cells of the first budgets at which a learner's mean success reaches 0.5 and 0.9."""
    return f"{_budget(learner['first_0.5'], largest)} | {_budget(learner['first_0.9'], largest)}"


def _warm_up_note(table: dict[str, Any]) -> str:
    """Which learners make no gradient step before ``learning_starts`` steps: a point at or below it is their
    seeded initial actor, not something learned."""
    by_value: dict[int, set[str]] = {}
    for env in table["envs"].values():
        for name, learner in env["learners"].items():
            if "learning_starts" in learner.get("hyperparameters", {}):
                by_value.setdefault(int(learner["hyperparameters"]["learning_starts"]), set()).add(name)
    if not by_value:
        return ""
    listed = "; ".join(f"{_steps(value)} for {', '.join(sorted(by_value[value]))}" for value in sorted(by_value))
    return (
        f" Off-policy learners make no gradient step before `learning_starts` steps ({listed}): a point at or below "
        "that budget evaluates the seeded initial actor, nothing learned."
    )


def _held_out(table: dict[str, Any]) -> str:
    """``held-out seeds 40000-40009`` (``held-out seed 40000`` for one episode)."""
    first, episodes = table["eval_seed"], table["episodes"]
    return f"held-out seed {first}" if episodes == 1 else f"held-out seeds {first}-{first + episodes - 1}"


def curves_markdown(table: dict[str, Any], *, command: str = "redundancy-gym bench curves") -> str:
    """Per env: the references, and per learner the largest budget its seeds reached, the success there (mean,
    min-max over seeds), the error, the CPU time per seed and the first budgets at which the mean success reaches
    0.5 and 0.9."""
    lines = [
        f"{table['seeds']} training seed{'s' if table['seeds'] != 1 else ''} per learner (the seeds column: how many "
        f"have points); every point evaluated on {_held_out(table)} ({table['episodes']} "
        f"episode{'s' if table['episodes'] != 1 else ''}, the deterministic agent). Largest budget: the largest "
        "that every seed with points has reached, where the means are taken; points of single seeds beyond it are "
        "listed under each env's table. Success: the mean over those seeds. This file was last written by `"
        f"{command}`; each learner's points come from the command under its table. "
        "CPU time: the training's, per seed, evaluations excluded." + _warm_up_note(table),
        "",
        *budget_table(table),
    ]
    for env in table["envs"].values():
        err = env["error"]
        lines += [f"### {env['title']}", "", f"`{env['env_id']}`, env kwargs `{json.dumps(env['env_kwargs'])}`.", ""]
        refs = "; ".join(
            f"{label}: success {r.get('success_rate', float('nan')):.2f}, {err['label']} "
            f"{(r.get(err['key']) or float('nan')) * err['scale']:.3g} {err['unit']}"
            + (f", return {r['episode_return']:.1f}" if r.get("episode_return") is not None else "")
            for label, r in env["references"].items()
        )
        lines += [f"References: {refs}.", ""]
        lines += [
            "| learner | seeds | largest budget [steps] | success (min-max) | "
            f"{err['label']} (min-max) [{err['unit']}] | return | CPU per seed [min] | first >= 0.5 | first >= 0.9 |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
        ]
        for name, learner in env["learners"].items():
            rows = learner["by_budget"]
            if not rows:
                lines.append(f"| {name} | {len(learner['seeds'])} | - | - | - | - | - | - | - |")
                continue
            last = rows[-1]
            error = _error(env, last, unit=False, spread=True)
            ret = "-" if last.get("return_mean") is None else f"{last['return_mean']:.1f}"
            lines.append(
                f"| {name} | {len(learner['seeds'])} | {_steps(last['budget'])} | {last['success_mean']:.2f} "
                f"({last['success_min']:.2f}-{last['success_max']:.2f}) | {error} | {ret} | "
                f"{last['cpu_s_mean'] / 60:.1f} | "
                f"{_firsts(learner, last['budget'])} |"
            )
        lines.append("")
        lines += _beyond(env)
        lines += [
            f"- {name}: `{learner['command']}`" for name, learner in env["learners"].items() if "command" in learner
        ]
        lines.append("")
    if table.get("notes"):
        lines += ["Runs not extended:", ""] + [f"- {k}: {v}" for k, v in table["notes"].items()] + [""]
    return "\n".join(lines)


def _beyond(env: dict[str, Any]) -> list[str]:
    """One line per learner whose seeds went past its largest common budget: each such seed's furthest point, so
    that a seed lost or behind does not hide what the others reached."""
    err = env["error"]
    lines = []
    for name, learner in env["learners"].items():
        rows = learner["by_budget"]
        common = rows[-1]["budget"] if rows else 0
        further = []
        for seed, points in learner["seeds"].items():
            if points and points[-1]["budget"] > common:
                last = points[-1]
                error = last.get(err["key"])
                shown = "-" if error is None else f"{float(error) * err['scale']:.3g} {err['unit']}"
                further.append(
                    f"seed {seed} at {_steps(last['steps'])} steps: success {last.get('success_rate', 0.0):.2f}, "
                    f"{err['label']} {shown}"
                )
        if further:
            lines.append(f"- {name} beyond {_steps(common)} steps (not every seed there): " + "; ".join(further) + ".")
    return [*lines, ""] if lines else []


def plot_curves_bench(table: dict[str, Any], directory: str | Path, prefix: str = "curves_") -> list[Path]:
    """One figure per env: success (top) and the error (bottom) against environment steps (left) and against
    training CPU time (right); each learner's mean over seeds with its min-max band, the references as horizontal
    lines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    from ..eval.plots import save_figure

    written = []
    for key, env in table["envs"].items():
        err = env["error"]
        fig, grid = plt.subplots(2, 2, figsize=(13, 8.4))
        axes = grid.ravel()  # success: steps, CPU; error: steps, CPU
        for (name, learner), color in zip(env["learners"].items(), plt.get_cmap("tab10")(range(10)), strict=False):
            rows = learner["by_budget"]
            if not rows:
                continue
            steps = [r["steps_mean"] for r in rows]
            cpu = [r["cpu_s_mean"] / 60 for r in rows]
            mean = [r["success_mean"] for r in rows]
            low, high = [r["success_min"] for r in rows], [r["success_max"] for r in rows]
            count = len(learner["seeds"])
            # learners that never succeed draw on top of each other at 0: the legend says each one's best
            best = max(mean)
            label = f"{name} ({count} seed{'' if count == 1 else 's'}, best {best:.2f})"
            axes[0].plot(steps, mean, "o-", color=color, label=label)
            axes[0].fill_between(steps, low, high, color=color, alpha=0.15)
            axes[1].plot(cpu, mean, "o-", color=color, label=label)
            axes[1].fill_between(cpu, low, high, color=color, alpha=0.15)
            errors = [np.nan if r["error_mean"] is None else r["error_mean"] * err["scale"] for r in rows]
            axes[2].plot(steps, errors, "o-", color=color, label=label)
            axes[3].plot(cpu, errors, "o-", color=color, label=label)
            # where every learner fails, the spread of the error over seeds is what tells them apart
            if all(r.get("error_min") is not None and r.get("error_max") is not None for r in rows):
                low = [r["error_min"] * err["scale"] for r in rows]
                high = [r["error_max"] * err["scale"] for r in rows]
                axes[2].fill_between(steps, low, high, color=color, alpha=0.15)
                axes[3].fill_between(cpu, low, high, color=color, alpha=0.15)
        handles = []
        for (label, ref), style in zip(env["references"].items(), ("--", ":", "-."), strict=False):
            shown = f"{label} ({'baseline' if label == 'zero action' else 'reference'})"
            for ax in axes[:2]:
                ax.axhline(ref.get("success_rate") or 0.0, ls=style, color="k", lw=1, label=shown)
            value = ref.get(err["key"])
            if value is not None and math.isfinite(float(value)):
                handles.append(axes[2].axhline(float(value) * err["scale"], ls=style, color="k", lw=1, label=shown))
                axes[3].axhline(float(value) * err["scale"], ls=style, color="k", lw=1)
        axes[0].axhline(0.5, color="0.4", lw=0.8, ls=(0, (1, 3)), label="0.5 (the table's first threshold)")
        axes[1].axhline(0.5, color="0.4", lw=0.8, ls=(0, (1, 3)))
        cpu_label = "training CPU time per seed [min] (runs on several machines)"
        error_label = f"{err['label']} [{err['unit']}]"
        for ax, xlabel, ylabel in (
            (axes[0], "environment steps", "success rate"),
            (axes[1], cpu_label, "success rate"),
            (axes[2], "environment steps", error_label),
            (axes[3], cpu_label, error_label),
        ):
            ax.set_xscale("log")
            ax.set_xlabel(xlabel)
            ax.set_ylabel(ylabel)
            ax.grid(True, which="both", alpha=0.3)
        # a CPU range of less than a decade got crowded labels at every minor tick (0.3, 0.4, ... overlapping)
        for ax in axes[1::2]:
            ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
            ax.xaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g}"))
            ax.xaxis.set_minor_formatter(NullFormatter())
        for ax in axes[:2]:
            ax.set_ylim(-0.05, 1.05)
        for ax in axes[2:]:
            ax.set_yscale("log")
        axes[0].legend(fontsize=8)
        if handles:
            axes[2].legend(handles=handles, fontsize=8)
        fig.suptitle(
            f"{env['title']}: learning curves, mean over training seeds with min-max band ({_held_out(table)})"
        )
        fig.tight_layout()
        written.append(save_figure(fig, Path(directory) / f"{prefix}{key}.png"))
    return written
