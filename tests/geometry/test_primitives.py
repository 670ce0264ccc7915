"""Swept-sphere volumes built from their packed form."""

from __future__ import annotations

import pytest

from redundancy_gym.geometry import LSS, PSS, SSV, TSS, GeometryError


def test_from_kind_builds_each_volume_from_its_packed_rows_and_rejects_another_kind():
    rows = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    assert SSV.from_kind(0, rows, 0.1) == PSS(rows[0], 0.1)
    assert SSV.from_kind(1, rows, 0.1) == LSS(rows[0], rows[1], 0.1)
    assert SSV.from_kind(2, rows, 0.1) == TSS(rows[0], rows[1], rows[2], 0.1)
    with pytest.raises(GeometryError, match="kind must be 0"):
        SSV.from_kind(3, rows, 0.1)
