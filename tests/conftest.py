"""Shared fixtures: headless rendering and the planar-arm model."""

from __future__ import annotations

import os

os.environ.setdefault("MUJOCO_GL", "osmesa")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from redundancy_gym.assets import PLANAR_ARM_XML  # noqa: E402
from redundancy_gym.model import RobotModel  # noqa: E402


@pytest.fixture()
def planar_model() -> RobotModel:
    return RobotModel.from_mjcf(PLANAR_ARM_XML)


@pytest.fixture()
def rng() -> np.random.Generator:
    return np.random.default_rng(1234)


@pytest.fixture(autouse=True, scope="session")
def _sb3_logs_in_the_session_folder(tmp_path_factory: pytest.TempPathFactory) -> None:
    """The tests that train as a user's plain script does (SB3's default logger) put its ``SB3-<date>`` folders
    under pytest's own temporary folder, not in /tmp; child processes inherit it."""
    os.environ.setdefault("SB3_LOGDIR", str(tmp_path_factory.mktemp("sb3_logs")))


# hypothesis profiles for tests/fuzz: "fast" (default, `make test`: deterministic, a few dozen examples per
# test) and "nightly" (>= 1000 examples per test): HYPOTHESIS_PROFILE=nightly pytest tests/fuzz
try:
    from hypothesis import HealthCheck, settings
except ImportError:  # hypothesis comes with the `test` extra; only tests/fuzz needs it
    pass
else:
    _SUPPRESSED = [
        HealthCheck.too_slow,
        HealthCheck.function_scoped_fixture,
        HealthCheck.data_too_large,
        HealthCheck.filter_too_much,
    ]
    settings.register_profile(
        "fast",
        max_examples=30,
        deadline=None,
        derandomize=True,
        database=None,
        print_blob=True,
        suppress_health_check=_SUPPRESSED,
    )
    settings.register_profile(
        "nightly", max_examples=1000, deadline=None, print_blob=True, suppress_health_check=_SUPPRESSED
    )
    settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "fast"))
