"""The learned baselines of ``redundancy_gym/baselines/`` (``baselines/`` of a clone, installed with the package):
one YAML file per trained model, named like the model (``<learner>-<action>-<env>.yaml`` ->
``baselines/models/<learner>-<action>-<env>.zip``), trained reproducibly by :func:`train_baseline`
(``redundancy-gym baselines``, ``make baselines``).

A file holds one section in the layout of ``configs/`` (rl-zoo3), keyed by the env id trained on (the wrapped id
for a wrapper's action, e.g. ``redundancy_gym/AgriReach-Residual-v0``); for ``bc`` its keys are
:func:`~redundancy_gym.learning.behaviour_cloning.train_behaviour_cloning`'s options. Every PPO/SAC run is seeded
(seed 0), evaluated every tenth of its budget on 5 episodes from seed
:data:`~redundancy_gym.learning.training.EVAL_CALLBACK_SEED` (apart from the table's held-out seeds) and ships the
evaluation's best agent; its TensorBoard logs go to ``runs/baselines_tb``, its checkpoints and last agent to
``runs/baselines/``. Next to each model goes its training record (``.json``: steps, wall and CPU time).
"""

from __future__ import annotations

import shutil
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..policies.shipped_models import ACTIONS, LEARNERS, SHIPPED_MODELS_DIR, VARIANTS, model_name
from ..registration import ENV_IDS
from .exceptions import LearningError
from .training_record import TrainingRecord, read_training_record, record_path

__all__ = ["BASELINES_DIR", "Baseline", "baselines", "train_baseline"]

BASELINES_DIR = SHIPPED_MODELS_DIR.parent
"""``redundancy_gym/baselines/`` (package data; ``baselines/`` of a clone is a symlink to it): the YAML files and
``models/``, which the wheel ships, and the generated ``results/`` of a clone, which it does not."""
EVALUATIONS = 10  # evaluations of the callback over a run
CHECKPOINTS = 4  # checkpoints over a run
EVAL_EPISODES = 5


@dataclass(frozen=True)
class Baseline:
    """One trained baseline.

    Attributes:
        name: ``<learner>-<action>-<env>[-<variant>]`` (the file stem).
        learner: ``ppo``, ``sac`` or ``bc``; action: the action space (``joint`` or a wrapper's name).
        env_id: the env id trained and evaluated on (a wrapped id for a wrapper's action).
        config: the YAML file.
        slug: the env's name in the file name (``agri_reach``).
        variant: how it was trained differently from its nominal twin (``dynamics``), None for the twin itself.
    """

    name: str
    learner: str
    action: str
    env_id: str
    config: Path
    slug: str = ""
    variant: str | None = None

    @property
    def short_name(self) -> str:
        """``<learner>-<action>[-<variant>]``: the name ``make_policy`` and ``eval --policy`` take on the env."""
        return f"{self.learner}-{self.action}" + ("" if self.variant is None else f"-{self.variant}")

    @property
    def model(self) -> Path:
        """The shipped model (``baselines/models/<name>.zip``)."""
        return SHIPPED_MODELS_DIR / f"{self.name}.zip"

    @property
    def env_kwargs(self) -> dict[str, Any]:
        """The file's ``env_kwargs``: the env (and wrapper) options the model was trained with, and is evaluated
        with (e.g. a ``WalkingCommandAction``'s ``command_period``)."""
        from .training import load_config

        return dict(load_config(self.config, self.env_id).env_kwargs)

    def record(self) -> TrainingRecord | None:
        """The training record beside the shipped model, None when there is none."""
        return read_training_record(self.model)


def _parse(path: Path) -> Baseline:
    import yaml

    try:
        learner, action, slug, variant = model_name(path.stem)
    except ValueError:
        raise LearningError(
            f"{path.name}: a baseline is named <learner>-<action>-<env>[-<variant>].yaml with learner in "
            f"{', '.join(LEARNERS)}, action in {', '.join(ACTIONS)} and variant in {', '.join(VARIANTS)}"
        ) from None
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise LearningError(f"cannot read {path}: {exc}") from None
    if not isinstance(data, dict) or len(data) != 1 or next(iter(data)) not in ENV_IDS:
        raise LearningError(
            f"{path}: a baseline holds one section keyed by a registered env id; found "
            f"{', '.join(map(str, data)) if isinstance(data, dict) else type(data).__name__}"
        )
    return Baseline(path.stem, learner, action, next(iter(data)), path, slug, variant)


def baselines(names: Sequence[str] = (), directory: str | Path | None = None) -> list[Baseline]:
    """The baselines of ``directory``'s YAML files (all, or those named, in the order given; default directory:
    :data:`BASELINES_DIR`).

    Raises:
        LearningError: no baseline file in ``directory`` (the message names it), a name without a file (the message
            lists the files), or a file not named or laid out as a baseline.
    """
    directory = BASELINES_DIR if directory is None else directory
    found = {p.stem: p for p in sorted(Path(directory).glob("*.yaml"))}
    if not found:
        where = (
            "does not exist"
            if not Path(directory).is_dir()
            else "holds no baseline file (<learner>-<action>-<env>.yaml)"
        )
        raise LearningError(f"no baselines found: {directory} {where}")
    missing = [n for n in names if n not in found]
    if missing:
        raise LearningError(f"no baseline {', '.join(missing)} in {directory}; baselines: {', '.join(found) or 'none'}")
    return [_parse(found[n]) for n in (names or list(found))]


def train_baseline(
    baseline: Baseline,
    *,
    work_dir: str | Path = "runs/baselines",
    tensorboard_log: str | None = "runs/baselines_tb",
    models_dir: str | Path = SHIPPED_MODELS_DIR,
    steps: int | None = None,
    log: Callable[[str], None] | None = print,
) -> Path:
    """Train ``baseline`` as its YAML file says (seed 0) and copy the model and its training record into
    ``models_dir``; returns the model's path there.

    Args:
        work_dir: where the run writes its checkpoints, last agent and evaluation's best agent.
        tensorboard_log: TensorBoard directory of PPO/SAC runs (None: none).
        models_dir: where the model and its record go.
        steps: the PPO/SAC budget instead of the file's ``n_timesteps`` (a smoke test's); None: the file's.
        log: where progress lines go.
    """
    from .training import load_config, train

    config = load_config(baseline.config, baseline.env_id)
    work = Path(work_dir) / f"{baseline.name}.zip"
    if baseline.learner == "bc":
        from .behaviour_cloning import train_behaviour_cloning

        options: dict[str, Any] = dict(config.hyperparameters)
        if "net_arch" in options:
            options["net_arch"] = tuple(options["net_arch"])
        train_behaviour_cloning(
            baseline.env_id, work, env_kwargs=config.env_kwargs, seed=0, progress=False, log=log, **options
        )
    else:
        budget = steps if steps is not None else config.n_timesteps
        if budget is None:
            raise LearningError(f"{baseline.config}: n_timesteps is missing")
        n_envs = config.n_envs or 1
        # PPO learns once per rollout of n_steps x n_envs steps: evaluating more often would see the same agent
        rollout = n_envs * int(config.hyperparameters.get("n_steps", 2048) if baseline.learner == "ppo" else 1)
        train(
            baseline.env_id,
            baseline.learner,
            budget,
            work,
            seed=0,
            env_kwargs=config.env_kwargs,
            hyperparameters=config.hyperparameters,
            policy=config.policy,
            n_envs=n_envs,
            progress_bar=False,
            tensorboard_log=tensorboard_log,
            log=log,
            eval_freq=max(rollout, budget // EVALUATIONS),
            eval_episodes=EVAL_EPISODES,
            checkpoint_freq=max(rollout, budget // CHECKPOINTS),
            keep="best",
        )
    target = Path(models_dir) / f"{baseline.name}.zip"
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(work, target)
    shutil.copyfile(record_path(work), record_path(target))
    return target
