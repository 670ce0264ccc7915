"""warmup: every analytic policy an env supports is run once and the cache it fills is where it says; unknown ids
and bad worker counts are named. The warm-ups run in a subprocess with their own NUMBA_CACHE_DIR, so that they do not
change which kernels this test process compiles, in which order."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.eval.warmup import warmup


def _run(code: str, cache: str) -> subprocess.CompletedProcess[str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=1200)


def test_warmup_runs_every_analytic_policy_and_fills_the_named_cache(tmp_path):
    code = (
        "from redundancy_gym.cli import main; import sys; "
        "sys.exit(main(['warmup', 'redundancy_gym/PlanarReach-v0', '--no-progress']))"
    )
    done = _run(code, str(tmp_path))
    assert done.returncode == 0, done.stderr
    assert "redundancy_gym/PlanarReach-v0" in done.stdout and "clik, predictive, global" in done.stdout
    assert f"numba cache: {tmp_path} (NUMBA_CACHE_DIR moves it)" in done.stdout
    assert list(tmp_path.rglob("*.nbc"))  # the compiled kernels are there


@pytest.mark.parametrize(("kwargs", "named"), [({"env_ids": ["Nope-v0"]}, "Nope-v0"), ({"workers": 0}, "workers")])
def test_bad_arguments_are_named(kwargs, named):
    with pytest.raises(EvalError, match=named):
        warmup(progress=False, **kwargs)


def test_the_cli_refuses_unknown_ids(capsys):
    from redundancy_gym.cli import main

    assert main(["warmup", "Nope-v0", "--no-progress"]) == 2
    assert "unknown env id Nope-v0; valid: redundancy_gym/PlanarReach-v0" in capsys.readouterr().err
