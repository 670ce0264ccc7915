"""Kernels compiled ahead for the portable x86-64-v3 CPU and copied into a new process's numba cache
(redundancy_gym/kernel_pack.py): the seeder names the files numba itself looks for, keys them to this machine's
code generation as numba does, and refuses a pack that does not fit. That a wheel carrying a pack runs the README's
quick start in a fresh process without compiling, bit for bit as kernels compiled for the host: tests/test_wheel.py."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from redundancy_gym import kernel_pack
from redundancy_gym.kernel_pack import (
    host_magic_tuple,
    kernel_filename_base,
    missing_pack_features,
    numpy_version,
    pack_tag,
    read_index,
    seeding_state,
    sources_digest,
)


def _fresh_state(monkeypatch: pytest.MonkeyPatch, root: Path) -> None:
    monkeypatch.setenv("REDUNDANCY_GYM_KERNEL_PACK", str(root))
    monkeypatch.setattr(kernel_pack, "_STATE", None)


def test_the_host_magic_tuple_is_numbas() -> None:
    from numba.core import config
    from numba.core.registry import cpu_target

    if config.CPU_NAME is not None or config.CPU_FEATURES is not None:
        pytest.skip("this process chose its own numba CPU")
    assert host_magic_tuple() == cpu_target.target_context.codegen().magic_tuple()


def test_the_kernel_file_stem_is_the_one_numba_writes() -> None:
    from redundancy_gym.geometry import potentials

    kernels = [k for k in vars(potentials).values() if hasattr(k, "_cache") and hasattr(k, "py_func")]
    assert kernels
    for kernel in kernels:
        index_name = kernel._cache._cache_file._index_name
        assert index_name == kernel_filename_base(kernel.py_func, potentials.__file__) + ".nbi"


def test_no_pack_is_used_where_none_fits(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    _fresh_state(monkeypatch, tmp_path)
    assert seeding_state().pack is None and "no pack for" in seeding_state().reason

    pack = tmp_path / pack_tag()
    pack.mkdir()
    magic = host_magic_tuple()
    manifest = {"sources_sha256": "0" * 64, "triple": magic[0], "numpy": numpy_version(), "files": {}}
    (pack / "manifest.json").write_text(json.dumps(manifest))
    monkeypatch.setattr(kernel_pack, "_STATE", None)
    if missing_pack_features(magic[2]):
        assert "lacks" in seeding_state().reason
        return
    with pytest.warns(RuntimeWarning, match="are not used .*sources differ"):  # a refused pack says so, once
        assert seeding_state().pack is None and "sources differ" in seeding_state().reason  # an edited clone

    (pack / "manifest.json").write_text(json.dumps({**manifest, "sources_sha256": sources_digest()}))
    monkeypatch.setattr(kernel_pack, "_STATE", None)
    assert seeding_state().pack == pack and seeding_state().reason == ""

    (pack / "manifest.json").write_text(json.dumps({**manifest, "sources_sha256": sources_digest(), "numpy": "1.26"}))
    monkeypatch.setattr(kernel_pack, "_STATE", None)
    assert seeding_state().pack is None and "numpy 1.26" in seeding_state().reason

    # a CPU without AVX2 (x86-64-v2) gets no x86-64-v3 code
    without_avx2 = magic[2].replace("+avx2", "-avx2")
    monkeypatch.setattr(kernel_pack, "host_magic_tuple", lambda: (magic[0], "westmere", without_avx2))
    monkeypatch.setattr(kernel_pack, "_STATE", None)
    assert seeding_state().pack is None and "lacks avx2" in seeding_state().reason


def test_the_sources_digest_changes_with_a_source(tmp_path: Path) -> None:
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "packed_kernels").mkdir()
    (tmp_path / "packed_kernels" / "b.py").write_text("ignored\n")
    before = sources_digest(tmp_path)
    (tmp_path / "packed_kernels" / "b.py").write_text("still ignored\n")
    assert sources_digest(tmp_path) == before
    (tmp_path / "a.py").write_text("x = 2\n")
    assert sources_digest(tmp_path) != before


# one small kernel's pack, compiled for x86-64-v3 in a separate process, and a probe that defines and calls it in a
# fresh process (seeding happens when a kernel is defined): what it returns, how long numba compiled
KERNEL = "from redundancy_gym.geometry.potentials import piecewise_potential_kernel as kernel"
PROBE = f"""
import json
from redundancy_gym.eval.compile_clock import COMPILE_CLOCK
COMPILE_CLOCK.install()
{KERNEL}
from redundancy_gym.kernel_pack import seeding_state
value = kernel(0.01, 0.1, 1.0, 0.5)
print("PROBE " + json.dumps({{"value": list(value), "compiling_s": COMPILE_CLOCK.compiling_seconds,
      "reason": seeding_state().reason}}))
"""


def _clean_env(**extra: str) -> dict[str, str]:
    return {**{k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}, **extra}


def _probe(cache: Path, packs: Path) -> dict[str, Any]:
    env = _clean_env(NUMBA_CACHE_DIR=str(cache), REDUNDANCY_GYM_KERNEL_PACK=str(packs))
    done = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-3000:]
    result: dict[str, Any] = json.loads(next(x for x in done.stdout.splitlines() if x.startswith("PROBE "))[6:])
    return result


@pytest.fixture(scope="module")
def small_pack(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A pack of the potential kernel alone (``_pack_cache`` over a cache compiled for x86-64-v3)."""
    from redundancy_gym.eval.warmup import _pack_cache

    magic = host_magic_tuple()
    if missing_pack_features(magic[2]):
        pytest.skip(f"this CPU ({magic[1]}) is not x86-64-v3")
    tmp = tmp_path_factory.mktemp("small_pack")
    env = _clean_env(NUMBA_CACHE_DIR=str(tmp / "compiled"), NUMBA_CPU_NAME="x86-64-v3", NUMBA_CPU_FEATURES="")
    subprocess.run([sys.executable, "-c", f"{KERNEL}; kernel(0.01, 0.1, 1.0, 0.5)"], env=env, check=True, timeout=300)
    packed = _pack_cache(tmp / "compiled", tmp / "packs")
    assert packed.kernels >= 1 and packed.folder == tmp / "packs" / pack_tag()
    manifest = json.loads((packed.folder / "manifest.json").read_text())
    assert manifest["cpu"] == "x86-64-v3" and set(manifest["files"]) == {
        p.relative_to(packed.folder).as_posix() for p in packed.folder.rglob("*.nb?")
    }
    return tmp / "packs"


def _expected() -> list[float]:
    from redundancy_gym.geometry.potentials import piecewise_potential_kernel

    return list(piecewise_potential_kernel(0.01, 0.1, 1.0, 0.5))


def _read(index: Path) -> tuple[str, Any, dict[Any, str]]:
    read = read_index(index)
    assert read is not None, index
    return read


def _write_index(index: Path, version: str, stamp: Any, overloads: dict[Any, str]) -> None:
    """An index file as numba writes one: its version, then the stamp and overloads."""
    import pickle

    index.write_bytes(pickle.dumps(version, protocol=-1) + pickle.dumps((stamp, overloads)))


def _index(cache: Path) -> Path:
    (index,) = [p for p in cache.rglob("potentials.piecewise_potential_kernel-*.nbi")]
    return index


def test_a_packed_kernel_is_copied_into_an_empty_cache_and_loads_without_compiling(
    small_pack: Path, tmp_path: Path
) -> None:
    seeded = _probe(tmp_path / "cache", small_pack)
    assert seeded["reason"] == "" and seeded["compiling_s"] == 0.0
    assert seeded["value"] == _expected()
    assert not list((tmp_path / "cache").rglob("*.tmp.*"))  # written atomically, nothing left behind


def test_an_index_of_older_sources_is_seeded_over(small_pack: Path, tmp_path: Path) -> None:
    """After an upgrade, numba ignores the old release's index (another stamp); the pack replaces it."""
    _probe(tmp_path / "cache", small_pack)
    index = _index(tmp_path / "cache")
    version, _stamp, overloads = _read(index)
    _write_index(index, version, b"older sources", overloads)
    again = _probe(tmp_path / "cache", small_pack)
    assert again["compiling_s"] == 0.0 and again["value"] == _expected()


def test_a_current_index_without_the_packed_entries_gets_them_beside_its_own(small_pack: Path, tmp_path: Path) -> None:
    _probe(tmp_path / "cache", small_pack)
    index = _index(tmp_path / "cache")
    version, stamp, overloads = _read(index)
    (key, name), *_ = overloads.items()
    other = (key[0], ("another", "cpu", ""), key[2])  # an entry numba keeps but this machine does not use
    _write_index(index, version, stamp, {other: name})
    again = _probe(tmp_path / "cache", small_pack)
    assert again["compiling_s"] == 0.0
    merged = _read(index)[2]
    assert merged[other] == name and len(merged) == 2 and len(set(merged.values())) == 2


def test_a_damaged_pack_is_refused_and_the_kernel_compiles(small_pack: Path, tmp_path: Path) -> None:
    import shutil

    damaged = tmp_path / "packs"
    shutil.copytree(small_pack, damaged)
    (data,) = [p for p in damaged.rglob("potentials.piecewise_potential_kernel-*.nbc")]
    data.write_bytes(data.read_bytes()[:100])  # truncated, as by a copy cut short
    truncated = _probe(tmp_path / "cache", damaged)
    assert truncated["compiling_s"] > 0 and truncated["value"] == _expected()

    (damaged / pack_tag() / "manifest.json").write_text('{"sources_sha256": ')  # unreadable
    unreadable = _probe(tmp_path / "cache2", damaged)
    assert "could not be read" in unreadable["reason"] and unreadable["value"] == _expected()
