"""redundancy_gym: Gymnasium environments on MuJoCo for redundant robots, with the model-based controllers of
"Dynamics and Control of Redundant Robots" as reference policies.

Importing the package registers the env ids (see :data:`ENV_IDS`) with gymnasium; the simulator, pinocchio and
the controllers load only when used.
"""

from __future__ import annotations

from typing import Any

from .registration import ENV_IDS, register_envs

__all__ = ["ENV_IDS", "__version__", "make_policy", "register_envs"]

__version__ = "0.1.0"

register_envs()


def make_policy(name: str, env: Any, **kwargs: Any) -> Any:
    """Build a policy for ``env`` by name (``clik``, ``zero``, ``random``) or from a stable-baselines3 ``.zip``.

    See :func:`redundancy_gym.controllers.policies.make_policy`.
    """
    from .controllers.policies import make_policy as _make_policy

    return _make_policy(name, env, **kwargs)
