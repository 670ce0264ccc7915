"""Kernels compiled ahead for the portable x86-64-v3 CPU and copied into a new process's numba cache
(redundancy_gym/kernel_pack.py): the seeder names the files numba itself looks for, keys them to this machine's
code generation as numba does, and refuses a pack that does not fit. That a wheel carrying a pack runs the README's
quick start in a fresh process without compiling, bit for bit as kernels compiled for the host: tests/test_wheel.py."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from redundancy_gym import kernel_pack
from redundancy_gym.kernel_pack import (
    PACK_CPU_FEATURES,
    host_magic_tuple,
    kernel_filename_base,
    pack_tag,
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
    manifest = {"sources_sha256": "0" * 64, "triple": magic[0]}
    (pack / "manifest.json").write_text(json.dumps(manifest))
    monkeypatch.setattr(kernel_pack, "_STATE", None)
    if PACK_CPU_FEATURES - {f[1:] for f in magic[2].split(",") if f.startswith("+")}:
        assert "lacks" in seeding_state().reason
        return
    assert seeding_state().pack is None and "sources differ" in seeding_state().reason  # an edited clone

    (pack / "manifest.json").write_text(json.dumps({**manifest, "sources_sha256": sources_digest()}))
    monkeypatch.setattr(kernel_pack, "_STATE", None)
    assert seeding_state().pack == pack and seeding_state().reason == ""

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
