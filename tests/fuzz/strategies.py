"""Shared hypothesis strategies: well-formed values, and hostile ones (NaN, inf, huge, wrong types/shapes)."""

from __future__ import annotations

import numpy as np
from hypothesis import strategies as st

HUGE = 1e300
NON_FINITE = st.sampled_from([float("nan"), float("inf"), float("-inf")])
# ordinary magnitudes, plus the edge values
SANE_FLOATS = st.floats(min_value=-10.0, max_value=10.0, allow_nan=False, allow_infinity=False)
ANY_FLOATS = st.one_of(
    SANE_FLOATS,
    NON_FINITE,
    st.sampled_from([HUGE, -HUGE, 1e-300, 0.0, -0.0]),
    st.floats(allow_nan=True, allow_infinity=True),
)
JUNK = st.one_of(
    st.none(),
    st.text(max_size=3),
    st.booleans(),
    st.just([]),
    st.just({}),
    st.just(object()),
    st.lists(st.integers(-3, 3), max_size=5),
    st.just(np.array(["a", "b", "c"])),
    st.just(1 + 2j),
)


def vectors(n: int, elements: st.SearchStrategy = SANE_FLOATS) -> st.SearchStrategy:
    return st.lists(elements, min_size=n, max_size=n).map(lambda v: np.array(v, dtype=np.float64))


def hostile_vectors(n: int) -> st.SearchStrategy:
    """Mostly well-formed n-vectors, some with non-finite or huge entries, some of the wrong shape or type."""
    return st.one_of(
        vectors(n),
        vectors(n, ANY_FLOATS),
        st.integers(0, 7).filter(lambda k: k != n).flatmap(lambda k: vectors(k)),
        st.lists(st.integers(-5, 5), min_size=n, max_size=n),
        JUNK,
    )


def points3() -> st.SearchStrategy:
    return hostile_vectors(3)


def radii() -> st.SearchStrategy:
    return st.one_of(st.floats(0.0, 2.0), ANY_FLOATS, st.integers(-3, 3), JUNK)
