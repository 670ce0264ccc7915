"""Time spent preparing numba kernels, so that a first run's step times are the steps' and not the compiler's.

A kernel is prepared at its first call with new argument types (:class:`~redundancy_gym.kernel_options.LazyEntryPoint`
defers it from building an env or policy to that call): numba compiles it, or loads its machine code from the
on-disk cache. Both happen under numba's compiler lock, whose ``numba:compiler_lock`` events :data:`COMPILE_CLOCK`
listens to from the first time it is read; :attr:`CompileClock.seconds` sums the wall time of the outermost spans
(a kernel preparing the kernels it calls counts once), :attr:`CompileClock.compiling_seconds` the outermost
``numba:compile`` spans alone (compiling, without cache loads). The evaluation reads :attr:`~CompileClock.seconds`
around every timed call and takes the difference out of the step's time (``compile_time_s`` in the report).
"""

from __future__ import annotations

import time
from typing import Any

__all__ = ["COMPILE_CLOCK", "CompileClock"]


class _Span:
    """The summed wall time of the outermost spans of one numba event kind."""

    def __init__(self) -> None:
        self.depth = 0
        self.start = 0.0
        self.total = 0.0

    def listener(self) -> Any:
        from numba.core import event

        span = self

        class _Listener(event.Listener):
            def on_start(self, _event: Any) -> None:
                if span.depth == 0:
                    span.start = time.perf_counter()
                span.depth += 1

            def on_end(self, _event: Any) -> None:
                span.depth = max(span.depth - 1, 0)
                if span.depth == 0:
                    span.total += time.perf_counter() - span.start

        return _Listener()


class CompileClock:
    """Seconds of numba kernel preparation so far in this process: :attr:`seconds` (compiling or loading from the
    cache) and :attr:`compiling_seconds` (compiling); counting starts at :meth:`install`, which the first read of
    either calls."""

    def __init__(self) -> None:
        self._locked = _Span()
        self._compiling = _Span()
        self._installed = False

    def install(self) -> None:
        """Start listening (once per process)."""
        if self._installed:
            return
        from numba.core import event

        event.register("numba:compiler_lock", self._locked.listener())
        event.register("numba:compile", self._compiling.listener())
        self._installed = True

    @property
    def seconds(self) -> float:
        """Wall time [s] under numba's compiler lock since :meth:`install`: compiling kernels or loading them from
        the on-disk cache."""
        self.install()
        return self._locked.total

    @property
    def compiling_seconds(self) -> float:
        """Wall time [s] of the outermost compilations since :meth:`install` (cache loads excluded)."""
        self.install()
        return self._compiling.total


COMPILE_CLOCK = CompileClock()
"""The process's clock."""
