"""One table of the policies and action wrappers that join controllers and envs, read by :func:`make_policy`,
:func:`~redundancy_gym.wrappers.make_wrapper`, the wrapped env ids, ``redundancy-gym list`` and the error for an
unsupported env.

An env says what it offers by a class attribute ``CAPABILITIES`` (a frozenset of the names in
:data:`CAPABILITY_ATTRIBUTES`); each policy or wrapper registers (in the manner of ``gymnasium.register``) its
name, one implementation per set of capabilities it supports (an entry point ``"module:Class"`` and its options
dataclass, both imported only when used) and a summary. Two capabilities come from the outermost action space
instead of the class: ``box_action`` (a ``Box``) and ``bounded_action`` (with finite bounds). An action wrapper of
this package declares ``CAPABILITIES`` itself (none of the env's: its action is no longer the env's joint
command), so a reference policy is not offered on a wrapped env whose action it would misread.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from .exceptions import PolicyError
from .options import env_name
from .per_env_policy import Policy
from .shipped_models import is_shipped_name, shipped_model_path

__all__ = [
    "CAPABILITY_ATTRIBUTES",
    "GENERIC_POLICIES",
    "KINDS",
    "POLICY_NAMES",
    "WRAPPER_NAMES",
    "Implementation",
    "RegistryEntry",
    "action_wrapper",
    "build",
    "capability_problems",
    "env_capabilities",
    "lookup",
    "make_policy",
    "missing_capabilities",
    "policy_supports",
    "reference_policy",
    "register",
    "registered",
    "supported_env_ids",
    "supported_names",
    "supported_policies",
    "unsupported_error",
]

KINDS: tuple[str, ...] = ("policy", "wrapper")


GENERIC_POLICIES: tuple[str, ...] = ("zero", "random")
"""The registered policies that are no analytic reference: every env takes them and they run no kernel of their
own (``warmup`` and ``bench startup`` skip them)."""


def reference_policy(env_id: str) -> str:
    """The analytic reference of an env id by name: ``walking`` on the bipeds, ``clik`` on the arms (what behaviour
    cloning clones and ``collect`` records when no policy is named)."""
    return "walking" if "Biped" in env_id else "clik"


CAPABILITY_ATTRIBUTES: dict[str, tuple[str, ...]] = {
    # a joint-velocity arm whose TCP follows a path given in the observation (PlanarReach)
    "tcp_tracking": ("OBSERVATION_LAYOUT", "ROBOT_XML", "TCP_FRAME", "TASK_AXES", "max_joint_speed"),
    # the path of a tcp_tracking task as a function of time, and the control period (predictive IK plans on it)
    "tcp_reference": ("reference", "dt"),
    # a joint-velocity arm that reaches a grasp pose among observed obstacles (AgriReach)
    "grasp_task": ("observation_layout", "ROBOT_XML", "TCP_FRAME", "max_joint_speeds", "dt"),
    # a position-controlled floating-base biped with ankle wrench sensors and a speed command (BipedWalk)
    "biped": (
        "OBSERVATION_LAYOUT",
        "ROBOT_XML",
        "SOFT_LIMIT_MARGIN",
        "joint_limits",
        "nominal_configuration",
        "action_scale",
        "dt",
    ),
    # from the outermost action space
    "box_action": (),
    "bounded_action": (),
}
"""Every capability an env may declare, with the attributes of the unwrapped env it promises."""

_LAYOUT_KEYS: dict[str, tuple[str, str, tuple[str, ...]]] = {
    "tcp_tracking": ("OBSERVATION_LAYOUT", "layout", ("q", "tcp_ref", "tcp_ref_vel")),
    "grasp_task": ("observation_layout", "layout", ("q", "grasp_position")),
    "biped": (
        "OBSERVATION_LAYOUT",
        "layout",
        ("base_position", "q", "base_linear_velocity", "qdot", "right_force", "left_torque", "command"),
    ),
}


def _load(reference: str) -> Any:
    """The object named by ``"module:attribute"``."""
    module, _, name = reference.partition(":")
    return getattr(importlib.import_module(module), name)


@dataclass(frozen=True)
class Implementation:
    """How a registered name is built on envs with the given capabilities.

    Attributes:
        capabilities: what the env must offer (all of them).
        entry_point: ``"module:Class"``, called as ``Class(env, **fixed, **options)``.
        options: ``"module:Dataclass"`` of the options (its fields are the valid keyword arguments), or None for
            a class without options.
        fixed: arguments the name itself fixes (``mode="global"``).
    """

    capabilities: frozenset[str]
    entry_point: str
    options: str | None = None
    fixed: Mapping[str, Any] = field(default_factory=dict)

    def load(self) -> Callable[..., Any]:
        """The class (imported now)."""
        return _load(self.entry_point)

    def option_names(self) -> tuple[str, ...]:
        """The names of the options (imports the options dataclass)."""
        return () if self.options is None else tuple(f.name for f in fields(_load(self.options)))


@dataclass(frozen=True)
class RegistryEntry:
    """A registered policy or wrapper: its name, kind, implementations (the first whose capabilities the env has
    is used) and a one-line summary."""

    name: str
    kind: str
    implementations: tuple[Implementation, ...]
    summary: str

    def implementation_for(self, capabilities: frozenset[str]) -> Implementation | None:
        """The first implementation whose capabilities are all in ``capabilities``."""
        return next((i for i in self.implementations if i.capabilities <= capabilities), None)

    @property
    def supports(self) -> str:
        """The capability sets it supports, for messages: ``"tcp_tracking or grasp_task"``."""
        return " or ".join("+".join(sorted(i.capabilities)) for i in self.implementations)


_REGISTRY: dict[str, RegistryEntry] = {}


def register(name: str, kind: str, implementations: Iterable[Implementation], summary: str) -> None:
    """Register a policy or wrapper ``name`` (a new name, or a replacement of a registered one).

    Raises:
        PolicyError: a kind other than :data:`KINDS`, no implementation, or a capability not in
            :data:`CAPABILITY_ATTRIBUTES`.
    """
    if kind not in KINDS:
        raise PolicyError(f"kind must be one of {', '.join(KINDS)}, got {kind!r}")
    implementations = tuple(implementations)
    if not implementations:
        raise PolicyError(f"{kind} {name!r} needs at least one implementation")
    for impl in implementations:
        unknown = sorted(impl.capabilities - set(CAPABILITY_ATTRIBUTES))
        if unknown:
            raise PolicyError(
                f"unknown capability {', '.join(unknown)} of {kind} {name!r}; valid: {', '.join(CAPABILITY_ATTRIBUTES)}"
            )
    _REGISTRY[name] = RegistryEntry(name, kind, implementations, summary)


def registered(kind: str) -> tuple[RegistryEntry, ...]:
    """The registered entries of one kind, in registration order."""
    return tuple(e for e in _REGISTRY.values() if e.kind == kind)


def lookup(name: Any, kind: str, error: type[Exception] = PolicyError) -> RegistryEntry:
    """The entry ``name`` of ``kind``, or ``error`` naming the registered ones."""
    entry = _REGISTRY.get(name) if isinstance(name, str) else None
    if entry is None or entry.kind != kind:
        names = ", ".join(e.name for e in registered(kind))
        extra = " or the path of an SB3 .zip" if kind == "policy" else ""
        raise error(f"unknown {kind} {name!r}; valid: {names}{extra}")
    return entry


def action_wrapper(env: Any) -> Any:
    """The outermost wrapper in ``env``'s chain whose own class hierarchy declares ``CAPABILITIES`` (an action
    wrapper of this package; a plain ``gym.Wrapper`` only forwards the env's), or None."""
    current, seen = env, 0
    while current is not None and seen < 64:
        if (
            any("CAPABILITIES" in vars(cls) for cls in type(current).__mro__)
            and hasattr(current, "env")
            and current is not getattr(current, "unwrapped", current)
        ):
            return current
        nxt = getattr(current, "env", None)
        current, seen = (nxt if nxt is not current else None), seen + 1
    return None


def _declared(env: Any) -> frozenset[str]:
    """``CAPABILITIES`` of the outermost object of the wrapper chain that declares them."""
    current, seen = env, 0
    while current is not None and seen < 64:
        declared = getattr(type(current), "CAPABILITIES", None)
        if declared is not None:
            return frozenset(declared)
        nxt = getattr(current, "env", None)
        current, seen = (nxt if nxt is not current else None), seen + 1
    return frozenset()


def env_capabilities(env: Any) -> frozenset[str]:
    """What ``env`` (wrapped or not) offers: the declared ``CAPABILITIES`` and those of its action space."""
    capabilities = set(_declared(env))
    space = getattr(env, "action_space", None)
    low, high = getattr(space, "low", None), getattr(space, "high", None)
    if low is not None and high is not None and getattr(space, "shape", None) is not None:
        capabilities.add("box_action")
        if np.all(np.isfinite(low)) and np.all(np.isfinite(high)):
            capabilities.add("bounded_action")
    return frozenset(capabilities)


def capability_problems(env: Any, capabilities: Iterable[str]) -> list[str]:
    """What the unwrapped ``env`` lacks of the attributes (and observation entries) the ``capabilities`` promise."""
    base = getattr(env, "unwrapped", env)
    problems = []
    for capability in capabilities:
        problems += [a for a in CAPABILITY_ATTRIBUTES[capability] if not hasattr(base, a)]
        if capability in _LAYOUT_KEYS:
            attribute, _, keys = _LAYOUT_KEYS[capability]
            layout = getattr(base, attribute, None)
            if isinstance(layout, Mapping):
                absent = [k for k in keys if k not in layout]
                if absent:
                    problems.append(f"{attribute} entries {', '.join(absent)}")
    return problems


def missing_capabilities(name: str, env: Any, kind: str = "policy") -> list[str]:
    """What ``env`` lacks for the policy or wrapper ``name`` (empty when it is supported), without building it.

    Args:
        name: a registered name or, for a policy, the path of an SB3 ``.zip`` (which only needs matching spaces,
            checked when it is loaded).
        env: the environment (wrapped or not).
        kind: ``"policy"`` or ``"wrapper"``.

    Raises:
        PolicyError: for an unknown name.
    """
    if kind == "policy" and _is_model_file(name):
        return []
    entry = lookup(name, kind)
    capabilities = env_capabilities(env)
    if entry.implementation_for(capabilities) is not None:
        return []
    best = min(entry.implementations, key=lambda i: len(i.capabilities - capabilities))
    return sorted(best.capabilities - capabilities)


def policy_supports(name: str, env: Any) -> bool:
    """Whether :func:`make_policy` can build the policy ``name`` for ``env`` (its options aside)."""
    return not missing_capabilities(name, env)


def supported_policies(env: Any) -> tuple[str, ...]:
    """The registered policy names that support ``env`` (an SB3 ``.zip`` fits any env with its spaces)."""
    return tuple(e.name for e in registered("policy") if policy_supports(e.name, env))


def supported_env_ids(name: str, kind: str = "policy") -> tuple[str, ...]:
    """The registered env ids on which the policy (or wrapper) ``name`` can be built (read from their cards, no env
    is built)."""
    from ..registration import ENV_CARDS

    entry = lookup(name, kind)
    return tuple(env_id for env_id, card in ENV_CARDS.items() if entry.implementation_for(card.capabilities))


def supported_names(env_id: str, kind: str = "policy") -> tuple[str, ...]:
    """The registered policies (or wrappers) that the registered env id ``env_id`` supports, read from its card (no
    env is built)."""
    from ..registration import ENV_CARDS

    capabilities = ENV_CARDS[env_id].capabilities
    return tuple(e.name for e in registered(kind) if e.implementation_for(capabilities))


def unsupported_error(
    name: str, env: Any, missing: list[str], kind: str = "policy", error: type[Exception] = PolicyError
) -> Exception:
    """The error for a policy or wrapper on an env that lacks ``missing``: it names the registered envs that are
    supported and what an env of one's own must declare."""
    if hasattr(env, "num_envs"):  # a VecEnv that is not a plain DummyVecEnv
        return error(
            f"{kind} {name!r} is built from one env, got the VecEnv {type(env).__name__}: pass one "
            "of its envs (e.g. gym.make(env_id))"
            + ("; the policy then takes the VecEnv's batches" if kind == "policy" else "")
        )
    entry = lookup(name, kind, error)
    ids = supported_env_ids(name, kind)
    supports = ", ".join(ids) if ids else "no registered env"
    wrapper = action_wrapper(env)
    if wrapper is not None:  # the env offers what the policy needs, but its action is now the wrapper's
        offered = ", ".join(e.name for e in registered("policy") if not missing_capabilities(e.name, env))
        return error(
            f"{kind} {name!r} supports {supports}; got {env_name(env)}, which is in the action wrapper "
            f"{type(wrapper).__name__}: its action is the wrapper's, so it takes {offered} or an SB3 .zip "
            "(build the policy on the env without the wrapper)"
        )
    base = getattr(env, "unwrapped", env)
    return error(
        f"{kind} {name!r} supports {supports}; got {env_name(env)} (for an env of your own: "
        f"{type(base).__name__} lacks the capabilities {', '.join(missing)}; {name!r} needs "
        f"{entry.supports}, declared in CAPABILITIES with the attributes listed in "
        "redundancy_gym.policies.CAPABILITY_ATTRIBUTES)"
    )


def _one_env(env: Any) -> Any:
    """The first env of a plain stable-baselines3 ``DummyVecEnv`` (its envs live in this process and are built
    alike), else ``env``. A wrapped VecEnv (VecNormalize, ...) is left as it is: its observations are not the
    env's, so an analytic policy must not take it."""
    envs = getattr(env, "envs", None)
    if hasattr(env, "num_envs") and not hasattr(env, "venv") and isinstance(envs, list) and envs:
        return envs[0]
    return env


def _is_model_file(name: Any) -> bool:
    return isinstance(name, (str, Path)) and (str(name).endswith(".zip") or Path(name).is_file())


def build(name: str, kind: str, env: Any, kwargs: dict[str, Any], error: type[Exception] = PolicyError) -> Any:
    """The registered policy or wrapper ``name`` built on ``env`` with options ``kwargs``.

    Raises:
        error: unknown name, an env that lacks a capability (naming the supported env ids), or an env that
            declares a capability without what it promises.
    """
    entry = lookup(name, kind, error)
    impl = entry.implementation_for(env_capabilities(env))
    if impl is None:
        raise unsupported_error(name, env, missing_capabilities(name, env, kind), kind, error)
    valid = impl.option_names()
    unknown = sorted(set(kwargs) - set(valid))
    if unknown and not valid:
        raise error(f"the {name} {kind} takes no options, got {', '.join(unknown)}")
    if unknown:
        raise error(f"unknown option(s) of the {name} {kind}: {', '.join(unknown)}; valid: {', '.join(sorted(valid))}")
    problems = capability_problems(env, impl.capabilities)
    if problems:
        base = getattr(env, "unwrapped", env)
        raise error(
            f"{type(base).__name__} declares {', '.join(sorted(impl.capabilities))} but lacks {', '.join(problems)}"
        )
    return impl.load()(env, **impl.fixed, **kwargs)


def make_policy(name: str, env: Any, **kwargs: Any) -> Policy:
    """Build a policy for ``env``.

    Args:
        name: a registered policy (``redundancy-gym list`` shows them with the envs they support: ``"clik"``,
            the CLIK reference (:class:`~redundancy_gym.policies.ClikPolicy`, or
            :class:`~redundancy_gym.policies.GraspClikPolicy` on grasp tasks); ``"walking"``
            (:class:`~redundancy_gym.policies.WalkingPolicy`); ``"predictive"`` or ``"global"``
            (:class:`~redundancy_gym.policies.PredictivePolicy`); ``"zero"``; ``"random"``), or the path of a
            stable-baselines3 ``.zip``, or a shipped learned baseline by short name ``<learner>-<action>``
            (``"ppo-nullspace"``, ``"bc-joint"``: ``redundancy_gym/baselines/models/<name>-<env>.zip``, shipped
            in the wheel).
        env: the environment the policy will act in (or a stable-baselines3 ``DummyVecEnv`` of such envs). The
            policy takes one observation of it or a batch (a VecEnv's, one controller state per env index).
        **kwargs: options of the policy (the fields of its options dataclass: ``ClikPolicyConfig`` for ``clik``,
            ``seed`` for ``random``, ``algo`` and ``fast_path`` for a ``.zip``:
            :class:`~redundancy_gym.policies.Sb3Policy`).

    Raises:
        PolicyError: unknown name or options, an option value the policy or its controller rejects (the message
            names it), or an env the policy does not support (the message names the registered env ids it
            supports).
    """
    env = _one_env(env)
    if is_shipped_name(name) and name not in _REGISTRY:  # a shipped baseline by short name, e.g. "ppo-nullspace"
        name = str(shipped_model_path(name, env))
    if _is_model_file(name) and name not in _REGISTRY:
        from .sb3_policy import Sb3Policy

        unknown = set(kwargs) - {"algo", "fast_path"}
        if unknown:
            raise PolicyError(
                f"unknown option(s) {', '.join(sorted(unknown))} for a .zip policy; valid: algo, fast_path"
            )
        return Sb3Policy(name, env, **kwargs)
    try:
        return build(name, "policy", env, kwargs)
    except ValueError as exc:  # ControllerError from a controller that rejects an option (its message names it)
        if isinstance(exc, PolicyError):
            raise
        raise PolicyError(f"invalid option for the {name} policy: {exc}") from exc


def _policy(capabilities: Iterable[str], entry_point: str, options: str | None = None, **fixed: Any) -> Implementation:
    return Implementation(
        frozenset(capabilities),
        f"redundancy_gym.policies.{entry_point}",
        None if options is None else f"redundancy_gym.policies.{options}",
        fixed,
    )


# The built-in policies and wrappers, by name (entry points are strings: nothing is imported until it is built).
register(
    "clik",
    "policy",
    (
        _policy({"tcp_tracking"}, "clik_policy:ClikPolicy", "clik_policy:ClikPolicyConfig"),
        _policy({"grasp_task"}, "grasp_clik_policy:GraspClikPolicy", "grasp_clik_policy:GraspClikConfig"),
    ),
    "CLIK (5.14) on the env's task with nullspace joint-limit and collision avoidance",
)
register(
    "walking",
    "policy",
    (_policy({"biped"}, "walking_policy:WalkingPolicy", "walking_policy:WalkingPolicyConfig"),),
    "DCM walking pattern, stabilizer, step adjustment and whole-body CLIK",
)
for _mode, _summary in (
    ("predictive", "receding-horizon predictive IK (algorithm 12)"),
    ("global", "predictive IK over the whole episode, planned once"),
):
    register(
        _mode,
        "policy",
        (
            _policy(
                {"tcp_tracking", "tcp_reference"},
                "predictive_policy:PredictivePolicy",
                "predictive_policy:PredictivePolicyConfig",
                mode=_mode,
            ),
            _policy(
                {"grasp_task"},
                "predictive_policy:PredictivePolicy",
                "predictive_policy:PredictivePolicyConfig",
                mode=_mode,
            ),
        ),
        _summary,
    )
register("zero", "policy", (_policy({"box_action"}, "zero_policy:ZeroPolicy"),), "always the zero action")
register(
    "random",
    "policy",
    (_policy({"bounded_action"}, "random_policy:RandomPolicy", "random_policy:RandomPolicyConfig"),),
    "uniform random actions from a seeded generator",
)

POLICY_NAMES: tuple[str, ...] = tuple(e.name for e in registered("policy"))
"""The built-in policy names."""


def _wrapper(capability_sets: Iterable[Iterable[str]], module: str, name: str) -> tuple[Implementation, ...]:
    return tuple(
        Implementation(
            frozenset(caps),
            f"redundancy_gym.wrappers.{module}:{name}",
            f"redundancy_gym.wrappers.{module}:{name}Config",
        )
        for caps in capability_sets
    )


_ARMS = ({"tcp_tracking"}, {"grasp_task"})
register(
    "task_space",
    "wrapper",
    _wrapper(_ARMS, "task_space_action", "TaskSpaceAction"),
    "the action is a TCP velocity; CLIK with joint-limit and collision avoidance moves the joints",
)
register(
    "nullspace",
    "wrapper",
    _wrapper(_ARMS, "nullspace_action", "NullspaceAction"),
    "CLIK tracks the env's reference; the action is the nullspace input u of (5.100)",
)
register(
    "residual",
    "wrapper",
    _wrapper((*_ARMS, {"biped"}), "residual_action", "ResidualAction"),
    "the action is a bounded correction added to the reference policy's",
)
register(
    "walking_command",
    "wrapper",
    _wrapper(({"biped"},), "walking_command_action", "WalkingCommandAction"),
    "the action is the walking velocity and yaw rate; the walking reference moves the joints",
)

WRAPPER_NAMES: tuple[str, ...] = tuple(e.name for e in registered("wrapper"))
"""The built-in wrapper names."""
