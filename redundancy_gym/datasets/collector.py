"""A policy's episodes written as a Minari dataset (Farama's standard for offline RL and imitation data).

Each episode starts from ``env.reset(seed=s)`` (seeds ``seed``, ``seed + 1``, ...; Minari keeps each episode's seed)
and records what the env saw: observations (the reset's and every step's), the actions stepped, rewards,
terminations, truncations and, as ``infos``, the env's scalar metrics of the evaluation contract (every number or
flag its reset ``info`` holds: tracking and goal errors, clearances, ``collision``, ``fell``, ``is_success``, ...),
one entry per observation. The dataset keeps the env's spec (id and ``gym.make`` keyword arguments), so
``dataset.recover_environment()`` builds the same env, in which the recorded actions replay the recorded observations
bit for bit from the episode's seed.

``action_noise`` > 0 steps the policy's action plus Gaussian noise of that standard deviation [fraction of the
action space's half range], clipped into the space (DART, Laskey et al. 2017: the expert's corrections from the
states its own mistakes lead to); the policy's own action at every observation is then kept as
``infos["expert_action"]`` (its last entry labels the final observation), the label that behaviour cloning reads.
The noise is drawn from one generator seeded with ``seed``.

Datasets go to ``out/<dataset_id>`` (Minari's ``MINARI_DATASETS_PATH`` set to ``out`` for the write): open one with
``minari.load_dataset(dataset_id)`` under ``MINARI_DATASETS_PATH=out``, or with :func:`~.demonstrations.find_dataset`.
"""

from __future__ import annotations

import contextlib
import math
import os
import shutil
import time
import warnings
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray
from tqdm.auto import tqdm

from ..eval.evaluate import make_env, reseed_policy
from ..policies import make_policy, reference_policy
from ..sb3_import import install_hint
from ..validation import check_required_int, check_required_real
from .exceptions import DatasetError

__all__ = ["MINARI_EXTRA_HINT", "CollectSummary", "collect_dataset", "import_minari"]

MINARI_EXTRA_HINT = install_hint("dataset")
"""How to install Minari (the ``dataset`` extra: minari with its HDF5 storage)."""

DATASET_NAMESPACE = "redundancy_gym"
"""The Minari namespace of the default dataset ids."""


def import_minari() -> ModuleType:
    """The ``minari`` module; :class:`DatasetError` naming the ``dataset`` extra when it is missing."""
    try:
        import minari
    except ImportError as exc:
        raise DatasetError(f"Minari is not installed; {MINARI_EXTRA_HINT}") from exc
    return minari


@dataclass(frozen=True)
class CollectSummary:
    """What :func:`collect_dataset` wrote.

    Attributes:
        dataset_id: the Minari dataset id.
        path: the dataset's folder (``out/<dataset_id>``).
        episodes: episodes recorded.
        steps: environment steps recorded.
        success_rate: share of the episodes that ended with ``info["is_success"]``.
        size_bytes: the dataset's size on disk [bytes].
        seconds: wall time of the collection [s].
    """

    dataset_id: str
    path: Path
    episodes: int
    steps: int
    success_rate: float
    size_bytes: int
    seconds: float

    def format(self) -> str:
        """One line."""
        return (
            f"dataset {self.dataset_id}: {self.episodes} episodes, {self.steps} steps, success "
            f"{self.success_rate:.2f}, {self.size_bytes / 1e6:.2f} MB in {self.path} ({self.seconds:.1f} s)"
        )


def default_dataset_id(env_id: str, policy: str) -> str:
    """``redundancy_gym/<env name>/<policy>-v0`` (Minari's ``namespace/env_name/dataset_name-vN``)."""
    name = env_id.split("/")[-1].rsplit("-v", 1)[0]
    stem = Path(policy).stem if policy.endswith(".zip") else policy
    clean = "".join(ch if ch.isalnum() or ch in "_-" else "_" for ch in stem)
    return f"{DATASET_NAMESPACE}/{name}/{clean}-v0"


@contextlib.contextmanager
def _datasets_path(out: Path) -> Iterator[None]:
    """Minari's root folder set to ``out`` for the enclosed calls (it reads the environment variable)."""
    before = os.environ.get("MINARI_DATASETS_PATH")
    os.environ["MINARI_DATASETS_PATH"] = str(out)
    try:
        yield
    finally:
        if before is None:
            del os.environ["MINARI_DATASETS_PATH"]
        else:
            os.environ["MINARI_DATASETS_PATH"] = before


def _metric_keys(info: dict[str, Any]) -> list[str]:
    """The reset info's scalar entries (numbers and flags): the env's metrics."""
    return [k for k, v in info.items() if isinstance(v, (bool, int, float, np.bool_, np.integer, np.floating))]


def _metric(value: Any, flag: bool) -> np.bool_ | np.float64:
    """One metric value in its column's type (a missing one: False or NaN)."""
    if flag:
        return np.bool_(bool(value)) if value is not None else np.bool_(False)
    return np.float64(value) if value is not None else np.float64(math.nan)


def collect_dataset(
    env_id: str,
    out: str | Path,
    *,
    policy: str | None = None,
    policy_kwargs: dict[str, Any] | None = None,
    env_kwargs: dict[str, Any] | None = None,
    episodes: int = 10,
    seed: int = 0,
    action_noise: float = 0.0,
    dataset_id: str | None = None,
    overwrite: bool = False,
    progress: bool = True,
) -> CollectSummary:
    """Record ``episodes`` episodes of ``policy`` on ``env_id`` as a Minari dataset in ``out`` (module docstring).

    Args:
        env_id: a registered env id (a wrapped id too, with a policy that acts in its action space).
        out: the root folder of the datasets (Minari's ``MINARI_DATASETS_PATH``).
        policy: a registered policy name or an SB3 ``.zip`` (None: the env's reference, ``walking`` on the bipeds,
            else ``clik``).
        policy_kwargs, env_kwargs: the policy's options; ``gym.make`` keyword arguments (kept in the dataset's env
            spec).
        episodes: episodes to record (>= 1), from seeds ``seed`` on.
        seed: the first episode's seed and the action noise's seed.
        action_noise: standard deviation [fraction of the action's half range, >= 0] of the Gaussian noise added to
            the stepped action (DART); 0: the policy's actions as they are.
        dataset_id: the Minari id (None: ``redundancy_gym/<env name>/<policy>-v0``).
        overwrite: replace an existing dataset of that id in ``out`` (else it is an error).
        progress: a progress bar over the episodes.
    """
    minari = import_minari()
    from minari.data_collector import EpisodeBuffer

    episodes = check_required_int("episodes", episodes, low=1, error=DatasetError)
    seed = check_required_int("seed", seed, low=0, error=DatasetError)
    action_noise = check_required_real(
        "action_noise", action_noise, low=0.0, unit="fraction of the half range", error=DatasetError
    )
    out = Path(out).resolve()  # Minari joins a relative root to paths it already made relative
    policy_name = policy or reference_policy(env_id)
    dataset_id = dataset_id or default_dataset_id(env_id, policy_name)
    from minari.dataset.minari_dataset import parse_dataset_id

    try:
        parse_dataset_id(dataset_id)
    except ValueError:
        raise DatasetError(
            f"dataset_id {dataset_id!r} is not a Minari id: [namespace/][env_name/]dataset_name-vN"
        ) from None
    folder = out / dataset_id
    if folder.exists():
        if not overwrite:
            raise DatasetError(f"a dataset {dataset_id!r} exists in {out}; pass overwrite (--overwrite) or another id")
        shutil.rmtree(folder)
    start = time.perf_counter()
    env = make_env(env_id, env_kwargs)
    try:
        agent = make_policy(policy_name, env, **(policy_kwargs or {}))
        action_space = env.action_space
        if action_noise > 0.0 and not isinstance(action_space, spaces.Box):
            raise DatasetError(f"action_noise needs a Box action space; {env_id} has {action_space}")
        rng = np.random.default_rng(seed)
        buffers = []
        successes = steps = 0
        keys: list[str] | None = None
        flags: list[bool] = []
        for episode in tqdm(range(episodes), desc=f"collect {policy_name}", unit="episode", disable=not progress):
            episode_seed = seed + episode
            obs, info = env.reset(seed=episode_seed)
            reseed_policy(agent, episode_seed)
            if keys is None:
                keys = _metric_keys(info)
                flags = [isinstance(info[k], (bool, np.bool_)) for k in keys]
            observations: list[NDArray[Any]] = [obs]
            actions: list[NDArray[Any]] = []
            labels: list[NDArray[Any]] = []
            rewards: list[float] = []
            terminations: list[bool] = []
            truncations: list[bool] = []
            infos: dict[str, list[Any]] = {k: [_metric(info.get(k), f)] for k, f in zip(keys, flags, strict=True)}
            start_flag = np.array([True])
            while True:
                label, _ = agent.predict(obs, episode_start=start_flag, deterministic=True)
                start_flag = np.array([False])
                label = np.asarray(label, dtype=action_space.dtype).reshape(action_space.shape)
                action = label
                if action_noise > 0.0:
                    assert isinstance(action_space, spaces.Box)
                    half = 0.5 * (action_space.high - action_space.low)
                    noisy = label + action_noise * half * rng.standard_normal(label.shape)
                    action = np.clip(noisy, action_space.low, action_space.high).astype(action_space.dtype)
                labels.append(label)
                obs, reward, terminated, truncated, info = env.step(action)
                observations.append(obs)
                actions.append(action)
                rewards.append(float(reward))
                terminations.append(bool(terminated))
                truncations.append(bool(truncated))
                for k, f in zip(keys, flags, strict=True):
                    infos[k].append(_metric(info.get(k), f))
                if terminated or truncated:
                    break
            if action_noise > 0.0:
                final, _ = agent.predict(obs, episode_start=start_flag, deterministic=True)
                labels.append(np.asarray(final, dtype=action_space.dtype).reshape(action_space.shape))
                infos["expert_action"] = labels
            successes += bool(info.get("is_success", False))
            steps += len(actions)
            buffers.append(
                EpisodeBuffer(
                    id=episode,
                    seed=episode_seed,
                    observations=observations,
                    actions=actions,
                    rewards=rewards,
                    terminations=terminations,
                    truncations=truncations,
                    infos={k: np.asarray(v) for k, v in infos.items()},
                )
            )
        from .. import __version__

        with _datasets_path(out), warnings.catch_warnings():
            # the project has no public code link or contact address to give; its version is in the requirements
            warnings.filterwarnings("ignore", message="`(code_permalink|author_email)` is set to None")
            dataset = minari.create_dataset_from_buffers(
                dataset_id,
                buffers,
                env=env,
                eval_env=env.spec,
                algorithm_name=policy_name,
                author="redundancy_gym collect",
                description=(
                    f"{episodes} episodes of the {policy_name} policy on {env_id} (env kwargs {env_kwargs or {}}), "
                    f"seeds {seed}-{seed + episodes - 1}, action noise {action_noise}; infos: the env's metrics"
                    + (" and expert_action (the policy's own action, the label)" if action_noise > 0.0 else "")
                ),
                requirements=[f"redundancy-gym=={__version__}"],
            )
            dataset.storage.update_metadata(
                {
                    "policy": policy_name,
                    "policy_kwargs": dict(policy_kwargs or {}),
                    "env_id": env_id,
                    "env_kwargs": dict(env_kwargs or {}),
                    "seeds": [seed, seed + episodes - 1],
                    "action_noise": float(action_noise),
                    "success_rate": successes / episodes,
                    "redundancy_gym_version": __version__,
                }
            )
    finally:
        env.close()
    size = sum(p.stat().st_size for p in folder.rglob("*") if p.is_file())
    return CollectSummary(dataset_id, folder, episodes, steps, successes / episodes, size, time.perf_counter() - start)
