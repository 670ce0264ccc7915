"""Time spent compiling numba kernels, so that a first run's step times are the steps' and not the compiler's.

A kernel compiles at its first call with new argument types (or loads from numba's on-disk cache, which is not
compiling). :data:`COMPILE_CLOCK` listens to numba's ``numba:compile`` events from the first time it is read and
sums the wall time of the outermost compilations (a kernel compiling the kernels it calls counts once); the
evaluation reads it around every timed call and takes the difference out of the step's time
(``compile_time_s`` in the report).
"""

from __future__ import annotations

import time
from typing import Any

__all__ = ["COMPILE_CLOCK", "CompileClock"]


class CompileClock:
    """Seconds of numba compilation so far in this process (:attr:`seconds`; it starts counting at
    :meth:`install`, which the first :attr:`seconds` read calls)."""

    def __init__(self) -> None:
        self._depth = 0
        self._start = 0.0
        self._total = 0.0
        self._installed = False

    def install(self) -> None:
        """Start listening (once per process)."""
        if self._installed:
            return
        from numba.core import event

        clock = self

        class _Listener(event.Listener):
            def on_start(self, _event: Any) -> None:
                if clock._depth == 0:
                    clock._start = time.perf_counter()
                clock._depth += 1

            def on_end(self, _event: Any) -> None:
                clock._depth = max(clock._depth - 1, 0)
                if clock._depth == 0:
                    clock._total += time.perf_counter() - clock._start

        event.register("numba:compile", _Listener())
        self._installed = True

    @property
    def seconds(self) -> float:
        """The outermost compilations' wall time [s] since :meth:`install`."""
        self.install()
        return self._total


COMPILE_CLOCK = CompileClock()
"""The process's clock."""
