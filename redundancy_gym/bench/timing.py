"""Alternating-rounds timing and the machine record shared by the benchmarks.

A benchmark compares ours with one or more peers. Timing each candidate once, one after the other, lets a slow
moment of the machine (another process, a frequency change) fall on one candidate only, and the ratio moves from
run to run. :func:`alternating_rounds` instead runs a warm-up round (not recorded), then ``rounds`` rounds in
which every candidate is sampled once, in the candidates' order in even rounds and in the reverse order in odd
rounds (``AB BA AB ...``), so that neither always goes first. Each ratio ``a / b`` is formed per round, from two
samples taken moments apart, and reported by its median over the rounds with the smallest and largest round
(:class:`RatioStats`); ``spread`` is ``(max - min) / median``.

Every time is taken with :func:`timed_call` (or over many calls, :func:`timed_calls`): the smaller of the wall-clock
time and the process's CPU time over the call. On a busy machine the scheduler may take the core away in the
middle of a call; the wall clock then counts the other process's turn, the CPU clock does not. The CPU clock costs
a system call (about 2.5 us here), so a call that runs undisturbed reads a little longer on it than on the wall
clock, whose time is then kept; multi-threaded work (CPU time above wall time) is timed by the wall clock too.
Waiting (I/O, sleep, another process's result) is not counted either: it suits the benches' compute-bound calls,
not a call that blocks.

A sample is whatever a candidate's sampler returns, in seconds: :func:`timed_calls` makes a sampler that times
enough calls of a function to last at least ``min_time`` (above the timer's resolution) and returns the time per
call; :class:`TimedPasses` one that makes a pass over recorded inputs (states) and returns the median time per
input; a bench that times its own work (one walk) returns its own figure.

The machine beside the figures is recorded by :mod:`redundancy_gym.eval.machine`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Generic, TypeVar

import numpy as np
from numpy.typing import NDArray
from tqdm.auto import tqdm

from .exceptions import BenchError

__all__ = [
    "CLOCK",
    "RatioStats",
    "Rounds",
    "TimedPasses",
    "alternating_rounds",
    "check_rounds",
    "timed_call",
    "timed_calls",
]

T = TypeVar("T")
R = TypeVar("R")
Sampler = Callable[[], float]
"""One sample of a candidate: its time [s] (per call, per state, per step: the same unit for all candidates)."""

CLOCK = "min(wall clock, process CPU time)"
"""What every bench time is (recorded in the reports' ``timing``)."""


def timed_call(fn: Callable[[], R]) -> tuple[R, float]:
    """Call ``fn``; returns its result and its time [s]: the smaller of the wall-clock time and the process's CPU
    time over the call, so that a preemption in the middle of it does not count."""
    cpu = time.process_time()
    wall = time.perf_counter()
    result = fn()
    wall = time.perf_counter() - wall
    cpu = time.process_time() - cpu
    return result, min(wall, cpu)


@dataclass(frozen=True)
class RatioStats:
    """A ratio over rounds: its median, smallest and largest round value, and the number of rounds.

    Attributes:
        median: median over the rounds of the per-round ratio [-].
        min: smallest round ratio [-].
        max: largest round ratio [-].
        rounds: number of rounds.
    """

    median: float
    min: float
    max: float
    rounds: int

    @property
    def spread(self) -> float:
        """``(max - min) / median`` [-]: how far apart the rounds were, relative to the reported median."""
        return (self.max - self.min) / self.median if self.median else float("nan")

    def to_json(self) -> dict[str, float | int]:
        """``{"median", "min", "max", "spread", "rounds"}``."""
        return {"median": self.median, "min": self.min, "max": self.max, "spread": self.spread, "rounds": self.rounds}

    @classmethod
    def of(cls, values: Sequence[float]) -> RatioStats:
        """The statistics of per-round ratios ``values`` (at least one)."""
        if not len(values):
            raise BenchError("a ratio needs at least one round")
        array = np.asarray(values, dtype=np.float64)
        return cls(float(np.median(array)), float(array.min()), float(array.max()), int(array.size))


@dataclass
class Rounds:
    """The samples of :func:`alternating_rounds`.

    Attributes:
        names: the candidates, in the order of the even rounds.
        samples: per candidate, its sample of each round [s].
        orders: the order in which the candidates ran in each round.
        warmup: untimed warm-up rounds run before.
    """

    names: tuple[str, ...]
    samples: dict[str, list[float]] = field(default_factory=dict)
    orders: list[list[str]] = field(default_factory=list)
    warmup: int = 1

    def median(self, name: str) -> float:
        """Median over the rounds of ``name``'s samples [s]."""
        return float(np.median(self._samples(name)))

    def round_ratios(self, numerator: str, denominator: str | Sequence[str]) -> list[float]:
        """Per round, ``numerator``'s sample over ``denominator``'s (a sequence of names: the smallest of theirs in
        that round, i.e. against the fastest peer)."""
        top = self._samples(numerator)
        names = [denominator] if isinstance(denominator, str) else list(denominator)
        if not names:
            raise BenchError("a ratio needs at least one denominator candidate")
        bottom = np.min([self._samples(n) for n in names], axis=0)
        return [float(a / b) for a, b in zip(top, bottom, strict=False)]

    def ratio(self, numerator: str, denominator: str | Sequence[str]) -> RatioStats:
        """:meth:`round_ratios` by their median, min and max."""
        return RatioStats.of(self.round_ratios(numerator, denominator))

    def to_json(self) -> dict[str, Any]:
        """Rounds, warm-up, order of each round and every sample [s]."""
        return {
            "rounds": len(self.orders),
            "warmup": self.warmup,
            "orders": self.orders,
            "samples_s": {n: list(v) for n, v in self.samples.items()},
        }

    def _samples(self, name: str) -> NDArray[np.float64]:
        if name not in self.samples:
            raise BenchError(f"unknown candidate {name!r}; the candidates are {list(self.names)}")
        return np.asarray(self.samples[name], dtype=np.float64)


def check_rounds(rounds: float) -> None:
    """Raise :class:`BenchError` unless ``rounds`` is a whole number >= 1 (every bench's ``--rounds``)."""
    if int(rounds) != rounds or rounds < 1:
        raise BenchError(f"rounds must be an integer >= 1, got {rounds!r}")


def alternating_rounds(
    samplers: Mapping[str, Sampler], *, rounds: int, warmup: int = 1, progress: bool = False, desc: str = "rounds"
) -> Rounds:
    """Sample every candidate once per round, alternating the order, after ``warmup`` unrecorded rounds.

    Args:
        samplers: candidate name -> sampler returning one sample [s] (e.g. :func:`timed_calls`); ours first.
        rounds: recorded rounds (>= 1). Round ``k`` runs the candidates in the mapping's order for even ``k`` and
            in the reverse order for odd ``k`` (``AB BA AB ...``).
        warmup: rounds run first and discarded (compilation, caches, a :func:`timed_calls` calibration).
        progress: show a progress bar over the rounds.
        desc: the progress bar's label.

    Returns:
        The samples, per candidate and round, with each round's order.

    Raises:
        BenchError: no candidate, ``rounds < 1`` or ``warmup < 0``, or a sampler returned a non-positive or
            non-finite time.
    """
    if not samplers:
        raise BenchError("alternating_rounds needs at least one candidate")
    check_rounds(rounds)
    if int(warmup) != warmup or warmup < 0:
        raise BenchError(f"warmup must be an integer >= 0, got {warmup!r}")
    names = tuple(samplers)
    result = Rounds(names, {n: [] for n in names}, [], int(warmup))
    for k in tqdm(range(-int(warmup), int(rounds)), desc=desc, disable=not progress):
        order = list(names) if k % 2 == 0 else list(reversed(names))
        values = {}
        for name in order:
            value = float(samplers[name]())
            if not np.isfinite(value) or value <= 0.0:
                raise BenchError(f"candidate {name!r} returned the time {value!r}; a sample must be finite and > 0 s")
            values[name] = value
        if k >= 0:
            result.orders.append(order)
            for name in names:
                result.samples[name].append(values[name])
    return result


def timed_calls(fn: Callable[[], Any], *, min_time: float, max_calls: int = 1 << 20) -> Sampler:
    """A sampler of ``fn``'s time per call [s]: each sample times (:func:`timed_call`) a fixed number of calls
    lasting at least ``min_time`` [s]. The number is found on the first sample (which is therefore slower: run it in a
    warm-up round) by growing from one call, at most ``max_calls``, until two runs in a row last ``min_time``; a later
    sample that runs short (the calibration was slowed by the machine) doubles the number until one lasts ``min_time``.

    Raises:
        BenchError: ``min_time`` not finite and > 0, or ``max_calls < 1``.
    """
    if not np.isfinite(min_time) or min_time <= 0.0:
        raise BenchError(f"min_time must be finite and > 0 s, got {min_time!r}")
    if max_calls < 1:
        raise BenchError(f"max_calls must be >= 1, got {max_calls}")
    number = 0

    def repeat(count: int) -> None:
        for _ in range(count):
            fn()

    def run(count: int) -> float:
        return timed_call(lambda: repeat(count))[1]

    def sample() -> float:
        nonlocal number
        if number == 0:
            fn()  # first call: compilation, lazy set-up
            count = 1
            while True:
                elapsed = run(count)
                if elapsed >= min_time or count >= max_calls:
                    # a second run decides: a first one slowed by the machine (an interrupt, another process) left
                    # the count short, and later samples lasted less than min_time
                    elapsed = run(count)
                    if elapsed >= min_time or count >= max_calls:
                        break
                grow = 2 if elapsed <= 0.0 else max(2, min(16, int(min_time / elapsed) + 1))
                count = min(max_calls, count * grow)
            number = count
            return elapsed / count
        elapsed = run(number)
        # a calibration slowed by the machine in both its runs left the count short: grow it until a run lasts
        # min_time, so that every sample times at least that long
        while elapsed < min_time and number < max_calls:
            number = min(max_calls, number * 2)
            elapsed = run(number)
        return elapsed / number

    return sample


class TimedPasses(Generic[T]):
    """A sampler that makes one pass over ``items``: ``repeats`` calls of ``timed(item)`` per item (each returns its
    own time [s], so set-up outside the timed part is left out), the median kept per item; returns the median over
    the items [s] and keeps every pass's per-item times.

    Raises:
        BenchError: no items or ``repeats < 1``.
    """

    def __init__(self, timed: Callable[[T], float], items: Sequence[T], repeats: int = 1) -> None:
        if not len(items):
            raise BenchError("TimedPasses needs at least one item")
        if repeats < 1:
            raise BenchError(f"repeats must be >= 1, got {repeats}")
        self.timed, self.items, self.repeats = timed, items, int(repeats)
        self.passes: list[list[float]] = []

    def __call__(self) -> float:
        times = [float(np.median([self.timed(item) for _ in range(self.repeats)])) for item in self.items]
        self.passes.append(times)
        return float(np.median(times))

    def per_item(self, skip: int = 0) -> NDArray[np.float64]:
        """Each item's median time [s] over the passes after the first ``skip`` (the warm-up rounds)."""
        kept = self.passes[skip:]
        if not kept:
            raise BenchError(f"no pass after the first {skip}")
        return np.median(np.array(kept), axis=0)

    def summary_us(self, skip: int = 0, percentile: float = 90.0) -> tuple[float, float]:
        """Median and ``percentile`` over the items of :meth:`per_item` [us]."""
        per_item = self.per_item(skip) * 1e6
        return float(np.median(per_item)), float(np.percentile(per_item, percentile))
