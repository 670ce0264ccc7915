"""Shared numba kernels of the controllers: flat buffers, linear algebra (the rotation error, the one Cholesky
factorization and solve) and the package's numba options (re-exported from :mod:`redundancy_gym.kernel_options`)."""

from ...kernel_options import BORROW, BORROW_EXACT, JIT, JIT_EXACT
from .buffers import buffer_view, pack_fields
from .linalg import cholesky_factor, cholesky_solve, rotation_error, rotation_error_into

__all__ = [
    "BORROW",
    "BORROW_EXACT",
    "JIT",
    "JIT_EXACT",
    "buffer_view",
    "cholesky_factor",
    "cholesky_solve",
    "pack_fields",
    "rotation_error",
    "rotation_error_into",
]
