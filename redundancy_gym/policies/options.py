"""Checks shared by the reference policies: options against their config dataclass, and what the env must expose."""

from __future__ import annotations

import math
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, TypeVar

from .. import validation as checks
from ..controllers import DESCENT_METHODS, METHODS
from ..kernel_options import BACKENDS
from .exceptions import PolicyError
from .plant_compensation import MAX_LATENCY

__all__ = [
    "BACKENDS",
    "OPTION_RULES",
    "SUFFIX_RULES",
    "WALKING_IK",
    "OptionRule",
    "config_from_options",
    "control_period",
    "env_name",
    "env_with_attributes",
    "option_rule",
]

C = TypeVar("C")
# BACKENDS (re-exported, the one tuple of kernel_options): how a policy runs its controller, the compiled twin
# (CompiledClik, CompiledWholeBodyIk with CompiledMeasurement) or the Python reference (Clik, WholeBodyIk)
# how the walking policy turns its pattern into joint trajectories: whole-body CLIK or Inverse Kineto-Dynamics
WALKING_IK: tuple[str, ...] = ("clik", "ikd")


@dataclass(frozen=True)
class OptionRule:
    """How one policy option is checked: its kind (``"bool"``, ``"int"``, ``"real"``, ``"str"``), whether None
    is valid, its range (``low``/``high``, open or closed, with a unit for the message) or its choices.

    A field's kind and ``optional`` come from the config dataclass's annotation (``float | None``); the range
    from :data:`OPTION_RULES` (by option name), :data:`SUFFIX_RULES` (by the name's ending), a config class's own
    ``OPTION_RULES`` mapping, or the field's ``metadata["option_rule"]``.
    """

    kind: str = "real"
    optional: bool = False
    low: float | None = None
    high: float | None = None
    low_open: bool = False
    high_open: bool = False
    unit: str | None = None
    choices: tuple[Any, ...] | None = None

    def check(self, name: str, value: Any, error: type[Exception] = PolicyError) -> Any:
        """``value`` (a bool, an int, a float or a str) when it obeys the rule; otherwise ``error`` naming
        ``name``, the value and the valid range or choices."""
        if value is None and self.optional:
            return None
        if self.choices is not None:
            return checks.check_choice(name, value, self.choices, error=error)
        if self.kind == "bool":
            return checks.check_bool(name, value, error=error)
        if self.kind == "int":
            return checks.check_int(
                name,
                value,
                low=None if self.low is None else int(self.low),
                high=None if self.high is None else int(self.high),
                optional=self.optional,
                error=error,
            )
        if self.kind == "str":
            if isinstance(value, str):
                return value
            raise error(
                f"{name} must be {'None or ' if self.optional else ''}a str, got {value!r} ({type(value).__name__})"
            )
        return checks.check_real(
            name,
            value,
            low=self.low,
            high=self.high,
            low_open=self.low_open,
            high_open=self.high_open,
            unit=self.unit,
            optional=self.optional,
            error=error,
        )

    @property
    def has_range(self) -> bool:
        """Whether the rule says more than the kind (a bound or choices)."""
        return self.low is not None or self.high is not None or self.choices is not None


def _at_least(low: float, unit: str | None = None) -> OptionRule:
    return OptionRule(low=low, unit=unit)


def _above(low: float, unit: str | None = None) -> OptionRule:
    return OptionRule(low=low, low_open=True, unit=unit)


OPTION_RULES: dict[str, OptionRule] = {
    # task-space feedback K: > 0 (0 leaves the task error uncorrected); nullspace and stabilizer gains may be 0 (off)
    "gain": _above(0.0, "1/s"),
    "nullspace_gain": _at_least(0.0),
    "dcm_gain": _at_least(0.0),
    "zmp_gain": _at_least(0.0),
    "com_gain": _at_least(0.0, "1/s"),
    # potentials: activation distances and slopes > 0, weights >= 0 (0 switches the objective off)
    "joint_limit_activation": _above(0.0),
    "joint_limit_slope": _above(0.0),
    "joint_limit_weight": _at_least(0.0),
    "collision_activation": _above(0.0, "m"),
    "collision_slope": _above(0.0, "1/m"),
    "collision_weight": _at_least(0.0),
    "self_collision_activation": _above(0.0, "m"),
    "self_collision_slope": _above(0.0, "1/m"),
    "self_collision_weight": _at_least(0.0),
    "posture_weight": _at_least(0.0),
    "velocity_weight": _at_least(0.0),
    "input_weight": _at_least(0.0),
    "dls_threshold": _above(0.0),
    "dls_max_damping": _at_least(0.0),
    "damping": _at_least(0.0),
    # the grasp path's timing: speeds > 0 (a time divides by them), a duration >= 0
    "max_speed": _above(0.0, "m/s"),
    "approach_speed": _above(0.0, "m/s"),
    "max_turn_rate": _above(0.0, "rad/s"),
    "min_duration": _at_least(0.0, "s"),
    # prediction
    "horizon": _above(0.0, "s"),
    "sample_time": _above(0.0, "s"),
    "tolerance": _at_least(0.0),
    "iterations": _at_least(0),
    "global_iterations": _at_least(0),
    # walking: W = gamma I + J^T J must be invertible, beta divides the nullspace step
    "gamma": _above(0.0),
    "beta": _above(0.0),
    "step_duration": _above(0.0, "s"),
    "com_height": _above(0.0, "m"),
    "correction_iterations": _at_least(0),
    "correction_first_steps": OptionRule(low=0, high=2),
    "foot_force_gain": _at_least(0.0, "m/(N s)"),
    "step_min_remaining": _above(0.0, "s"),
    "step_max_forward": _at_least(0.0, "m"),
    "step_max_backward": _at_least(0.0, "m"),
    "step_min_width": _at_least(0.0, "m"),
    "step_max_width": _above(0.0, "m"),
    # obstacles (SSTA): a clearance above a box [m], a step-over single support (0: the nominal one) [s]
    "obstacle_clearance": _at_least(0.0, "m"),
    "step_over_duration": _at_least(0.0, "s"),
    # the plant's actuation delay a controller compensates [control periods]
    "latency": OptionRule(low=0, high=MAX_LATENCY),
    # choices
    "method": OptionRule(kind="str", choices=METHODS),
    "backend": OptionRule(kind="str", choices=BACKENDS),
    "descent": OptionRule(kind="str", choices=DESCENT_METHODS),
    "collision_avoidance": OptionRule(kind="str", choices=("auto", "on", "off")),
    "ik": OptionRule(kind="str", choices=WALKING_IK),
}
"""The range or choices of a policy option, by its name (the same name means the same thing in every config)."""

_CLASS_RULES: dict[tuple[str, str], OptionRule] = {
    ("GraspClikConfig", "collision_avoidance"): OptionRule(kind="str", choices=("on", "off")),
}

SUFFIX_RULES: tuple[tuple[str, OptionRule], ...] = (
    ("_weight", _at_least(0.0)),
    ("_gain", _at_least(0.0)),
    ("_activation", _above(0.0)),
    ("_slope", _above(0.0)),
    ("_speed", _above(0.0)),
    ("_rate", _above(0.0)),
    ("_duration", _at_least(0.0, "s")),
    ("_time", _above(0.0, "s")),
    ("_iterations", _at_least(0)),
    ("_damping", _at_least(0.0)),
    ("_distance", _above(0.0, "m")),
)
"""Ranges of options that :data:`OPTION_RULES` does not name, by how the name ends."""


def _kind(annotation: Any) -> tuple[str | None, bool]:
    """``(kind, optional)`` of a field annotation (a type or, unresolved, its string)."""
    if isinstance(annotation, str):
        parts = {p.strip() for p in annotation.split("|")}
        optional = "None" in parts or annotation.startswith("Optional[")
        parts.discard("None")
        base = parts.pop() if len(parts) == 1 else None
        base = base[len("Optional[") : -1] if base and base.startswith("Optional[") else base
        return {"bool": "bool", "int": "int", "float": "real", "str": "str"}.get(base or "", None), optional
    optional = False
    if typing.get_origin(annotation) in (typing.Union, types.UnionType):
        args = [a for a in typing.get_args(annotation) if a is not type(None)]
        optional = len(args) < len(typing.get_args(annotation))
        if len(args) != 1:
            return None, optional
        annotation = args[0]
    return {bool: "bool", int: "int", float: "real", str: "str"}.get(annotation), optional


def _annotations(config_type: type) -> dict[str, Any]:
    try:
        return typing.get_type_hints(config_type)
    except Exception:  # an annotation that cannot be resolved here: read the strings
        return {f.name: f.type for f in fields(config_type)}


def option_rule(config_type: type, name: str) -> OptionRule | None:
    """The rule that checks option ``name`` of ``config_type`` (a config dataclass), or None when its type is
    none of bool, int, float, str (optionally ``| None``): such an option is passed through unchecked."""
    field = {f.name: f for f in fields(config_type)}[name]
    kind, optional = _kind(_annotations(config_type).get(name, field.type))
    if kind is None:
        return None
    own: Mapping[str, OptionRule] = getattr(config_type, "OPTION_RULES", {})
    rule = (
        field.metadata.get("option_rule")
        or own.get(name)
        or _CLASS_RULES.get((config_type.__name__, name))
        or OPTION_RULES.get(name)
    )
    if rule is None and kind in ("int", "real"):
        rule = next((r for suffix, r in SUFFIX_RULES if name.endswith(suffix)), None)
    if rule is None or (rule.choices is None and kind in ("bool", "str")):
        rule = OptionRule()
    return OptionRule(
        kind=kind,
        optional=optional,
        low=rule.low,
        high=rule.high,
        low_open=rule.low_open,
        high_open=rule.high_open,
        unit=rule.unit,
        choices=rule.choices if kind == "str" else None,
    )


def config_from_options(config_type: type[C], options: dict[str, Any]) -> C:
    """``config_type(**options)`` after checking every option against its field's type and range.

    A bool option must be a bool (``"no"`` is not ``False``), a number a finite real number (not a string) in
    its range (:data:`OPTION_RULES`), a string one of its choices; ``None`` only where the field allows it.

    Raises:
        PolicyError: an unknown option (naming the valid ones), or a value that breaks its rule (naming the
            option, the value and the valid range or choices).
    """
    valid = {f.name for f in fields(config_type)}  # type: ignore[arg-type]
    unknown = set(options) - valid
    if unknown:
        raise PolicyError(
            f"unknown option(s) of {config_type.__name__}: {', '.join(sorted(unknown))}; "
            f"valid: {', '.join(sorted(valid))}"
        )
    checked = {}
    for name, value in options.items():
        rule = option_rule(config_type, name)
        checked[name] = value if rule is None else rule.check(name, value, PolicyError)
    return config_type(**checked)


def env_with_attributes(env: Any, required: tuple[str, ...], policy: str) -> Any:
    """The unwrapped env, after checking that it has every attribute in ``required``.

    :func:`~redundancy_gym.policies.make_policy` checks support first and names the registered envs a
    policy supports; this is the check of a policy class built directly.
    """
    base = getattr(env, "unwrapped", env)
    missing = [name for name in required if not hasattr(base, name)]
    if missing:
        raise PolicyError(
            f"policy {policy!r} does not support {env_name(env)} "
            f"(for an env of your own: {type(base).__name__} lacks {', '.join(missing)})"
        )
    return base


def env_name(env: Any) -> str:
    """The env's registered id (``env.spec.id``) when it has one, else its class name."""
    spec = getattr(env, "spec", None) or getattr(getattr(env, "unwrapped", env), "spec", None)
    env_id = getattr(spec, "id", None)
    return str(env_id) if env_id else type(getattr(env, "unwrapped", env)).__name__


def control_period(base: Any) -> float | None:
    """The env's control period ``dt`` [s], over which a CLIK command must keep every joint inside its range;
    None when the env has none."""
    dt = getattr(base, "dt", None)
    return float(dt) if isinstance(dt, (int, float)) and math.isfinite(dt) and dt > 0 else None
