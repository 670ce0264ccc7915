"""The references on plants that differ from their model (``redundancy-gym bench robustness``, issue 36).

Every env's analytic references (and the IKD walker) run on held-out seeds under the env's ``dynamics``
randomization (:mod:`redundancy_gym.envs.dynamics`) along two axes: the model-error level ``L`` (masses, inertias,
CoM offsets, damping, armature, servo gains, the ground's friction, a payload and the base's placement; no latency)
and the actuation latency ``k`` (control periods; nothing else changed), plus the level shorthand ``dynamics=L``
(the level with its own latency ``floor(10 L)``). For each: success, the failure rate (collision or fall), the
env's error measures and the step time; a markdown table and a paragraph per env saying where each reference
breaks, and a figure per env (success and error against the level and against the latency).

The arm CLIKs run twice: as they are (measuring the latency at each episode's start and compensating it, their
placement calibrated from the observed TCP; :mod:`redundancy_gym.policies.plant_compensation`), and with
``latency=0`` (no latency compensation). On
AgriReach the shipped PPO-nullspace model trained on the nominal plant runs beside its twin trained under
``dynamics=0.1`` (``ppo-nullspace-dynamics``), where stable-baselines3 and the models are installed.
The held-out seeds (default 760000 onwards) were not used while developing the randomization or the compensation.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from ..eval.evaluate import evaluate  # noqa: E402
from ..eval.plots import save_figure  # noqa: E402
from ..eval.speed_error import METRICS  # noqa: E402
from ..learning.training_record import machine  # noqa: E402
from .exceptions import BenchError  # noqa: E402

__all__ = [
    "CONDITIONS",
    "HELD_OUT_SEED",
    "ROBUSTNESS_SETTINGS",
    "Condition",
    "RobustnessSetting",
    "plot_robustness_bench",
    "robustness_markdown",
    "run_robustness_bench",
]

HELD_OUT_SEED = 760000
"""First seed of the bench's episodes."""
SUCCESS_THRESHOLD = 0.95  # a reference holds a condition with at least this success and no failure


@dataclass(frozen=True)
class Condition:
    """One plant: ``label`` (the table's column), ``dynamics`` (the env argument; None: nominal), ``axis``
    (``"level"``, ``"latency"`` or ``"shorthand"``), ``x`` (its value on the axis) and ``latency`` (its control
    periods of delay)."""

    label: str
    dynamics: Any
    axis: str
    x: float
    latency: int


CONDITIONS: tuple[Condition, ...] = (
    Condition("nominal", None, "level", 0.0, 0),
    Condition("level 0.05", {"level": 0.05, "latency": 0}, "level", 0.05, 0),
    Condition("level 0.1", {"level": 0.1, "latency": 0}, "level", 0.1, 0),
    Condition("level 0.2", {"level": 0.2, "latency": 0}, "level", 0.2, 0),
    Condition("latency 1", {"latency": 1}, "latency", 1.0, 1),
    Condition("latency 2", {"latency": 2}, "latency", 2.0, 2),
    Condition("dynamics=0.1", 0.1, "shorthand", 0.1, 1),
    Condition("dynamics=0.2", 0.2, "shorthand", 0.2, 2),
)
"""The plants of the bench, in the table's order (the nominal one is level 0 and latency 0 alike)."""


@dataclass(frozen=True)
class RobustnessSetting:
    """One env of the bench.

    Attributes:
        key: the env's name in the JSON (``planar_reach``).
        title: the section title.
        env_id: the env id; env_kwargs: its ``gym.make`` arguments besides ``dynamics``.
        references: label -> (policy name, options).
        learned: label -> (env id, shipped model's short name): learned policies run on their wrapped env id.
        errors: names of :data:`~redundancy_gym.eval.speed_error.METRICS` shown as columns (the first is plotted).
        rate: the contract field of the failure rate (``collision_rate``, ``fall_rate``).
    """

    key: str
    title: str
    env_id: str
    env_kwargs: dict[str, Any]
    references: dict[str, tuple[str, dict[str, Any]]]
    errors: tuple[str, ...]
    rate: str = "collision_rate"
    learned: dict[str, tuple[str, str]] = field(default_factory=dict)


_ARM_REFERENCES: dict[str, tuple[str, dict[str, Any]]] = {
    "clik": ("clik", {}),
    "clik, latency=0 (no latency compensation)": ("clik", {"latency": 0}),
}
_WALKERS: dict[str, tuple[str, dict[str, Any]]] = {
    "walking": ("walking", {}),
    "walking (IKD)": ("walking", {"ik": "ikd"}),
}
ROBUSTNESS_SETTINGS: tuple[RobustnessSetting, ...] = (
    RobustnessSetting(
        "planar_reach",
        "PlanarReach-v0 (obstacle)",
        "redundancy_gym/PlanarReach-v0",
        {},
        _ARM_REFERENCES,
        ("tracking_max", "tracking_rms"),
    ),
    RobustnessSetting(
        "agri_reach",
        "AgriReach-v0 (medium)",
        "redundancy_gym/AgriReach-v0",
        {"difficulty": "medium"},
        _ARM_REFERENCES,
        ("tracking_rms", "goal"),
        learned={
            "ppo-nullspace (trained nominal)": ("redundancy_gym/AgriReach-Nullspace-v0", "ppo-nullspace"),
            "ppo-nullspace-dynamics (trained at dynamics=0.1)": (
                "redundancy_gym/AgriReach-Nullspace-v0",
                "ppo-nullspace-dynamics",
            ),
        },
    ),
    RobustnessSetting(
        "biped_walk",
        "BipedWalk-v0 at 0.5 m/s",
        "redundancy_gym/BipedWalk-v0",
        {"target_speed": 0.5},
        _WALKERS,
        ("speed", "speed_rms"),
        rate="fall_rate",
    ),
    RobustnessSetting(
        "biped_obstacles",
        "BipedObstacles-v0, random courses",
        "redundancy_gym/BipedObstacles-v0",
        {"course": "random"},
        _WALKERS,
        ("speed",),
        rate="fall_rate",
    ),
)
"""The bench's envs, in its order."""


def _setting(key: str) -> RobustnessSetting:
    for setting in ROBUSTNESS_SETTINGS:
        if setting.key == key:
            return setting
    valid = ", ".join(s.key for s in ROBUSTNESS_SETTINGS)
    raise BenchError(f"unknown env {key!r} for bench robustness; valid: {valid}")


def _learned_skipped(settings: Sequence[RobustnessSetting]) -> str | None:
    """Why the learned rows cannot run (stable-baselines3 or a model missing), None when they can."""
    from ..policies.shipped_models import SHIPPED_MODELS_DIR
    from ..sb3_import import import_stable_baselines3

    files = [_model_file(name, s.key) for s in settings for _, name in s.learned.values()]
    if not files:
        return None
    try:
        import_stable_baselines3()
    except ImportError as exc:
        return str(exc)
    missing = [f for f in files if not (SHIPPED_MODELS_DIR / f).is_file()]
    return f"models not shipped: {', '.join(missing)}" if missing else None


def _model_file(short: str, slug: str) -> str:
    """The file of a shipped model's short name on an env (``ppo-nullspace-dynamics``, ``agri_reach`` ->
    ``ppo-nullspace-agri_reach-dynamics.zip``)."""
    learner, action, *variant = short.split("-")
    return f"{learner}-{action}-{slug}" + "".join(f"-{v}" for v in variant) + ".zip"


def _summary(setting: RobustnessSetting, report: Mapping[str, Any]) -> dict[str, Any]:
    """What the table keeps of an evaluation-contract report: success, the failure rates, the setting's errors
    (in their units), the median step time and the seeds of the failed episodes."""
    out: dict[str, Any] = {
        "success_rate": float(report["success_rate"]),
        setting.rate: float(report.get(setting.rate) or 0.0),
        "step_time_median_us": float(report["step_time_us"]["median"]),
        "failed_seeds": [int(e["seed"]) for e in report["per_episode"] if not e["success"]],
    }
    if "obstacle_contact_rate" in report:
        out["obstacle_contact_rate"] = float(report["obstacle_contact_rate"])
    for name in setting.errors:
        out[name] = METRICS[name].value(report)
    return out


def run_robustness_bench(
    *,
    episodes: int = 10,
    seed: int = HELD_OUT_SEED,
    envs: Sequence[str] | None = None,
    conditions: Sequence[Condition] = CONDITIONS,
    progress: bool = True,
    log: Callable[[str], None] | None = print,
    workers: int = 1,
) -> dict[str, Any]:
    """Evaluate every reference of each env under every condition on ``episodes`` episodes from ``seed`` (the
    same seeds in every condition).

    Args:
        envs: keys of :data:`ROBUSTNESS_SETTINGS` (default: all).
        conditions: the plants (default :data:`CONDITIONS`).
        workers: processes each evaluation's episodes are split across (the table is the serial one's, step times
            excepted).

    Returns:
        The table as JSON: ``conditions`` (label, dynamics, axis, x, latency), and per env, per reference label, per
        condition label, the :func:`_summary` of its evaluation.
    """
    if isinstance(episodes, bool) or not isinstance(episodes, int) or episodes < 1:
        raise BenchError(f"episodes must be an int >= 1, got {episodes!r}")
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise BenchError(f"workers must be an int >= 1, got {workers!r}")
    chosen = [_setting(k) for k in envs] if envs else list(ROBUSTNESS_SETTINGS)
    learned_skipped = _learned_skipped(chosen)
    table: dict[str, Any] = {
        "episodes": episodes,
        "seed": seed,
        "machine": machine(),
        "conditions": [c.__dict__ for c in conditions],
        "envs": {},
    }
    if learned_skipped:
        table["learned_skipped"] = learned_skipped
        if log is not None:
            log(f"learned rows left out: {learned_skipped}")
    for setting in chosen:
        learned = {} if learned_skipped else setting.learned
        runs = {label: (setting.env_id, policy, options) for label, (policy, options) in setting.references.items()}
        runs.update({label: (env_id, policy, {}) for label, (env_id, policy) in learned.items()})
        rows: dict[str, dict[str, Any]] = {label: {} for label in runs}
        for condition in conditions:
            for label, (env_id, policy, options) in runs.items():
                if log is not None:
                    log(f"{setting.title}: {label} on {condition.label}")
                env_kwargs = dict(setting.env_kwargs)
                if condition.dynamics is not None:
                    env_kwargs["dynamics"] = condition.dynamics
                report = evaluate(
                    env_id,
                    policy,
                    episodes=episodes,
                    seed=seed,
                    env_kwargs=env_kwargs,
                    policy_kwargs=options,
                    progress=progress,
                    warmup=1,
                    workers=workers,
                ).to_json()
                rows[label][condition.label] = _summary(setting, report)
        table["envs"][setting.key] = {
            "title": setting.title,
            "env_id": setting.env_id,
            "env_kwargs": setting.env_kwargs,
            "errors": list(setting.errors),
            "rate": setting.rate,
            "rows": rows,
        }
    return table


def _fmt(value: float | None) -> str:
    if value is None or not math.isfinite(value):
        return "n/a"
    if value == 0.0:
        return "0"
    return f"{value:.0f}" if abs(value) >= 100.0 else f"{value:.3g}"


def _holds(cell: Mapping[str, Any], rate: str, nominal: Mapping[str, Any] | None = None) -> bool:
    """Whether a reference holds a condition: success >= :data:`SUCCESS_THRESHOLD` and no failure, or, for a
    reference below that on the nominal plant already, no lower success and no higher failure rate than there."""
    if nominal is None or _holds(nominal, rate):
        return cell["success_rate"] >= SUCCESS_THRESHOLD and cell[rate] == 0.0
    return cell["success_rate"] >= nominal["success_rate"] and cell[rate] <= nominal[rate]


def _breaks(env: Mapping[str, Any], label: str, conditions: Sequence[Mapping[str, Any]]) -> str:
    """Where the reference ``label`` breaks along each axis: the first condition it does not hold (:func:`_holds`),
    or that it holds throughout."""
    cells, rate = env["rows"][label], env["rate"]
    failure = rate.removesuffix("_rate")
    nominal = cells.get("nominal")
    parts = []
    if nominal is not None and not _holds(nominal, rate):
        parts.append(
            f"below the threshold on the nominal plant already (success {nominal['success_rate']:.2f}, {failure} "
            f"rate {nominal[rate]:.2f}; judged against that below)"
        )
    for axis, name in (("level", "model error"), ("latency", "latency"), ("shorthand", "the level shorthand")):
        along = sorted((c for c in conditions if c["axis"] == axis or c["label"] == "nominal"), key=lambda c: c["x"])
        broken = next((c for c in along if c["label"] in cells and not _holds(cells[c["label"]], rate, nominal)), None)
        if broken is None:
            last = along[-1]["label"] if along else "-"
            parts.append(f"{name}: holds through {last}")
        else:
            cell = cells[broken["label"]]
            parts.append(
                f"{name}: breaks at {broken['label']} (success {cell['success_rate']:.2f}, {failure} rate "
                f"{cell[rate]:.2f})"
            )
    return f"**{label}**: " + "; ".join(parts) + "."


def robustness_markdown(table: Mapping[str, Any], *, command: str = "redundancy-gym bench robustness") -> str:
    """The table as markdown: per env, a row per reference and condition, and where each reference breaks."""
    conditions = table["conditions"]
    lines = [
        f"`{command}`: {table['episodes']} episodes per reference and condition from seed {table['seed']} (the same "
        f"seeds in every condition); a reference holds a condition with success >= {SUCCESS_THRESHOLD} and no "
        "failure. Levels: every scale +-L, CoM offsets and placement up to L/10 m, the ground's friction +-3L, a "
        "payload up to 10 L kg (arms), no latency; latencies: nothing else changed; `dynamics=L`: the level with "
        "floor(10 L) periods of latency.",
        "",
    ]
    for env in table["envs"].values():
        metrics = [METRICS[name] for name in env["errors"]]
        rate = env["rate"]
        lines += [f"### {env['title']}", ""]
        head = ["reference", "plant", "success", rate.replace("_", " ")]
        has_contacts = any("obstacle_contact_rate" in cell for row in env["rows"].values() for cell in row.values())
        if has_contacts:
            head.append("obstacle contact rate")
        head += [m.heading for m in metrics] + ["step median [us]"]
        lines += ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
        for label, cells in env["rows"].items():
            for condition in conditions:
                cell = cells.get(condition["label"])
                if cell is None:
                    continue
                row = [label, condition["label"], f"{cell['success_rate']:.2f}", f"{cell[rate]:.2f}"]
                if has_contacts:
                    row.append(f"{cell.get('obstacle_contact_rate', 0.0):.2f}")
                row += [_fmt(cell.get(name)) for name in env["errors"]]
                row.append(_fmt(cell["step_time_median_us"]))
                lines.append("| " + " | ".join(row) + " |")
        lines.append("")
        lines += [_breaks(env, label, conditions) for label in env["rows"]]
        lines.append("")
    return "\n".join(lines)


def plot_robustness_bench(table: Mapping[str, Any], out: str | Path, *, prefix: str = "robustness_") -> list[Path]:
    """One figure per env (``<out>/<prefix><env>.png``): success (top) and the first error (bottom) against the
    level (left, no latency) and against the latency (right, no other change), a line per reference."""
    out = Path(out)
    conditions = table["conditions"]
    written = []
    for key, env in table["envs"].items():
        metric = METRICS[env["errors"][0]]
        fig, axes = plt.subplots(2, 2, figsize=(9.5, 6.0), sharey="row")
        for column, (axis, xlabel) in enumerate(
            (("level", "model-error level L [-]"), ("latency", "latency [periods]"))
        ):
            along = sorted(
                (c for c in conditions if c["axis"] == axis or c["label"] == "nominal"), key=lambda c: c["x"]
            )
            for k, (label, cells) in enumerate(env["rows"].items()):
                xs = [c["x"] for c in along if c["label"] in cells]
                present = [cells[c["label"]] for c in along if c["label"] in cells]
                style = {"marker": "os^D"[k % 4], "label": label, "linestyle": "-" if k % 2 == 0 else "--"}
                axes[0, column].plot(xs, [c["success_rate"] for c in present], **style)
                values = [c.get(env["errors"][0]) for c in present]  # in the metric's unit; None: undefined
                axes[1, column].plot(xs, [math.nan if v is None else v for v in values], **style)
            axes[1, column].set_xlabel(xlabel)
            for row in axes[:, column]:
                row.set_xticks(sorted({c["x"] for c in along}))
        axes[0, 0].set_ylabel("success rate")
        axes[0, 0].set_ylim(-0.05, 1.05)
        axes[1, 0].set_ylabel(metric.heading)
        axes[0, 0].axhline(SUCCESS_THRESHOLD, color="0.6", linewidth=0.8, linestyle=":")
        axes[0, 1].axhline(SUCCESS_THRESHOLD, color="0.6", linewidth=0.8, linestyle=":")
        axes[0, 0].legend(fontsize=8, loc="lower left")
        fig.suptitle(f"{env['title']}: the references on a plant that differs from their model")
        written.append(save_figure(fig, out / f"{prefix}{key}.png"))
    return written
