"""Algorithm 12: the predictive IK in a receding horizon, warm-started from the last solution."""

from __future__ import annotations

import time
import warnings
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...kernel_options import DEFAULT_BACKEND
from ..exceptions import ControllerError
from .predictive_ik import DESCENT_METHODS, PredictiveIk, PredictiveResult, resolve_backend

__all__ = ["HorizonUpdate", "RecedingHorizon"]


class HorizonUpdate(NamedTuple):
    """One update of :class:`RecedingHorizon`.

    Attributes:
        u: the nullspace input to apply now (n).
        result: the optimization of this update.
        seconds: wall time of the update [s].
    """

    u: NDArray[np.float64]
    result: PredictiveResult
    seconds: float


class RecedingHorizon:
    """At every control step, optimize the nullspace input over ``[t_k, t_k + horizon]`` from the measured
    configuration, starting from the last solution shifted by one sample, and apply its first input
    (algorithm 12).

    With the augmented problem (``pik.augmented``) the horizon starts from the input applied last (5.127), which
    is also what is applied now; the optimized rate then sets the next step's input, so the applied input
    changes by ``dt * udot`` per step and the joint velocity stays continuous.

    Args:
        pik: the optimal control problem.
        steps: samples ``N`` of the horizon.
        dt: sample time [s] (the control period).
        iterations: conjugate gradient iterations per update (``j_max``).
        tolerance: relative cost decrease that ends an update early.
        method: descent direction (:data:`~redundancy_gym.controllers.DESCENT_METHODS`).
        backend: ``"compiled"`` (the default: each update in one compiled call) or ``"python"`` (the Python loop
            of :meth:`PredictiveIk.optimize`, the reference; the same iterates to round-off).
        compiled: deprecated (goes in redundancy_gym 0.3): ``True`` is ``backend="compiled"``, ``False``
            ``backend="python"``.
        warm_step: start each update's backtracking line search from the step size the last update ended with
            (warm-started like the inputs) instead of from 1.0: about a third fewer forward integrations per
            update, and a different (on the fig. 5.10 move: lower) pseudoenergy, so off by default.
    """

    def __init__(
        self,
        pik: PredictiveIk,
        steps: int,
        dt: float,
        *,
        iterations: int = 2,
        tolerance: float = 1e-6,
        method: str = "fletcher_reeves",
        backend: str = DEFAULT_BACKEND,
        compiled: bool | None = None,
        warm_step: bool = False,
    ) -> None:
        if not isinstance(steps, (int, np.integer)) or steps < 1:
            raise ControllerError(f"steps must be an int >= 1, got {steps!r}")
        if not np.isfinite(dt) or dt <= 0.0:
            raise ControllerError(f"dt must be finite and > 0, got {dt!r}")
        if method not in DESCENT_METHODS:
            raise ControllerError(f"unknown method {method!r}; valid: {', '.join(DESCENT_METHODS)}")
        self.pik, self.steps, self.dt = pik, int(steps), float(dt)
        self.iterations, self.tolerance, self.method = int(iterations), float(tolerance), method
        self.backend = resolve_backend(backend, compiled, stacklevel=3)
        self.warm_step = bool(warm_step)
        self.reset()

    @property
    def compiled(self) -> bool:
        """Deprecated (goes in redundancy_gym 0.3): ``backend == "compiled"``."""
        warnings.warn(
            "RecedingHorizon.compiled is deprecated and goes in redundancy_gym 0.3; read backend",
            DeprecationWarning,
            stacklevel=2,
        )
        return self.backend == "compiled"

    def reset(self) -> None:
        """Forget the last solution (a new episode): the next update starts from zero inputs."""
        self._params = np.zeros((self.steps, self.pik.n))
        self._u_b = np.zeros(self.pik.n)
        self._step = 1.0  # the first trial step size of the next line search
        self.last: HorizonUpdate | None = None

    def update(self, q: ArrayLike, wdot: ArrayLike) -> HorizonUpdate:
        """Optimize from ``q`` with the task velocity reference ``wdot`` (N, 6) of the horizon's samples."""
        start = time.perf_counter()
        result = self.pik.optimize(
            q,
            wdot,
            self.dt,
            self._params,
            u_b=self._u_b,
            max_iterations=self.iterations,
            tolerance=self.tolerance,
            method=self.method,
            backend=self.backend,
            step=self._step,
        )
        if self.warm_step and result.iterations > 0 and np.isfinite(result.step) and result.step > 0.0:
            # result.step is twice the last accepted step (the next iteration's first trial); the next update's
            # problem is this one shifted by a sample, so its first step is about the last accepted one (an update
            # that accepted no step leaves it: its halved trials say nothing of the next problem's scale)
            self._step = 0.5 * result.step
        params = result.params
        u = result.rollout.u
        applied = u[0].copy()
        # warm start: the solution shifted by one sample, its last sample repeated
        self._params = np.concatenate([params[1:], params[-1:]])
        if self.pik.augmented:
            self._u_b = u[1].copy() if self.steps > 1 else applied + self.dt * params[0]
        update = HorizonUpdate(applied, result, time.perf_counter() - start)
        self.last = update
        return update

    def input_at(self, elapsed: float) -> NDArray[np.float64]:
        """The nullspace input ``elapsed`` seconds after the last update, for control steps between updates
        (a sample time longer than the control period).

        Velocity level: the first input, held over the sample (the inputs are piecewise constant, so the joint
        velocity jumps where the next update starts, fig. 5.33). Augmented: ``u_b + elapsed * udot_0``, which
        reaches the next update's ``u_b`` at the end of the sample: the input is continuous (fig. 5.34).
        """
        if self.last is None:
            raise ControllerError("no update yet: call update() first")
        if not np.isfinite(elapsed) or elapsed < 0.0 or elapsed > self.dt * (1.0 + 1e-9):
            raise ControllerError(f"elapsed must be in [0, dt = {self.dt:g}] s, got {elapsed!r}")
        if not self.pik.augmented:
            return self.last.u.copy()
        return self.last.u + elapsed * self.last.result.params[0]
