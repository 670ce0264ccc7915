"""The rewards rank behaviour as a user would: on held-out seeds, every episode of the reference controller earns
more than every episode of standing still (the zero action: the nominal posture held), and every episode of
standing still more than every episode of random actions, each by a clear margin."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from redundancy_gym.eval.evaluate import evaluate

# (env id, env kwargs, reference policy, episodes, largest share of the reference's gain over random actions that
# standing still may earn); seeds 13000+ are used by no other test or figure. On the walkers standing still must
# not pay: with the earlier reward (a quadratic speed penalty under a healthy reward of 1 per step) it earned 77 %
# of the walking reference's gain and a barely trained PPO learned to stand.
CASES: list[tuple[str, dict[str, Any], str, int, float]] = [
    ("redundancy_gym/PlanarReach-v0", {"obstacle": True}, "clik", 3, 0.9),
    ("redundancy_gym/PlanarReach-v0", {"obstacle": False}, "clik", 3, 0.9),
    ("redundancy_gym/AgriReach-v0", {"difficulty": "medium"}, "clik", 3, 0.9),
    ("redundancy_gym/BipedWalk-v0", {"target_speed": 0.5}, "walking", 2, 1.0 / 3.0),
    ("redundancy_gym/BipedObstacles-v0", {"course": "random"}, "walking", 2, 1.0 / 3.0),
    ("redundancy_gym/BipedTerrain-v0", {"terrain": "slope"}, "walking", 2, 1.0 / 3.0),
]


def _returns(env_id: str, env_kwargs: dict[str, Any], policy: str, episodes: int) -> np.ndarray:
    report = evaluate(env_id, policy, episodes=episodes, seed=13000, env_kwargs=env_kwargs, progress=False)
    return np.array([episode["return"] for episode in report.to_json()["per_episode"]])


@pytest.mark.parametrize(
    "env_id, env_kwargs, reference, episodes, still_share",
    CASES,
    ids=[f"{c[0].split('/')[1]}-{c[2]}-{'-'.join(f'{k}={v}' for k, v in c[1].items())}" for c in CASES],
)
def test_reference_beats_standing_still_which_beats_random_actions(
    env_id: str, env_kwargs: dict[str, Any], reference: str, episodes: int, still_share: float
) -> None:
    best = _returns(env_id, env_kwargs, reference, episodes)
    still = _returns(env_id, env_kwargs, "zero", episodes)
    random = _returns(env_id, env_kwargs, "random", episodes)
    # a clear margin: every gap between the groups is at least 5 % of the span from random actions to the reference
    span = best.mean() - random.mean()
    assert span > 0.0
    assert best.min() > still.max() + 0.05 * span, (best, still)
    assert still.min() > random.max() + 0.05 * span, (still, random)
    assert still.mean() - random.mean() <= still_share * span, (best, still, random)


def test_ending_the_episode_by_a_collision_pays_less_than_finishing_it():
    # through the nullspace wrapper the zero action is the plain minimum-norm tracker, which runs into
    # PlanarReach's obstacle: its shorter episode must not pay more than the reference's full, collision-free one
    # (with a collision penalty of 10 it did, -38 against -41: the energy of the rest of the line was saved)
    crash = evaluate("redundancy_gym/PlanarReach-Nullspace-v0", "zero", episodes=2, seed=13000, progress=False)
    crash_json = crash.to_json()
    assert crash_json["collision_rate"] == 1.0
    best = _returns("redundancy_gym/PlanarReach-v0", {"obstacle": True}, "clik", 2)
    worst_crash = max(episode["return"] for episode in crash_json["per_episode"])
    assert worst_crash < best.min() - 50.0
