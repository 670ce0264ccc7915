"""The machine record that every benchmark and training record keeps beside its figures.

:func:`machine_info` records the CPU model, family and model numbers, the vector flags that the compiled kernels can
use, logical and usable cores, platform, Python, package versions and the load average; :func:`finish_machine_info`
adds the load average at the end of the run.
"""

from __future__ import annotations

import os
import platform
import sys
from collections.abc import Mapping
from typing import Any

__all__ = ["RELEVANT_CPU_FLAGS", "finish_machine_info", "machine_info"]

RELEVANT_CPU_FLAGS = (
    "sse4_2",
    "avx",
    "avx2",
    "fma",
    "bmi2",
    "avx512f",
    "avx512dq",
    "avx512cd",
    "avx512bw",
    "avx512vl",
    "avx512_vnni",
    "avx512_bf16",
    "avx512ifma",
    "avx_vnni",
    "neon",
    "asimd",
)
"""CPU flags that numba/LLVM, numpy, MuJoCo and pinocchio may use for vector code; those present are recorded."""

_VERSIONS = {
    "numpy": "numpy",
    "numba": "numba",
    "llvmlite": "llvmlite",
    "scipy": "scipy",
    "mujoco": "mujoco",
    "pinocchio": "pin",
    "coal": "coal",
    "gymnasium": "gymnasium",
    "mink": "mink",
    "daqp": "daqp",
}
"""Recorded package -> its distribution name (pinocchio's wheel is ``pin``)."""


def machine_info() -> dict[str, Any]:
    """This machine, as every bench records it.

    Keys: ``processor``, ``python``, ``platform``, ``cpu_count`` (logical cores), ``affinity_cores`` (the cores
    this process may run on), ``cpu_model`` (model name), ``cpu_family`` and ``cpu_model_number`` (``/proc/cpuinfo``
    numbers), ``cpu_mhz``, ``cpu_flags`` (those of :data:`RELEVANT_CPU_FLAGS` present), ``llvm_cpu`` (the target
    numba compiles for), ``versions`` (numpy, numba, llvmlite, scipy, mujoco, pinocchio, coal, gymnasium, mink,
    daqp where installed; torch when already imported) and ``load_average`` (1, 5 and 15 min, now). Keys that this
    machine cannot tell are left out.
    """
    info: dict[str, Any] = {
        "processor": platform.processor() or platform.machine(),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpu_count": os.cpu_count(),
    }
    try:
        info["affinity_cores"] = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        pass
    info.update(_cpuinfo())
    try:
        import llvmlite.binding as llvm  # noqa: PLC0415 - numba's backend, a dependency

        info["llvm_cpu"] = str(llvm.get_host_cpu_name())
    except Exception:  # noqa: BLE001 - recorded when available
        pass
    info["versions"] = _versions()
    info["load_average"] = _load_average()
    return info


def finish_machine_info(info: Mapping[str, Any]) -> dict[str, Any]:
    """``info`` (from :func:`machine_info` at the bench's start) with ``load_average_start`` (its load average)
    and ``load_average_end`` (now): how busy the machine was while the bench ran."""
    out = dict(info)
    out["load_average_start"] = out.pop("load_average", None)
    out["load_average_end"] = _load_average()
    return out


def _load_average() -> list[float] | None:
    try:
        return [float(x) for x in os.getloadavg()]
    except (AttributeError, OSError):
        return None


def _cpuinfo() -> dict[str, Any]:
    """Model name, family and model numbers, clock and relevant flags of the first CPU in ``/proc/cpuinfo``."""
    out: dict[str, Any] = {}
    try:
        with open("/proc/cpuinfo") as f:
            text = f.read()
    except OSError:
        return out
    keys = {
        "model name": "cpu_model",
        "cpu family": "cpu_family",
        "model": "cpu_model_number",
        "cpu MHz": "cpu_mhz",
        "flags": "cpu_flags",
        "Features": "cpu_flags",
    }
    for line in text.splitlines():
        if not line.strip():
            if out:
                break  # the first processor only
            continue
        key, _, value = line.partition(":")
        name = keys.get(key.strip())
        if name is None or name in out:
            continue
        value = value.strip()
        if name == "cpu_flags":
            present = set(value.split())
            out[name] = [f for f in RELEVANT_CPU_FLAGS if f in present]
        elif name in ("cpu_family", "cpu_model_number"):
            out[name] = int(value) if value.isdigit() else value
        elif name == "cpu_mhz":
            try:
                out[name] = float(value)
            except ValueError:
                pass
        else:
            out[name] = value
    return out


def _versions() -> dict[str, str]:
    """Installed versions of the packages that the timed code runs on; torch only when already imported."""
    from importlib.metadata import PackageNotFoundError, version  # noqa: PLC0415

    out = {}
    for name, dist in _VERSIONS.items():
        try:
            out[name] = version(dist)
        except PackageNotFoundError:
            continue
    if "torch" in sys.modules:
        out["torch"] = str(getattr(sys.modules["torch"], "__version__", "?"))
    return out
