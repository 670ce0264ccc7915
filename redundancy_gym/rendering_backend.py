"""The OpenGL backend MuJoCo renders with, chosen before anything loads it, and torch's triton kept safe from Mesa.

Two facts of a headless Linux machine shape this module:

- MuJoCo and dm_control read ``MUJOCO_GL`` once, when they are imported. Unset on a machine without a display,
  MuJoCo falls back to GLFW, which cannot open a window: ``render_mode="rgb_array"`` then fails with
  ``an OpenGL platform library has not been loaded``. :func:`configure_rendering` therefore picks a headless
  backend that is installed (EGL on an NVIDIA driver, else OSMesa, else Mesa's EGL) before MuJoCo is imported,
  and leaves an explicit ``MUJOCO_GL`` or a machine with a display alone.
- Mesa's software renderer (``libOSMesa``, and EGL/GLX without a GPU driver) links its own LLVM. torch imports
  triton lazily, when the first optimizer is built; triton brings a second LLVM, and if Mesa's was mapped first
  the process dies with a segmentation fault. Loaded the other way round both live side by side (tested by
  ``tests/test_rendering_backend.py`` in subprocesses, every import order, every backend). :func:`guard_triton`
  imports triton first when it is installed and a GPU driver is present (about 0.15 s) and, where Mesa is already
  mapped (someone imported MuJoCo under ``MUJOCO_GL=osmesa`` before this package) or no GPU driver is (triton
  compiles GPU kernels only, so it could run nothing), marks triton unavailable instead: torch then takes its
  no-triton path, which is all a CPU agent uses.

``import redundancy_gym`` calls both, so a user's script needs no helper and no import order.
"""

from __future__ import annotations

import ctypes.util
import importlib.util
import os
import platform
import sys
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

__all__ = [
    "HEADLESS_BACKENDS",
    "RenderBackendError",
    "can_open_window",
    "configure_rendering",
    "gpu_driver_present",
    "guard_triton",
    "mesa_loaded",
    "require_render_backend",
    "require_window",
    "select_backend",
]

HEADLESS_BACKENDS: tuple[str, ...] = ("egl", "osmesa")
"""The ``MUJOCO_GL`` values that render without a display."""

_INSTALL_HINT = (
    "install a headless OpenGL library: 'apt-get install libosmesa6' (Debian/Ubuntu; then "
    "MUJOCO_GL=osmesa) or 'apt-get install libegl1 libegl-mesa0' (MUJOCO_GL=egl), or run with a display"
)
_NVIDIA_EGL_VENDORS = (
    Path("/usr/share/glvnd/egl_vendor.d/10_nvidia.json"),
    Path("/etc/glvnd/egl_vendor.d/10_nvidia.json"),
)
_DISABLED = ("disable", "disabled", "off", "false", "0")
_MESA_MAPPINGS = ("libOSMesa", "libLLVM", "swrast_dri", "libgallium", "llvmpipe")
# the device nodes of the GPU drivers triton compiles for: NVIDIA, AMD's ROCm, and WSL's GPU paravirtualization
_GPU_DRIVER_NODES = tuple(
    Path(node) for node in ("/dev/nvidiactl", "/dev/nvidia0", "/proc/driver/nvidia", "/dev/kfd", "/dev/dxg")
)


class RenderBackendError(RuntimeError):
    """No OpenGL backend can render here; the message names what to install."""


def _has_display(environ: Mapping[str, str]) -> bool:
    return bool(environ.get("DISPLAY") or environ.get("WAYLAND_DISPLAY"))


def select_backend(
    environ: Mapping[str, str] | None = None,
    find_library: Callable[[str], str | None] = ctypes.util.find_library,
    nvidia_egl: bool | None = None,
) -> str | None:
    """The ``MUJOCO_GL`` value to render with, or ``None`` where MuJoCo's own default (GLFW) is right.

    An explicit ``MUJOCO_GL`` wins. On Linux without ``DISPLAY``/``WAYLAND_DISPLAY``: ``"egl"`` on an NVIDIA EGL
    driver, else ``"osmesa"`` when ``libOSMesa`` is installed, else ``"egl"`` when ``libEGL`` is, else
    ``"none"`` (nothing can render; :func:`require_render_backend` raises). Other systems: ``None``.

    Args:
        environ: the environment to read (default ``os.environ``).
        find_library: how a shared library is found (``ctypes.util.find_library``; injectable for tests).
        nvidia_egl: whether an NVIDIA EGL vendor is installed (default: look for its glvnd file).
    """
    environ = os.environ if environ is None else environ
    explicit = environ.get("MUJOCO_GL", "").strip().lower()
    if explicit:
        return explicit
    if platform.system() != "Linux" or _has_display(environ):
        return None
    if nvidia_egl is None:
        nvidia_egl = any(path.is_file() for path in _NVIDIA_EGL_VENDORS)
    has_egl = find_library("EGL") is not None
    if nvidia_egl and has_egl:
        return "egl"
    if find_library("OSMesa") is not None:
        return "osmesa"
    if has_egl:
        return "egl"
    return "none"


def configure_rendering() -> str | None:
    """Set ``MUJOCO_GL`` to :func:`select_backend`'s choice where it is unset and the machine has no display.

    Returns the backend in force (``None``: MuJoCo's default). Where nothing can render (``"none"``),
    ``MUJOCO_GL=disable`` keeps MuJoCo from trying a window, and a render request raises
    :class:`RenderBackendError` naming what to install.
    """
    backend = select_backend()
    if not os.environ.get("MUJOCO_GL"):
        if backend in HEADLESS_BACKENDS:
            os.environ["MUJOCO_GL"] = backend
        elif backend == "none":
            # nothing can render: keep MuJoCo and dm_control from trying GLFW (and printing a DISPLAY error)
            os.environ["MUJOCO_GL"] = "disable"
    return backend


def require_render_backend(find_library: Callable[[str], str | None] = ctypes.util.find_library) -> str | None:
    """Check that the configured backend can render; raise :class:`RenderBackendError` naming the fix otherwise.

    Called when an env is made with a ``render_mode``, so the error comes at ``gym.make``, not deep inside
    PyOpenGL (``'NoneType' object has no attribute 'glGetError'`` when libOSMesa is missing).
    """
    backend = select_backend()
    if backend == "none":
        raise RenderBackendError(f"no display and no headless OpenGL library found; {_INSTALL_HINT}")
    if backend in _DISABLED:
        hint = (
            f"no display and no headless OpenGL library found; {_INSTALL_HINT}"
            if not _has_display(os.environ) and select_backend({}, find_library) == "none"
            else f"MUJOCO_GL={backend} disables rendering; unset it or set MUJOCO_GL=egl or osmesa"
        )
        raise RenderBackendError(hint)
    if backend == "osmesa" and find_library("OSMesa") is None:
        raise RenderBackendError(f"MUJOCO_GL=osmesa but libOSMesa is not installed; {_INSTALL_HINT}")
    if backend == "egl" and find_library("EGL") is None:
        raise RenderBackendError(f"MUJOCO_GL=egl but libEGL is not installed; {_INSTALL_HINT}")
    return backend


def can_open_window(environ: Mapping[str, str] | None = None) -> bool:
    """Whether ``render_mode="human"`` can open a window: a display on Linux; assumed elsewhere."""
    return platform.system() != "Linux" or _has_display(os.environ if environ is None else environ)


def require_window() -> None:
    """Raise :class:`RenderBackendError` where ``render_mode="human"`` cannot open a window.

    Without a display GLFW does not fail with a Python error: it aborts the process (``glfwGetVideoMode:
    Assertion 'monitor != NULL' failed``), so the check must come first.
    """
    if not can_open_window():
        raise RenderBackendError(
            "render_mode='human' opens a window and needs a display (DISPLAY or "
            "WAYLAND_DISPLAY); on a machine without one use render_mode='rgb_array'"
        )


def mesa_loaded() -> bool:
    """Whether Mesa's software renderer (and with it Mesa's LLVM) is mapped into this process (Linux only)."""
    try:
        maps = Path("/proc/self/maps").read_text()
    except OSError:
        return False
    return any(name in maps for name in _MESA_MAPPINGS)


def gpu_driver_present(nodes: Sequence[Path] = _GPU_DRIVER_NODES) -> bool:
    """Whether a GPU driver that triton can compile for is installed (Linux: its device node; elsewhere assumed).

    Args:
        nodes: the device nodes to look for (injectable for tests).
    """
    if platform.system() != "Linux":
        return True
    return any(node.exists() for node in nodes)


def guard_triton(gpu: bool | None = None) -> str:
    """Keep torch's triton from loading its LLVM after Mesa's; returns what was done.

    ``"absent"``: triton is not installed; ``"loaded"``: it was imported already (first, so safe);
    ``"imported"``: imported now, before any Mesa library; ``"blocked"``: Mesa was mapped first, so triton is
    marked unavailable (``import triton`` raises ImportError and torch runs without it); ``"unused"``: no GPU
    driver is present, so triton, which compiles GPU kernels only, is marked unavailable the same way instead of
    being imported (that import was about 0.15 s of every ``import redundancy_gym`` on a CPU machine). Set
    ``TRITON_INTERPRET=1`` (triton's CPU interpreter) to have it imported all the same.

    Args:
        gpu: whether a GPU driver is present (default: :func:`gpu_driver_present`).
    """
    if sys.modules.get("triton", False) is None:
        return "blocked"
    if "triton" in sys.modules:
        return "loaded"
    if importlib.util.find_spec("triton") is None:
        return "absent"
    if mesa_loaded():
        sys.modules["triton"] = None  # type: ignore[assignment]  # import raises ImportError from now on
        return "blocked"
    if not (gpu_driver_present() if gpu is None else gpu) and os.environ.get("TRITON_INTERPRET", "") in ("", "0"):
        sys.modules["triton"] = None  # type: ignore[assignment]
        return "unused"
    try:
        import triton  # noqa: F401
    except Exception:  # a broken triton install must not break the package; torch copes without it
        sys.modules["triton"] = None  # type: ignore[assignment]
        return "blocked"
    return "imported"
