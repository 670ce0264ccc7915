"""The learned baselines shipped with the package (``redundancy_gym/baselines/models/<learner>-<action>-<env>.zip``,
``baselines/models/`` of a clone), by short name: ``make_policy("ppo-nullspace", env)`` loads
``ppo-nullspace-planar_reach.zip`` on a PlanarReach env. A model trained another way carries a variant
(:data:`VARIANTS`) at the end of both names: ``ppo-nullspace-dynamics`` loads
``ppo-nullspace-agri_reach-dynamics.zip``."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

from .exceptions import PolicyError

__all__ = [
    "ACTIONS",
    "LEARNERS",
    "SHIPPED_MODELS_DIR",
    "VARIANTS",
    "model_name",
    "env_slug",
    "is_shipped_name",
    "shipped_model_path",
    "shipped_models",
]

# Package data, beside the code: the same folder in a wheel's install, an editable install and a clone (whose
# top-level baselines/ is a symlink to redundancy_gym/baselines/), so one copy serves all three.
SHIPPED_MODELS_DIR = Path(__file__).resolve().parents[1] / "baselines" / "models"
"""Where the trained baselines live: ``redundancy_gym/baselines/models/``, installed with the package
(``make baselines`` writes it in a clone)."""
LEARNERS: tuple[str, ...] = ("ppo", "sac", "bc")
"""The learners of the shipped models."""
ACTIONS: tuple[str, ...] = ("joint", "nullspace", "task_space", "residual", "walking_command")
"""Their action spaces: the raw joint action, or the action wrapper's."""
VARIANTS: tuple[str, ...] = ("dynamics",)
"""How a model may differ from its nominal twin: ``dynamics``, trained under the env's dynamics randomization (its
YAML's ``env_kwargs`` say how much)."""
_NAME = re.compile(rf"({'|'.join(LEARNERS)})-({'|'.join(ACTIONS)})(?:-({'|'.join(VARIANTS)}))?")


def is_shipped_name(name: Any) -> bool:
    """Whether ``name`` has the form ``<learner>-<action>[-<variant>]`` of a shipped model."""
    return isinstance(name, str) and _NAME.fullmatch(name) is not None


def model_name(stem: str) -> tuple[str, str, str, str | None]:
    """``(learner, action, env slug, variant or None)`` of a model's file stem
    (``ppo-nullspace-agri_reach-dynamics``); ValueError for a stem not laid out so."""
    parts = stem.split("-")
    if len(parts) not in (3, 4) or parts[0] not in LEARNERS or parts[1] not in ACTIONS or not parts[2]:
        raise ValueError(f"{stem!r} is no <learner>-<action>-<env>[-<variant>] model name")
    if len(parts) == 4 and parts[3] not in VARIANTS:
        raise ValueError(f"{stem!r}: unknown variant {parts[3]!r}; valid: {', '.join(VARIANTS)}")
    return parts[0], parts[1], parts[2], parts[3] if len(parts) == 4 else None


def env_slug(env: Any) -> str:
    """The env's name in model file names: its base class name without ``Env``, in snake case
    (``PlanarReachEnv`` -> ``planar_reach``)."""
    name = type(getattr(env, "unwrapped", env)).__name__.removesuffix("Env")
    return re.sub(r"(?<!^)(?=[A-Z])", "_", name).lower()


def shipped_models() -> tuple[str, ...]:
    """The file stems of the shipped models (``ppo-nullspace-planar_reach``, ...)."""
    if not SHIPPED_MODELS_DIR.is_dir():
        return ()
    return tuple(sorted(p.stem for p in SHIPPED_MODELS_DIR.glob("*.zip")))


def _check_action_space(name: str, env: Any) -> None:
    """A model acts in its action space: a wrapper's model runs on that wrapper's env id, a joint model on the raw
    env (the network's output means something else elsewhere, even where the shapes agree)."""
    from ..registration import BASE_ENV_IDS, WRAPPED_ENV_IDS, wrapped_env_id

    spec = getattr(env, "spec", None)
    env_id = getattr(spec, "id", None)
    if env_id not in BASE_ENV_IDS and env_id not in WRAPPED_ENV_IDS:
        return  # an env built outside the registry: nothing to compare against
    action = name.split("-")[1]
    base = next((b for b in BASE_ENV_IDS if b == env_id or env_id in (wrapped_env_id(b, a) for a in ACTIONS)), env_id)
    expected = base if action == "joint" else wrapped_env_id(base, action)
    if expected is not None and env_id != expected:
        where = "the raw env" if action == "joint" else f"--wrapper {action}"
        raise PolicyError(
            f"{name} acts in the {action} action space: evaluate it on {expected} ({where}), not on {env_id}"
        )


def shipped_model_path(name: str, env: Any) -> Path:
    """The ``.zip`` of the shipped model ``name`` (``<learner>-<action>``) for ``env``.

    Raises:
        PolicyError: no such model for this env (the message lists the shipped ones), or an env in another action
            space than the model's (a wrapper's model on the raw env, a joint model in a wrapper).
    """
    match = _NAME.fullmatch(name)
    learner, action, variant = match.groups() if match is not None else (name, "", None)
    path = SHIPPED_MODELS_DIR / f"{learner}-{action}-{env_slug(env)}{'' if variant is None else '-' + variant}.zip"
    if path.is_file():
        _check_action_space(name, env)
        return path
    available = (
        ", ".join(shipped_models())
        or f"none ({SHIPPED_MODELS_DIR} is empty or absent: the models ship "
        "with the package; `make baselines` trains them in a clone)"
    )
    raise PolicyError(
        f"no shipped model {name!r} for {type(getattr(env, 'unwrapped', env)).__name__} "
        f"({path.name}); shipped: {available}"
    )
