"""One learner's learning curve: trained in segments up to a list of budgets, evaluated on held-out seeds at each,
resumable (the ``learn`` extra; TQC and CrossQ from sb3-contrib, which it brings).

A run keeps its state in a folder: ``<name>.json`` (settings and the points so far, written after every point and
checkpoint), and in ``agents`` (the same folder by default) ``<name>.zip`` (the agent at the last point or checkpoint;
off-policy learners also ``<name>_replay.pkl``, their replay buffer; a run with ``normalize`` also
``<name>_vecnormalize.pkl``, SB3's ``VecNormalize`` statistics, which the evaluation's policy reads beside the
``.zip``). Within a segment the agent (and buffer) is saved every ``checkpoint_every`` environment steps (100k
on-policy, 20k off-policy by default) and the state notes the steps saved (``checkpoint_steps``); a checkpoint is
written to temporary files moved into place, the state last, so a run killed while saving keeps the one before whole.
Called again, it loads the agent (and buffer) and trains on to the next budget, so an interrupted or extended study
loses at most the steps since the last checkpoint. The agents folder may be shared by several state folders: a run
without points refuses to start over an agent already there, and a resumed agent must have trained the steps its state
says (either is another run's). A resumed run is not bitwise the uninterrupted one (the envs restart from fresh resets);
its points are still each a trained agent's at that many environment steps.

Each point: the environment steps actually taken (SB3 finishes a PPO rollout, so a budget is met or passed), the
training's CPU and wall time so far [s] (this process: envs stepped in it, torch on ``torch_threads`` threads, every
thread's CPU time counted; the evaluations excluded), the threads of the segment that reached it (not a setting: a run
resumes on any number of them), and the deterministic agent's evaluation on ``eval_episodes`` held-out episodes from
``eval_seed`` through the evaluation harness (success rate, the failure rate, the env's error measures, return, episode
length).
"""

from __future__ import annotations

import functools
import json
import math
import os
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from ..eval.evaluate import evaluate, make_env
from ..policies.sb3_policy import vecnormalize_path
from ..sb3_import import LEARN_EXTRA_HINT, import_stable_baselines3, set_torch_threads, silent_logger
from .exceptions import LearningError
from .training_record import CpuClock

__all__ = ["CURVE_ALGOS", "POINT_METRICS", "CurveRun", "budgets_between", "train_learning_curve"]

CURVE_ALGOS: dict[str, tuple[str, str, bool]] = {
    "ppo": ("stable_baselines3", "PPO", False),
    "sac": ("stable_baselines3", "SAC", True),
    "tqc": ("sb3_contrib", "TQC", True),
    "crossq": ("sb3_contrib", "CrossQ", True),
}
"""algo -> (module, class, off-policy: keeps a replay buffer between segments)."""

POINT_METRICS: tuple[str, ...] = (
    "success_rate",
    "collision_rate",
    "fall_rate",
    "tracking_error_rms",
    "tracking_error_max",
    "goal_error",
    "speed_error",
    "forward_speed",
    "episode_return",
    "episode_length",
)
"""The evaluation contract's fields a point keeps (those the env defines)."""


@dataclass(frozen=True)
class CurveRun:
    """One learner on one env with one seed.

    Attributes:
        name: the run's file stem (``planar_reach-ppo-s0``).
        env_id: the env trained and evaluated on (a wrapped id for a wrapper's action).
        env_kwargs: its ``gym.make`` keyword arguments.
        algo: a key of :data:`CURVE_ALGOS`.
        seed: the agent's seed (its env is reset with it first).
        budgets: the environment steps at which to evaluate, increasing.
        hyperparameters: the algorithm's constructor keyword arguments.
        eval_episodes, eval_seed: the held-out evaluation episodes of every point.
        torch_threads: torch's CPU threads while training.
        normalize: train behind SB3's ``VecNormalize`` (observations and rewards normalized by running
            statistics, observations clipped to +-10, rl-zoo3's ``normalize: true``; the statistics frozen for
            the evaluations).
        train_env_kwargs: keyword arguments on top of ``env_kwargs`` for the training env only (a reward variant,
            such as another ``energy_weight``); every point is evaluated on ``env_kwargs`` alone, so its success,
            error and return compare with the other learners' and the references'.
    """

    name: str
    env_id: str
    env_kwargs: dict[str, Any]
    algo: str
    seed: int
    budgets: tuple[int, ...]
    hyperparameters: dict[str, Any]
    eval_episodes: int = 10
    eval_seed: int = 40000
    torch_threads: int = 1
    normalize: bool = False
    train_env_kwargs: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.algo not in CURVE_ALGOS:
            raise LearningError(f"unknown algo {self.algo!r}; valid: {', '.join(CURVE_ALGOS)}")
        if not self.budgets or any(int(b) < 1 for b in self.budgets) or list(self.budgets) != sorted(self.budgets):
            raise LearningError(f"budgets must be increasing ints >= 1, got {self.budgets!r}")
        if self.eval_episodes < 1:
            raise LearningError(f"eval_episodes must be >= 1, got {self.eval_episodes!r}")

    def settings(self) -> dict[str, Any]:
        """What a state file must match to be resumed (the budgets may grow)."""
        kept = asdict(self)
        # threads change only the order of float sums, not the experiment: a run resumes on any number of them
        kept.pop("budgets")
        kept.pop("torch_threads")
        # states written before these options existed stay valid
        if not self.normalize:
            kept.pop("normalize")
        if not self.train_env_kwargs:
            kept.pop("train_env_kwargs")
        return kept


def _load_state(path: Path, run: CurveRun) -> dict[str, Any]:
    if not path.is_file():
        return {"settings": run.settings(), "points": [], "cpu_s": 0.0, "wall_s": 0.0}
    state: dict[str, Any] = json.loads(path.read_text())
    kept = {k: v for k, v in state.get("settings", {}).items() if k != "torch_threads"}  # earlier states record them
    if kept != json.loads(json.dumps(run.settings())):
        raise LearningError(
            f"{path} was made with other settings ({state.get('settings')}); delete it (and its .zip) to restart, "
            "or keep its settings"
        )
    return state


def _write_whole(savers: dict[Path, Callable[[str], Any]], state_path: Path, state: dict[str, Any]) -> None:
    """Write each file through its saver (none for a point's state alone) to a temporary name beside it, then move
    them all into place, the state last: a run killed while writing (a replay buffer takes seconds to pickle) keeps
    its previous checkpoint whole instead of a truncated buffer or an agent ahead of its state."""
    temporary = {path: path.with_name(path.name + ".partial") for path in [*savers, state_path]}
    for path, save in savers.items():
        save(str(temporary[path]))
    temporary[state_path].write_text(json.dumps(state, indent=1) + "\n")
    for path in [*savers, state_path]:
        os.replace(temporary[path], path)


def train_learning_curve(
    run: CurveRun,
    folder: str | Path,
    *,
    agents: str | Path | None = None,
    checkpoint_every: int | None = None,
    log: Callable[[str], None] | None = print,
) -> dict[str, Any]:
    """Train ``run`` on to its last budget from where its state in ``folder`` (its agent in ``agents``, default
    ``folder``) left off, saving the agent every ``checkpoint_every`` environment steps (default: 100 000 on-policy,
    20 000 off-policy, whose steps cost tens of times more CPU time) (module docstring); returns
    the state: ``{"settings", "points": [...], "cpu_s", "wall_s"}``. A state with points or a checkpoint whose agent
    is missing raises :class:`LearningError` (its points are kept)."""
    if checkpoint_every is not None and checkpoint_every < 1:
        raise LearningError(f"checkpoint_every must be >= 1 environment step, got {checkpoint_every!r}")
    try:
        import_stable_baselines3()
        import importlib

        module_name, class_name, off_policy = CURVE_ALGOS[run.algo]
        every = checkpoint_every or (20_000 if off_policy else 100_000)
        cls = getattr(importlib.import_module(module_name), class_name)
        from stable_baselines3.common.env_util import make_vec_env
        from stable_baselines3.common.vec_env import DummyVecEnv, VecNormalize
    except ImportError as exc:
        raise LearningError(f"learning curves need the learn extra: {LEARN_EXTRA_HINT}") from exc
    folder = Path(folder)
    store = Path(agents) if agents is not None else folder
    folder.mkdir(parents=True, exist_ok=True)
    store.mkdir(parents=True, exist_ok=True)
    state_path, model_path = folder / f"{run.name}.json", store / f"{run.name}.zip"
    replay_path = store / f"{run.name}_replay.pkl"
    stats_path = vecnormalize_path(model_path)
    state = _load_state(state_path, run)
    reached = state["points"][-1]["steps"] if state["points"] else 0
    todo = [int(b) for b in run.budgets if int(b) > reached]
    if not todo:
        return state
    # steps trained past the last point, saved at a checkpoint of an interrupted segment
    reached = max(reached, int(state.get("checkpoint_steps", 0)))
    if reached and not model_path.is_file():
        raise LearningError(
            f"{state_path} has points or a checkpoint but its agent {model_path} is missing; delete the .json to "
            "restart"
        )
    # the agents folder is shared by every state folder (every --json): a run starting afresh must not overwrite
    # the agent of a same-named run whose state lives elsewhere (hours of off-policy training)
    stale = [p for p in (model_path, replay_path, stats_path) if p.is_file()]
    if not reached and stale:
        raise LearningError(
            f"{state_path} has no points, but {stale[0]} exists: the agent of a run of the same name whose state is "
            "in another folder (another --json), or of a deleted state; move it away, or delete it (and its "
            "_replay.pkl / _vecnormalize.pkl) to start this run afresh"
        )
    restore_threads = set_torch_threads(run.torch_threads)
    # our envs and wrapped ids report is_success; SB3's Monitor records it per episode
    monitor = {"info_keywords": ("is_success",) if run.env_id.startswith("redundancy_gym/") else ()}
    env = make_vec_env(
        functools.partial(make_env, run.env_id, {**run.env_kwargs, **run.train_env_kwargs}),
        n_envs=1,
        seed=run.seed + reached,  # a resumed segment starts from other resets than the first did
        vec_env_cls=DummyVecEnv,
        monitor_kwargs=monitor,
    )
    normalizer: VecNormalize | None = None
    if run.normalize:
        if reached:
            if not stats_path.is_file():
                env.close()
                raise LearningError(f"{state_path} normalizes, but its statistics {stats_path} are missing")
            normalizer = VecNormalize.load(str(stats_path), env)
            normalizer.training = True
        else:
            gamma = float(run.hyperparameters.get("gamma", 0.99))
            normalizer = VecNormalize(env, norm_obs=True, norm_reward=True, clip_obs=10.0, gamma=gamma)
        env = normalizer
    try:
        if reached:
            model = cls.load(str(model_path), env=env, device="cpu")
            if int(model.num_timesteps) != reached:
                raise LearningError(
                    f"{model_path} has trained {int(model.num_timesteps)} steps, but {state_path} says {reached}: "
                    "it is another run's agent; restore this run's, or delete both to restart"
                )
            if off_policy and replay_path.is_file():
                model.load_replay_buffer(str(replay_path))
        else:
            try:
                model = cls("MlpPolicy", env, seed=run.seed, device="cpu", verbose=0, **run.hyperparameters)
            except TypeError as exc:
                raise LearningError(f"invalid {class_name} hyperparameters: {exc}") from None
        model.set_logger(silent_logger())
        for budget in todo:
            # SB3 ends a learn() call only after a whole PPO rollout: a budget already passed is evaluated as is
            while int(model.num_timesteps) < budget:
                with CpuClock() as clock:
                    model.learn(
                        total_timesteps=min(budget - int(model.num_timesteps), every),
                        reset_num_timesteps=False,
                        progress_bar=False,
                    )
                state["cpu_s"] += clock.cpu_s
                state["wall_s"] += clock.wall_s
                state["checkpoint_steps"] = int(model.num_timesteps)
                _write_whole(
                    {
                        model_path: model.save,
                        **({replay_path: model.save_replay_buffer} if off_policy else {}),
                        **({stats_path: normalizer.save} if normalizer is not None else {}),
                    },
                    state_path,
                    state,
                )
            report = evaluate(
                run.env_id,
                str(model_path),
                episodes=run.eval_episodes,
                seed=run.eval_seed,
                env_kwargs=run.env_kwargs,
                policy_kwargs={"algo": class_name},
                progress=False,
            ).to_json()
            point: dict[str, Any] = {
                "steps": int(model.num_timesteps),
                "budget": budget,
                "cpu_s": round(state["cpu_s"], 2),
                "wall_s": round(state["wall_s"], 2),
                "torch_threads": run.torch_threads,
            }
            for key in POINT_METRICS:
                value = report.get(key)
                if isinstance(value, (int, float)) and math.isfinite(float(value)):
                    point[key] = float(value)
            state["points"].append(point)
            state.pop("checkpoint_steps", None)
            _write_whole({}, state_path, state)
            if log is not None:
                success, ret = point.get("success_rate", math.nan), point.get("episode_return", math.nan)
                log(
                    f"{run.name}: {point['steps']} steps, {point['cpu_s'] / 60:.1f} CPU-min, success {success:.2f}, "
                    f"return {ret:.1f}"
                )
    finally:
        env.close()
        restore_threads()
    return state


def budgets_between(first: int, last: int, per_decade: int = 2) -> tuple[int, ...]:
    """Logarithmically spaced budgets from ``first`` to ``last`` (both kept), ``per_decade`` per factor 10, rounded
    to 1-2-3-5 style round numbers (10k, 30k, 100k, ... at 2 per decade)."""
    if first < 1 or last < first or per_decade < 1:
        raise LearningError(f"budgets need 1 <= first <= last and per_decade >= 1, got {first}, {last}, {per_decade}")
    out: list[int] = []
    k = 0
    while True:
        value = first * 10 ** (k / per_decade)
        if value > last * (1 + 1e-9):
            break
        digits = 10 ** math.floor(math.log10(value))
        out.append(int(round(value / digits) * digits))
        k += 1
    if out[-1] != last:
        out.append(last)
    return tuple(sorted(set(out)))
