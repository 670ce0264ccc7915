"""The box covers of :func:`box_volumes`: two TSS on the box's mid-plane hold the whole box, and reach no further
than their radius beyond its sides."""

from __future__ import annotations

import itertools

import mujoco
import numpy as np
import pytest

from redundancy_gym.assets import BIPED_XML
from redundancy_gym.geometry import PSS, distance
from redundancy_gym.model import ModelError, RobotModel, box_volumes


@pytest.fixture(scope="module")
def model() -> RobotModel:
    return RobotModel.from_mjcf(BIPED_XML)


def _cover_distance(point: np.ndarray, cover) -> float:
    return min(distance(PSS(point, 0.0), v).distance for v in cover)


@pytest.mark.parametrize("name, segment", [("r_sole_geom", "r_foot"), ("l_toe_sole_geom", "l_toe")])
def test_a_box_cover_holds_the_box_and_ends_a_radius_beyond_its_sides(model: RobotModel, name: str, segment: str):
    mj = mujoco.MjModel.from_xml_path(str(BIPED_XML))
    geom = mj.geom(name)
    half, center = np.asarray(geom.size), np.asarray(geom.pos)  # the body frame is the joint frame here
    cover = box_volumes(model, [name])[segment]
    assert len(cover) == 2 and all(v.radius == pytest.approx(half.min()) for v in cover)
    rng = np.random.default_rng(0)
    corners = [center + np.array(s) * half for s in itertools.product((-1, 1), repeat=3)]
    for point in corners + list(center + rng.uniform(-1, 1, (200, 3)) * half):
        assert _cover_distance(point, cover) <= 1e-12  # inside the cover
    # beyond a side by the radius and 1 mm: 1 mm outside; above the top face by as much: that far, the cover's top
    # being the box's
    thin = float(half.min())
    for axis in (0, 1):
        for sign in (-1, 1):
            point = center.copy()
            point[axis] += sign * (half[axis] + thin + 1e-3)
            assert _cover_distance(point, cover) == pytest.approx(1e-3, abs=1e-12)
    assert _cover_distance(center + np.array([0.0, 0.0, 2 * thin + 1e-3]), cover) == pytest.approx(1e-3 + thin)


def test_box_volumes_names_the_boxes_when_a_name_is_not_one(model: RobotModel):
    with pytest.raises(ModelError, match=r"box geoms \['r_foot_geom'\] not in .*r_sole_geom"):
        box_volumes(model, ["r_foot_geom"])
