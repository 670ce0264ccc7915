"""Training stable-baselines3 agents on the registered envs (the ``learn`` extra)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ..sb3_import import import_stable_baselines3
from .evaluate import make_env
from .exceptions import EvalError

__all__ = ["ALGOS", "load_hyperparameters", "train"]

ALGOS: tuple[str, ...] = ("ppo", "sac")


def load_hyperparameters(path: str | Path) -> dict[str, Any]:
    """Read SB3 constructor keyword arguments from a YAML file (a mapping)."""
    import yaml

    data = yaml.safe_load(Path(path).read_text()) or {}
    if not isinstance(data, dict):
        raise EvalError(f"{path} must hold a mapping of SB3 keyword arguments")
    return data


def train(env_id: str, algo: str, steps: int, out: str | Path, *, seed: int = 0,
          env_kwargs: dict[str, Any] | None = None, hyperparameters: dict[str, Any] | None = None,
          progress_bar: bool = True, tensorboard_log: str | None = None) -> Path:
    """Train an SB3 agent for ``steps`` environment steps and save it to ``out`` (a ``.zip`` that ``eval`` loads).

    Args:
        env_id: a registered env id.
        algo: ``"ppo"`` or ``"sac"``.
        steps: total environment steps (>= 1).
        out: output path; ``.zip`` is appended by SB3 when missing.
        seed: seed of the agent and the env.
        env_kwargs: keyword arguments for ``gym.make``.
        hyperparameters: SB3 constructor keyword arguments (e.g. from ``configs/``).
        progress_bar: show SB3's progress bar.
        tensorboard_log: TensorBoard log directory.
    """
    try:
        sb3 = import_stable_baselines3()
    except ImportError as exc:
        raise EvalError("training needs the learn extra: pip install 'redundancy-gym[learn]'") from exc
    if algo not in ALGOS:
        raise EvalError(f"unknown algo {algo!r}; valid: {', '.join(ALGOS)}")
    if steps < 1:
        raise EvalError(f"steps must be >= 1, got {steps}")
    env = make_env(env_id, env_kwargs)
    try:
        cls = {"ppo": sb3.PPO, "sac": sb3.SAC}[algo]
        model = cls("MlpPolicy", env, seed=seed, device="cpu", verbose=0, tensorboard_log=tensorboard_log,
                    **(hyperparameters or {}))
        model.learn(total_timesteps=int(steps), progress_bar=progress_bar)
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        model.save(str(out))
    finally:
        env.close()
    return out if out.suffix == ".zip" else out.with_name(out.name + ".zip")
