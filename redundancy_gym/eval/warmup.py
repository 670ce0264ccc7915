"""Fill numba's on-disk cache ahead of use (``redundancy-gym warmup [ENV...]``), so that a first episode, a test
run or a fresh cluster worker loads compiled kernels instead of compiling them.

A kernel compiles at its first call (:class:`~redundancy_gym.kernel_options.LazyEntryPoint`), so the warm-up
makes each env, resets it, builds every analytic policy the env supports (``clik``, ``predictive``, ``global``,
``walking``), calls its ``predict`` and steps the env with it (a wrapped id: with a zero action, which runs the
wrapper's reference). numba writes the cache where :func:`numba_cache_location` says: ``NUMBA_CACHE_DIR`` when set,
else ``__pycache__`` folders beside the package's sources, else (a read-only install) its per-user cache folder. A
worker that shares the folder (or the installed package) shares the cache; the cache is valid for the same
package sources, Python, numba and CPU.

``redundancy-gym warmup --pack`` (:func:`pack_kernels`) compiles the same kernels for the portable x86-64-v3 CPU
into the package instead, for a wheel to carry: a process of an installed wheel then copies them into its cache
(:mod:`redundancy_gym.kernel_pack`) and compiles nothing the warm-up covers.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path
from typing import NamedTuple

from ..kernel_pack import PACK_CPU, PACKAGE_DIR, numpy_version, pack_root, pack_tag, read_index, sources_digest
from .compile_clock import COMPILE_CLOCK
from .exceptions import EvalError

__all__ = ["PackResult", "WarmupRow", "numba_cache_location", "pack_kernels", "warmup", "warmup_env"]


class WarmupRow(NamedTuple):
    """One env id warmed up: its wall time [s], of which numba compiled [s], and the policies it ran."""

    env_id: str
    seconds: float
    compile_s: float
    policies: tuple[str, ...]


def numba_cache_location() -> str:
    """Where numba keeps this package's compiled kernels in this process (``NUMBA_CACHE_DIR`` overrides it)."""
    from numba.core import config

    cache_dir = getattr(config, "CACHE_DIR", "")  # numba's reading of NUMBA_CACHE_DIR
    if cache_dir:
        return str(cache_dir)
    from ..controllers.clik.clik_kernels import clik_step

    # numba's own choice for a kernel of this package: beside its source, or per user where that is read-only
    # (a private attribute of numba's dispatcher: a numba without it gets the general answer)
    cache_path = getattr(getattr(clik_step, "_cache", None), "_cache_path", None)
    if cache_path is None:
        return "numba's default: __pycache__ beside the sources, or its per-user cache folder where they are read-only"
    path = Path(cache_path)
    package = Path(__file__).resolve().parents[1]
    if package in path.resolve().parents:
        return f"__pycache__ folders beside the sources in {package}"
    return str(path.parents[1])


def _check_env_ids(ids: Sequence[str]) -> None:
    from ..registration import ENV_IDS

    unknown = [e for e in ids if e not in ENV_IDS]
    if unknown:
        raise EvalError(f"unknown env id {', '.join(unknown)}; valid: {', '.join(ENV_IDS)}")


def warmup_env(env_id: str) -> WarmupRow:
    """Compile (or load) every kernel that ``env_id`` and its analytic policies run (module docstring)."""
    import gymnasium as gym
    import numpy as np

    from ..policies import GENERIC_POLICIES, make_policy, supported_policies

    _check_env_ids([env_id])
    start, compiled = time.perf_counter(), COMPILE_CLOCK.compiling_seconds
    env = gym.make(env_id)
    ran: list[str] = []
    try:
        obs, _ = env.reset(seed=0)
        env.step(np.zeros(env.action_space.shape, dtype=env.action_space.dtype))
        policies = [p for p in supported_policies(env) if p not in GENERIC_POLICIES]
        for name in policies:
            obs, _ = env.reset(seed=0)
            policy = make_policy(name, env)
            action, _ = policy.predict(obs, deterministic=True)
            env.step(action)
            ran.append(name)
    finally:
        env.close()
    return WarmupRow(env_id, time.perf_counter() - start, COMPILE_CLOCK.compiling_seconds - compiled, tuple(ran))


def warmup(env_ids: Sequence[str] | None = None, *, workers: int = 1, progress: bool = True) -> list[WarmupRow]:
    """:func:`warmup_env` for each env id (default: every registered one), in ``workers`` processes."""
    from ..registration import ENV_IDS

    ids = list(ENV_IDS if env_ids is None else env_ids)
    _check_env_ids(ids)
    if workers < 1:
        raise EvalError(f"workers must be >= 1, got {workers!r}")
    from tqdm.auto import tqdm

    rows: list[WarmupRow] = []
    with tqdm(total=len(ids), desc="warmup", unit="env", disable=not progress) as bar:
        if workers == 1:
            for env_id in ids:
                rows.append(warmup_env(env_id))
                bar.update(1)
        else:
            with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn")) as pool:
                for row in pool.map(warmup_env, ids):
                    rows.append(row)
                    bar.update(1)
    return rows


class PackResult(NamedTuple):
    """A pack written by :func:`pack_kernels`: its folder, how many kernels (cache index files) and compiled
    entries it holds, its size [bytes], and the warm-up's wall time [s]."""

    folder: Path
    kernels: int
    entries: int
    size_bytes: int
    seconds: float


def pack_kernels(
    env_ids: Sequence[str] | None = None, *, root: str | Path | None = None, progress: bool = True
) -> PackResult:
    """Compile every kernel that ``env_ids`` (default: every registered one) and their analytic policies run for the
    portable CPU :data:`~redundancy_gym.kernel_pack.PACK_CPU`, in one separate process with an empty cache (one:
    numba's cache index is not safe against two processes adding entries to one kernel at once), and lay numba's
    cache files out by the package's folders in ``root``/:func:`~redundancy_gym.kernel_pack.pack_tag` (default
    root: :func:`~redundancy_gym.kernel_pack.pack_root`), with a manifest; a wheel built next ships them
    (:mod:`redundancy_gym.kernel_pack`). The tag's folder is replaced.

    Raises:
        EvalError: an unknown env id, a warm-up that fails, or a pack that would hold no kernel.
    """
    import os
    import subprocess
    import sys
    import tempfile

    ids = list(env_ids) if env_ids else []
    _check_env_ids(ids)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="redundancy_gym_pack_") as cache:
        # no other NUMBA_* setting of this shell (NUMBA_OPT, NUMBA_BOUNDSCHECK, ...) goes into the shipped code
        env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
        env.update({"NUMBA_CACHE_DIR": cache, "NUMBA_CPU_NAME": PACK_CPU, "NUMBA_CPU_FEATURES": ""})
        env["REDUNDANCY_GYM_KERNEL_PACK"] = str(Path(cache) / "none")  # an earlier pack is not this one's source
        # this package, whatever folder the command runs in
        env["PYTHONPATH"] = os.pathsep.join([str(PACKAGE_DIR.parent), *filter(None, [env.get("PYTHONPATH")])])
        args = ["warmup", *([] if progress else ["--no-progress"]), *ids]
        code = "import sys; from redundancy_gym.cli import main; sys.exit(main(sys.argv[1:]))"
        done = subprocess.run([sys.executable, "-c", code, *args], env=env, cwd=cache, check=False)
        if done.returncode != 0:
            raise EvalError(f"the warm-up for the pack exited {done.returncode}")
        folder = Path(root if root is not None else pack_root())
        result = _pack_cache(Path(cache), folder)
    return result._replace(seconds=time.perf_counter() - start)


def _pack_cache(cache: Path, root: Path) -> PackResult:
    """Lay out the kernels of this package that ``cache`` (a ``NUMBA_CACHE_DIR``) holds in ``root``/tag, with the
    manifest; every index is checked: compiled for the pack's CPU, and no data file named twice."""
    import hashlib
    import json
    import os
    import shutil

    import llvmlite.binding as ll
    from numba.core.caching import _CacheLocator

    # numba names a cache folder after the source folder's path as the kernel's module was imported (abspath, not
    # resolved: a package reached through a symlink has two names)
    from .. import __file__ as package_init

    imported = Path(os.path.abspath(str(package_init))).parent
    by_subpath: dict[str, Path] = {}
    for base in {PACKAGE_DIR, imported}:
        for folder in [base, *(p for p in base.rglob("*") if p.is_dir())]:
            by_subpath[_CacheLocator.get_suitable_cache_subpath(str(folder / "module.py"))] = folder.relative_to(base)
    pack = root / pack_tag()
    if pack.exists():
        shutil.rmtree(pack)
    files: dict[str, str] = {}
    kernels = entries = size = 0
    expected_magic = (ll.get_process_triple(), PACK_CPU, "")
    for sub in sorted(cache.iterdir()):
        relative = by_subpath.get(sub.name)
        if relative is None:
            continue  # another package's kernels
        for path in sorted(sub.iterdir()):
            if path.suffix not in (".nbi", ".nbc"):
                continue
            if path.suffix == ".nbi":
                index = read_index(path)
                overloads = index[2] if index is not None else {}
                names = list(overloads.values())
                if len(set(names)) != len(names) or any(key[1] != expected_magic for key in overloads):
                    raise EvalError(f"{path} names a data file twice or holds code for another CPU: not packed")
                kernels += 1
                entries += len(overloads)
            data = path.read_bytes()
            name = (relative / path.name).as_posix()
            (pack / relative).mkdir(parents=True, exist_ok=True)
            (pack / name).write_bytes(data)
            files[name] = hashlib.sha256(data).hexdigest()
            size += len(data)
    if kernels == 0:
        raise EvalError(f"the warm-up's cache {cache} holds no kernel of {PACKAGE_DIR}: nothing to pack")
    manifest = {
        "tag": pack_tag(),
        "cpu": PACK_CPU,
        "triple": expected_magic[0],
        "numpy": numpy_version(),
        "sources_sha256": sources_digest(),
        "kernels": kernels,
        "entries": entries,
        "size_bytes": size,
        "files": files,
    }
    (pack / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")
    return PackResult(pack, kernels, entries, size, 0.0)
