"""The feet's centres of pressure and the zero-moment point from MuJoCo's contact forces (the biped envs' ``cop``,
``zmp`` and ``normal_force``).

Each contact between the ground (the floor, and BipedTerrain's terrain geoms) and a sole adds its world-frame normal
force ``f_z`` to its foot, and ``f_z`` times its position to the foot's first moment; a foot's CoP is its moment
over its force, the ZMP the moment of both feet over their summed force (on flat ground the ZMP is the CoP of all
contacts). :func:`contact_pressure` does this
with MuJoCo's ``mj_contactForce`` per contact (the readable reference) or, :func:`compiled_contact_pressure`, in
one compiled pass over MuJoCo's contact arrays, which decodes the pyramidal or elliptic cone forces as
``mj_contactForce`` does and sums in the same order: both give the same bits.
"""

from __future__ import annotations

from typing import NamedTuple

import mujoco
import numpy as np
from numba import carray, njit, types
from numpy.typing import NDArray

from ..geometry.ssv_kernels import pointer_intrinsic
from ..kernel_options import JIT_EXACT
from .exceptions import EnvConfigError

__all__ = [
    "ContactPressure",
    "compiled_contact_pressure",
    "compiled_touches_geoms",
    "contact_pressure_kernel",
    "contact_layout",
    "contact_pressure",
    "foot_of_geom",
    "touches_geoms",
]

_float64_pointer = pointer_intrinsic(types.float64)
_int32_pointer = pointer_intrinsic(types.int32)
_PYRAMIDAL = int(mujoco.mjtConstraint.mjCNSTR_CONTACT_PYRAMIDAL)
_MIN_FORCE = 1e-9  # [N] a foot (or both) with less normal force has no CoP (ZMP): NaN, not a division by ~0


class ContactPressure(NamedTuple):
    """The floor contacts of both feet (world frame; index 0 the right foot, 1 the left).

    Finite values with validity flags rather than NaN: tools that compare infos (Gymnasium's ``check_env``) take
    NaN for a difference.

    Attributes:
        cop: (2, 2) each foot's centre of pressure (x, y) [m]; 0 for a foot without load.
        cop_valid: (2,) whether each foot carries load (more than 1e-9 N), so that its ``cop`` is one.
        zmp: (2,) the zero-moment point (x, y) [m] of both feet; 0 when neither carries load.
        zmp_valid: whether the feet carry load, so that ``zmp`` is one.
        normal: (2,) each foot's normal force [N].
    """

    cop: NDArray[np.float64]
    cop_valid: NDArray[np.bool_]
    zmp: NDArray[np.float64]
    zmp_valid: bool
    normal: NDArray[np.float64]


def foot_of_geom(ngeom: int, sole_geoms: dict[int, int]) -> NDArray[np.int64]:
    """(ngeom,) the foot (0 right, 1 left) of each sole geom id in ``sole_geoms`` (geom id -> foot), -1 elsewhere."""
    foot = np.full(ngeom, -1, dtype=np.int64)
    for geom, side in sole_geoms.items():
        if not 0 <= geom < ngeom or side not in (0, 1):
            raise EnvConfigError(f"sole geom {geom} -> foot {side}: a geom id in [0, {ngeom}) and a foot 0 or 1")
        foot[geom] = side
    return foot


def contact_pressure(
    model: mujoco.MjModel, data: mujoco.MjData, ground: tuple[int, int], foot: NDArray[np.int64]
) -> ContactPressure:
    """Each foot's CoP and normal force and the ZMP of ``data``'s contacts between the ground's geoms and the
    soles, with ``mj_contactForce`` per contact: the readable reference of :func:`compiled_contact_pressure`.

    Args:
        model, data: the simulation, after a step (its ``efc_force`` solved).
        ground: the ground's geom ids ``[low, high)``: the floor, and a terrain's geoms after it.
        foot: (ngeom,) the foot of each geom (:func:`foot_of_geom`): 0 right, 1 left, -1 not a sole.
    """
    weighted = np.zeros((2, 2))
    normal = np.zeros(2)
    force = np.zeros(6)
    low, high = ground
    for i in range(data.ncon):
        contact = data.contact[i]
        g1, g2 = int(contact.geom1), int(contact.geom2)
        other = g2 if low <= g1 < high else g1 if low <= g2 < high else -1
        side = int(foot[other]) if other >= 0 else -1
        if side < 0:
            continue
        mujoco.mj_contactForce(model, data, i, force)
        # the world z component of the contact-frame force: the frame's rows are its axes. The frame's normal
        # points from geom1 to geom2 and the force is the one on geom2: on the sole when the ground is geom1 (a
        # plane, a heightfield, a box of lower id), on the ground when the sole is (a ramp's mesh, whose type sorts
        # after the sole's box): then the sole's is its opposite
        sign = 1.0 if other == g2 else -1.0
        fz = sign * float(contact.frame[2] * force[0] + contact.frame[5] * force[1] + contact.frame[8] * force[2])
        normal[side] += fz
        weighted[side] += fz * contact.pos[:2]
    cop = np.full((2, 2), np.nan)
    loaded = normal > _MIN_FORCE
    cop[loaded] = weighted[loaded] / normal[loaded, None]
    total = normal.sum()
    zmp = weighted.sum(axis=0) / total if total > _MIN_FORCE else np.full(2, np.nan)
    cop_valid, zmp_valid = ~np.isnan(cop[:, 0]), bool(not np.isnan(zmp[0]))
    return ContactPressure(
        np.where(cop_valid[:, None], cop, 0.0), cop_valid, zmp if zmp_valid else np.zeros(2), zmp_valid, normal
    )


def contact_layout(data: mujoco.MjData) -> NDArray[np.int64]:
    """Where :func:`compiled_contact_pressure` finds the fields of MuJoCo's ``mjContact`` records: the record's
    size and the byte offsets of ``pos``, ``frame``, ``friction``, ``geom``, ``dim`` and ``efc_address``, read from
    the strided views of ``data.contact`` (the same for every ``MjData`` of this MuJoCo build)."""
    c = data.contact
    base = c.dist.ctypes.data
    fields = (c.pos, c.frame, c.friction, c.geom, c.dim, c.efc_address)
    layout = np.array([c.dist.strides[0], *(f.ctypes.data - base for f in fields)], dtype=np.int64)
    if layout[0] % 8 or np.any(layout[1:4] % 8) or np.any(layout[4:] % 4):
        raise EnvConfigError(f"unexpected mjContact layout {layout.tolist()} (record size, field offsets [bytes])")
    return layout


def compiled_contact_pressure(
    data: mujoco.MjData, ground: tuple[int, int], foot: NDArray[np.int64], layout: NDArray[np.int64]
) -> ContactPressure:
    """:func:`contact_pressure` in one compiled pass over MuJoCo's contact records (``layout``:
    :func:`contact_layout`): the same bits."""
    cop, cop_valid, zmp, zmp_valid, normal = contact_pressure_kernel(
        data.contact.dist, data.ncon, layout, data.efc_force, data.efc_type, foot, ground[0], ground[1]
    )
    return ContactPressure(cop, cop_valid, zmp, bool(zmp_valid), normal)


def touches_geoms(data: mujoco.MjData, low: int, high: int) -> bool:
    """Whether a contact of ``data`` involves a geom with id in ``[low, high)``: the readable reference of
    :func:`compiled_touches_geoms`."""
    if data.ncon == 0 or low >= high:
        return False
    # a loop over Python ints: for the few contacts of a biped, 4x faster than NumPy's comparisons
    return any(low <= g < high for g in data.contact.geom.ravel().tolist())


def compiled_touches_geoms(data: mujoco.MjData, low: int, high: int, layout: NDArray[np.int64]) -> bool:
    """:func:`touches_geoms` in one compiled pass over the contact records (``layout``: :func:`contact_layout`)."""
    return bool(_touches(data.contact.dist, data.ncon, layout, low, high))


@njit(**JIT_EXACT)
def _touches(dist, ncon, layout, low, high):  # noqa: ANN001, ANN202
    ints = carray(_int32_pointer(dist.ctypes.data), (ncon * layout[0] // 4,))
    geom = layout[4] // 4
    for i in range(ncon):
        k = i * layout[0] // 4 + geom
        if low <= ints[k] < high or low <= ints[k + 1] < high:
            return True
    return False


@njit(**JIT_EXACT)
def contact_pressure_kernel(dist, ncon, layout, efc_force, efc_type, foot, low, high):  # noqa: ANN001, ANN202
    """The fields of :class:`ContactPressure` (``mj_contactForce``'s decoding and the reference's sums, in their
    order), reading the ``ncon`` contact records that start at ``dist``'s address through ``layout``; the ground is
    the geoms ``[low, high)``."""
    stride = layout[0]
    records = _float64_pointer(dist.ctypes.data)
    counts = _int32_pointer(dist.ctypes.data)
    reals = carray(records, (ncon * stride // 8,))
    ints = carray(counts, (ncon * stride // 4,))
    pos, frame, friction = layout[1] // 8, layout[2] // 8, layout[3] // 8
    geom, dims, address = layout[4] // 4, layout[5] // 4, layout[6] // 4
    weighted = np.zeros((2, 2))
    normal = np.zeros(2)
    for i in range(ncon):
        r = i * stride // 8
        k = i * stride // 4
        g1, g2 = ints[k + geom], ints[k + geom + 1]
        other = g2 if low <= g1 < high else (g1 if low <= g2 < high else -1)
        adr = ints[k + address]
        if other < 0 or foot[other] < 0 or adr < 0:
            continue  # not a sole on the ground, or a contact without a constraint (mj_contactForce gives 0)
        side = foot[other]
        n = ints[k + dims]
        f0 = f1 = f2 = 0.0
        # the constraint's type says the cone (mj_contactForce asks the model: the same, frictionless rows aside,
        # which both decode as their one normal force)
        if efc_type[adr] == _PYRAMIDAL:
            # mju_decodePyramid: the normal force is the sum of the pyramid's edge forces, each tangential one the
            # difference of an opposite pair times its friction coefficient
            for e in range(2 * (n - 1)):
                f0 += efc_force[adr + e]
            f1 = (efc_force[adr] - efc_force[adr + 1]) * reals[r + friction]
            if n > 2:
                f2 = (efc_force[adr + 2] - efc_force[adr + 3]) * reals[r + friction + 1]
        else:
            f0 = efc_force[adr]
            if n > 1:
                f1 = efc_force[adr + 1]
            if n > 2:
                f2 = efc_force[adr + 2]
        fz = reals[r + frame + 2] * f0 + reals[r + frame + 5] * f1 + reals[r + frame + 8] * f2
        if other == g1:  # the force on the sole: geom2's force reversed (the reference's comment)
            fz = -fz
        normal[side] += fz
        weighted[side, 0] += fz * reals[r + pos]
        weighted[side, 1] += fz * reals[r + pos + 1]
    cop = np.zeros((2, 2))
    cop_valid = np.zeros(2, dtype=np.bool_)
    for side in range(2):
        if normal[side] > _MIN_FORCE:
            cop_valid[side] = True
            cop[side, 0] = weighted[side, 0] / normal[side]
            cop[side, 1] = weighted[side, 1] / normal[side]
    zmp = np.zeros(2)
    total = normal[0] + normal[1]
    zmp_valid = total > _MIN_FORCE
    if zmp_valid:
        zmp[0] = (weighted[0, 0] + weighted[1, 0]) / total
        zmp[1] = (weighted[0, 1] + weighted[1, 1]) / total
    return cop, cop_valid, zmp, zmp_valid, normal
