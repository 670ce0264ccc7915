"""The numba options of every compiled kernel and how an owner compiles its kernels (at their first call), defined
once (geometry, model and controllers import them; the lowest layer of the package, beside
:mod:`redundancy_gym.validation`)."""

from __future__ import annotations

from typing import Any

from .kernel_pack import install_seeding

__all__ = [
    "BACKENDS",
    "BORROW",
    "BORROW_EXACT",
    "DEFAULT_BACKEND",
    "JIT",
    "JIT_EXACT",
    "LazyEntryPoint",
    "njit_on_first_call",
]

# before any kernel is defined: every module that defines kernels imports this one first
install_seeding()

# error_model="numpy": a division by zero gives inf instead of a checked branch that raises (every division
# in the kernels is guarded or measured afterwards). The fast-math subset allows fused multiply-adds and ignoring
# the sign of zero; it keeps IEEE NaN/inf semantics, which the guards rely on. Not "arcp" (x / y as x * (1 / y)):
# LLVM applies it where it sees the divisions after inlining, and what it inlines depends on what the process
# compiled before (numba's symbol ids and link order), so a kernel compiled after a warm-up rounded differently
# from the same kernel compiled first: one 52 s BipedTerrain episode returned 8363.5 against 8277.5. Without it
# the compiled code rounds the same in every compile history (tests/test_kernel_options.py).
JIT: dict[str, Any] = {"cache": True, "error_model": "numpy", "fastmath": {"contract", "nsz"}}
"""The default: cached, numpy's error model, the fast-math subset that keeps NaN/inf semantics."""

JIT_EXACT: dict[str, Any] = {"cache": True, "error_model": "numpy"}
"""Without fast math, for kernels held bit for bit to a Python twin that evaluates in plain IEEE order."""

# Kernels that only borrow arrays (they never allocate, keep or return one) are compiled without numba's
# reference counting: with it, every call paid an NRT_incref and an NRT_decref per array argument, 26 calls for
# a pair loop's 13 arrays, about 200 ns per batch on AMD Zen 5 whatever its size (as much as 40 sphere pairs).
# ``_nrt`` is outside numba's documented options; the tests cover every kernel compiled with it.
BORROW: dict[str, Any] = {**JIT, "_nrt": False}
""":data:`JIT` without reference counting, for kernels that only borrow arrays."""

# Which twin runs: every controller with a compiled twin (Clik/CompiledClik, WholeBodyIk/CompiledWholeBodyIk, the
# walking measurement/CompiledMeasurement, PredictiveIk.optimize's Python loop/pik_optimize, TerrainMap.observe's
# NumPy path/write_scan) and every policy option that picks one takes ``backend`` with these choices and this
# default (checked by validation.check_backend).
BACKENDS: tuple[str, ...] = ("compiled", "python")
"""The implementations a ``backend`` argument chooses between: the compiled twin, or the readable Python reference
it is held equal to (to round-off) by the tests."""

DEFAULT_BACKEND = "compiled"
"""The ``backend`` of every controller and policy that has a compiled twin, unless the caller says otherwise."""

BORROW_EXACT: dict[str, Any] = {**JIT_EXACT, "_nrt": False}
""":data:`JIT_EXACT` without reference counting, for exact kernels that only borrow arrays."""


class LazyEntryPoint:
    """A compiled kernel's entry point as an attribute of the object that calls it, compiled (or loaded from
    numba's on-disk cache) at its first call, not when its owner is built: an env, controller or policy that is
    made but never stepped (``redundancy-gym list``, a wrapper's reference, a collision batch a policy does not
    query) compiles nothing.

    At its first call it compiles ``kernel`` for ``signature`` (a numba signature string; ``None``: the types of
    that call's arguments), puts the compiled entry point in ``owner.<attribute>`` in its place and calls it; from
    then on the owner calls the entry point directly, which skips the dispatcher's type matching on every call.
    """

    __slots__ = ("_attribute", "_entry", "_kernel", "_owner", "_signature")

    def __init__(self, owner: object, attribute: str, kernel: Any, signature: str | None = None) -> None:
        self._owner: object | None = owner
        self._attribute = attribute
        self._kernel = kernel
        self._signature = signature
        self._entry: Any = None

    def resolve(self, *args: Any) -> Any:
        """Compile (or load) the kernel for the signature, or for ``args``' types, and put its entry point in
        the owner's attribute; returns it (a stand-in kept elsewhere goes on calling it)."""
        if self._entry is None:
            from numba import typeof

            signature = self._signature if self._signature is not None else tuple(typeof(a) for a in args)
            self._entry = self._kernel.compile(signature)
            setattr(self._owner, self._attribute, self._entry)
            self._owner = None  # the owner holds the entry point now; no cycle left behind
        return self._entry

    def __call__(self, *args: Any) -> Any:
        return self.resolve(*args)(*args)


class _LazyJit:
    """A module-level function that numba compiles for one signature at its first call (see
    :func:`njit_on_first_call`); it then puts the compiled dispatcher in the module in its place."""

    __slots__ = ("_options", "_py_func", "_signature")

    def __init__(self, py_func: Any, signature: Any, options: dict[str, Any]) -> None:
        self._py_func = py_func
        self._signature = signature
        self._options = options

    def __call__(self, *args: Any) -> Any:
        import sys

        from numba import njit

        dispatcher = njit(self._signature, **self._options)(self._py_func)
        setattr(sys.modules[self._py_func.__module__], self._py_func.__name__, dispatcher)
        return dispatcher(*args)


def njit_on_first_call(signature: Any, **options: Any) -> Any:
    """``numba.njit(signature, **options)`` deferred from import to the function's first call: a decorator for a
    module-level kernel with one explicit signature that Python code calls by its module global (the compiled
    dispatcher replaces that global, so later calls cost what a plain ``njit`` function's do). Importing the module
    (``redundancy-gym list``, a policy registry lookup) then compiles nothing."""

    def wrap(py_func: Any) -> Any:
        return _LazyJit(py_func, signature, options)

    return wrap
