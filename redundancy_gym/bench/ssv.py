"""``redundancy-gym bench ssv``: our compiled SSV distances against coal on the same pairs.

For each of the six pair types, a seeded set of separated random pairs is timed at batch sizes 1, 10, 100
and 1000 with three implementations measured in the same run:

- ``ours``: :meth:`PairBatch.compute` over the batch (the way the collision model calls it).
- ``coal``: a Python loop of ``coal.distance`` over the batch (sphere, capsule, one-triangle convex with a
  swept-sphere radius; default coal tolerances).
- ``coal_pinocchio``: ``pinocchio.computeDistances`` over a geometry model holding the same pairs (coal's
  C++ loop, no Python per pair).

The three are timed in alternating rounds (:func:`~redundancy_gym.bench.timing.alternating_rounds`: a
warm-up round, then ``rounds`` rounds of ours, coal, pinocchio / pinocchio, coal, ours, ...; each sample lasts at
least ``min_time``); the per-pair times are medians over the rounds. ``ratio_vs_coal_batch100`` is, per pair type,
the median over rounds of our time divided by the faster coal variant's in the same round, for the same 100 pairs;
``ratio_vs_coal_batch100_rounds`` gives its median, min, max and spread ``(max - min) / median`` over the rounds.
The monograph's Table 5.1 (C++ on a Core2 Duo) is printed next to our relative costs.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import coal
import numpy as np
import pinocchio as pin
from tqdm.auto import tqdm

from ..eval.machine import finish_machine_info, machine_info
from ..geometry import LSS, PSS, SSV, TSS, PairBatch, distance
from .coal_shapes import to_coal
from .exceptions import BenchError
from .timing import CLOCK, alternating_rounds, check_rounds, timed_calls

__all__ = ["PAIR_TYPES", "TABLE_5_1", "format_ssv_bench", "run_ssv_bench"]

PAIR_TYPES = ("PSS-PSS", "PSS-LSS", "LSS-LSS", "PSS-TSS", "LSS-TSS", "TSS-TSS")
# monograph Table 5.1: absolute [us] and relative run-time on Lola's Core2 Duo 2.33 GHz
TABLE_5_1 = {
    "PSS-PSS": (0.0538, 1.00),
    "PSS-LSS": (0.0555, 1.03),
    "LSS-LSS": (0.0773, 1.44),
    "PSS-TSS": (0.0909, 1.69),
    "LSS-TSS": (0.3351, 6.23),
    "TSS-TSS": (0.9007, 16.74),
}
BATCH_SIZES = (1, 10, 100, 1000)


def _random_volume(rng: np.random.Generator, kind: str) -> SSV:
    c = rng.uniform(-1.0, 1.0, 3)
    r = rng.uniform(0.01, 0.1)
    p = [c + rng.uniform(-0.3, 0.3, 3) for _ in range(3)]
    return {"PSS": PSS(c, r), "LSS": LSS(p[0], p[1], r), "TSS": TSS(p[0], p[1], p[2], r)}[kind]


def _separated_pairs(rng: np.random.Generator, pair_type: str, n: int) -> list[tuple[SSV, SSV]]:
    ka, kb = pair_type.split("-")
    pairs: list[tuple[SSV, SSV]] = []
    while len(pairs) < n:
        a, b = _random_volume(rng, ka), _random_volume(rng, kb)
        if distance(a, b).distance > 1e-3:  # coal reports penetration depth, not the SSV distance, on overlap
            pairs.append((a, b))
    return pairs


def _ours(pairs: Sequence[tuple[SSV, SSV]]) -> Callable[[], Any]:
    n = len(pairs)
    batch = PairBatch([a for a, _ in pairs] + [b for _, b in pairs], np.arange(n), np.arange(n, 2 * n))
    return batch.compute


def _coal_loop(pairs: Sequence[tuple[SSV, SSV]]) -> Callable[[], Any]:
    shapes = [(*to_coal(a), *to_coal(b)) for a, b in pairs]
    request = coal.DistanceRequest()
    result = coal.DistanceResult()
    query = coal.distance

    def run() -> None:
        for ga, ta, gb, tb in shapes:
            result.clear()
            query(ga, ta, gb, tb, request, result)

    return run


def _coal_pinocchio(pairs: Sequence[tuple[SSV, SSV]]) -> Callable[[], Any]:
    model = pin.Model()
    geom_model = pin.GeometryModel()
    for k, (a, b) in enumerate(pairs):
        for name, vol in ((f"a{k}", a), (f"b{k}", b)):
            shape, placement = to_coal(vol)
            obj = pin.GeometryObject(name, 0, 0, pin.SE3(placement.getRotation(), placement.getTranslation()), shape)
            geom_model.addGeometryObject(obj)
    for k in range(len(pairs)):
        geom_model.addCollisionPair(pin.CollisionPair(2 * k, 2 * k + 1))
    data = model.createData()
    geom_data = geom_model.createData()
    pin.updateGeometryPlacements(model, data, geom_model, geom_data, np.zeros(0))

    def run() -> None:
        pin.computeDistances(geom_model, geom_data)

    return run


def run_ssv_bench(
    *,
    batch_sizes: Sequence[int] = BATCH_SIZES,
    seed: int = 0,
    min_time: float = 0.02,
    rounds: int = 9,
    progress: bool = True,
) -> dict[str, Any]:
    """Time ours and coal on the same pairs in alternating rounds; returns the report written by ``bench ssv --json``.

    Args:
        batch_sizes: pairs per call; 100 must be among them for ``ratio_vs_coal_batch100``.
        seed: seed of the pair generator.
        min_time: least duration of each timing sample [s].
        rounds: alternating rounds per pair type and batch size (after one warm-up round); medians are reported.
        progress: show a progress bar.

    Raises:
        BenchError: a batch size below 1, no batch size 100, ``rounds < 1`` or ``min_time <= 0``.
    """
    sizes = sorted({int(s) for s in batch_sizes})
    if not sizes or sizes[0] < 1:
        raise BenchError(f"batch sizes must be positive integers, got {list(batch_sizes)}")
    if 100 not in sizes:
        raise BenchError("batch sizes must include 100 (ratio_vs_coal_batch100)")
    check_rounds(rounds)
    if not np.isfinite(min_time) or min_time <= 0.0:
        raise BenchError(f"min_time must be finite and > 0 s, got {min_time!r}")
    machine = machine_info()
    rng = np.random.default_rng(seed)
    per_type: dict[str, Any] = {}
    ratios: dict[str, float] = {}
    ratio_rounds: dict[str, Any] = {}
    bar = tqdm(total=len(PAIR_TYPES) * len(sizes), desc="bench ssv", disable=not progress)
    for pair_type in PAIR_TYPES:
        pairs = _separated_pairs(rng, pair_type, max(sizes))
        rows = {}
        for size in sizes:
            subset = pairs[:size]
            samplers = {
                name: timed_calls(make(subset), min_time=min_time)
                for name, make in (("ours", _ours), ("coal", _coal_loop), ("coal_pinocchio", _coal_pinocchio))
            }
            timed = alternating_rounds(samplers, rounds=rounds)
            rows[str(size)] = {f"{name}_us_per_pair": timed.median(name) / size * 1e6 for name in samplers}
            if size == 100:
                stats = timed.ratio("ours", ("coal", "coal_pinocchio"))
                ratios[pair_type] = stats.median
                ratio_rounds[pair_type] = stats.to_json()
            bar.update()
        per_type[pair_type] = rows
    bar.close()
    largest = str(sizes[-1])
    base = per_type["PSS-PSS"][largest]["ours_us_per_pair"]
    table = {
        t: {
            "monograph_abs_us": TABLE_5_1[t][0],
            "monograph_rel": TABLE_5_1[t][1],
            f"ours_abs_us_batch{largest}": per_type[t][largest]["ours_us_per_pair"],
            "ours_rel": per_type[t][largest]["ours_us_per_pair"] / base,
        }
        for t in PAIR_TYPES
    }
    return {
        "benchmark": "ssv",
        "seed": seed,
        "batch_sizes": sizes,
        "peer": f"coal {coal.__version__} (coal.distance loop and pinocchio.computeDistances)",
        "timing": {
            "rounds": rounds,
            "warmup": 1,
            "min_time_s": min_time,
            "clock": CLOCK,
            "order": "ours, coal, coal_pinocchio; reversed every other round",
        },
        "machine": finish_machine_info(machine),
        "per_pair_us": per_type,
        "ratio_vs_coal_batch100": ratios,
        "ratio_vs_coal_batch100_rounds": ratio_rounds,
        "ratio_vs_coal_batch100_max": max(ratios.values()),
        "table_5_1": table,
    }


def format_ssv_bench(report: dict[str, Any]) -> str:
    """A plain-text table of per-pair times, ratios and Table 5.1."""
    sizes = [str(s) for s in report["batch_sizes"]]
    largest = sizes[-1]
    head = (
        "pair type | " + " | ".join(f"ours@{s}" for s in sizes) + " | coal@100 | pin@100 | ratio@100 | "
        f"Table5.1 [us] | Table5.1 rel | ours rel@{largest}"
    )
    lines = [head, "-" * len(head)]
    for t, rows in report["per_pair_us"].items():
        tab = report["table_5_1"][t]
        lines.append(
            f"{t:9s} | "
            + " | ".join(f"{rows[s]['ours_us_per_pair']:.3f}" for s in sizes)
            + f" | {rows['100']['coal_us_per_pair']:.3f} | {rows['100']['coal_pinocchio_us_per_pair']:.3f}"
            + f" | {_ratio_cell(report, t)} | {tab['monograph_abs_us']:.4f}"
            + f" | {tab['monograph_rel']:.2f} | {tab['ours_rel']:.2f}"
        )
    lines.append(
        "times are microseconds per pair (medians over rounds); ratio = ours / faster coal variant on the same "
        "100 pairs, median (min-max) over rounds"
    )
    lines.append(f"max ratio_vs_coal_batch100 = {report['ratio_vs_coal_batch100_max']:.3f}")
    return "\n".join(lines)


def _ratio_cell(report: dict[str, Any], pair_type: str) -> str:
    """``median (min-max)`` of one pair type's ratio, or the median alone in a report without rounds."""
    median = report["ratio_vs_coal_batch100"][pair_type]
    stats = report.get("ratio_vs_coal_batch100_rounds", {}).get(pair_type)
    return f"{median:.3f}" + (f" ({stats['min']:.3f}-{stats['max']:.3f})" if stats else "")
