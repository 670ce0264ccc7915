"""The one compiled Cholesky factorization and solve of the controllers against numpy.linalg."""

from __future__ import annotations

import numpy as np
import pytest

from redundancy_gym.controllers.kernels.linalg import cholesky_factor, cholesky_solve


def _spd(rng: np.random.Generator, m: int) -> np.ndarray:
    """A random symmetric positive definite m x m matrix, condition number up to about 1e6."""
    basis, _ = np.linalg.qr(rng.normal(size=(m, m)))
    return (basis * np.logspace(0.0, -6.0 * rng.uniform(), m)) @ basis.T


@pytest.mark.parametrize("m", [1, 2, 5, 6, 18])
def test_factor_and_solve_match_numpy_on_random_spd_matrices(m: int) -> None:
    rng = np.random.default_rng(m)
    for _ in range(20):
        a = _spd(rng, m)
        a = 0.5 * (a + a.T)
        low = np.full((m, m), 7.0)  # the upper triangle must stay as it was
        pivot = cholesky_factor(a, m, low)
        expected = np.linalg.cholesky(a)
        np.testing.assert_allclose(np.tril(low), expected, rtol=1e-10, atol=1e-12 * np.abs(expected).max())
        assert np.all(low[np.triu_indices(m, 1)] == 7.0)
        assert pivot == np.diag(low).min() and pivot > 0.0
        rhs = rng.normal(size=m)
        x = rhs.copy()
        cholesky_solve(low, m, x)
        solution = np.linalg.solve(a, rhs)
        np.testing.assert_allclose(x, solution, rtol=1e-6, atol=1e-9 * np.abs(solution).max())
        assert np.linalg.norm(a @ x - rhs) <= 1e-9 * np.linalg.norm(rhs)


def test_leading_block_of_a_larger_buffer() -> None:
    # the kernels factor the leading m x m block of a fixed 6 x 6 scratch: the rest is neither read nor written
    rng = np.random.default_rng(3)
    a = np.full((6, 6), np.nan)
    a[:4, :4] = _spd(rng, 4)
    low = np.full((6, 6), -1.0)
    assert cholesky_factor(a, 4, low) > 0.0
    np.testing.assert_allclose(np.tril(low[:4, :4]), np.linalg.cholesky(a[:4, :4]), rtol=1e-10, atol=1e-14)
    assert np.all(low[4:, :] == -1.0) and np.all(low[:, 4:] == -1.0)
    x = np.array([1.0, 2.0, 3.0, 4.0, np.nan, np.nan])
    cholesky_solve(low, 4, x)
    np.testing.assert_allclose(a[:4, :4] @ x[:4], [1.0, 2.0, 3.0, 4.0], atol=1e-9)
    assert np.all(np.isnan(x[4:]))


@pytest.mark.parametrize(
    "name, a",
    [
        ("singular", np.array([[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [3.0, 6.0, 10.0]])),  # rank 2: second pivot 0
        ("zero", np.zeros((3, 3))),
        ("indefinite", np.diag([1.0, -1.0, 2.0])),
        ("nan", np.array([[1.0, 0.0], [0.0, np.nan]])),
    ],
)
def test_not_positive_definite_returns_failure_not_nan(name: str, a: np.ndarray) -> None:
    # where LAPACK fails, so does the kernel; a NaN pivot, which LAPACK passes on into its factor, fails too
    m = a.shape[0]
    if name != "nan":
        with pytest.raises(np.linalg.LinAlgError):
            np.linalg.cholesky(a)
    assert cholesky_factor(a, m, np.zeros((m, m))) == 0.0, name


def test_empty_system_has_no_pivot() -> None:
    # m = 0 (a task of no rows): nothing to factor, the smallest pivot is that of an empty set
    assert cholesky_factor(np.zeros((0, 0)), 0, np.zeros((0, 0))) == np.inf
