"""warmup: every analytic policy an env supports is run once; unknown ids and bad worker counts are named; the cache
location follows NUMBA_CACHE_DIR; the CLI prints where the cache is."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.eval.warmup import warmup


def test_warmup_runs_every_analytic_policy_of_the_env():
    (row,) = warmup(["redundancy_gym/PlanarReach-v0"], progress=False)
    assert row.env_id == "redundancy_gym/PlanarReach-v0"
    assert set(row.policies) == {"clik", "predictive", "global"}
    assert 0.0 <= row.compile_s <= row.seconds


@pytest.mark.parametrize(("kwargs", "named"), [({"env_ids": ["Nope-v0"]}, "Nope-v0"), ({"workers": 0}, "workers")])
def test_bad_arguments_are_named(kwargs, named):
    with pytest.raises(EvalError, match=named):
        warmup(progress=False, **kwargs)


def test_the_cache_location_follows_numba_cache_dir(tmp_path):
    code = "from redundancy_gym.eval.warmup import numba_cache_location; print(numba_cache_location())"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    assert done.stdout.strip() == str(tmp_path)


def test_the_cli_names_the_cache_and_refuses_unknown_ids(capsys):
    from redundancy_gym.cli import main

    assert main(["warmup", "redundancy_gym/PlanarReach-v0", "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "clik, predictive, global" in out and "numba cache: " in out and "NUMBA_CACHE_DIR" in out
    assert main(["warmup", "Nope-v0", "--no-progress"]) == 2
    assert "unknown env id Nope-v0; valid: redundancy_gym/PlanarReach-v0" in capsys.readouterr().err
