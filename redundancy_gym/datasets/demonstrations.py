"""A collected Minari dataset read back as labelled ``(observation, action)`` pairs, the data of behaviour cloning."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .collector import import_minari
from .exceptions import DatasetError

__all__ = ["Demonstrations", "find_dataset", "load_demonstrations"]


@dataclass(frozen=True)
class Demonstrations:
    """A dataset's labelled pairs.

    Attributes:
        observations: (N, obs) every observation an action was taken at (float32, as SB3's networks take them).
        actions: (N, act) the label of each: ``infos["expert_action"]`` where the dataset has it (collected with
            action noise), else the action stepped (float32).
        episodes: episodes read.
        metadata: the dataset's metadata (Minari's and :func:`~.collector.collect_dataset`'s: policy, seeds,
            success rate, env id and kwargs).
        path: the dataset's ``data`` folder.
    """

    observations: NDArray[np.float32]
    actions: NDArray[np.float32]
    episodes: int
    metadata: dict[str, Any]
    path: Path


def find_dataset(path: str | Path) -> Path:
    """The ``data`` folder of the one Minari dataset at or under ``path`` (a dataset's folder, its ``data``
    folder, or a root folder holding exactly one dataset)."""
    root = Path(path)
    if not root.exists():
        raise DatasetError(f"dataset path {str(root)!r} does not exist")
    for candidate in (root, root / "data"):
        if (candidate / "metadata.json").is_file():
            return candidate
    found = sorted(p.parent for p in root.rglob("data/metadata.json"))
    if len(found) == 1:
        return found[0]
    if not found:
        raise DatasetError(f"no Minari dataset (a data/metadata.json) in {str(root)!r}")
    names = ", ".join(str(p.parent.relative_to(root)) for p in found)
    raise DatasetError(f"{len(found)} datasets in {str(root)!r}; give one of: {names}")


def load_demonstrations(path: str | Path) -> Demonstrations:
    """Every ``(observation, label)`` pair of the dataset at ``path`` (:func:`find_dataset`)."""
    minari = import_minari()
    data = find_dataset(path)
    dataset = minari.MinariDataset(data)
    observations: list[NDArray[Any]] = []
    labels: list[NDArray[Any]] = []
    episodes = 0
    for episode in dataset.iterate_episodes():
        obs = np.asarray(episode.observations)
        if obs.ndim != 2:
            raise DatasetError(f"behaviour cloning reads flat Box observations; {data} has {obs.shape[1:]} per step")
        steps = len(episode.actions)
        expert = episode.infos.get("expert_action") if isinstance(episode.infos, dict) else None
        labels.append(np.asarray(expert if expert is not None else episode.actions)[:steps])
        observations.append(obs[:steps])
        episodes += 1
    if not episodes:
        raise DatasetError(f"the dataset in {str(data)!r} holds no episodes")
    return Demonstrations(
        np.concatenate(observations).astype(np.float32),
        np.concatenate(labels).astype(np.float32).reshape(sum(len(o) for o in observations), -1),
        episodes,
        dict(dataset.storage.metadata),
        data,
    )
