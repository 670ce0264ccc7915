"""redundancy_gym: Gymnasium environments on MuJoCo for redundant robots, with the model-based controllers of
"Dynamics and Control of Redundant Robots" as reference policies.

Importing the package registers the env ids (see :data:`ENV_IDS`) with gymnasium; the simulator, pinocchio and
the controllers load only when used. It also picks a headless OpenGL backend where the machine has no display and
keeps torch's triton safe from Mesa's LLVM (:mod:`redundancy_gym.rendering_backend`), before MuJoCo is imported:
scripts that train and render work in any import order.
"""

from __future__ import annotations

from typing import Any

from . import _moved
from .rendering_backend import configure_rendering, guard_triton

configure_rendering()
guard_triton()
_moved.install()

from .registration import ENV_IDS, register_envs  # noqa: E402

__all__ = ["ENV_IDS", "__version__", "make_policy", "register_envs"]

__version__ = "0.1.0"

register_envs()


def make_policy(name: str, env: Any, **kwargs: Any) -> Any:
    """Build a policy for ``env`` by name (``clik``, ``zero``, ``random``) or from a stable-baselines3 ``.zip``.

    See :func:`redundancy_gym.policies.make_policy`.
    """
    from .policies import make_policy as _make_policy

    return _make_policy(name, env, **kwargs)
