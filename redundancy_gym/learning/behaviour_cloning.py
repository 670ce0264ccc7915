"""Behaviour cloning with DAgger from a reference policy (the ``learn`` extra): an SB3 PPO policy network trained by
regression on the reference's actions, saved as a PPO ``.zip`` that ``eval``, ``make_policy`` and SB3 load.

Round 0 rolls the reference (the expert) out and records ``(observation, expert action)``; every further round
(DAgger, Ross et al. 2011) rolls the learner out, labels the states it visits with the expert's action and adds
them to the data; after each round the network is fitted again on all data (mean squared error of the Gaussian
policy's mean against the expert's action, Adam). The expert reads only the observation, so it can label any state.
Round 0's data may come from a collected Minari dataset instead (``dataset``; :mod:`redundancy_gym.datasets`): with
no DAgger rounds the network learns from the dataset alone.
The policy's log standard deviation is set to ``log_std`` so that the saved agent acts nearly deterministically
even when sampled (and could be fine-tuned with PPO from there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray
from tqdm.auto import tqdm

from ..datasets import load_demonstrations
from ..eval.evaluate import make_env
from ..policies import make_policy, reference_policy
from ..sb3_import import LEARN_EXTRA_HINT, import_stable_baselines3, set_torch_threads
from .exceptions import LearningError
from .training_record import CpuClock, TrainingRecord, machine

__all__ = ["BehaviourCloningSummary", "train_behaviour_cloning"]


@dataclass(frozen=True)
class BehaviourCloningSummary:
    """What :func:`train_behaviour_cloning` did.

    Attributes:
        samples: labelled ``(observation, action)`` pairs at the end.
        rounds: data-collection rounds (1 + DAgger rounds).
        env_steps: environment steps over all rounds.
        seconds: wall time [s].
        loss: mean squared action error [-] on all data after the last fit.
        learner_success: success rate of the learner's own rollouts per DAgger round (empty without DAgger).
        path: the saved ``.zip``.
    """

    samples: int
    rounds: int
    env_steps: int
    seconds: float
    loss: float
    learner_success: tuple[float, ...]
    path: Path

    def format(self) -> str:
        """One line."""
        dagger = ", ".join(f"{s:.0%}" for s in self.learner_success) or "none"
        return (
            f"behaviour cloning: {self.samples} samples from {self.env_steps} env steps in {self.rounds} rounds, "
            f"{self.seconds:.1f} s; action MSE {self.loss:.2e}; learner's success per DAgger round: {dagger}"
        )


def _rollout(
    env: Any, act: Any, expert: Any, episodes: int, seed: int
) -> tuple[list[NDArray[np.float32]], list[NDArray[np.float32]], int, float]:
    """``episodes`` episodes acted by ``act(obs, start)``, each state labelled by the expert: ``(observations, expert
    actions, steps, success rate)``."""
    observations, labels, steps, successes = [], [], 0, 0
    for episode in range(episodes):
        obs, _ = env.reset(seed=seed + episode)
        start = True
        while True:
            label, _ = expert.predict(obs, episode_start=np.array([start]), deterministic=True)
            observations.append(np.asarray(obs, dtype=np.float32))
            labels.append(np.asarray(label, dtype=np.float32))
            action = act(obs, start, label)
            start = False
            obs, _, terminated, truncated, info = env.step(action)
            steps += 1
            if terminated or truncated:
                successes += bool(info.get("is_success", False))
                break
    return observations, labels, steps, successes / max(episodes, 1)


def train_behaviour_cloning(
    env_id: str,
    out: str | Path,
    *,
    expert: str | None = None,
    expert_kwargs: dict[str, Any] | None = None,
    env_kwargs: dict[str, Any] | None = None,
    episodes: int = 20,
    dagger_rounds: int | None = None,
    dagger_episodes: int = 10,
    epochs: int = 30,
    batch_size: int = 256,
    learning_rate: float = 1e-3,
    net_arch: tuple[int, ...] = (64, 64),
    log_std: float = -3.0,
    seed: int = 0,
    progress: bool = True,
    log: Any = print,
    dataset: str | Path | None = None,
    torch_threads: int | None = 1,
) -> BehaviourCloningSummary:
    """Clone ``expert`` (a registered policy; default: the env's reference, ``clik`` or ``walking``) into an SB3 PPO
    policy and save it to ``out``.

    Args:
        env_id: a registered env id (a wrapped id too: the expert then acts in the wrapper's action space only
            if it supports that id).
        out: the ``.zip`` path.
        expert: the policy to clone (None: the env's reference policy).
        expert_kwargs, env_kwargs: its options; ``gym.make`` keyword arguments.
        episodes: expert episodes of round 0 (seeds ``seed`` ...).
        dagger_rounds: DAgger rounds after it (0: plain behaviour cloning; None: 4, or 0 from a ``dataset``).
        dagger_episodes: learner episodes per DAgger round (seeds continue after the expert's).
        epochs: passes over all data after each round.
        batch_size, learning_rate: Adam's minibatch size and step size.
        net_arch: hidden layers of the policy and value networks.
        log_std: the policy's fixed log standard deviation.
        seed: seed of the network and the first episode.
        progress: a progress bar over the rounds.
        log: where the summary line goes (None: nowhere).
        dataset: a Minari dataset of ``env_id`` (:func:`~redundancy_gym.datasets.collect_dataset`; its folder,
            :func:`~redundancy_gym.datasets.find_dataset`) whose pairs are round 0's data in place of ``episodes``
            expert rollouts; the expert then only labels the DAgger rounds (none with ``dagger_rounds=0``: the
            dataset alone).
        torch_threads: torch's CPU threads while fitting (None: torch's default, one per core;
            :func:`~redundancy_gym.sb3_import.set_torch_threads`).
    """
    try:
        sb3 = import_stable_baselines3()
        import torch
    except ImportError as exc:
        raise LearningError(f"behaviour cloning needs the learn extra: {LEARN_EXTRA_HINT}") from exc
    if dagger_rounds is None:
        dagger_rounds = 0 if dataset is not None else 4
    for name, value, least in (
        ("episodes", episodes, 1),
        ("dagger_rounds", dagger_rounds, 0),
        ("dagger_episodes", dagger_episodes, 1),
        ("epochs", epochs, 1),
        ("batch_size", batch_size, 1),
    ):
        if not isinstance(value, int) or value < least:
            raise LearningError(f"{name} must be an int >= {least}, got {value!r}")
    if not math.isfinite(learning_rate) or learning_rate <= 0.0:
        raise LearningError(f"learning_rate must be finite and > 0, got {learning_rate!r}")
    if torch_threads is not None and (not isinstance(torch_threads, int) or torch_threads < 1):
        raise LearningError(f"torch_threads must be an int >= 1 or None, got {torch_threads!r}")
    demonstrations = None
    if dataset is not None:
        demonstrations = load_demonstrations(dataset)
        recorded = demonstrations.metadata.get("env_id")
        if recorded != env_id:
            raise LearningError(f"the dataset in {demonstrations.path} was collected on {recorded}, not {env_id}")
    clock = CpuClock().__enter__()
    restore_threads = set_torch_threads(torch_threads)
    env = make_env(env_id, env_kwargs)
    if expert is None:
        expert = reference_policy(env_id)
    teacher = make_policy(expert, env, **(expert_kwargs or {})) if demonstrations is None or dagger_rounds else None
    torch.manual_seed(seed)
    model = sb3.PPO(
        "MlpPolicy",
        env,
        seed=seed,
        device="cpu",
        verbose=0,
        policy_kwargs={"net_arch": list(net_arch), "log_std_init": float(log_std)},
    )
    policy = model.policy
    optimizer = torch.optim.Adam(policy.parameters(), lr=learning_rate)
    action_space = env.action_space
    if not isinstance(action_space, spaces.Box):  # the labels are clipped into its bounds
        raise LearningError(f"behaviour cloning needs a Box action space; {env_id} has {action_space}")
    low, high = action_space.low, action_space.high
    rng = np.random.default_rng(seed)

    def fit(observations: NDArray[np.float32], labels: NDArray[np.float32]) -> float:
        obs_t = torch.as_tensor(observations)
        act_t = torch.as_tensor(np.clip(labels, low, high))
        policy.set_training_mode(True)
        for _ in range(epochs):
            order = rng.permutation(len(obs_t))
            for i in range(0, len(order), batch_size):
                batch = torch.as_tensor(order[i : i + batch_size])
                mean = policy.get_distribution(obs_t[batch]).distribution.mean
                loss = torch.mean((mean - act_t[batch]) ** 2)
                optimizer.zero_grad()
                loss.backward()
                optimizer.step()
        policy.set_training_mode(False)
        with torch.no_grad():
            return float(torch.mean((policy.get_distribution(obs_t).distribution.mean - act_t) ** 2))

    def learner(obs: NDArray[np.float64], start: bool, label: NDArray[np.float32]) -> NDArray[np.float32]:
        action, _ = model.predict(obs, deterministic=True)
        return action

    try:
        with tqdm(
            total=1 + dagger_rounds, desc=f"behaviour cloning {expert}", unit="round", disable=not progress
        ) as bar:
            if demonstrations is None:
                observations, labels, steps, _ = _rollout(env, lambda obs, start, label: label, teacher, episodes, seed)
            else:
                if demonstrations.observations.shape[1:] != env.observation_space.shape:
                    raise LearningError(
                        f"the dataset's observations have shape {demonstrations.observations.shape[1:]}; "
                        f"{env_id} observes {env.observation_space.shape}"
                    )
                observations, labels = list(demonstrations.observations), list(demonstrations.actions)
                steps = len(observations)
            loss = fit(np.array(observations), np.array(labels))
            bar.update(1)
            success: list[float] = []
            next_seed = seed + episodes
            for _ in range(dagger_rounds):
                more_obs, more_labels, more_steps, rate = _rollout(env, learner, teacher, dagger_episodes, next_seed)
                next_seed += dagger_episodes
                observations += more_obs
                labels += more_labels
                steps += more_steps
                success.append(rate)
                loss = fit(np.array(observations), np.array(labels))
                bar.update(1)
        out = Path(out)
        out.parent.mkdir(parents=True, exist_ok=True)
        model.save(str(out))
    finally:
        env.close()
        restore_threads()
    path = out if out.suffix == ".zip" else out.with_name(out.name + ".zip")
    clock.__exit__()
    summary = BehaviourCloningSummary(
        len(observations), 1 + dagger_rounds, steps, clock.wall_s, loss, tuple(success), path
    )
    TrainingRecord(
        learner="bc",
        env_id=env_id,
        env_steps=steps,
        wall_s=clock.wall_s,
        cpu_s=clock.cpu_s,
        seed=seed,
        # a dataset alone has no expert and no rollouts of its own: its episodes are the dataset's
        settings={
            "expert": expert if teacher is not None else None,
            "expert_kwargs": dict(expert_kwargs or {}) if teacher is not None else {},
            "env_kwargs": dict(env_kwargs or {}),
            "episodes": episodes if demonstrations is None else demonstrations.episodes,
            "dagger_rounds": dagger_rounds,
            "dagger_episodes": dagger_episodes if dagger_rounds else None,
            "epochs": epochs,
            "batch_size": batch_size,
            "learning_rate": learning_rate,
            "net_arch": list(net_arch),
            "log_std": log_std,
            "dataset": None if demonstrations is None else str(demonstrations.path),
            "torch_threads": torch_threads,
        },
        machine=machine(),
        result={"samples": len(observations), "action_mse": loss, "learner_success_per_dagger_round": list(success)},
    ).write(path)
    if log is not None:
        log(summary.format())
    return summary
