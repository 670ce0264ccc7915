"""The wheel is what a pip-install user gets: it carries the MJCF files, the shipped learned baselines with their
training records, the baselines' configs and configs/, and installed outside the checkout it lists the envs, warms
numba's cache up beside its own sources, evaluates a shipped model by its short name and lists the baselines with
their models.

The wheel is built offline from a copy of the working tree (``pip wheel --no-build-isolation`` with the installed
setuptools; building in place would write build/ and the egg-info into the checkout) and installed with
``pip install --target``; the commands then run from a folder outside the checkout with only that target on
PYTHONPATH, so the import resolves to the installed copy (asserted) ahead of the editable install's finder, which
Python consults after PYTHONPATH.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import zipfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from redundancy_gym.kernel_pack import host_magic_tuple, missing_pack_features, pack_tag
from redundancy_gym.learning.baselines import BASELINES_DIR, baselines
from redundancy_gym.policies.shipped_models import SHIPPED_MODELS_DIR, shipped_models

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "redundancy_gym"
# the package data a pip-install user needs, as globs relative to the package (pyproject.toml's package-data)
DATA_GLOBS = ("assets/*.xml", "baselines/*.yaml", "baselines/models/*.zip", "baselines/models/*.json", "configs/*.yaml")
# what the copy of the tree leaves out: environments, caches, generated output and earlier builds
_TOP_LEVEL_SKIPPED = {".venv", ".git", ".hypothesis", "runs", "results", "build", "dist", "redundancy_gym.egg-info"}
TRUST_LINE = "can run code from the file"  # the line a .zip from outside the shipped models logs


def _skip_in_copy(directory: str, names: list[str]) -> set[str]:
    skipped = {n for n in names if n == "__pycache__" or n.endswith("_cache")}
    if Path(directory).resolve() == ROOT:
        skipped |= _TOP_LEVEL_SKIPPED & set(names)
    return skipped


def _run(args: list[str], *, cwd: Path, timeout: float, env: dict[str, str] | None = None) -> str:
    """Run ``args`` and return its stdout and stderr; a failure shows both."""
    done = subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    assert done.returncode == 0, f"{' '.join(args)} exited {done.returncode}:\n{done.stdout}\n{done.stderr}"
    return done.stdout + done.stderr


def _expected_data() -> set[str]:
    """The package-data files of the checkout, as wheel entry names."""
    return {f"redundancy_gym/{p.relative_to(PACKAGE).as_posix()}" for g in DATA_GLOBS for p in PACKAGE.glob(g)}


def _reuse_numba_cache(installed: Path, source: Path) -> None:
    """Give the installed package the checkout's numba cache, so that the test measures the packaging, not a cold
    compile of the kernels (minutes on 2 cores). numba keys a cached kernel on its source file (the content's hash;
    in older numba its mtime and size) and on the function's bytecode, not on its path: each installed module
    that is byte-identical to its twin gets the twin's mtime and ``__pycache__/*.nb[ic]`` files. A stale or missing
    cache only costs the compile."""
    for module in installed.rglob("*.py"):
        twin = source / module.relative_to(installed)
        if not twin.is_file() or twin.read_bytes() != module.read_bytes():
            continue
        stat = twin.stat()
        os.utime(module, ns=(stat.st_atime_ns, stat.st_mtime_ns))
        cached = sorted((twin.parent / "__pycache__").glob(f"{twin.stem}.*.nb[ic]"))
        if cached:
            (module.parent / "__pycache__").mkdir(exist_ok=True)
            for path in cached:
                shutil.copy2(path, module.parent / "__pycache__" / path.name)


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The wheel built from a copy of the working tree."""
    tmp = tmp_path_factory.mktemp("wheel")
    source = tmp / "source"
    shutil.copytree(ROOT, source, symlinks=True, ignore=_skip_in_copy)
    # the quick start's kernels compiled ahead for x86-64-v3, as `make wheel` packs every env's (a fresh clone has
    # no pack; this one holds PlanarReach's, about a minute to compile on 2 cores)
    from redundancy_gym.eval.warmup import pack_kernels

    pack_kernels(["redundancy_gym/PlanarReach-v0"], root=source / "redundancy_gym" / "packed_kernels", progress=False)
    command = [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index", "-q"]
    _run([*command, "-w", str(tmp / "dist"), str(source)], cwd=tmp, timeout=300)
    (built,) = (tmp / "dist").glob("redundancy_gym-*.whl")
    return built


@pytest.fixture(scope="module")
def installed(wheel: Path, tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Path, dict[str, str]]]:
    """The wheel installed into a fresh target folder outside the checkout, and the environment that imports it."""
    tmp = tmp_path_factory.mktemp("installed")
    target = tmp / "site"
    command = [sys.executable, "-m", "pip", "install", "--no-deps", "--no-index", "--no-compile", "-q"]
    _run([*command, "--target", str(target), str(wheel)], cwd=tmp, timeout=300)
    _reuse_numba_cache(target / "redundancy_gym", PACKAGE)
    # NUMBA_CACHE_DIR would key the installed kernels' cache on their folder elsewhere: the in-tree cache is used
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME", "NUMBA_CACHE_DIR")}
    env["PYTHONPATH"] = str(target)
    yield target, env


def test_the_clone_reaches_the_package_data_through_one_copy() -> None:
    """baselines/ and configs/ of a clone are the package's folders (symlinks), not second copies."""
    assert (ROOT / "baselines").resolve() == BASELINES_DIR.resolve() == (PACKAGE / "baselines").resolve()
    assert (ROOT / "configs").resolve() == (PACKAGE / "configs").resolve()
    assert SHIPPED_MODELS_DIR.resolve().is_relative_to(PACKAGE.resolve())
    assert (ROOT / "configs" / "ppo_planar_reach.yaml").is_file()
    assert {p.stem for p in (ROOT / "baselines").glob("*.yaml")} == {b.name for b in baselines()}


def test_configs_of_the_readme_resolve_to_the_package_from_any_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``configs/NAME`` (as the README writes it) reads the package's copy where the folder has no such file; a
    user's own file of that name wins."""
    from redundancy_gym.learning.training import CONFIGS_DIR, load_config

    monkeypatch.chdir(tmp_path)
    env_id = "redundancy_gym/PlanarReach-v0"
    shipped = load_config("configs/ppo_planar_reach.yaml", env_id)
    assert shipped == load_config(CONFIGS_DIR / "ppo_planar_reach.yaml", env_id)
    assert load_config("baselines/ppo-joint-planar_reach.yaml", env_id).n_timesteps is not None
    (tmp_path / "configs").mkdir()
    (tmp_path / "configs" / "ppo_planar_reach.yaml").write_text(f"{env_id}:\n  n_timesteps: 7\n")
    assert load_config("configs/ppo_planar_reach.yaml", env_id).n_timesteps == 7
    with pytest.raises(Exception, match="cannot read configs/nope.yaml"):
        load_config("configs/nope.yaml", env_id)


def test_the_wheel_holds_the_models_records_configs_and_mjcf(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
    expected = _expected_data()
    packed = f"redundancy_gym/packed_kernels/{pack_tag()}/"
    assert f"{packed}manifest.json" in names
    assert {n.rsplit(".", 1)[-1] for n in names if n.startswith(packed + "controllers/clik/")} == {"nbi", "nbc"}
    stems = shipped_models()
    assert stems, "no shipped models in the checkout"
    for stem in stems:  # each model with its training record
        assert {f"redundancy_gym/baselines/models/{stem}.zip", f"redundancy_gym/baselines/models/{stem}.json"} <= names
    assert {f"redundancy_gym/baselines/{b.name}.yaml" for b in baselines()} <= names
    assert {"redundancy_gym/configs/ppo_planar_reach.yaml", "redundancy_gym/assets/planar_arm.xml"} <= names
    assert expected <= names, f"missing from the wheel: {sorted(expected - names)}"
    # the generated tables and plots of `make baselines` stay in the clone
    assert not [n for n in names if n.startswith("redundancy_gym/baselines/results/")]


# about a minute with the checkout's numba cache warm (the suite runs this file after the tests that compile the
# kernels); the limit leaves room for a cold compile when the file runs alone on a fresh clone
@pytest.mark.timeout(1500)
def test_the_installed_package_lists_evaluates_and_sees_its_baselines(
    installed: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    target, env = installed
    python = sys.executable
    probe = (
        "import redundancy_gym; from redundancy_gym.policies.shipped_models import SHIPPED_MODELS_DIR; "
        "from redundancy_gym.learning.training import CONFIGS_DIR, load_config; "
        "print(redundancy_gym.__file__); print(SHIPPED_MODELS_DIR); print(CONFIGS_DIR); "
        "print(load_config('configs/ppo_planar_reach.yaml', 'redundancy_gym/PlanarReach-v0').n_timesteps)"
    )
    where = _run([python, "-c", probe], cwd=tmp_path, env=env, timeout=120).split()
    for path in where[:3]:  # the installed copy, not the checkout's editable install
        assert Path(path).resolve().is_relative_to(target.resolve()), where
        assert not Path(path).resolve().is_relative_to(ROOT), where
    assert int(where[3]) > 0  # the README's `--config configs/...` reads the installed config from any folder

    script = str(target / "bin" / "redundancy-gym")  # the console script of the wheel's entry point
    listed = _run([python, script, "list"], cwd=tmp_path, env=env, timeout=600)
    assert "redundancy_gym/PlanarReach-v0" in listed
    assert "ppo-nullspace" in listed and "shipped learned baseline" in listed

    # warmup for a wheel user: it runs the env's references and names the installed package's cache
    warmed = _run(
        [python, script, "warmup", "redundancy_gym/PlanarReach-v0", "--no-progress"], cwd=tmp_path, env=env, timeout=600
    )
    assert "clik, predictive, global" in warmed
    assert f"numba cache: __pycache__ folders beside the sources in {(target / 'redundancy_gym').resolve()}" in warmed

    report = tmp_path / "report.json"
    env_id = "redundancy_gym/PlanarReach-Nullspace-v0"
    command = [python, script, "eval", env_id, "--policy", "ppo-nullspace", "--episodes", "2", "--json", str(report)]
    evaluated = _run(command, cwd=tmp_path, env=env, timeout=600)
    assert TRUST_LINE not in evaluated  # a shipped model loads quietly
    assert len(json.loads(report.read_text())["per_episode"]) == 2

    listed = _run([python, script, "baselines", "--list"], cwd=tmp_path, env=env, timeout=120)
    lines = {line.split()[0]: line for line in listed.splitlines() if line.strip()}
    for b in baselines():
        assert b.name in lines, listed
        assert "not trained" not in lines[b.name] and "steps" in lines[b.name], lines[b.name]

    # a Minari dataset from the installed package, opened by a plain script with minari alone
    pytest.importorskip("minari", reason="the dataset extra")
    out = _run(
        [python, script, "collect", "redundancy_gym/PlanarReach-v0", "--episodes", "1", "--out", "ds", "--no-progress"],
        cwd=tmp_path,
        env=env,
        timeout=300,
    )
    assert "redundancy_gym/PlanarReach/clik-v0" in out
    probe = (
        "import os, minari, redundancy_gym; os.environ['MINARI_DATASETS_PATH'] = 'ds'; "
        "d = minari.load_dataset('redundancy_gym/PlanarReach/clik-v0'); e = d.recover_environment(); "
        "print(d.total_steps, e.spec.id, d.storage.metadata['policy'])"
    )
    assert _run([python, "-c", probe], cwd=tmp_path, env=env, timeout=120).split()[-3:] == [
        "250",
        "redundancy_gym/PlanarReach-v0",
        "clik",
    ]


# the README's quick start for 120 steps: numba's compile time in the process, and a hash of the trajectory
EPISODE = """
import hashlib, json, time
start = time.perf_counter()
import gymnasium as gym, numpy as np, redundancy_gym
from redundancy_gym.eval.compile_clock import COMPILE_CLOCK
from redundancy_gym.kernel_pack import seeding_state
COMPILE_CLOCK.install()
env = gym.make("redundancy_gym/PlanarReach-v0")
policy = redundancy_gym.make_policy("clik", env)
obs, _ = env.reset(seed=11)
digest = hashlib.sha256()
for _ in range(120):
    action, _ = policy.predict(obs, deterministic=True)
    obs, reward, terminated, truncated, _ = env.step(action)
    digest.update(obs.tobytes() + action.tobytes() + np.float64(reward).tobytes())
    if terminated or truncated:
        break
state = seeding_state()
print("EPISODE " + json.dumps({"compiling_s": COMPILE_CLOCK.compiling_seconds, "sha256": digest.hexdigest(),
      "seconds": time.perf_counter() - start, "pack": str(state.pack), "reason": state.reason,
      "file": redundancy_gym.__file__}))
"""


def _episode(cwd: Path, env: dict[str, str]) -> dict[str, Any]:
    out = _run([sys.executable, "-c", EPISODE], cwd=cwd, env=env, timeout=900)
    line = next(x for x in out.splitlines() if x.startswith("EPISODE "))
    result: dict[str, Any] = json.loads(line[len("EPISODE ") :])
    return result


@pytest.mark.timeout(1500)
def test_a_fresh_process_of_the_installed_wheel_loads_its_packed_kernels_and_runs_bit_for_bit(
    installed: tuple[Path, dict[str, str]], tmp_path: Path
) -> None:
    """With an empty numba cache, the installed package copies the wheel's x86-64-v3 kernels into it and compiles
    nothing; the episode is the one kernels compiled for this host give."""
    target, env = installed
    magic = host_magic_tuple()
    if missing_pack_features(magic[2]):
        pytest.skip(f"this CPU ({magic[1]}) is not x86-64-v3: the pack is refused")
    seeded = _episode(tmp_path, {**env, "NUMBA_CACHE_DIR": str(tmp_path / "empty")})
    assert Path(seeded["file"]).resolve().is_relative_to(target.resolve())
    assert seeded["pack"] == str(target / "redundancy_gym" / "packed_kernels" / pack_tag()), seeded["reason"]
    assert seeded["compiling_s"] == 0.0, seeded  # every kernel loaded from the copied entries
    assert list((tmp_path / "empty").rglob("*.nbi"))

    # the pack switched off: the same process compiles for this host, to the same episode bit for bit
    off = _episode(tmp_path, {**env, "NUMBA_CACHE_DIR": str(tmp_path / "cold"), "REDUNDANCY_GYM_KERNEL_PACK": "none"})
    assert off["pack"] == "None" and off["compiling_s"] > 0 and off["sha256"] == seeded["sha256"]
