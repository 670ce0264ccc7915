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
