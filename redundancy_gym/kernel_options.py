"""The numba options of every compiled kernel, defined once (geometry, model and controllers import them; the
lowest layer of the package, beside :mod:`redundancy_gym.validation`)."""

from __future__ import annotations

from typing import Any

__all__ = ["BORROW", "JIT", "JIT_EXACT"]

# error_model="numpy": a division by zero gives inf instead of a checked branch that raises (every division
# in the kernels is guarded or measured afterwards). The fast-math subset allows fused multiply-adds, reciprocal
# multiplication and ignoring the sign of zero; it keeps IEEE NaN/inf semantics, which the guards rely on.
JIT: dict[str, Any] = {"cache": True, "error_model": "numpy", "fastmath": {"contract", "arcp", "nsz"}}
"""The default: cached, numpy's error model, the fast-math subset that keeps NaN/inf semantics."""

JIT_EXACT: dict[str, Any] = {"cache": True, "error_model": "numpy"}
"""Without fast math, for kernels held bit for bit to a Python twin that evaluates in plain IEEE order."""

# Kernels that only borrow arrays (they never allocate, keep or return one) are compiled without numba's
# reference counting: with it, every call paid an NRT_incref and an NRT_decref per array argument, 26 calls for
# a pair loop's 13 arrays, about 200 ns per batch on AMD Zen 5 whatever its size (as much as 40 sphere pairs).
# ``_nrt`` is outside numba's documented options; the tests cover every kernel compiled with it.
BORROW: dict[str, Any] = {**JIT, "_nrt": False}
""":data:`JIT` without reference counting, for kernels that only borrow arrays."""
