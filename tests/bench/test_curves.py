"""bench curves (seconds): the quick study writes its JSON, markdown and plot, says a learner that never reaches a
threshold did not within its budget, picks runs by env or env-learner, summarizes seeds over common budgets and
names a learner's best budget when it unlearns; the plot draws success and the error against steps and CPU time."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from redundancy_gym.bench.curves import _select, _steps, _summary, _warm_up_note, budget_table, curves_markdown
from redundancy_gym.bench.exceptions import BenchError
from redundancy_gym.cli import main


def test_the_quick_study_writes_a_two_point_curve(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "curves.json"
    assert main(["bench", "curves", "--quick", "--json", str(path), "--no-progress"]) == 0
    table = json.loads(path.read_text())
    learner = table["envs"]["planar_reach"]["learners"]["ppo"]
    assert [p["budget"] for p in learner["seeds"]["0"]] == [64, 128]
    assert learner["largest_budget"] == 128 and learner["first_0.5"] is None  # 128 steps learn nothing
    assert learner["command"] == f"redundancy-gym bench curves --quick --json {path}"  # what gives these points
    assert table["envs"]["planar_reach"]["references"]["clik"]["success_rate"] == 1.0
    assert "not within 128" in path.with_suffix(".md").read_text()
    assert (tmp_path / "curves_planar_reach.png").stat().st_size > 0
    assert (tmp_path / "runs" / "curves" / "planar_reach-ppo-s0.zip").is_file()  # the agent, apart from the points


def test_runs_are_picked_by_env_or_learner():
    assert {learner.name for _, learner in _select(["planar_reach"], False)} == {"ppo", "ppo-norm", "sac", "tqc"}
    assert [(e.key, learner.name) for e, learner in _select(["agri_reach_easy-ppo"], False)] == [
        ("agri_reach_easy", "ppo")
    ]
    with pytest.raises(BenchError, match="unknown curve env or learner nowhere; valid: planar_reach"):
        _select(["nowhere"], False)


def test_a_variant_changes_the_env_it_trains_and_is_evaluated_on_or_only_the_training_env():
    from redundancy_gym.bench.curves import _run

    (env, no_energy), (_, blind) = _select(["agri_reach_easy-ppo-no-obstacles", "agri_reach_easy-ppo-no-energy"], False)
    run = _run(env, blind, 0, None, 10)
    assert run.env_kwargs == {"difficulty": "easy", "observed_obstacles": 0} and run.train_env_kwargs == {}
    run = _run(env, no_energy, 0, None, 10)
    assert run.env_kwargs == {"difficulty": "easy"} and run.train_env_kwargs == {"energy_weight": 0.0}
    assert env.env_kwargs == {"difficulty": "easy"}  # the study's env is left as it was


def points(successes):
    """A seed's points at budgets 10, 100 and 1000, as far as ``successes`` goes."""
    return [
        {"budget": b, "steps": b, "cpu_s": b / 100, "success_rate": s, "goal_error": 0.1 / b}
        for b, s in zip((10, 100, 1000), successes, strict=False)
    ]


def one_env_table(learners, references):
    """A study of one env ``x`` with 2 training seeds, as ``run_curves_bench`` writes it."""
    error = {"key": "goal_error", "label": "goal error", "unit": "mm", "scale": 1e3}
    env = {"title": "X", "env_id": "e", "env_kwargs": {}, "error": error, "references": references}
    return {"seeds": 2, "eval_seed": 40000, "episodes": 3, "envs": {"x": {**env, "learners": learners}}}


def test_the_summary_uses_budgets_every_seed_reached():
    summary = _summary({"0": points([0.0, 0.6, 1.0]), "1": points([0.0, 0.2])}, "goal_error")
    assert [r["budget"] for r in summary["by_budget"]] == [10, 100]  # seed 1 has not reached 1000
    assert summary["by_budget"][1]["success_mean"] == pytest.approx(0.4)
    apart = {"0": points([0.0, 0.6]), "1": points([0.0, 0.2])}
    apart["1"][1]["goal_error"] = 0.004  # seed 0 at 100 steps: 1 mm
    row = _summary(apart, "goal_error")["by_budget"][1]
    assert (row["error_min"], row["error_mean"], row["error_max"]) == pytest.approx((0.001, 0.0025, 0.004))
    assert summary["first_0.5"] is None and summary["largest_budget"] == 100
    both = _summary({"0": points([0.0, 0.6, 1.0]), "1": points([0.0, 0.5, 0.8])}, "goal_error")
    assert both["first_0.5"] == 100 and both["first_0.9"] == 1000
    references = {"clik": {"success_rate": 1.0, "goal_error": 0.001}}
    text = curves_markdown(one_env_table({"ppo": {"seeds": {"0": [], "1": []}, **both}}, references))
    assert "| ppo | 2 | 1k | 0.90 (0.80-1.00) |" in text and "| 100 | 1k |" in text


def test_the_markdown_lists_the_points_of_seeds_beyond_the_common_budget():
    """A seed lost or behind caps the learner's row at the budget every seed reached; what the others reached past it
    is listed under the env's table, not hidden."""
    seeds = {"0": points([0.0, 0.6, 1.0]), "1": points([0.0, 0.2])}
    table = one_env_table({"ppo": {"seeds": seeds, **_summary(seeds, "goal_error")}}, {})
    text = curves_markdown(table)
    assert "| ppo | 2 | 100 | 0.40 (0.20-0.60) |" in text
    beyond = "- ppo beyond 100 steps (not every seed there): seed 0 at 1k steps: success 1.00, goal error 0.1 mm."
    assert beyond in text
    assert "seed 1 at" not in text
    seeds["1"] = points([0.0, 0.2, 0.4])
    table["envs"]["x"]["learners"]["ppo"] = {"seeds": seeds, **_summary(seeds, "goal_error")}
    assert "beyond" not in curves_markdown(table).split("Largest budget")[1].split("### X")[1]


def test_the_budget_table_names_the_peak_of_a_learner_that_unlearns():
    drifting = [points([0.8, 1.0, 0.0]), points([0.6, 1.0, 0.2])]
    for seed in drifting:  # nearest at 100 steps, then farther again: 10, 1 and 5 mm
        seed[2]["goal_error"] = 0.005
    peaked = _summary(dict(enumerate(drifting)), "goal_error")
    never = _summary({"0": points([0.0, 0.0, 0.0])}, "goal_error")
    error = {"key": "goal_error", "label": "goal error", "unit": "mm", "scale": 1e3}
    envs = {"x": {"title": "X", "error": error, "learners": {"slow": {"seeds": {"0": [], "1": []}, **peaked}}}}
    envs["y"] = {"title": "Y", "error": error, "learners": {"ppo": {"seeds": {"0": []}, **never}}}
    lines = budget_table({"envs": envs})
    assert "| X | slow | 2 | 1k | 0.10 | 5 mm | 1.00 (100); 1 mm (100) | 10 | 100 |" in lines
    never_row = "| Y | ppo | 1 | 1k | 0.00 | 0.1 mm | 0.00; 0.1 mm (1k) | not within 1k | not within 1k |"
    assert never_row in lines


def test_budgets_are_written_short_only_where_exact():
    assert [_steps(n) for n in (3_000_000, 300_000, 10_000, 1_500, 1_001_472, 999)] == [
        "3M",
        "300k",
        "10k",
        "1,500",
        "1,001,472",
        "999",
    ]


def test_an_error_of_a_metre_or_more_is_written_in_millimetres_in_full():
    from redundancy_gym.bench.curves import _error

    env = {"error": {"scale": 1000.0, "unit": "mm"}}
    assert _error(env, {"error_mean": 1.0043}) == "1004 mm"
    assert _error(env, {"error_mean": 0.0583}) == "58.3 mm" and _error(env, {"error_mean": None}) == "-"
    row = {"error_mean": 0.501, "error_min": 0.412, "error_max": 1.2}
    assert _error(env, row, spread=True) == "501 (412-1200) mm" and _error(env, row) == "501 mm"


def test_the_readme_table_is_the_committed_study():
    """The README copies the budget table; it must say what ``baselines/results/curves.json`` says."""
    root = Path(__file__).resolve().parents[2]
    table = json.loads((root / "baselines" / "results" / "curves.json").read_text())
    expected = [line for line in budget_table(table) if line]
    readme = (root / "README.md").read_text().splitlines()
    start = readme.index(expected[0])
    assert readme[start : start + len(expected) + 1] == [*expected, ""]


def test_every_learner_of_the_study_trains_on_a_registered_env_id():
    """A learner named by the study but not registered (BipedObstacles' residual once was) fails only hours into a
    run; the table is checked here instead."""
    from redundancy_gym.bench.curves import CURVE_ENVS
    from redundancy_gym.registration import ENV_IDS

    learners = [(env.key, learner.name, learner.env_id) for env in CURVE_ENVS for learner in env.learners]
    assert [entry for entry in learners if entry[2] not in ENV_IDS] == []


def test_the_committed_study_is_complete_at_the_budgets_it_defines():
    """Every learner of the study has the points of its 3 seeds at each of its budgets (a capped run may have added
    one between), and no points are committed for a learner the study does not define: the whole study's command
    trains nothing on a clone, and the table's "not within N" is the learner's own last budget."""
    from redundancy_gym.bench.curves import CURVE_ENVS
    from redundancy_gym.learning.baselines import BASELINES_DIR

    folder = BASELINES_DIR / "results" / "curves"
    defined, short = set(), []
    for env in CURVE_ENVS:
        for learner in env.learners:
            for seed in range(3):
                name = f"{env.key}-{learner.name}-s{seed}"
                defined.add(f"{name}.json")
                path = folder / f"{name}.json"
                budgets = [p["budget"] for p in json.loads(path.read_text())["points"]] if path.is_file() else []
                if not set(learner.budgets) <= set(budgets):  # a capped run (--steps 200000) adds its own point
                    short.append((name, budgets))
    assert short == []
    committed = {p.name for p in folder.glob("*.json") if not p.name.startswith("references-")}
    assert committed - defined == set()


def test_a_run_that_cannot_be_trained_on_is_written_up_and_fails_the_command(tmp_path, monkeypatch, capsys):
    """A second study (another --json) finds the first's agent in the shared runs/curves: its run is refused, the
    refusal is in the study's notes and on stderr, and the exit status says the command did not do what it asked."""
    monkeypatch.chdir(tmp_path)
    assert main(["bench", "curves", "--quick", "--json", str(tmp_path / "a.json"), "--no-progress"]) == 0
    assert main(["bench", "curves", "--quick", "--json", str(tmp_path / "b.json"), "--no-progress"]) == 1
    notes = json.loads((tmp_path / "b.json").read_text())["notes"]
    assert "has no points, but" in notes["planar_reach-ppo-s0"]
    assert "not extended: planar_reach-ppo-s0" in capsys.readouterr().err
    assert "Runs not extended" in (tmp_path / "b.md").read_text()


def test_the_plot_draws_success_and_error_against_steps_and_cpu_time(tmp_path, monkeypatch):
    from redundancy_gym.bench.curves import plot_curves_bench
    from redundancy_gym.eval import plots

    kept = []

    def keep(fig, path, dpi=110):
        kept.append(fig)
        return Path(path)

    monkeypatch.setattr(plots, "save_figure", keep)
    rows = [
        {
            "budget": b,
            "steps_mean": b,
            "success_mean": s,
            "success_min": 0.0,
            "success_max": 2 * s,
            "error_mean": e,
            "error_min": e / 2,
            "error_max": 2 * e,
            "cpu_s_mean": c,
        }
        for b, s, e, c in ((10, 0.1, 0.02, 60.0), (100, 0.3, 0.005, 600.0))
    ]
    env = {
        "title": "T",
        "error": {"key": "goal_error", "label": "goal error", "unit": "mm", "scale": 1000.0},
        "references": {"clik": {"success_rate": 1.0, "goal_error": 0.001}},
        "learners": {"ppo": {"by_budget": rows, "seeds": {"0": [], "1": []}}},
    }
    assert plot_curves_bench({"envs": {"t": env}, "eval_seed": 7, "episodes": 3}, tmp_path) == [
        tmp_path / "curves_t.png"
    ]
    success_steps, success_cpu, error_steps, error_cpu = kept[0].axes
    for ax, x, y in (
        (success_steps, [10, 100], [0.1, 0.3]),
        (success_cpu, [1.0, 10.0], [0.1, 0.3]),  # CPU time in minutes
        (error_steps, [10, 100], [20.0, 5.0]),  # the error in its unit
        (error_cpu, [1.0, 10.0], [20.0, 5.0]),
    ):
        line = ax.get_lines()[0]
        assert list(line.get_xdata()) == pytest.approx(x) and list(line.get_ydata()) == pytest.approx(y)
    assert "CPU time" in error_cpu.get_xlabel() and error_cpu.get_ylabel() == "goal error [mm]"
    for ax in (error_steps, error_cpu):  # the min-max band over seeds, in the error's unit
        (band,) = ax.collections
        assert band.get_paths()[0].vertices[:, 1].min() == pytest.approx(2.5)  # 5 mm / 2
        assert band.get_paths()[0].vertices[:, 1].max() == pytest.approx(40.0)  # 20 mm * 2
    assert [ln.get_ydata()[0] for ln in error_cpu.get_lines()[1:]] == pytest.approx([1.0])  # clik's 1 mm


def test_the_markdown_says_which_points_precede_learning():
    def table(**hyperparameters):
        learner = {"hyperparameters": hyperparameters}
        return {"envs": {"a": {"learners": {"sac": learner, "tqc": learner}}, "b": {"learners": {"ppo": {}}}}}

    note = _warm_up_note(table(learning_starts=10_000))
    assert "(10k for sac, tqc)" in note and "ppo" not in note
    assert _warm_up_note(table(batch_size=64)) == ""  # on-policy learners learn from the first rollout
