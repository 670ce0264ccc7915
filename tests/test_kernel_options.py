"""Kernels compiled at their first call: nothing compiles before it, the owner's attribute (or the module global)
becomes the compiled kernel, results are the kernel's, and a stand-in kept elsewhere still works. The fast-math
subset leaves out the flag whose effect depended on the process's compile history."""

from __future__ import annotations

import types

import numpy as np
from numba import njit

from redundancy_gym.kernel_options import BORROW, JIT, LazyEntryPoint, njit_on_first_call


def test_the_fast_math_subset_rounds_the_same_in_every_compile_history():
    # "arcp" made the whole-body IK's step round differently when compiled after other kernels (one BipedTerrain
    # episode: 8363.5 against 8277.5); `make test` runs the shipped models' episodes on warmed-up kernels to check it
    for options in (JIT, BORROW):
        assert set(options["fastmath"]) == {"contract", "nsz"}


def test_a_lazy_entry_point_compiles_at_its_first_call_and_hands_over():
    @njit(cache=False)
    def scaled_sum(x, k):
        return k * x.sum()

    class Owner:
        pass

    owner = Owner()
    owner.kernel = LazyEntryPoint(owner, "kernel", scaled_sum, "float64(float64[::1], float64)")
    kept = owner.kernel
    assert scaled_sum.signatures == []  # built, not compiled
    x = np.arange(4.0)
    assert owner.kernel(x, 2.0) == 12.0
    assert len(scaled_sum.signatures) == 1
    assert not isinstance(owner.kernel, LazyEntryPoint)  # the entry point itself from now on
    assert owner.kernel(x, 3.0) == 18.0 and kept(x, 1.0) == 6.0


def test_a_lazy_entry_point_without_a_signature_takes_the_first_call_types():
    @njit(cache=False)
    def add(a, b):
        return a + b

    holder = types.SimpleNamespace()
    holder.kernel = LazyEntryPoint(holder, "kernel", add)
    assert holder.kernel(2, 3) == 5 and [str(s) for s in add.signatures] == ["(int64, int64)"]


def test_njit_on_first_call_replaces_the_module_global():
    module = types.ModuleType("lazy_kernel_module")
    module.njit_on_first_call = njit_on_first_call
    exec(
        "@njit_on_first_call('float64(float64)', cache=False)\ndef twice(x):\n    return 2.0 * x\n"
        "def call(x):\n    return twice(x)\n",
        module.__dict__,
    )
    import sys

    sys.modules[module.__name__] = module
    try:
        assert not hasattr(module.twice, "signatures")  # imported, not compiled
        assert module.call(1.5) == 3.0
        assert [str(s) for s in module.twice.signatures] == ["(float64,)"]  # a numba dispatcher now
        assert module.call(2.0) == 4.0
    finally:
        del sys.modules[module.__name__]
