"""Training and rendering in one process, in every import order and on every OpenGL backend (subprocesses: a
segmentation fault must fail the test, not the test run)."""

from __future__ import annotations

import ctypes.util
import importlib.machinery
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from redundancy_gym.rendering_backend import (
    RenderBackendError,
    gpu_driver_present,
    require_render_backend,
    select_backend,
)

HAS_OSMESA = ctypes.util.find_library("OSMesa") is not None
HAS_EGL = ctypes.util.find_library("EGL") is not None
# on the path, whatever the package's guard put in sys.modules
HAS_TRITON = importlib.machinery.PathFinder.find_spec("triton") is not None

_IMPORTS = {
    "package_first": "import redundancy_gym\nfrom stable_baselines3 import PPO\n",
    "sb3_first": "from stable_baselines3 import PPO\nimport redundancy_gym\n",
    # MuJoCo imported by the user before the package: under osmesa Mesa is mapped before triton can be
    "mujoco_first": "import mujoco\nfrom stable_baselines3 import PPO\nimport redundancy_gym\n",
}

_TRAIN = """
import gymnasium as gym
env = gym.make("redundancy_gym/PlanarReach-v0")
PPO("MlpPolicy", env, n_steps=128, batch_size=64, device="cpu", seed=0).learn(256)
print("trained")
"""

_RENDER = """
import numpy as np
env = gym.make("redundancy_gym/PlanarReach-v0", render_mode="rgb_array", width=64, height=48)
env.reset(seed=0)
frame = env.render()
assert frame.shape == (48, 64, 3) and frame.std() > 0, frame.shape
env.close()
print("rendered")
"""


def _run(code: str, gl: str | None, timeout: float = 240.0) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM", "DISPLAY")}
    if gl is not None:
        env["MUJOCO_GL"] = gl
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)], env=env, capture_output=True, text=True, timeout=timeout
    )


def _backends() -> list[str | None]:
    return [None] + (["osmesa"] if HAS_OSMESA else []) + (["egl"] if HAS_EGL else [])


@pytest.mark.timeout(600)
@pytest.mark.parametrize("gl", _backends())
@pytest.mark.parametrize("order", sorted(_IMPORTS))
def test_ppo_learns_in_any_import_order_and_backend(order: str, gl: str | None) -> None:
    result = _run(_IMPORTS[order] + _TRAIN, gl)
    assert result.returncode == 0, (result.returncode, result.stderr[-2000:])
    assert "trained" in result.stdout


@pytest.mark.timeout(600)
@pytest.mark.parametrize("gl", _backends())
def test_render_then_train_in_one_process(gl: str | None) -> None:
    """A frame rendered (Mesa mapped) before the first optimizer is built (triton imported)."""
    result = _run("import redundancy_gym, gymnasium as gym\nfrom stable_baselines3 import PPO\n" + _RENDER + _TRAIN, gl)
    assert result.returncode == 0, (result.returncode, result.stderr[-2000:])
    assert "rendered" in result.stdout and "trained" in result.stdout


# the package's own import has run guard_triton already; undo its choice, then guard as a GPU machine would
_GUARD_AS = """
import sys
import redundancy_gym.rendering_backend as rb
sys.modules.pop("triton", None)
{setup}print("guard:", rb.guard_triton(gpu={gpu}))
"""


@pytest.mark.timeout(600)
@pytest.mark.skipif(not HAS_TRITON, reason="triton is not installed (it comes with torch on Linux x86-64)")
@pytest.mark.parametrize("gl", _backends())
def test_on_a_gpu_machine_triton_is_imported_before_mesa_and_both_work(gl: str | None) -> None:
    imports = "import gymnasium as gym\nfrom stable_baselines3 import PPO\n"
    result = _run(_GUARD_AS.format(gpu=True, setup="") + imports + _RENDER + _TRAIN, gl)
    assert result.returncode == 0, (result.returncode, result.stderr[-2000:])
    assert "guard: imported" in result.stdout and "rendered" in result.stdout and "trained" in result.stdout


@pytest.mark.skipif(not HAS_TRITON, reason="triton is not installed (it comes with torch on Linux x86-64)")
@pytest.mark.parametrize(("interpret", "expected"), [(None, "unused"), ("1", "imported")])
def test_without_a_gpu_driver_triton_is_not_imported(interpret: str | None, expected: str) -> None:
    setup = "" if interpret is None else f"import os\nos.environ['TRITON_INTERPRET'] = {interpret!r}\n"
    probe = """
try:
    import triton
    print("triton importable")
except ImportError:
    print("triton unavailable")
"""
    result = _run(_GUARD_AS.format(gpu=False, setup=setup) + probe, None)
    assert result.returncode == 0, result.stderr[-2000:]
    assert f"guard: {expected}" in result.stdout
    assert ("triton unavailable" if expected == "unused" else "triton importable") in result.stdout


def test_gpu_driver_present_looks_for_a_driver_device_node(tmp_path: Path) -> None:
    if sys.platform != "linux":
        pytest.skip("device nodes are looked for on Linux only")
    node = tmp_path / "nvidiactl"
    assert not gpu_driver_present((node,))
    node.touch()
    assert gpu_driver_present((tmp_path / "kfd", node))


@pytest.mark.skipif(not (HAS_OSMESA or HAS_EGL), reason="no headless OpenGL library on this machine")
def test_rgb_array_renders_without_mujoco_gl_and_without_display() -> None:
    result = _run("import redundancy_gym, gymnasium as gym, os\n" + _RENDER + "print(os.environ['MUJOCO_GL'])\n", None)
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.split()[-1] in ("osmesa", "egl")
    assert "DISPLAY" not in result.stderr  # GLFW is never tried on a machine without a display


def _libs(*present: str):
    return lambda name: f"lib{name}.so" if name in present else None


def test_select_backend_headless_choices() -> None:
    headless: dict[str, str] = {}
    if sys.platform != "linux":
        pytest.skip("the headless choice is made on Linux only")
    assert select_backend(headless, _libs("OSMesa", "EGL"), nvidia_egl=False) == "osmesa"
    assert select_backend(headless, _libs("OSMesa", "EGL"), nvidia_egl=True) == "egl"
    assert select_backend(headless, _libs("EGL"), nvidia_egl=False) == "egl"
    assert select_backend(headless, _libs(), nvidia_egl=False) == "none"
    assert select_backend({"DISPLAY": ":0"}, _libs(), nvidia_egl=False) is None  # GLFW, MuJoCo's default
    assert select_backend({"MUJOCO_GL": "EGL "}, _libs(), nvidia_egl=False) == "egl"  # explicit wins


def test_missing_library_raises_one_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    with pytest.raises(RenderBackendError, match="libosmesa6"):
        require_render_backend(_libs("EGL"))
    monkeypatch.setenv("MUJOCO_GL", "egl")
    with pytest.raises(RenderBackendError, match="libegl1"):
        require_render_backend(_libs("OSMesa"))
    monkeypatch.setenv("MUJOCO_GL", "disable")
    monkeypatch.delenv("DISPLAY", raising=False)
    if sys.platform == "linux":
        with pytest.raises(RenderBackendError, match="libosmesa6"):
            require_render_backend(_libs())
    monkeypatch.setenv("MUJOCO_GL", "osmesa")
    assert require_render_backend(_libs("OSMesa")) == "osmesa"


@pytest.mark.skipif(sys.platform != "linux", reason="headless detection is for Linux")
def test_human_mode_without_display_is_a_clear_error_and_not_listed() -> None:
    """GLFW aborts the process without a display, so check_env (which renders every listed mode) and
    render_mode="human" must not reach it."""
    code = """
import gymnasium as gym, redundancy_gym
from gymnasium.utils.env_checker import check_env
from redundancy_gym.envs import EnvConfigError
from redundancy_gym.rendering_backend import RenderBackendError
for env_id in redundancy_gym.ENV_IDS:
    env = gym.make(env_id)
    assert "human" not in env.metadata["render_modes"], env.metadata
    check_env(env.unwrapped)
    if env_id.endswith("AgriReach-v0"):
        continue  # offscreen only: gym.make serves "human" itself through its HumanRendering wrapper (pygame)
    try:
        gym.make(env_id, render_mode="human")
    except (RenderBackendError, EnvConfigError) as exc:  # a wrapped AgriReach id: the env names its modes
        assert "rgb_array" in str(exc)
    else:
        raise AssertionError("render_mode='human' without a display was accepted")
print("checked")
"""
    result = _run(code, None)
    assert result.returncode == 0, (result.returncode, result.stderr[-2000:])
    assert "checked" in result.stdout
