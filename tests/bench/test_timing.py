"""The benches' alternating-rounds timer and machine record: ratios of known work, the order of each round, the
statistics' bounds, bad arguments, and the machine's fields."""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from functools import partial

import pytest

from redundancy_gym.bench.timing import RatioStats, TimedPasses, alternating_rounds, timed_call, timed_calls
from redundancy_gym.eval.exceptions import EvalError
from redundancy_gym.eval.machine import finish_machine_info, machine_info


def _work(n: int) -> int:
    return sum(range(n))


def test_twice_the_work_gives_a_ratio_near_two() -> None:
    rounds = alternating_rounds(
        {
            "ours": timed_calls(lambda: _work(20000), min_time=0.01),
            "peer": timed_calls(lambda: _work(10000), min_time=0.01),
        },
        rounds=7,
    )
    stats = rounds.ratio("ours", "peer")
    assert stats.rounds == 7
    assert stats.min <= stats.median <= stats.max
    assert 1.6 < stats.median < 2.5
    assert stats.spread == pytest.approx((stats.max - stats.min) / stats.median)
    assert rounds.median("ours") > rounds.median("peer") > 0.0
    # the inverse ratio is the reciprocal, round by round
    inverse = rounds.round_ratios("peer", "ours")
    assert [1.0 / r for r in inverse] == pytest.approx(rounds.round_ratios("ours", "peer"))


def test_order_alternates_and_warmup_is_not_recorded() -> None:
    calls: list[str] = []
    values = itertools.count(1)

    def sampler(name: str) -> Callable[[], float]:
        def sample() -> float:
            calls.append(name)
            return float(next(values))

        return sample

    rounds = alternating_rounds({"a": sampler("a"), "b": sampler("b"), "c": sampler("c")}, rounds=4, warmup=2)
    assert rounds.orders == [["a", "b", "c"], ["c", "b", "a"], ["a", "b", "c"], ["c", "b", "a"]]
    assert len(calls) == 3 * 6 and calls[:6] == ["a", "b", "c", "c", "b", "a"]  # two warm-up rounds first
    # samples 1..6 were the warm-up; round 0 ran a, b, c -> 7, 8, 9; round 1 ran c, b, a -> 10, 11, 12
    assert rounds.samples["a"][:2] == [7.0, 12.0] and rounds.samples["c"][:2] == [9.0, 10.0]
    report = rounds.to_json()
    assert report["rounds"] == 4 and report["warmup"] == 2 and report["orders"] == rounds.orders


def test_ratio_against_the_fastest_peer_takes_each_rounds_smaller_time() -> None:
    samples = {"ours": iter([2.0, 4.0, 3.0]), "p": iter([4.0, 2.0, 6.0]), "q": iter([8.0, 8.0, 1.0])}
    rounds = alternating_rounds({k: partial(next, it) for k, it in samples.items()}, rounds=3, warmup=0)
    assert rounds.round_ratios("ours", ("p", "q")) == [0.5, 2.0, 3.0]
    assert rounds.ratio("ours", ("p", "q")) == RatioStats(2.0, 0.5, 3.0, 3)
    assert rounds.median("p") == 4.0


def test_bad_arguments_raise_eval_error() -> None:
    one = {"a": lambda: 1.0}
    with pytest.raises(EvalError, match="rounds"):
        alternating_rounds(one, rounds=0)
    with pytest.raises(EvalError, match="warmup"):
        alternating_rounds(one, rounds=1, warmup=-1)
    with pytest.raises(EvalError, match="candidate"):
        alternating_rounds({}, rounds=1)
    with pytest.raises(EvalError, match="finite"):
        alternating_rounds({"a": lambda: 0.0}, rounds=1)
    with pytest.raises(EvalError, match="min_time"):
        timed_calls(lambda: None, min_time=0.0)
    with pytest.raises(EvalError, match="unknown candidate"):
        alternating_rounds(one, rounds=1).ratio("a", "b")
    with pytest.raises(EvalError, match="at least one"):
        RatioStats.of([])


def test_timed_calls_sample_lasts_at_least_min_time() -> None:
    count = 0

    def fn() -> None:
        nonlocal count
        count += 1

    sample = timed_calls(fn, min_time=0.002)
    sample()  # calibration
    before = count
    start = time.perf_counter()
    per_call = sample()
    assert time.perf_counter() - start >= 0.002 and count - before > 1
    assert 0.0 < per_call < 1e-3


def test_a_sample_after_a_slowed_calibration_still_lasts_min_time() -> None:
    """A calibration slowed by the machine (here: each call sleeps while it runs) leaves the number of calls short;
    the next sample must grow it rather than time a few microseconds."""
    slow = True

    def fn() -> None:
        if slow:
            time.sleep(0.001)

    sample = timed_calls(fn, min_time=0.002)
    sample()
    slow = False
    start = time.perf_counter()
    per_call = sample()
    assert time.perf_counter() - start >= 0.002
    assert 0.0 < per_call < 1e-4  # the fast calls' time, not the slowed calibration's


def test_machine_record_fields() -> None:
    info = machine_info()
    for key in ("processor", "python", "platform", "cpu_count", "versions", "load_average"):
        assert key in info
    assert info["cpu_count"] >= 1 and len(info["load_average"]) == 3
    assert {"numpy", "numba", "mujoco", "pinocchio", "gymnasium"} <= set(info["versions"])
    if "cpu_flags" in info:  # Linux: the first CPU's relevant flags, family and model numbers
        assert isinstance(info["cpu_flags"], list) and isinstance(info["cpu_family"], int)
    finished = finish_machine_info(info)
    assert finished["load_average_start"] == info["load_average"] and len(finished["load_average_end"]) == 3
    assert "load_average" not in finished and finished["versions"] == info["versions"]


def test_timed_passes_keep_each_pass_and_drop_the_warmup() -> None:
    clock = itertools.count(1)
    passes = TimedPasses(lambda item: float(item) * next(clock), [1, 2, 3], repeats=1)
    assert passes() == 2.0 * 2  # items 1, 2, 3 times clocks 1, 2, 3: 1, 4, 9 -> median 4
    assert passes() == 2.0 * 5  # 4, 10, 18 -> 10
    assert passes.per_item(skip=1).tolist() == [4.0, 10.0, 18.0]
    assert passes.summary_us(skip=1)[0] == pytest.approx(10.0e6)
    with pytest.raises(EvalError, match="item"):
        TimedPasses(lambda item: 1.0, [])
    with pytest.raises(EvalError, match="no pass"):
        passes.per_item(skip=2)


def test_timed_call_returns_the_result_and_leaves_out_a_sleep() -> None:
    result, seconds = timed_call(lambda: 42)
    assert result == 42 and 0.0 <= seconds < 1e-3
    # a sleep is wall time the process does not run, as a preemption is: the CPU clock leaves it out
    _, seconds = timed_call(lambda: time.sleep(0.05))
    assert seconds < 0.02
    start = time.perf_counter()
    total, seconds = timed_call(lambda: _work(200000))
    assert total == 199999 * 100000 and 0.0 < seconds <= time.perf_counter() - start
