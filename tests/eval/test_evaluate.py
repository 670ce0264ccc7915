import json

import pytest

from redundancy_gym.cli import main
from redundancy_gym.eval import EvalError, evaluate, format_report

ENV_ID = "redundancy_gym/PlanarReach-v0"
CONTRACT = {
    "env",
    "policy",
    "episodes",
    "success_rate",
    "collision_rate",
    "tracking_error_rms",
    "tracking_error_max",
    "goal_error",
    "goal_error_max",
    "goal_reached_rate",
    "time_to_goal",
    "pseudoenergy",
    "peak_joint_speed",
    "min_clearance",
    "step_time_us",
    "compute_time_per_episode_ms",
    "episode_return",
}


def test_json_contract_and_clik_success() -> None:
    report = evaluate(ENV_ID, "clik", episodes=3, seed=0, env_kwargs={"obstacle": False}, progress=False)
    data = report.to_json()
    assert CONTRACT <= set(data)
    assert set(data["step_time_us"]) >= {"median", "p99"}
    assert data["step_time_us"]["median"] > 0 and data["step_time_us"]["p99"] >= data["step_time_us"]["median"]
    assert data["success_rate"] == 1.0 and data["collision_rate"] == 0.0
    assert data["tracking_error_max"] <= 1e-3 and data["tracking_error_rms"] <= data["tracking_error_max"]
    assert data["goal_error"] <= 1e-3 and data["goal_reached_rate"] == 1.0
    assert 1.7 <= data["time_to_goal"] <= 2.5  # within 1 mm of the end of the 2 s quintic line
    assert data["min_clearance"] is None  # no obstacle: null, never inf in JSON
    assert data["pseudoenergy"] > 0 and data["peak_joint_speed"] > 0
    assert [e["seed"] for e in data["per_episode"]] == [0, 1, 2]
    json.dumps(data, allow_nan=False)
    assert "success rate" in format_report(data)


def test_zero_policy_fails_and_collision_is_counted() -> None:
    data = evaluate(ENV_ID, "zero", episodes=2, seed=0, progress=False).to_json()
    assert data["success_rate"] == 0.0 and data["tracking_error_max"] > 0.1
    assert data["goal_reached_rate"] == 0.0 and data["time_to_goal"] is None
    blocked = evaluate(
        ENV_ID,
        "clik",
        episodes=2,
        seed=0,
        progress=False,
        env_kwargs={"obstacle_center": (0.9, 0.2), "obstacle_radius": 0.05},
    ).to_json()
    assert blocked["collision_rate"] == 1.0 and blocked["min_clearance"] <= 0.0


def test_cli_eval_writes_json(tmp_path, capsys) -> None:
    out = tmp_path / "report.json"
    code = main(
        [
            "eval",
            ENV_ID,
            "--policy",
            "clik",
            "--episodes",
            "2",
            "--seed",
            "5",
            "--no-progress",
            "--env-kwargs",
            '{"obstacle": false}',
            "--json",
            str(out),
        ]
    )
    assert code == 0
    data = json.loads(out.read_text())
    assert CONTRACT <= set(data) and data["episodes"] == 2 and data["env_kwargs"] == {"obstacle": False}
    assert "success rate" in capsys.readouterr().out


def test_cli_errors_are_clear(capsys) -> None:
    assert main(["eval", "redundancy_gym/Nope-v0", "--policy", "clik", "--no-progress"]) == 2
    assert "PlanarReach-v0" in capsys.readouterr().err
    assert main(["eval", ENV_ID, "--policy", "nope", "--no-progress"]) == 2
    assert "clik, walking, predictive, global, zero, random" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["eval", ENV_ID, "--policy", "clik", "--env-kwargs", "[1, 2]"])


def test_episode_count_validated() -> None:
    with pytest.raises(EvalError):
        evaluate(ENV_ID, "zero", episodes=0)


def test_agri_tracking_error_separates_the_reference_from_holding_still() -> None:
    """Tracking error is against the env's reference path, not the distance to the goal during the approach: mm for
    the clik reference, tenths of a metre for the zero policy; the goal error says where each one ended."""
    agri = "redundancy_gym/AgriReach-v0"
    clik = evaluate(agri, "clik", episodes=2, seed=0, progress=False).to_json()
    zero = evaluate(agri, "zero", episodes=2, seed=0, progress=False).to_json()
    assert clik["success_rate"] == 1.0 and clik["tracking_error_rms"] < 0.002 and clik["tracking_error_max"] < 0.008
    assert zero["tracking_error_rms"] > 0.1 and zero["tracking_error_rms"] > 20 * clik["tracking_error_rms"]
    assert clik["goal_error"] <= 0.01 and zero["goal_error"] > 0.2 and clik["time_to_goal"] > 1.0
    assert zero["time_to_goal"] is None and "speed_error" not in clik
    step = clik["step_time_us"]
    # the plan (collision model, path) is made at the first step: counted in the mean, shown on its own
    assert step["first_step_mean"] > step["median"] and step["mean"] >= step["median"]


def test_biped_reports_speed_error_not_tracking_error() -> None:
    data = evaluate(
        "redundancy_gym/BipedWalk-v0", "zero", episodes=1, seed=0, progress=False, env_kwargs={"target_speed": 0.5}
    ).to_json()
    assert data["tracking_error_rms"] is None and data["goal_error"] is None
    # standing still (or falling) at a 0.5 m/s command: the mean speed error is about the command
    assert data["speed_error"] == pytest.approx(0.5, abs=0.1) and data["speed_error_rms"] > 0.3
    assert "speed error mean / rms [m/s]" in format_report(data)


def test_warmup_runs_untimed_episodes_first() -> None:
    """The global policy solves at every episode's first step: with a warm-up episode its first-step time is the
    solve alone, and the reported episodes and their seeds are the same as without."""
    cold = evaluate(ENV_ID, "clik", episodes=1, seed=3, progress=False).to_json()
    warm = evaluate(ENV_ID, "clik", episodes=1, seed=3, progress=False, warmup=1).to_json()
    assert warm["per_episode"][0]["seed"] == 3 and warm["episodes"] == 1
    assert warm["pseudoenergy"] == pytest.approx(cold["pseudoenergy"], rel=1e-9)  # same episode, same policy state
    with pytest.raises(EvalError, match="warmup"):
        evaluate(ENV_ID, "zero", episodes=1, warmup=-1)


def test_a_policys_stop_reason_is_kept_per_episode_and_printed_for_a_failed_episode() -> None:
    import gymnasium as gym
    import numpy as np

    import redundancy_gym
    from redundancy_gym.eval.evaluate import EvalReport, run_episode

    env = gym.make(ENV_ID)
    zero = redundancy_gym.make_policy("zero", env)

    class Stopping:  # a policy that says why it stopped (as the walking policy does)
        stop_reason = "too_large before foothold 6: box x [1.400, 1.600]"

        def predict(self, *args, **kwargs):
            return zero.predict(*args, **kwargs)

    stopped, _ = run_episode(env, Stopping(), seed=0)
    plain, _ = run_episode(env, zero, seed=0)
    env.close()
    assert stopped.stop_reason == Stopping.stop_reason and not stopped.success
    assert plain.stop_reason is None
    data = EvalReport(ENV_ID, "zero", 2, 0, {}, [stopped, plain], np.array([1.0, 2.0])).to_json()
    assert data["per_episode"][0]["stop_reason"] == Stopping.stop_reason
    assert "stop_reason" not in data["per_episode"][1]
    lines = [line.split(None, 3) for line in format_report(data).splitlines() if line.startswith("stopped")]
    assert lines == [["stopped,", "seed", "0", Stopping.stop_reason]]


def test_terrain_metrics_count_failures_by_the_class_where_they_failed() -> None:
    import numpy as np

    from redundancy_gym.eval.evaluate import EpisodeSummary, EvalReport

    def episode(seed: int, success: bool, kind: str, unsupported: int, support: float) -> EpisodeSummary:
        return EpisodeSummary(
            seed,
            100,
            1.0,
            success,
            False,
            0.0,
            0.0,
            1.0,
            1.0,
            terrain_kind=kind,
            unsupported_steps=unsupported,
            min_support_fraction=support,
            fell=not success,
            forward_speed=0.4,
        )

    summaries = [
        episode(0, True, "stairs", 0, 0.9),
        episode(1, False, "stairs", 1, 0.3),
        episode(2, False, "rough", 0, 0.8),
        episode(3, False, "stairs", 0, 0.7),
    ]
    data = EvalReport("redundancy_gym/BipedTerrain-v0", "walking", 4, 0, {}, summaries, np.ones(4)).to_json()
    assert data["failures_by_terrain"] == {"rough": 1, "stairs": 2}
    assert data["unsupported_rate"] == 0.25 and data["min_support_fraction"] == 0.3
    assert data["per_episode"][1]["terrain_kind"] == "stairs" and data["per_episode"][1]["unsupported_steps"] == 1
    rows = {line[:37].strip(): line[37:].strip() for line in format_report(data).splitlines()}
    assert rows["failures by terrain class"] == "rough 1, stairs 2" and rows["min support fraction"] == "0.30"
    plain = EvalReport(
        ENV_ID, "zero", 1, 0, {}, [EpisodeSummary(0, 1, 0.0, False, False, 0.0, 0.0, 1.0, 1.0)], np.ones(1)
    )
    assert "failures_by_terrain" not in plain.to_json()


def test_a_walk_that_lands_unsupported_fails_on_that_segment_though_it_walks_on() -> None:
    import gymnasium as gym
    import numpy as np

    from redundancy_gym.eval.evaluate import run_episode

    class Scripted(gym.Env):
        """A walk over stones, flat ground and a slope: an unsupported touchdown on the stones at step 2."""

        observation_space = gym.spaces.Box(-1.0, 1.0, (1,))
        action_space = gym.spaces.Box(-1.0, 1.0, (1,))
        kinds = ("flat", "stepping_stones", "stepping_stones", "flat", "slope", "slope")

        def __init__(self, unsupported: bool) -> None:
            self.unsupported = unsupported

        def reset(self, *, seed: int | None = None, options: dict[str, object] | None = None) -> tuple:
            self.n = 0
            return np.zeros(1), {}

        def step(self, action: object) -> tuple:
            self.n += 1
            info = {
                "terrain_kind": self.kinds[self.n - 1],
                "unsupported_steps": int(self.n >= 2 and self.unsupported),
                "min_support_fraction": 0.4,
            }
            return np.zeros(1), 0.0, False, self.n == len(self.kinds), info

    class Still:
        def predict(self, obs: object, **_: object) -> tuple:
            return np.zeros(1), None

    summary, _ = run_episode(Scripted(unsupported=True), Still(), 0)
    assert summary.terrain_kind == "stepping_stones" and summary.unsupported_steps == 1
    # a walk that ends on the slope is reported there
    summary, _ = run_episode(Scripted(unsupported=False), Still(), 0)
    assert summary.terrain_kind == "slope"


def test_numba_compilation_is_counted_apart_from_the_step_times() -> None:
    import gymnasium as gym
    import numba

    from redundancy_gym import make_policy
    from redundancy_gym.eval.evaluate import run_episode

    @numba.njit(cache=False)
    def fresh(x: float) -> float:  # compiles at its first call: a cold kernel in this process
        return x * 2.0 + 1.0

    class CompilingClik:
        """The clik policy, with a kernel compiled inside its first predict."""

        def __init__(self, env):
            self.inner = make_policy("clik", env)
            self.calls = 0

        def predict(self, obs, state=None, episode_start=None, deterministic=True):
            self.calls += 1
            if self.calls == 1:
                fresh(1.0)
            return self.inner.predict(obs, state=state, episode_start=episode_start, deterministic=deterministic)

    env = gym.make("redundancy_gym/PlanarReach-v0", max_episode_steps=5)
    summary, trace = run_episode(env, CompilingClik(env), 0)
    assert summary.compile_time_s > 0.02  # a fresh njit takes tens of milliseconds to compile
    # the first step's time is the policy's own, not the compiler's
    assert trace.step_time_us[0] < summary.compile_time_s * 1e6 / 2
