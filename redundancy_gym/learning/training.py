"""Training stable-baselines3 agents on the registered envs (the ``learn`` extra).

Hyperparameters are read from the YAML files of ``configs/`` (:data:`CONFIGS_DIR`, installed with the package) in
the rl-zoo3 layout: one file per algorithm, keyed by env id, each section holding SB3 constructor keyword arguments
plus rl-zoo3's own keys (``policy``, ``n_timesteps``, ``n_envs``, ``normalize``, ``env_kwargs``, ...). The same
file trains with ``redundancy-gym train --config`` and with ``python -m rl_zoo3.train -conf``.

While it trains, :func:`train` prints a line every ``print_every`` steps with the mean return, success rate
and length of the recent episodes, and a summary at the end.
"""

from __future__ import annotations

import functools
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..eval.evaluate import make_env
from ..registration import ENV_IDS
from ..sb3_import import LEARN_EXTRA_HINT, import_stable_baselines3, set_torch_threads, silent_logger
from .exceptions import LearningError
from .training_record import CpuClock, TrainingRecord, machine

__all__ = [
    "ALGOS",
    "CONFIGS_DIR",
    "EVAL_CALLBACK_SEED",
    "KEEP",
    "LEARN_EXTRA_HINT",
    "VEC_ENVS",
    "LinearSchedule",
    "TrainingConfig",
    "TrainingSummary",
    "load_config",
    "load_hyperparameters",
    "train",
]

ALGOS: tuple[str, ...] = ("ppo", "sac")
KEEP: tuple[str, ...] = ("last", "best")
EVAL_CALLBACK_SEED = 30000
"""First seed of the episodes the training-time evaluation callback runs: apart from the seeds results are reported
on (the learned-baselines table uses 21000 onwards)."""
VEC_ENVS: tuple[str, ...] = ("dummy", "subproc", "sync", "async")
"""SB3's vector envs by name: ``dummy`` (= ``sync``, every env in this process) and ``subproc`` (= ``async``, one
process per env), as Gymnasium's ``make_vec`` names them too."""
DEFAULT_POLICY = "MlpPolicy"
CONFIGS_DIR = Path(__file__).resolve().parents[1] / "configs"
"""``redundancy_gym/configs/``: the rl-zoo3 configs, package data (``configs/`` of a clone is a symlink to it)."""
# the folders of package data that the README's commands name relative to a clone (configs/..., baselines/...)
_PACKAGE_DATA_DIRS = {"configs": CONFIGS_DIR, "baselines": CONFIGS_DIR.parent / "baselines"}
RECENT_EPISODES = 20  # episodes averaged in the printed statistics

# rl-zoo3 keys that change the training set-up in ways `redundancy-gym train` does not reproduce
_ZOO_ONLY = (
    "env_wrapper",
    "vec_env_wrapper",
    "callback",
    "frame_stack",
    "monitor_kwargs",
    "noise_type",
    "noise_std",
    "replay_buffer_class",
    "replay_buffer_kwargs",
)
# keys that rl-zoo3 reads as schedules ("lin_<initial value>": linear decay to 0)
_SCHEDULE_KEYS = ("learning_rate", "clip_range", "clip_range_vf", "delta_std")


class LinearSchedule:
    """Linear decay from ``initial`` to 0 over training (rl-zoo3's ``lin_<value>``); picklable."""

    def __init__(self, initial: float) -> None:
        self.initial = float(initial)

    def __call__(self, progress_remaining: float) -> float:
        return progress_remaining * self.initial

    def __repr__(self) -> str:
        return f"lin_{self.initial:g}"


@dataclass(frozen=True)
class TrainingConfig:
    """One env's section of an rl-zoo3 hyperparameter file.

    Attributes:
        hyperparameters: SB3 constructor keyword arguments (schedules and ``policy_kwargs`` already converted).
        policy: SB3 policy name (``policy``; default ``MlpPolicy``).
        n_timesteps: training steps (``n_timesteps``), the default of ``--steps``; None when absent.
        n_envs: parallel envs (``n_envs``), the default of ``--n-envs``; None when absent.
        env_kwargs: keyword arguments for ``gym.make`` (``env_kwargs``).
    """

    hyperparameters: dict[str, Any]
    policy: str = DEFAULT_POLICY
    n_timesteps: int | None = None
    n_envs: int | None = None
    env_kwargs: dict[str, Any] = field(default_factory=dict)


def _policy_kwargs(value: Any, path: Path) -> dict[str, Any]:
    if isinstance(value, dict):
        return value
    if isinstance(value, str):  # rl-zoo3 writes them as Python, e.g. "dict(net_arch=[64, 64], activation_fn=nn.Tanh)"
        import torch

        try:
            result = eval(value, {"__builtins__": {}, "dict": dict, "list": list, "nn": torch.nn, "th": torch})
        except Exception as exc:
            raise LearningError(f"{path}: cannot read policy_kwargs {value!r}: {exc}") from None
        if isinstance(result, dict):
            return result
    raise LearningError(f"{path}: policy_kwargs must be a mapping or a dict(...) expression, got {value!r}")


def _config_path(path: Path) -> Path:
    """``path``; where no such file exists and it reads ``configs/NAME`` or ``baselines/NAME`` (as the README writes
    them, relative to a clone), the package's own copy, so that an installed package runs those commands from any
    folder. A file that exists always wins: a user's own ``configs/`` is never shadowed."""
    if path.is_file() or path.is_absolute() or len(path.parts) < 2 or path.parts[0] not in _PACKAGE_DATA_DIRS:
        return path
    shipped = _PACKAGE_DATA_DIRS[path.parts[0]].joinpath(*path.parts[1:])
    return shipped if shipped.is_file() else path


def load_config(path: str | Path, env_id: str) -> TrainingConfig:
    """Read the section of ``env_id`` (or ``default``) from an rl-zoo3 hyperparameter YAML file.

    ``path`` is a file, or ``configs/NAME`` / ``baselines/NAME`` of the package's data where no such file exists
    (an installed package has no clone to run from).

    Raises:
        LearningError: unreadable file, no section for the env, or rl-zoo3 options this trainer does not reproduce
            (wrappers, callbacks, action noise, ``normalize: true``; train with ``rl_zoo3.train`` for those).
    """
    import yaml

    path = _config_path(Path(path))
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError) as exc:
        raise LearningError(f"cannot read {path}: {exc}") from None
    if not isinstance(data, dict):
        raise LearningError(f"{path} must map env ids to hyperparameters (the rl-zoo3 layout, see configs/)")
    if env_id not in data and "default" not in data and not any(isinstance(v, dict) for v in data.values()):
        raise LearningError(
            f"{path} must map env ids to hyperparameters (the rl-zoo3 layout): put its keys under "
            f"'{env_id}:' (see configs/)"
        )
    if env_id in data:
        section = data[env_id]
    elif "default" in data:
        section = data["default"]
    else:
        raise LearningError(
            f"{path} has no section for {env_id} (nor 'default'); sections: {', '.join(map(str, data)) or 'none'}"
        )
    if not isinstance(section, dict):
        raise LearningError(f"{path}: the section of {env_id} must be a mapping of hyperparameters")
    hyper = dict(section)
    unsupported = sorted(k for k in hyper if k in _ZOO_ONLY)
    if hyper.get("normalize"):
        unsupported.append("normalize")
    if unsupported:
        raise LearningError(
            f"{path}: {', '.join(unsupported)} not supported by redundancy-gym train (the .zip must hold "
            "the whole policy); train with python -m rl_zoo3.train for these"
        )
    policy = hyper.pop("policy", DEFAULT_POLICY)
    if not isinstance(policy, str) or "." in policy:
        raise LearningError(f"{path}: policy must be an SB3 policy name such as MlpPolicy, got {policy!r}")
    n_timesteps = hyper.pop("n_timesteps", None)
    n_envs = hyper.pop("n_envs", None)
    hyper.pop("normalize", None)
    env_kwargs = hyper.pop("env_kwargs", None) or {}
    if not isinstance(env_kwargs, dict):
        raise LearningError(f"{path}: env_kwargs must be a mapping")
    for key in _SCHEDULE_KEYS:
        value = hyper.get(key)
        if isinstance(value, str):
            kind, _, initial = value.partition("_")
            try:
                if kind != "lin":
                    raise ValueError(kind)
                hyper[key] = LinearSchedule(float(initial))
            except ValueError:
                raise LearningError(f"{path}: {key} {value!r} is not a number or lin_<initial value>") from None
    if isinstance(hyper.get("train_freq"), list):
        hyper["train_freq"] = tuple(hyper["train_freq"])
    if "policy_kwargs" in hyper:
        hyper["policy_kwargs"] = _policy_kwargs(hyper["policy_kwargs"], path)
    return TrainingConfig(
        hyperparameters=hyper,
        policy=policy,
        n_timesteps=None if n_timesteps is None else int(float(n_timesteps)),
        n_envs=None if n_envs is None else int(n_envs),
        env_kwargs=env_kwargs,
    )


def load_hyperparameters(path: str | Path, env_id: str) -> dict[str, Any]:
    """SB3 constructor keyword arguments of ``env_id`` from an rl-zoo3 YAML file (see :func:`load_config`)."""
    return load_config(path, env_id).hyperparameters


@dataclass(frozen=True)
class TrainingSummary:
    """What a training run did (printed at its end).

    Attributes:
        steps: environment steps taken; episodes: episodes finished; seconds: wall time.
        recent_return, recent_success, recent_length: means over the last :data:`RECENT_EPISODES` episodes
            (NaN before the first one ends).
    """

    steps: int
    episodes: int
    seconds: float
    recent_return: float
    recent_success: float
    recent_length: float

    def format(self) -> str:
        rate = self.steps / self.seconds if self.seconds > 0 else float("nan")
        plural = "" if self.episodes == 1 else "s"
        head = (
            f"trained {self.steps} steps in {self.seconds:.1f} s ({rate:.0f} steps/s), {self.episodes} episode{plural}"
        )
        if not self.episodes:
            return head + " (none finished: train longer to see returns)"
        return (
            head
            + f"; last {min(self.episodes, RECENT_EPISODES)}: "
            + _stats(self.recent_return, self.recent_success, self.recent_length)
        )


def _stats(ret: float, success: float, length: float) -> str:
    success_text = "n/a" if math.isnan(success) else f"{100.0 * success:.0f}%"
    return f"return {ret:.2f}  success {success_text}  length {length:.0f}"


def _mean(values: list[float]) -> float:
    return sum(values) / len(values) if values else float("nan")


def _statistics_callback(base_callback: type, total: int, every: int, log: Callable[[str], None]) -> Any:
    """An SB3 callback printing the recent episodes' statistics every ``every`` steps and a summary at the end."""

    class TrainingLog(base_callback):
        def __init__(self) -> None:
            super().__init__()
            self.recent: deque[tuple[float, float, float]] = deque(maxlen=RECENT_EPISODES)
            self.episodes = 0
            self.summary: TrainingSummary | None = None
            self._next = every
            self._start = time.perf_counter()

        def _on_training_start(self) -> None:
            self._start = time.perf_counter()

        def _on_step(self) -> bool:
            for info in self.locals.get("infos", ()):
                episode = info.get("episode")  # set by Monitor at an episode's end
                if episode is None:
                    continue
                success = episode.get("is_success", info.get("is_success"))
                self.recent.append(
                    (float(episode["r"]), math.nan if success is None else float(success), float(episode["l"]))
                )
                self.episodes += 1
            if self.num_timesteps >= self._next:
                while self._next <= self.num_timesteps:
                    self._next += every
                log(self._line())
            return True

        def _recent(self) -> tuple[float, float, float]:
            returns, successes, lengths = zip(*self.recent, strict=False) if self.recent else ((), (), ())
            known = [s for s in successes if not math.isnan(s)]
            return _mean(list(returns)), _mean(known), _mean(list(lengths))

        def _line(self) -> str:
            elapsed = time.perf_counter() - self._start
            rate = self.num_timesteps / elapsed if elapsed > 0 else float("nan")
            width = len(str(total))
            head = f"step {self.num_timesteps:>{width}}/{total}  episodes {self.episodes:>5}"
            body = _stats(*self._recent()) if self.recent else "no episode finished yet"
            return f"{head}  {body}  ({rate:.0f} steps/s)"

        def _on_training_end(self) -> None:
            ret, success, length = self._recent()
            self.summary = TrainingSummary(
                steps=int(self.num_timesteps),
                episodes=self.episodes,
                seconds=time.perf_counter() - self._start,
                recent_return=ret,
                recent_success=success,
                recent_length=length,
            )
            log(self.summary.format())

    return TrainingLog()


def train(
    env_id: str,
    algo: str,
    steps: int,
    out: str | Path,
    *,
    seed: int = 0,
    env_kwargs: dict[str, Any] | None = None,
    hyperparameters: dict[str, Any] | None = None,
    progress_bar: bool = True,
    tensorboard_log: str | None = None,
    n_envs: int = 1,
    vec_env: str = "dummy",
    policy: str = DEFAULT_POLICY,
    print_every: int | None = None,
    log: Callable[[str], None] | None = print,
    torch_threads: int | None = 1,
    eval_freq: int | None = None,
    eval_episodes: int = 5,
    eval_seed: int = EVAL_CALLBACK_SEED,
    checkpoint_freq: int | None = None,
    keep: str = "last",
) -> Path:
    """Train an SB3 agent for ``steps`` environment steps and save it to ``out`` (a ``.zip`` that ``eval`` loads).

    Every env is wrapped in SB3's ``Monitor`` (recording ``is_success``); the statistics of the recent episodes
    are printed through ``log`` every ``print_every`` steps, with a summary at the end.

    Args:
        env_id: a registered env id.
        algo: ``"ppo"`` or ``"sac"``.
        steps: total environment steps over all envs (>= 1).
        out: output path; ``.zip`` is appended by SB3 when missing.
        seed: seed of the agent; env ``i`` is reset with ``seed + i`` first.
        env_kwargs: keyword arguments for ``gym.make``.
        hyperparameters: SB3 constructor keyword arguments (e.g. :func:`load_hyperparameters`).
        progress_bar: show SB3's progress bar.
        tensorboard_log: TensorBoard log directory (``tensorboard --logdir`` it).
        n_envs: environments stepped together (a vectorized env).
        vec_env: ``"dummy"`` / ``"sync"`` (one process) or ``"subproc"`` / ``"async"`` (one process per env).
        policy: SB3 policy name.
        print_every: steps between printed lines; default: about 20 lines per run, at least 1000 steps apart.
        log: where the lines go (None: nowhere).
        torch_threads: torch's CPU threads while training (None: torch's default, one per core). The default 1
            suits MLP policies: their layers are too small to split, and on a busy machine torch's thread pool
            made a smoke run 30-100 times slower.
        eval_freq: every this many steps (over all envs), evaluate the deterministic agent on ``eval_episodes``
            episodes of a separate env with seeds from ``eval_seed`` (SB3's ``EvalCallback``; logged to
            TensorBoard, the best agent saved as ``<out>_best.zip``); None: no evaluation while training.
        eval_episodes, eval_seed: the callback's episodes and first seed (keep them apart from the seeds a
            result is reported on: the default :data:`EVAL_CALLBACK_SEED` is).
        checkpoint_freq: every this many steps (over all envs) save the agent as
            ``<out>_checkpoints/<algo>_<steps>_steps.zip``; None: no checkpoints.
        keep: ``"last"`` saves the agent at the end of training to ``out``; ``"best"`` saves the evaluation
            callback's best agent there instead (needs ``eval_freq``), and the last as ``<out>_last.zip``.

    Beside ``out`` goes its :class:`~redundancy_gym.learning.training_record.TrainingRecord` (``.json``): steps, wall
    and CPU time, settings, machine and the final statistics.
    """
    try:
        sb3 = import_stable_baselines3()
        from stable_baselines3.common.callbacks import BaseCallback, CallbackList, CheckpointCallback, EvalCallback
        from stable_baselines3.common.env_util import make_vec_env
        from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv
    except ImportError as exc:
        raise LearningError(f"training needs the learn extra: {LEARN_EXTRA_HINT}") from exc
    if algo not in ALGOS:
        raise LearningError(f"unknown algo {algo!r}; valid: {', '.join(ALGOS)}")
    if steps < 1:
        raise LearningError(f"steps must be >= 1, got {steps}")
    if n_envs < 1:
        raise LearningError(f"n_envs must be >= 1, got {n_envs}")
    if vec_env not in VEC_ENVS:
        raise LearningError(f"unknown vec_env {vec_env!r}; valid: {', '.join(VEC_ENVS)}")
    if print_every is not None and print_every < 1:
        raise LearningError(f"print_every must be >= 1, got {print_every}")
    if torch_threads is not None and torch_threads < 1:
        raise LearningError(f"torch_threads must be >= 1, got {torch_threads}")
    for name, value in (("eval_freq", eval_freq), ("checkpoint_freq", checkpoint_freq)):
        if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
            raise LearningError(f"{name} must be an int >= 1 or None, got {value!r}")
    if isinstance(eval_episodes, bool) or not isinstance(eval_episodes, int) or eval_episodes < 1:
        raise LearningError(f"eval_episodes must be an int >= 1, got {eval_episodes!r}")
    if keep not in KEEP:
        raise LearningError(f"unknown keep {keep!r}; valid: {', '.join(KEEP)}")
    if keep == "best" and eval_freq is None:
        raise LearningError("keep='best' needs eval_freq (the evaluation callback chooses the best agent)")
    make_env(env_id, env_kwargs).close()  # a clear error for a bad id or kwargs, before any worker starts
    out = Path(out)
    out = out if out.suffix == ".zip" else out.with_name(out.name + ".zip")
    stem = out.with_suffix("")
    monitor = {"info_keywords": ("is_success",) if env_id in ENV_IDS else ()}
    restore_threads = set_torch_threads(torch_threads)
    eval_env = None
    with CpuClock() as clock:
        env = make_vec_env(
            functools.partial(make_env, env_id, env_kwargs),
            n_envs=n_envs,
            seed=seed,
            vec_env_cls=SubprocVecEnv if vec_env in ("subproc", "async") else DummyVecEnv,
            monitor_kwargs=monitor,
        )
        try:
            cls = {"ppo": sb3.PPO, "sac": sb3.SAC}[algo]
            try:
                model = cls(
                    policy,
                    env,
                    seed=seed,
                    device="cpu",
                    verbose=0,
                    tensorboard_log=tensorboard_log,
                    **(hyperparameters or {}),
                )
            except TypeError as exc:  # a keyword the algorithm does not take
                raise LearningError(f"invalid {algo.upper()} hyperparameters: {exc}") from None
            if tensorboard_log is None:
                model.set_logger(silent_logger())
            total = int(steps)
            rollout = int(getattr(model, "n_steps", 0) or 0) * n_envs  # on-policy learners collect whole rollouts
            if rollout and total % rollout:
                total = -(-total // rollout) * rollout
                if log is not None:
                    log(
                        f"note: {algo.upper()} collects n_steps x n_envs = {rollout} steps per update, so training "
                        f"runs {total} steps, not {steps} (pass a multiple of {rollout} to --steps)"
                    )
            statistics = _statistics_callback(
                BaseCallback, total, print_every or max(1000, total // 20), log or (lambda line: None)
            )
            callbacks: list[Any] = [statistics]
            if eval_freq is not None:
                # a separate env, seeded apart from training and from the reported seeds; SB3 counts the
                # callback's frequency in calls, one per vectorized step of n_envs env steps
                eval_env = make_vec_env(
                    functools.partial(make_env, env_id, env_kwargs), n_envs=1, seed=eval_seed, monitor_kwargs=monitor
                )
                callbacks.append(
                    EvalCallback(
                        eval_env,
                        n_eval_episodes=eval_episodes,
                        eval_freq=max(1, eval_freq // n_envs),
                        best_model_save_path=str(stem) + "_best_dir",
                        log_path=None,
                        deterministic=True,
                        verbose=0,
                    )
                )
            if checkpoint_freq is not None:
                callbacks.append(
                    CheckpointCallback(
                        save_freq=max(1, checkpoint_freq // n_envs),
                        save_path=str(stem) + "_checkpoints",
                        name_prefix=algo,
                    )
                )
            model.learn(
                total_timesteps=int(steps),
                progress_bar=progress_bar,
                callback=CallbackList(callbacks),
                tb_log_name=f"{algo}_{env_id.split('/')[-1]}",
            )
            out.parent.mkdir(parents=True, exist_ok=True)
            best_eval = None
            if eval_freq is not None:
                best_dir = Path(str(stem) + "_best_dir")
                best_eval = float(callbacks[1].best_mean_reward)
                if (best_dir / "best_model.zip").is_file():
                    (best_dir / "best_model.zip").replace(str(stem) + "_best.zip")
                    best_dir.rmdir()
            if keep == "best" and Path(str(stem) + "_best.zip").is_file():
                model.save(str(stem) + "_last.zip")
                Path(str(stem) + "_best.zip").replace(out)
            else:
                model.save(str(out))
        finally:
            env.close()
            if eval_env is not None:
                eval_env.close()
            restore_threads()
    summary = statistics.summary
    result: dict[str, Any] = (
        {}
        if summary is None
        else {
            "recent_return": summary.recent_return,
            "recent_success": summary.recent_success,
            "episodes": summary.episodes,
        }
    )
    if best_eval is not None:
        result["best_eval_return"] = best_eval
        result["eval_seed"] = eval_seed
        result["kept"] = keep
    TrainingRecord(
        learner=algo,
        env_id=env_id,
        env_steps=int(model.num_timesteps),
        wall_s=clock.wall_s,
        cpu_s=clock.cpu_s,
        seed=seed,
        settings={
            "policy": policy,
            "n_envs": n_envs,
            "vec_env": vec_env,
            "steps": int(steps),
            "env_kwargs": dict(env_kwargs or {}),
            "hyperparameters": dict(hyperparameters or {}),
        },
        machine=machine(),
        result=result,
    ).write(out)
    return out
