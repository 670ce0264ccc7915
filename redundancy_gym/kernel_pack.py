"""Compiled kernels a wheel carries, so that a new process loads machine code instead of compiling it
(docs/architecture.md#kernels-shipped-in-the-wheel).

``redundancy-gym warmup --pack`` compiles every env's and analytic reference's kernels for the portable CPU
:data:`PACK_CPU` (x86-64-v3: AVX2 and fused multiply-adds; most x86-64 CPUs since 2013-2015, not every low-end
one) into ``redundancy_gym/packed_kernels/<tag>/`` (:func:`pack_tag`: Python, numba, machine, platform), numba's
own cache files laid out by the package's folders, with a manifest: the hash of the sources they were compiled
from, numpy's version, and every file's SHA-256. A wheel built after it ships them; a clone without one behaves as
before.

Seeding: numba asks its cache locators, in order, where a ``cache=True`` kernel's cache lives when the kernel is
defined. :func:`install_seeding` (run by :mod:`redundancy_gym.kernel_options`, which every kernel module imports
first) puts :class:`PackSeeder` at the head of that list. For a kernel of this package it finds the place numba's
own locators choose (``NUMBA_CACHE_DIR``, ``__pycache__`` beside the sources, or numba's per-user folder), and
where numba would find none of the kernel's packed entries there (no index, another numba's, one of older sources,
or a current one without them), copies them in, keyed to this machine's CPU, each file checked against the
manifest's SHA-256 and written as numba writes its own (a temporary name, then renamed); then it steps aside and
numba's locators go on as always. numba loads the copied entries at the kernel's first call. Code for x86-64-v3
runs on any CPU that has its features, and rounds as code compiled for the host does (both fuse multiply-adds where
the kernels allow it; held bit for bit by a test on the machines it ran on).

Nothing is copied (every kernel compiles as before) where the pack does not fit: another Python, numba or machine
(no folder for :func:`pack_tag`), another numpy minor version, a CPU without x86-64-v3's features, sources that
differ from the ones packed (an edited clone; numba keys a cache entry on its own file only, so a kernel whose
callee changed would load stale code), or a process that chose its own numba CPU
(``NUMBA_CPU_NAME``/``NUMBA_CPU_FEATURES``) or locators (``NUMBA_CACHE_LOCATOR_CLASSES``); nor where a pack cannot
be read. ``REDUNDANCY_GYM_KERNEL_PACK`` names another folder of packs (a path that holds none switches seeding
off); ``redundancy-gym warmup`` says whether the pack is used, or why not.
"""

from __future__ import annotations

import hashlib
import io
import itertools
import json
import logging
import os
import pickle
import platform
import sys
import warnings
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
    "missing_pack_features",
    "numpy_version",
    "pack_root",
    "pack_tag",
    "read_index",
    "seeding_state",
    "sources_digest",
]

PACK_CPU = "x86-64-v3"
"""The CPU model packed kernels are compiled for (LLVM's name of the x86-64-v3 level)."""

PACK_CPU_FEATURES = frozenset(
    {"cmov", "cx8", "fxsr", "sse2", "sse3", "ssse3", "sse4.1", "sse4.2", "popcnt", "cx16", "sahf", "crc32"}
    | {"avx", "avx2", "bmi", "bmi2", "f16c", "fma", "lzcnt", "movbe", "xsave"}
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


def missing_pack_features(features: str) -> set[str]:
    """The :data:`PACK_CPU_FEATURES` that a CPU feature string (LLVM's ``+avx2,-avx512f,...``, as
    :func:`host_magic_tuple` gives it) does not enable: empty where packed kernels run."""
    return set(PACK_CPU_FEATURES - {item[1:] for item in features.split(",") if item.startswith("+")})


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
    not), ``reason`` why not, ``magic`` the host's code generation the copied entries are keyed to, ``files`` the
    manifest's SHA-256 of every packed file (relative to ``pack``), checked before a file is copied."""

    pack: Path | None
    reason: str
    magic: tuple[str, str, str] | None
    files: dict[str, str]


_STATE: SeedingState | None = None


def seeding_state() -> SeedingState:
    """Decide once per process whether the pack fits this machine and these sources (module docstring)."""
    global _STATE
    if _STATE is None:
        try:
            _STATE = _decide()
        except Exception as exc:  # a pack that cannot be read is no pack: the kernels compile
            _STATE = SeedingState(None, f"the pack could not be read ({type(exc).__name__}: {exc})", None, {})
        if _STATE.pack is None and not _STATE.reason.startswith("no pack for"):
            # a pack is there but refused: say why the first run takes seconds instead of leaving the user to wait
            warnings.warn(
                f"redundancy_gym: the kernels compiled ahead in {pack_root()} are not used ({_STATE.reason}); "
                "this process compiles the kernels it runs (seconds to a minute, once per numba cache)",
                RuntimeWarning,
                stacklevel=2,
            )
    return _STATE


def numpy_version() -> str:
    """numpy's major.minor, which the compiled kernels depend on (numba types and lowers numpy calls per version)."""
    return ".".join(metadata.version("numpy").split(".")[:2])


def _decide() -> SeedingState:
    pack = pack_root() / pack_tag()
    manifest_path = pack / "manifest.json"
    if not manifest_path.is_file():
        return SeedingState(None, f"no pack for {pack_tag()} in {pack.parent}", None, {})
    from numba.core import config

    if getattr(config, "CPU_NAME", None) is not None or getattr(config, "CPU_FEATURES", None) is not None:
        return SeedingState(None, "the process chose its own numba CPU (NUMBA_CPU_NAME/NUMBA_CPU_FEATURES)", None, {})
    if getattr(config, "CACHE_LOCATOR_CLASSES", None) or getattr(config, "DISABLE_JIT", False):
        return SeedingState(None, "the process chose its own cache locators, or disabled the JIT", None, {})
    magic = host_magic_tuple()
    missing = missing_pack_features(magic[2])
    if missing:
        reason = f"this CPU ({magic[1]}) lacks {', '.join(sorted(missing))} of {PACK_CPU}"
        return SeedingState(None, reason, None, {})
    manifest = json.loads(manifest_path.read_text())
    if manifest.get("sources_sha256") != sources_digest():
        return SeedingState(None, f"the sources differ from those the pack in {pack} was compiled from", None, {})
    if manifest.get("triple") != magic[0]:
        return SeedingState(None, f"the pack was compiled for {manifest.get('triple')}, this is {magic[0]}", None, {})
    if manifest.get("numpy") != numpy_version():
        reason = f"the pack was compiled with numpy {manifest.get('numpy')}, this is numpy {numpy_version()}"
        return SeedingState(None, reason, None, {})
    return SeedingState(pack, "", magic, dict(manifest["files"]))


def _verified(pack: Path, relative: str, files: dict[str, str]) -> bytes:
    """A packed file's bytes, if the manifest lists it with this content (a file left from an older pack, or one
    truncated, is refused)."""
    data = (pack / relative).read_bytes()
    if files.get(relative) != hashlib.sha256(data).hexdigest():
        raise ValueError(f"{relative} is not the file the manifest lists")
    return data


def _write_atomic(path: Path, data: bytes) -> None:
    """Write ``path`` as numba writes its cache files: to a temporary name, then renamed over it, so that a process
    reading it meanwhile sees the old file or the whole new one."""
    temporary = path.with_name(f"{path.name}.tmp.{os.getpid()}.{id(data)}")
    try:
        temporary.write_bytes(data)
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def read_index(path: Path) -> tuple[str, Any, dict[Any, str]] | None:
    """numba's index file: its numba version, the source stamp and the overloads (key -> data file name)."""
    if not path.is_file():
        return None
    with path.open("rb") as handle:
        version = pickle.load(handle)
        stamp, overloads = pickle.loads(handle.read())
    return version, stamp, dict(overloads)


def _seed(state: SeedingState, relative_index: str, target_index: Path) -> int:
    """Copy one kernel's packed entries into its cache folder, keyed to this machine's CPU: over an index numba
    would not use (none, another numba's, stale sources), or beside the entries of a current one; returns the
    number of entries copied."""
    import numba
    from numba.core.serialize import dumps

    assert state.pack is not None and state.magic is not None
    handle = io.BytesIO(_verified(state.pack, relative_index, state.files))
    version = pickle.load(handle)
    stamp, packed = pickle.loads(handle.read())
    if version != numba.__version__:
        return 0
    packed_magic = (state.magic[0], PACK_CPU, "")
    wanted = {
        (sig, state.magic, hashes): name for (sig, magic, hashes), name in packed.items() if magic == packed_magic
    }
    current = read_index(target_index)
    overloads = current[2] if current is not None and current[:2] == (version, stamp) else {}
    missing = {key: name for key, name in wanted.items() if key not in overloads}
    if not missing:
        return 0
    folder = target_index.parent
    stem = target_index.name.removesuffix(".nbi")
    taken = set(overloads.values())
    for key, name in missing.items():
        data = _verified(state.pack, f"{relative_index.rsplit('/', 1)[0]}/{name}", state.files)
        target_name = name
        if target_name in taken:  # beside a current index: the first free number, as numba picks it
            target_name = next(f"{stem}.{n}.nbc" for n in itertools.count(1) if f"{stem}.{n}.nbc" not in taken)
        _write_atomic(folder / target_name, data)
        taken.add(target_name)
        overloads[key] = target_name
    # the index last: a process that reads it finds every data file it names
    _write_atomic(target_index, pickle.dumps(version, protocol=-1) + dumps((stamp, overloads)))
    return len(missing)


class PackSeeder:
    """A numba cache "locator" that locates nothing: asked where a kernel of this package caches, it copies the
    kernel's packed entries to the place numba's own locators choose, where numba would find none, and returns
    ``None`` so that numba asks them next (module docstring). Nothing it meets (an unreadable pack, a file the
    manifest does not list, a full disk) stops the kernel's definition: the kernel then compiles."""

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> None:
        try:
            relative = Path(py_file).resolve().relative_to(PACKAGE_DIR)
        except (ValueError, OSError, RuntimeError):
            return None  # not one of this package's kernels
        try:
            cls._seed_kernel(py_func, py_file, relative)
        except Exception as exc:  # seeding only saves a compile
            _log.debug("no packed copy of %s in %s: %s", getattr(py_func, "__qualname__", py_func), py_file, exc)
        return None

    @classmethod
    def _seed_kernel(cls, py_func: Any, py_file: str, relative: Path) -> None:
        state = seeding_state()
        if state.pack is None:
            return
        relative_index = (relative.parent / f"{kernel_filename_base(py_func, py_file)}.nbi").as_posix()
        if relative_index not in state.files:
            return
        from numba.core import caching

        locator_classes: list[Any] = list(caching.CacheImpl._locator_classes)
        for locator_class in locator_classes:
            if locator_class is cls:
                continue
            locator = locator_class.from_function(py_func, py_file)
            if locator is not None:
                break
        else:
            return
        _seed(state, relative_index, Path(locator.get_cache_path()) / relative_index.rsplit("/", 1)[-1])


def install_seeding() -> bool:
    """Put :class:`PackSeeder` first in numba's cache locators when a pack for :func:`pack_tag` exists (idempotent;
    cheap when none does: numba is not imported for it). Returns whether it is installed."""
    try:
        if not (pack_root() / pack_tag() / "manifest.json").is_file():
            return False
    except metadata.PackageNotFoundError:  # numba without its package metadata (a frozen application)
        return False
    from numba.core import caching

    if PackSeeder not in caching.CacheImpl._locator_classes:
        caching.CacheImpl._locator_classes.insert(0, PackSeeder)  # type: ignore[arg-type]
    return True
