"""Compiled kernels a wheel carries, so that a new process loads machine code instead of compiling it
(docs/architecture.md#kernels-shipped-in-the-wheel).

``redundancy-gym warmup --pack`` compiles every env's and analytic reference's kernels for the portable CPU
:data:`PACK_CPU` (x86-64-v3: AVX2 and fused multiply-adds, every x86-64 CPU since 2013-2015) into
``redundancy_gym/packed_kernels/<tag>/`` (:func:`pack_tag`: Python, numba, machine), numba's own cache files laid
out by the package's folders, with a manifest naming the sources they were compiled from. A wheel built after it
ships them; a clone without one behaves as before.

Seeding: numba asks its cache locators, in order, where a ``cache=True`` kernel's cache lives when the kernel is
defined. :func:`install_seeding` (run by :mod:`redundancy_gym.kernel_options`, which every kernel module imports
first) puts :class:`PackSeeder` at the head of that list. For a kernel of this package it finds the place numba's
own locators choose (``NUMBA_CACHE_DIR``, ``__pycache__`` beside the sources, or numba's per-user folder), and
where that place has no cache index for the kernel yet, copies the kernel's packed entries there, keyed to this
machine's CPU; then it steps aside and numba's locators go on as always. numba loads the copied entries at the
kernel's first call. Code for x86-64-v3 runs on any CPU that has its features, and rounds as code compiled for
the host does (both fuse multiply-adds where the kernels allow it; held bit for bit by a test).

Nothing is copied (every kernel compiles as before) where the pack does not fit: another Python, numba or machine
(no folder for :func:`pack_tag`), a CPU without x86-64-v3's features, sources that differ from the ones packed
(an edited clone; numba keys a cache entry on its own file only, so a kernel whose callee changed would load stale
code), or a process that chose its own numba CPU (``NUMBA_CPU_NAME``/``NUMBA_CPU_FEATURES``) or locators
(``NUMBA_CACHE_LOCATOR_CLASSES``). ``REDUNDANCY_GYM_KERNEL_PACK`` names another folder of packs (a path that
holds none switches seeding off).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import pickle
import platform
import shutil
import sys
from importlib import metadata
from pathlib import Path
from typing import Any, NamedTuple

__all__ = [
    "PACK_CPU",
    "PACK_CPU_FEATURES",
    "PACKAGE_DIR",
    "PackSeeder",
    "SeedingState",
    "host_magic_tuple",
    "install_seeding",
    "kernel_filename_base",
    "pack_root",
    "pack_tag",
    "seeding_state",
    "sources_digest",
]

PACK_CPU = "x86-64-v3"
"""The CPU model packed kernels are compiled for (LLVM's name of the x86-64-v3 level)."""

PACK_CPU_FEATURES = frozenset(
    {"avx", "avx2", "bmi", "bmi2", "cx16", "f16c", "fma", "lzcnt", "movbe", "popcnt", "sse4.1", "sse4.2", "ssse3"}
)
"""The x86-64-v3 features (LLVM's names) a host must have for packed kernels to be copied into its cache."""

PACKAGE_DIR = Path(__file__).resolve().parent
"""The package's folder: the sources packed kernels belong to, and the default home of the packs."""

_ENV_VAR = "REDUNDANCY_GYM_KERNEL_PACK"
_log = logging.getLogger(__name__)


def pack_root() -> Path:
    """The folder holding the packs, one subfolder per :func:`pack_tag` (``REDUNDANCY_GYM_KERNEL_PACK`` or
    ``redundancy_gym/packed_kernels``)."""
    override = os.environ.get(_ENV_VAR)
    return Path(override) if override else PACKAGE_DIR / "packed_kernels"


def pack_tag() -> str:
    """The pack a process can use: its Python, numba version and machine (``py311-numba0.68.1-x86_64-linux``)."""
    version = sys.version_info
    return f"py{version.major}{version.minor}-numba{metadata.version('numba')}-{platform.machine()}-{sys.platform}"


def sources_digest(package: Path = PACKAGE_DIR) -> str:
    """SHA-256 over the package's Python sources (relative paths and contents, in sorted order): a pack is used only
    with the sources it was compiled from."""
    digest = hashlib.sha256()
    for path in sorted(package.rglob("*.py")):
        relative = path.relative_to(package).as_posix()
        if relative.startswith("packed_kernels/"):
            continue
        digest.update(relative.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def host_magic_tuple() -> tuple[str, str, str]:
    """numba's description of this process's code generation (triple, CPU name, CPU features), as its JIT codegen's
    ``magic_tuple()`` gives it for a process that chose no CPU of its own, without initializing the codegen."""
    import llvmlite.binding as ll
    from numba.core.codegen import get_host_cpu_features

    return ll.get_process_triple(), ll.get_host_cpu_name(), get_host_cpu_features()


def _enabled_features(features: str) -> set[str]:
    return {item[1:] for item in features.split(",") if item.startswith("+")}


def kernel_filename_base(py_func: Any, py_file: str) -> str:
    """The stem numba gives a kernel's cache files (``module.qualname-line.py311``), as its ``CacheImpl`` does."""
    modname = os.path.splitext(os.path.basename(py_file))[0]
    qualname = getattr(py_func, "__qualname__", py_func.__name__).replace("<", "").replace(">", "")
    version = sys.version_info
    return f"{modname}.{qualname}-{py_func.__code__.co_firstlineno}.py{version.major}{version.minor}" + getattr(
        sys, "abiflags", ""
    )


class SeedingState(NamedTuple):
    """Whether this process copies packed kernels, and from where: ``pack`` the tag's folder (``None``: it does
    not), ``reason`` why not, ``magic`` the host's code generation the copied entries are keyed to."""

    pack: Path | None
    reason: str
    magic: tuple[str, str, str] | None


_STATE: SeedingState | None = None


def seeding_state() -> SeedingState:
    """Decide once per process whether the pack fits this machine and these sources (module docstring)."""
    global _STATE
    if _STATE is None:
        _STATE = _decide()
    return _STATE


def _decide() -> SeedingState:
    pack = pack_root() / pack_tag()
    manifest_path = pack / "manifest.json"
    if not manifest_path.is_file():
        return SeedingState(None, f"no pack for {pack_tag()} in {pack.parent}", None)
    from numba.core import config

    if getattr(config, "CPU_NAME", None) is not None or getattr(config, "CPU_FEATURES", None) is not None:
        return SeedingState(None, "the process chose its own numba CPU (NUMBA_CPU_NAME/NUMBA_CPU_FEATURES)", None)
    if getattr(config, "CACHE_LOCATOR_CLASSES", None) or getattr(config, "DISABLE_JIT", False):
        return SeedingState(None, "the process chose its own cache locators, or disabled the JIT", None)
    magic = host_magic_tuple()
    missing = PACK_CPU_FEATURES - _enabled_features(magic[2])
    if missing:
        return SeedingState(None, f"this CPU ({magic[1]}) lacks {', '.join(sorted(missing))} of {PACK_CPU}", None)
    manifest = json.loads(manifest_path.read_text())
    if manifest.get("sources_sha256") != sources_digest():
        return SeedingState(None, f"the sources differ from those the pack in {pack} was compiled from", None)
    if manifest.get("triple") != magic[0]:
        return SeedingState(None, f"the pack was compiled for {manifest.get('triple')}, this is {magic[0]}", None)
    return SeedingState(pack, "", magic)


def _seed(source_index: Path, target_index: Path, magic: tuple[str, str, str]) -> int:
    """Copy one kernel's packed index and data files into its cache folder, the index keyed to ``magic``; returns
    the number of entries copied (0 when the index is another numba's)."""
    import numba
    from numba.core.serialize import dumps

    with source_index.open("rb") as handle:
        version = pickle.load(handle)
        payload = handle.read()
    if version != numba.__version__:
        return 0
    stamp, overloads = pickle.loads(payload)
    rekeyed = {(sig, magic, hashes): name for (sig, _packed, hashes), name in overloads.items()}
    folder = target_index.parent
    folder.mkdir(parents=True, exist_ok=True)
    for name in set(rekeyed.values()):
        shutil.copyfile(source_index.parent / name, folder / name)
    # the index last and atomically: a process that reads it finds every data file it names
    temporary = folder / f"{target_index.name}.tmp.{os.getpid()}"
    with temporary.open("wb") as handle:
        pickle.dump(version, handle, protocol=-1)
        handle.write(dumps((stamp, rekeyed)))
    os.replace(temporary, target_index)
    return len(rekeyed)


class PackSeeder:
    """A numba cache "locator" that locates nothing: asked where a kernel of this package caches, it copies the
    kernel's packed entries to the place numba's own locators choose, when that place has none, and returns
    ``None`` so that numba asks them next (module docstring)."""

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> None:
        try:
            relative = Path(py_file).resolve().relative_to(PACKAGE_DIR)
        except (ValueError, OSError):
            return None  # not one of this package's kernels
        state = seeding_state()
        if state.pack is None or state.magic is None:
            return None
        base = kernel_filename_base(py_func, py_file)
        source = state.pack / relative.parent / f"{base}.nbi"
        if not source.is_file():
            return None
        from numba.core import caching

        locator_classes: list[Any] = list(caching.CacheImpl._locator_classes)
        for locator_class in locator_classes:
            if locator_class is cls:
                continue
            locator = locator_class.from_function(py_func, py_file)
            if locator is not None:
                break
        else:
            return None
        target = Path(locator.get_cache_path()) / f"{base}.nbi"
        if not target.exists():
            try:
                _seed(source, target, state.magic)
            except (OSError, pickle.UnpicklingError, EOFError, ValueError) as exc:
                # the kernel then compiles, as it would without a pack
                _log.debug("could not copy the packed kernel %s: %s", base, exc)
        return None


def install_seeding() -> bool:
    """Put :class:`PackSeeder` first in numba's cache locators when a pack for :func:`pack_tag` exists (idempotent;
    cheap when none does: numba is not imported for it). Returns whether it is installed."""
    if not (pack_root() / pack_tag() / "manifest.json").is_file():
        return False
    from numba.core import caching

    if PackSeeder not in caching.CacheImpl._locator_classes:
        caching.CacheImpl._locator_classes.insert(0, PackSeeder)  # type: ignore[arg-type]
    return True
