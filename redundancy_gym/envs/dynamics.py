"""Dynamics randomization shared by the envs: the ``dynamics`` argument of every env.

The simulated plant differs from the controllers' model: :class:`DynamicsRandomization` draws, at each reset
and from the env's own generator, link masses and inertias, CoM offsets, joint damping, friction loss and
armature, servo gains, an actuation latency, the ground's friction (bipeds), a payload at the TCP and the
robot's placement (arms), and writes them into the env's ``MjModel``. The controllers keep the nominal model
(pinocchio loads the MJCF as it is written). With ``dynamics=None`` (the default) nothing is drawn and nothing is
written: every episode is bitwise what it was without the argument.

The argument is a level or a dict:

- a level ``L`` in ``[0, MAX_LEVEL]``: every scale in ``(1 - L, 1 + L)`` (``mass``, ``damping``,
  ``armature``, ``servo_gain``), CoM offsets up to ``L / 10`` [m] per axis, the ground's friction scaled in
  ``(1 - 3 L, 1 + 3 L)`` (bipeds), ``floor(10 L)`` control periods of latency, a payload up to ``10 L`` [kg]
  and a placement jitter up to ``L / 10`` [m] per axis (arms). ``dynamics=0.1``: +-10 %, 1 cm, friction
  0.7-1.3, one period, up to 1 kg, 1 cm. Friction loss is not in the level: every robot's nominal friction loss
  is 0, which a scale leaves 0 (give it a range).
- a dict from item names (:data:`DYNAMICS_ITEMS`) to their settings (items not named are not randomized); a
  ``"level"`` key first sets every item of the level, the others then override theirs (``{"level": 0.1,
  "latency": 2}``; ``None`` turns an item off).

Every item of the dict:

- ``mass``, ``servo_gain``: a scale range ``(low, high)``, ``0 < low <= high``. ``mass`` multiplies each body's
  mass and its inertia by one draw per body (a denser or lighter link, its shape kept); ``servo_gain``
  multiplies each actuator's gains (position and velocity gain together, so a servo's ``kv / kp`` is kept) by
  one draw per actuator.
- ``damping``, ``frictionloss``, ``armature``: a scale range ``(low, high)`` of each joint DoF's nominal value, or
  ``{"range": (low, high)}``: the value itself drawn in the range (>= 0) [N m s/rad, N m, kg m^2], one draw per DoF
  (a biped's floating base is no joint: its six DoFs keep their values).
- ``com_offset``: the largest offset [m] per axis of each body's CoM (uniform in ``[-d, d]^3`` per body).
- ``latency``: control periods ``k`` (an int) or a range ``(low, high)`` of ints drawn per reset, each in
  ``[0, MAX_LATENCY]``: the actuators apply the command of ``k`` periods before (a delay line on the env's
  controls, filled with the reset's controls).
- ``friction`` (bipeds): a scale range of the sliding friction of every geom (MuJoCo takes the larger of two
  geoms' friction, so every contact's friction scales by the draw).
- ``payload`` (arms): a mass range ``(low, high)`` [kg] (>= 0) added at the TCP (the TCP's body gets the mass at the
  TCP site; its CoM and inertia follow exactly).
- ``placement`` (arms): the largest offset [m] per axis of the robot's base from its nominal placement.

``info["dynamics"]`` of a reset says what was drawn (:meth:`DynamicsRandomization.apply`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, NamedTuple

import mujoco
import numpy as np
from numpy.typing import NDArray

from .exceptions import EnvConfigError
from .validation import check_int, check_range_pair, check_real

__all__ = [
    "ARM_ITEMS",
    "BIPED_ITEMS",
    "DYNAMICS_ITEMS",
    "MAX_LATENCY",
    "MAX_LEVEL",
    "DynamicsRandomization",
    "DynamicsSpec",
    "ScaleOrRange",
    "parse_dynamics",
]

MAX_LEVEL = 0.3
"""Largest level of the shorthand (the ground's friction scale then reaches down to 0.1)."""
MAX_LATENCY = 10
"""Largest actuation latency [control periods]."""

DYNAMICS_ITEMS: dict[str, str] = {
    "mass": "scale range of each body's mass and inertia",
    "com_offset": "largest CoM offset per axis [m]",
    "damping": "scale range, or {'range': (low, high)} [N m s/rad], of each DoF's damping",
    "frictionloss": "scale range, or {'range': (low, high)} [N m], of each DoF's friction loss",
    "armature": "scale range, or {'range': (low, high)} [kg m^2], of each DoF's armature",
    "servo_gain": "scale range of each actuator's gains",
    "latency": "control periods of actuation delay (an int or a (low, high) range of ints)",
    "friction": "scale range of the ground contact's sliding friction (bipeds)",
    "payload": "mass range [kg] at the TCP (arms)",
    "placement": "largest offset per axis [m] of the robot's base (arms)",
}
"""The items of the ``dynamics`` argument and what each takes."""
_COMMON = ("mass", "com_offset", "damping", "frictionloss", "armature", "servo_gain", "latency")
ARM_ITEMS = (*_COMMON, "payload", "placement")
"""The items an arm env (PlanarReach, AgriReach) takes."""
BIPED_ITEMS = (*_COMMON, "friction")
"""The items a biped env (BipedWalk, BipedObstacles) takes."""
_JOINT_ITEMS = ("damping", "frictionloss", "armature")


class ScaleOrRange(NamedTuple):
    """A joint item's setting: ``kind`` ``"scale"`` (of the nominal value) or ``"range"`` (the value itself)."""

    kind: str
    low: float
    high: float


class DynamicsSpec(NamedTuple):
    """The parsed ``dynamics`` argument (None: the item is not randomized)."""

    mass: tuple[float, float] | None = None
    com_offset: float | None = None
    damping: ScaleOrRange | None = None
    frictionloss: ScaleOrRange | None = None
    armature: ScaleOrRange | None = None
    servo_gain: tuple[float, float] | None = None
    latency: tuple[int, int] | None = None
    friction: tuple[float, float] | None = None
    payload: tuple[float, float] | None = None
    placement: float | None = None


def _level_items(level: float, items: tuple[str, ...]) -> dict[str, Any]:
    """The settings of the level shorthand (the module's docstring), for the env's items."""
    scale = (1.0 - level, 1.0 + level)
    every: dict[str, Any] = {
        "mass": scale,
        "com_offset": level / 10.0,
        "damping": scale,
        "armature": scale,
        "servo_gain": scale,
        "latency": math.floor(10.0 * level + 1e-9),
        "friction": (1.0 - 3.0 * level, 1.0 + 3.0 * level),
        "payload": (0.0, 10.0 * level),
        "placement": level / 10.0,
    }
    return {k: v for k, v in every.items() if k in items}


def _scale(name: str, value: Any) -> tuple[float, float]:
    low, high = check_range_pair(name, value, low=0.0, low_open=True, note="a scale of the nominal value")
    return float(low), float(high)


def _scale_or_range(name: str, value: Any, unit: str) -> ScaleOrRange:
    if isinstance(value, Mapping):
        if set(value) != {"range"}:
            raise EnvConfigError(
                f"{name} must be a scale range (low, high) or a dict {{'range': (low, high)}}, got {value!r}"
            )
        low, high = check_range_pair(f"{name}['range']", value["range"], low=0.0, unit=unit)
        return ScaleOrRange("range", float(low), float(high))
    return ScaleOrRange("scale", *_scale(name, value))


def _item(name: str, key: str, value: Any) -> Any:
    """One item's setting, checked (None: off)."""
    where = f"{name}[{key!r}]"
    if value is None:
        return None
    if key in ("mass", "servo_gain", "friction"):
        return _scale(where, value)
    if key in _JOINT_ITEMS:
        unit = {"damping": "N m s/rad", "frictionloss": "N m", "armature": "kg m^2"}[key]
        return _scale_or_range(where, value, unit)
    if key in ("com_offset", "placement"):
        return check_real(where, value, low=0.0, high=0.5, unit="m")
    if key == "payload":
        low, high = check_range_pair(where, value, low=0.0, high=100.0, unit="kg")
        return float(low), float(high)
    # latency
    if isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_)):
        k = check_int(where, value, low=0, high=MAX_LATENCY)
        return k, k
    low, high = check_range_pair(where, value, integer=True, low=0, high=MAX_LATENCY, unit="control periods")
    return int(low), int(high)


def parse_dynamics(value: Any, items: tuple[str, ...], name: str = "dynamics") -> DynamicsSpec | None:
    """The ``dynamics`` argument as a :class:`DynamicsSpec`, or None when off (None, a level 0 or an empty dict
    give None: nothing is drawn).

    Args:
        value: the argument (None, a level, or a dict; the module's docstring).
        items: the items the env takes (:data:`ARM_ITEMS`, :data:`BIPED_ITEMS`).
        name: the argument's name in error messages.
    """
    if value is None:
        return None
    if isinstance(value, Mapping):
        unknown = sorted(str(k) for k in value if k != "level" and k not in items)
        if unknown:
            raise EnvConfigError(
                f"{name} has unknown item(s) {', '.join(unknown)} for this env; valid: level, {', '.join(items)}"
            )
        settings: dict[str, Any] = {}
        if "level" in value:
            level = check_real(f"{name}['level']", value["level"], low=0.0, high=MAX_LEVEL)
            settings.update(_level_items(level, items))
        settings.update({k: v for k, v in value.items() if k != "level"})
    else:
        level = check_real(
            name,
            value,
            low=0.0,
            high=MAX_LEVEL,
            note=f"None: off; a level; or a dict of items from {', '.join(items)}",
        )
        settings = _level_items(level, items)
        if level == 0.0:
            return None
    spec = DynamicsSpec(**{k: _item(name, k, v) for k, v in settings.items()})
    return None if all(v is None for v in spec) else spec


class _Nominal(NamedTuple):
    """The model's values that the randomization writes, as compiled."""

    body_mass: NDArray[np.float64]
    body_inertia: NDArray[np.float64]
    body_ipos: NDArray[np.float64]
    body_iquat: NDArray[np.float64]
    body_pos: NDArray[np.float64]
    dof_damping: NDArray[np.float64]
    dof_frictionloss: NDArray[np.float64]
    dof_armature: NDArray[np.float64]
    actuator_gainprm: NDArray[np.float64]
    actuator_biasprm: NDArray[np.float64]
    geom_friction: NDArray[np.float64]


class DynamicsRandomization:
    """Per-reset randomization of an env's ``MjModel`` from a :class:`DynamicsSpec`, and the latency's delay line.

    Args:
        spec: the parsed argument (:func:`parse_dynamics`).
        root_body: the robot's base body (``placement`` moves it).
        tcp_site: the TCP's site (``payload`` sits there); None for a robot without one.

    The env calls :meth:`apply` at each reset, once its model is final (a scene recompiled at reset is captured
    anew), then :meth:`start_delay` with the reset's controls, and :meth:`delay` on the controls of every step.
    """

    def __init__(self, spec: DynamicsSpec, root_body: str, tcp_site: str | None = None) -> None:
        self.spec = spec
        self.root_body = root_body
        self.tcp_site = tcp_site
        self._model: mujoco.MjModel | None = None
        self._nominal: _Nominal | None = None
        self.latency = 0
        self._line: NDArray[np.float64] = np.zeros((1, 0))
        self._head = 0

    def _capture(self, model: mujoco.MjModel) -> _Nominal:
        if self._model is not model or self._nominal is None:
            self._model = model
            self._nominal = _Nominal(*(getattr(model, f).copy() for f in _Nominal._fields))
        return self._nominal

    def apply(self, model: mujoco.MjModel, data: mujoco.MjData, rng: np.random.Generator) -> dict[str, Any]:
        """Restore ``model``'s nominal values, draw the items of the spec from ``rng`` (in :data:`DYNAMICS_ITEMS`
        order) and write them; returns what was drawn (``info["dynamics"]``): per-body mass scales and CoM offsets
        [m] (rows in body id order, the world's first), per-DoF damping, friction loss and armature, per-actuator
        gain scales, the latency [periods], the friction scale, the payload [kg] and the base offset [m]."""
        nominal = self._capture(model)
        for field, value in zip(_Nominal._fields, nominal, strict=True):
            getattr(model, field)[:] = value
        spec = self.spec
        drawn: dict[str, Any] = {}
        nbody = model.nbody
        if spec.mass is not None:
            scale = np.ones(nbody)
            scale[1:] = rng.uniform(*spec.mass, size=nbody - 1)
            model.body_mass[:] = nominal.body_mass * scale
            model.body_inertia[:] = nominal.body_inertia * scale[:, None]
            drawn["mass_scale"] = scale
        if spec.com_offset is not None:
            offset = np.zeros((nbody, 3))
            offset[1:] = rng.uniform(-spec.com_offset, spec.com_offset, size=(nbody - 1, 3))
            model.body_ipos[:] = nominal.body_ipos + offset
            drawn["com_offset"] = offset
        for key in _JOINT_ITEMS:
            setting: ScaleOrRange | None = getattr(spec, key)
            if setting is None:
                continue
            value = rng.uniform(setting.low, setting.high, size=model.nv)
            compiled = getattr(nominal, f"dof_{key}")
            if setting.kind == "scale":
                value = compiled * value
            # a floating base's six DoFs are no joint: they keep their values (one draw per DoF all the same, so
            # that the draws that follow do not depend on the robot's base)
            value = np.where(model.jnt_type[model.dof_jntid] == mujoco.mjtJoint.mjJNT_FREE, compiled, value)
            getattr(model, f"dof_{key}")[:] = value
            drawn[key] = value
        if spec.servo_gain is not None:
            gain = rng.uniform(*spec.servo_gain, size=model.nu)
            model.actuator_gainprm[:, 0] = nominal.actuator_gainprm[:, 0] * gain
            model.actuator_biasprm[:, 1:3] = nominal.actuator_biasprm[:, 1:3] * gain[:, None]
            drawn["servo_gain"] = gain
        self.latency = 0
        if spec.latency is not None:
            self.latency = int(rng.integers(spec.latency[0], spec.latency[1] + 1))
            drawn["latency"] = self.latency
        if spec.friction is not None:
            friction = float(rng.uniform(*spec.friction))
            model.geom_friction[:, 0] = nominal.geom_friction[:, 0] * friction
            drawn["friction"] = friction
        if spec.payload is not None:
            payload = float(rng.uniform(*spec.payload))
            self._add_payload(model, payload)
            drawn["payload"] = payload
        if spec.placement is not None:
            root = model.body(self.root_body).id
            shift = rng.uniform(-spec.placement, spec.placement, size=3)
            model.body_pos[root] = nominal.body_pos[root] + shift
            drawn["placement"] = shift
        # the compiler's derived constants (subtree masses, the constraint solver's inverse weights) of the new
        # values, as a model compiled with them would have
        mujoco.mj_setConst(model, data)
        return drawn

    def _add_payload(self, model: mujoco.MjModel, mass: float) -> None:
        """Add a point mass [kg] at the TCP site to its body: mass, CoM and the inertia about the new CoM (parallel
        axis theorem), its principal axes again."""
        if self.tcp_site is None or mass <= 0.0:
            return
        site = model.site(self.tcp_site)
        body = int(site.bodyid[0])
        m1, c1, m2, c2 = float(model.body_mass[body]), model.body_ipos[body].copy(), mass, site.pos.copy()
        flat = np.empty(9)
        mujoco.mju_quat2Mat(flat, model.body_iquat[body])
        rotation = flat.reshape(3, 3)
        inertia = rotation @ np.diag(model.body_inertia[body]) @ rotation.T  # about c1, in the body's frame
        total = m1 + m2
        com = (m1 * c1 + m2 * c2) / total

        def shifted(d: NDArray[np.float64]) -> NDArray[np.float64]:
            return float(d @ d) * np.eye(3) - np.outer(d, d)

        inertia = inertia + m1 * shifted(c1 - com) + m2 * shifted(c2 - com)
        principal, axes = np.linalg.eigh(inertia)
        if np.linalg.det(axes) < 0.0:
            axes[:, 0] = -axes[:, 0]
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, axes.reshape(-1))
        model.body_mass[body] = total
        model.body_ipos[body] = com
        model.body_inertia[body] = principal
        model.body_iquat[body] = quat

    def start_delay(self, ctrl: NDArray[np.float64]) -> None:
        """Fill the delay line with the reset's controls (the latency drawn by the last :meth:`apply`)."""
        self._line = np.tile(np.asarray(ctrl, dtype=np.float64), (self.latency + 1, 1))
        self._head = 0

    def delay(self, ctrl: NDArray[np.float64]) -> NDArray[np.float64]:
        """The controls to apply now: those given ``latency`` periods before (``ctrl`` itself without latency);
        ``ctrl`` enters the line."""
        if self.latency == 0:
            return ctrl
        line = self._line
        line[self._head] = ctrl
        self._head = (self._head + 1) % len(line)
        return line[self._head].copy()
