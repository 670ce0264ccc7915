"""bench pik: every part runs and its figures are consistent (quick settings)."""

from __future__ import annotations

import json

import pytest

from redundancy_gym.bench.pik import format_pik_bench, run_pik_bench
from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.eval.json_writer import write_json
from redundancy_gym.studies.predictive_figures import JUMP_SAMPLE_TIME


def test_pik_bench_report(tmp_path) -> None:
    report = run_pik_bench(episodes=1, rounds=2, quick=True, progress=False)
    planar = report["planar"]
    assert set(planar) == {"clik", "predictive", "global"}
    assert report["planar_mpc_vs_local_pseudoenergy"] == pytest.approx(
        planar["predictive"]["pseudoenergy"] / planar["clik"]["pseudoenergy"]
    )
    agri = report["agri_self_collision"]
    assert set(agri) == {"local CLIK", "MPC 0.15 s", "MPC 2 s", "global"}
    assert report["agri_horizon2s_update_ms_median"] == agri["MPC 2 s"]["update_ms_median"] > 0.0
    # the update times come from alternating rounds of timed rollouts: MPC against the local CLIK step
    assert report["timing"]["orders"] == [
        ["local CLIK", "MPC 0.15 s", "MPC 2 s"],
        ["MPC 2 s", "MPC 0.15 s", "local CLIK"],
    ]
    for name in ("agri_horizon2s_vs_local", "agri_horizon015s_vs_local"):
        stats = report[f"{name}_rounds"]
        assert report[name] == stats["median"] and stats["rounds"] == 2
        assert 1.0 < stats["min"] <= stats["median"] <= stats["max"]  # an MPC update costs more than a CLIK step
    assert report["agri_horizon2s_vs_local"] > report["agri_horizon015s_vs_local"]
    assert report["agri_horizon2s_vs_local"] == pytest.approx(
        agri["MPC 2 s"]["update_ms_median"] / agri["local CLIK"]["update_ms_median"], rel=0.5
    )
    assert len(report["machine"]["load_average_end"]) == 3
    descent = report["descent"]
    assert descent["cg_costs"][0] == descent["sd_costs"][0] > descent["best_cost"]
    # figs. 5.33/5.34: with a coarse prediction sample the velocity-level inputs are a staircase, the augmented
    # ones continuous
    coarse = next(r for r in report["velocity_jumps"] if r["sample_time"] == JUMP_SAMPLE_TIME)
    assert report["nullspace_jump_ratio"] == coarse["nullspace_jump_ratio"] >= 10.0
    assert coarse["velocity_kink_ratio"] >= 10.0 and coarse["velocity_jump_ratio"] > 1.0
    fine = next(r for r in report["velocity_jumps"] if r["sample_time"] == 0.01)
    assert fine["velocity_kink_ratio"] < 2.0  # one sample per control period: neither variant jumps
    for name in ("local CLIK", "MPC 0.15 s", "MPC 2 s", "global"):  # fig. 5.35: the self-collision move stays clear
        assert not agri[name]["collision"]
    assert agri["MPC 2 s"]["pseudoenergy"] < agri["MPC 0.15 s"]["pseudoenergy"] < agri["local CLIK"]["pseudoenergy"]
    assert "agri_horizon2s_update_ms_median" in format_pik_bench(report)
    written = json.loads(write_json(report, tmp_path / "pik.json").read_text())
    assert written["agri_horizon2s_update_ms_median"] == report["agri_horizon2s_update_ms_median"]
    with pytest.raises(EvalError, match="episodes"):
        run_pik_bench(episodes=0, progress=False)
    with pytest.raises(EvalError, match="rounds"):
        run_pik_bench(rounds=0, progress=False)
