"""Benchmarks: one file per benchmark (ours against a peer in alternating rounds, :mod:`.timing`) and the table
that ``redundancy-gym bench`` reads (:mod:`.table`)."""

from .exceptions import BenchError
from .table import BENCHES, Bench, BenchArgs, run_bench

__all__ = ["BENCHES", "Bench", "BenchArgs", "BenchError", "run_bench"]
