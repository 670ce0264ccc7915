"""The learned-baselines table (``redundancy-gym bench learned``): every analytic reference and every shipped learned
model (``baselines/models``) on the same held-out episodes of each env, with success, collision / fall rate, the
evaluation contract's error measures, pseudoenergy, compute time per step and the learner's training cost; a
markdown table, a paragraph per env naming what to pick for speed and for accuracy, and a time-vs-error plot per env
(analytic and learned policies with different markers).

The held-out seeds (default 20000 onwards) are neither training seeds (PPO/SAC reset their envs from seed 0, behaviour
cloning rolls seeds 0 onwards) nor the seeds of the training-time evaluation callback (30000 onwards).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..eval.evaluate import evaluate
from ..eval.speed_error import METRICS, plot_speed_error
from ..learning.baselines import Baseline, baselines
from ..learning.training_record import machine
from ..sb3_import import import_stable_baselines3
from .exceptions import BenchError

__all__ = [
    "HELD_OUT_SEED",
    "LEARNED_SETTINGS",
    "LearnedSetting",
    "format_learned_bench",
    "learned_markdown",
    "plot_learned_bench",
    "run_learned_bench",
]

HELD_OUT_SEED = 20000
"""First seed of the table's episodes."""
SUCCESS_SLACK = 0.05  # a policy counts as a pick when its success is within this of the best one's
RATE_SLACK = 0.05  # ... and its collision / fall rate within this of the lowest
ERROR_TIE = 0.05  # errors within this (relative, or the metric's absolute tolerance) of the lowest tie


@dataclass(frozen=True)
class LearnedSetting:
    """One env of the table.

    Attributes:
        key: the env's name in model files and in the JSON (``planar_reach``).
        title: the section title.
        env_id: the base env id (a learned model on a wrapper's action runs on the wrapped id).
        env_kwargs: the setting's ``gym.make`` keyword arguments.
        references: label -> (analytic policy name, policy options).
        errors: the names of :data:`~redundancy_gym.eval.speed_error.METRICS` shown as columns; the first is the
            plot's error axis and the accuracy a pick is chosen by.
        rate: the contract field of the failure rate shown next to success (``collision_rate``, ``fall_rate``).
        extra: further columns, each ``(contract field, heading with unit, scale from SI)``.
    """

    key: str
    title: str
    env_id: str
    env_kwargs: dict[str, Any]
    references: dict[str, tuple[str, dict[str, Any]]]
    errors: tuple[str, ...]
    rate: str = "collision_rate"
    extra: tuple[tuple[str, str, float], ...] = ()


LEARNED_SETTINGS: tuple[LearnedSetting, ...] = (
    LearnedSetting(
        "planar_reach",
        "PlanarReach-v0 with obstacle",
        "redundancy_gym/PlanarReach-v0",
        {"obstacle": True},
        {"clik": ("clik", {}), "predictive (1 s)": ("predictive", {"horizon": 1.0}), "global": ("global", {})},
        ("tracking_rms", "tracking_max"),
        extra=(("min_clearance", "min clearance [mm]", 1e3),),
    ),
    LearnedSetting(
        "agri_reach",
        "AgriReach-v0 (medium)",
        "redundancy_gym/AgriReach-v0",
        {"difficulty": "medium"},
        {
            "clik": ("clik", {}),
            "predictive (0.15 s)": ("predictive", {"horizon": 0.15}),
            "predictive (2 s)": ("predictive", {"horizon": 2.0}),
            "global": ("global", {}),
        },
        ("tracking_rms", "goal"),
        extra=(
            ("min_clearance", "min clearance [mm]", 1e3),
            ("leaf_contacts", "leaf contacts [leaf-steps/episode]", 1.0),
        ),
    ),
    LearnedSetting(
        "biped_walk",
        "BipedWalk-v0 at 0.5 m/s",
        "redundancy_gym/BipedWalk-v0",
        {"target_speed": 0.5},
        {"walking": ("walking", {}), "walking (IKD)": ("walking", {"ik": "ikd"})},
        ("speed", "speed_rms"),
        rate="fall_rate",
        extra=(("forward_speed", "forward speed [m/s]", 1.0),),
    ),
    LearnedSetting(
        "biped_obstacles",
        "BipedObstacles-v0, random courses",
        "redundancy_gym/BipedObstacles-v0",
        {"course": "random"},
        {"walking": ("walking", {}), "walking (IKD)": ("walking", {"ik": "ikd"})},
        ("speed",),
        rate="fall_rate",
        extra=(("obstacle_contact_rate", "obstacle contact rate", 1.0), ("forward_speed", "forward speed [m/s]", 1.0)),
    ),
    LearnedSetting(
        "biped_terrain",
        "BipedTerrain-v0, stairs",
        "redundancy_gym/BipedTerrain-v0",
        {"terrain": "stairs"},
        {"walking": ("walking", {})},
        ("speed",),
        rate="fall_rate",
        extra=(
            ("unsupported_rate", "unsupported touchdown rate", 1.0),
            ("min_support_fraction", "min support fraction", 1.0),
            ("forward_speed", "forward speed [m/s]", 1.0),
        ),
    ),
)
"""The table's envs, in its order."""

_RATE_NAMES = {"collision_rate": "collision", "fall_rate": "fall"}


def _setting(key: str) -> LearnedSetting:
    for setting in LEARNED_SETTINGS:
        if setting.key == key:
            return setting
    raise BenchError(f"unknown env {key!r} for bench learned; valid: {', '.join(s.key for s in LEARNED_SETTINGS)}")


def _models_for(setting: LearnedSetting, found: Sequence[Baseline]) -> list[Baseline]:
    return [b for b in found if b.slug == setting.key]


def run_learned_bench(
    *,
    episodes: int = 20,
    seed: int = HELD_OUT_SEED,
    envs: Sequence[str] | None = None,
    progress: bool = True,
    log: Callable[[str], None] | None = print,
    workers: int = 1,
    ray_address: str | None = None,
) -> dict[str, Any]:
    """Evaluate every reference and every shipped model of each env on ``episodes`` episodes from ``seed``.

    Each policy runs one untimed warm-up episode first (JIT compilation and model loading are not counted). A
    baseline whose model is not in ``baselines/models`` yet is listed under ``untrained``, not evaluated.

    Args:
        envs: keys of :data:`LEARNED_SETTINGS` (default: all).
        workers: processes each evaluation's episodes are split across (the table is the serial one's, step times
            excepted; with one worker per core the times stay comparable, on a busy machine they do not).
        ray_address: evaluate on ``workers`` Ray actors instead (a cluster's address or ``"local"``).

    Returns:
        The table as JSON: per env, per policy label, ``kind`` (analytic / learned), the evaluation-contract
        object and, for a learned policy, its ``training`` record (steps, wall and CPU time).
    """
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise BenchError(f"episodes must be an int >= 1, got {episodes!r}")
    chosen = [_setting(k) for k in envs] if envs else list(LEARNED_SETTINGS)
    found = baselines()
    table: dict[str, Any] = {"episodes": episodes, "seed": seed, "machine": machine(), "envs": {}}
    try:
        import_stable_baselines3()
    except ImportError as exc:  # a core install: the analytic rows still run, the table says what is missing
        table["learned_skipped"] = str(exc)
        found = []
        if log is not None:
            log(f"learned models left out: {exc}")
    for setting in chosen:
        rows: dict[str, Any] = {}
        untrained: list[str] = []
        runs: list[tuple[str, str, str, dict[str, Any], dict[str, Any], Baseline | None]] = [
            (label, setting.env_id, name, kwargs, setting.env_kwargs, None)
            for label, (name, kwargs) in setting.references.items()
        ]
        for b in _models_for(setting, found):
            if not b.model.is_file():
                untrained.append(b.name)
                continue
            # the options the model was trained with (a wrapper's command period, say) over the setting's; every
            # row runs on the nominal plant, a model trained under dynamics randomization too (bench robustness
            # compares it with its nominal twin on randomized plants)
            trained = {k: v for k, v in b.env_kwargs.items() if k != "dynamics"}
            runs.append((b.short_name, b.env_id, b.short_name, {}, {**setting.env_kwargs, **trained}, b))
        for label, env_id, policy, kwargs, env_kwargs, baseline in runs:
            if log is not None:
                log(f"{setting.title}: {label} on {env_id}")
            report = evaluate(
                env_id,
                policy,
                episodes=episodes,
                seed=seed,
                env_kwargs=env_kwargs,
                policy_kwargs=kwargs,
                progress=progress,
                warmup=1,
                workers=workers,
                ray_address=ray_address,
            ).to_json()
            row: dict[str, Any] = {
                "kind": "analytic" if baseline is None else "learned",
                "report": report,
                "periods_per_step": int(env_kwargs.get("command_period", 1)),
            }
            if baseline is not None:
                record = baseline.record()
                row["model"] = f"baselines/models/{baseline.name}.zip"
                row["training"] = (
                    None
                    if record is None
                    else {
                        "learner": record.learner,
                        "env_steps": record.env_steps,
                        "wall_s": record.wall_s,
                        "cpu_s": record.cpu_s,
                    }
                )
            rows[label] = row
        table["envs"][setting.key] = {
            "title": setting.title,
            "env_id": setting.env_id,
            "env_kwargs": setting.env_kwargs,
            "rows": rows,
            "untrained": untrained,
        }
    return table


def _fmt(value: float | None, digits: int = 3) -> str:
    if value is None or not math.isfinite(value):
        return "n/a"
    if value == 0.0:
        return "0"
    size = abs(value)
    if size >= 100.0:
        return f"{value:.0f}"
    return f"{value:.{digits}g}"


def _median_p99(times: Mapping[str, Any] | None) -> str:
    """``median / p99`` of a time block of the contract, ``-`` where the report has none (analytic policies, a
    learned one without the fast path, a table from before ``sb3_predict_us``)."""
    return "-" if times is None else f"{_fmt(times['median'])} / {_fmt(times['p99'])}"


def _per_period(rows: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """Label -> report with its step times per control period: a policy whose action holds k periods
    (``periods_per_step``, a ``WalkingCommandAction``'s ``command_period``) computes once per k periods, so its
    times per action (``step_time_us``, and a learned policy's ``sb3_predict_us``) are divided by k to compare with
    the others'."""
    out = {}
    for label, row in rows.items():
        k = int(row.get("periods_per_step", 1))
        report = dict(row["report"])
        for times in ("step_time_us", "sb3_predict_us"):
            if times in report:
                report[times] = {key: (value / k if key != "steps" else value) for key, value in report[times].items()}
        out[label] = report
    return out


def _picks(setting: LearnedSetting, rows: Mapping[str, Any]) -> str:
    """What to pick: among the policies whose success is within :data:`SUCCESS_SLACK` of the best and whose failure
    rate is within :data:`RATE_SLACK` of the lowest, the fastest (median step time) and the most accurate (the
    setting's first error; of those within :data:`ERROR_TIE` of the lowest, the fastest); then how the learned
    policies did."""
    reports = _per_period(rows)
    best_success = max(r["success_rate"] for r in reports.values())
    lowest_rate = min(float(r.get(setting.rate) or 0.0) for r in reports.values())
    good = {
        label: r
        for label, r in reports.items()
        if r["success_rate"] >= best_success - SUCCESS_SLACK
        and float(r.get(setting.rate) or 0.0) <= lowest_rate + RATE_SLACK
    }
    metric = METRICS[setting.errors[0]]
    rate = _RATE_NAMES[setting.rate]

    def median(label: str) -> float:
        return float(reports[label]["step_time_us"]["median"])

    fastest = min(good, key=median)
    errors = {label: v for label in good if (v := metric.value(reports[label])) is not None}
    tied: list[str] = []
    accurate = None
    if errors:
        best = min(errors.values())
        limit = max(best * (1.0 + ERROR_TIE), best + metric.abs_tol)
        tied = sorted((label for label, v in errors.items() if v <= limit), key=median)
        accurate = tied[0]  # of the equally accurate, the fastest
    text = [
        f"Candidates (success within {SUCCESS_SLACK:.2f} of the best, {best_success:.2f}, and {rate} rate within "
        f"{RATE_SLACK:.2f} of the lowest): {', '.join(f'**{label}**' for label in good)}."
    ]
    t = reports[fastest]["step_time_us"]
    text.append(f"For speed pick **{fastest}** ({_fmt(t['median'])} us median, p99 {_fmt(t['p99'])} us per step).")
    if accurate is not None:
        others = (
            f"; {', '.join(tied[1:])} {'is' if len(tied) == 2 else 'are'} as accurate (within "
            f"{ERROR_TIE:.0%}) but slower"
            if len(tied) > 1
            else ""
        )
        text.append(
            f"For accuracy pick **{accurate}** ({metric.label} {_fmt(metric.value(reports[accurate]))} "
            f"{metric.unit}{others})."
        )
    learned = [label for label, row in rows.items() if row["kind"] == "learned"]
    if learned:
        kept = [label for label in learned if label in good]
        lost = [label for label in learned if label not in good]
        if kept:
            text.append(f"Learned policies that match the references' success: {', '.join(kept)}.")
        if lost:
            text.append(
                "Learned policies that do not: "
                + ", ".join(
                    f"{label} (success {reports[label]['success_rate']:.2f}, {rate} "
                    f"{float(reports[label].get(setting.rate) or 0.0):.2f})"
                    for label in lost
                )
                + "."
            )
    return " ".join(text)


def learned_markdown(table: Mapping[str, Any], *, command: str = "redundancy-gym bench learned") -> str:
    """The table as markdown: one section per env with a row per policy and the paragraph of what to pick."""
    skipped = (
        [f"The learned models are left out: {table['learned_skipped']}.", ""] if table.get("learned_skipped") else []
    )
    out = skipped + [
        f"Held-out seeds {table['seed']}-{table['seed'] + table['episodes'] - 1} ({table['episodes']} episodes "
        f"per policy; `{command}`). Step time: the policy's compute per control period (an action wrapper's "
        "controller included, the simulation excluded; an action held for k periods counts 1/k of its time) after "
        "one warm-up episode; a learned policy's is its network run by the compiled fast path, and SB3 predict is "
        "the same step with stable-baselines3's own `predict` on the same observations instead. Training: "
        "environment steps and CPU time "
        "of the run that produced the shipped model (`baselines/models/<name>.json`).",
        "",
    ]
    for key, env in table["envs"].items():
        setting = _setting(key)
        metrics = [METRICS[name] for name in setting.errors]
        rate = _RATE_NAMES[setting.rate]
        head = (
            ["policy", "kind", "success", rate]
            + [m.heading for m in metrics]
            + [label for _, label, _ in setting.extra]
            + [
                "pseudoenergy [rad^2/s]",
                "return",
                "step time median / p99 [us]",
                "SB3 predict median / p99 [us]",
                "training steps",
                "training CPU [min]",
            ]
        )
        out += [
            f"### {env['title']}",
            "",
            f"`{env['env_id']}`, env kwargs `{json.dumps(env['env_kwargs'])}`.",
            "",
            "| " + " | ".join(head) + " |",
            "|" + " --- |" * len(head),
        ]
        display = _per_period(env["rows"])
        for label, row in env["rows"].items():
            r = display[label]
            training = row.get("training")
            cells = (
                [label, row["kind"], f"{r['success_rate']:.2f}", f"{float(r.get(setting.rate) or 0.0):.2f}"]
                + [_fmt(m.value(r)) for m in metrics]
                + [_fmt(None if r.get(k) is None else float(r[k]) * scale) for k, _, scale in setting.extra]
                + [
                    _fmt(r["pseudoenergy"]),
                    f"{r['episode_return']:.1f}",
                    f"{_fmt(r['step_time_us']['median'])} / {_fmt(r['step_time_us']['p99'])}",
                    _median_p99(r.get("sb3_predict_us")),
                    "-" if training is None else f"{training['env_steps']:,}",
                    "-" if training is None else f"{training['cpu_s'] / 60.0:.1f}",
                ]
            )
            out.append("| " + " | ".join(cells) + " |")
        own = [
            f"{label} `{json.dumps(row['report']['env_kwargs'])}`"
            for label, row in env["rows"].items()
            if row["report"]["env_kwargs"] != env["env_kwargs"]
        ]
        if own:
            out += ["", f"Run with the env kwargs they were trained with: {', '.join(own)}."]
        if env.get("untrained"):
            out.append("")
            out.append(f"Not trained yet (no model in baselines/models): {', '.join(env['untrained'])}.")
        out += ["", _picks(setting, env["rows"]), ""]
    return "\n".join(out)


def format_learned_bench(table: Mapping[str, Any]) -> str:
    """The markdown table (for the terminal)."""
    return learned_markdown(table)


def plot_learned_bench(table: Mapping[str, Any], directory: str | Path, prefix: str = "learned_") -> list[Path]:
    """One time-vs-error plot per env (``<prefix><env>.png``): analytic references and learned policies with
    different marker families, the error the setting's first."""
    written = []
    for key, env in table["envs"].items():
        setting = _setting(key)
        reports = _per_period(env["rows"])
        learned = {label for label, row in env["rows"].items() if row["kind"] == "learned"}
        written.append(
            plot_speed_error(
                reports,
                Path(directory) / f"{prefix}{key}.png",
                f"{env['title']}: time per step vs {METRICS[setting.errors[0]].label}",
                error=setting.errors[0],
                learned=learned,
            )
        )
    return written
