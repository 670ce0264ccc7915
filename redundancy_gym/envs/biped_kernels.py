"""Compiled kernels of the biped envs' step (``backend="compiled"``): the servo targets of an action and the
state's metrics in one pass each, so that a step costs its physics and a few calls, not some forty NumPy calls on
3-vectors. Each computes what :class:`~redundancy_gym.envs.biped_walk.BipedWalkEnv`'s ``backend="python"``
reference does with NumPy, in the same order where the order is the reference's (an elementwise expression), and to
round-off where NumPy sums otherwise (a dot product, a 3 x 3 product).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..geometry.ssv_kernels import smallest_pair_at
from ..kernel_options import JIT_EXACT
from .contact_pressure import contact_pressure_kernel

__all__ = ["biped_metrics", "biped_observation", "biped_state_numerics", "biped_targets"]


@njit(**JIT_EXACT)
def biped_targets(action, nominal, scale, lower, upper, last_targets, lead, dt, feedforward, targets, ctrl):  # noqa: ANN001, ANN201
    """The joint targets [rad] of a normalized ``action`` (clipped to [-1, 1], then into the joint range) into
    ``targets``, and the servo set points into ``ctrl`` (with ``feedforward``, the target rate times ``lead`` [s]
    added); returns False, writing nothing, when an entry of ``action`` is not finite."""
    n = action.shape[0]
    for j in range(n):
        if not math.isfinite(action[j]):
            return False
    for j in range(n):
        a = min(max(action[j], -1.0), 1.0)
        t = min(max(nominal[j] + a * scale[j], lower[j]), upper[j])
        c = t
        if feedforward:
            c = t + lead[j] * (t - last_targets[j]) / dt
        targets[j] = t
        ctrl[j] = c
    return True


@njit(**JIT_EXACT)
def biped_state_numerics(  # noqa: ANN201
    qpos,  # noqa: ANN001
    qvel,  # noqa: ANN001
    lower,  # noqa: ANN001
    upper,  # noqa: ANN001
    torso_xmat,  # noqa: ANN001
    site_xmat,  # noqa: ANN001
    ankle_sites,  # noqa: ANN001
    sensordata,  # noqa: ANN001
    torque_adr,  # noqa: ANN001
    geom_xpos,  # noqa: ANN001
    geom_xmat,  # noqa: ANN001
    ssv_geoms,  # noqa: ANN001
    half_length,  # noqa: ANN001
    vertices,  # noqa: ANN001
    mirror,  # noqa: ANN001
    subtree_angmom,  # noqa: ANN001
    subtree_com,  # noqa: ANN001
    pelvis,  # noqa: ANN001
):
    """The biped's per-step numbers: ``(torso tilt [rad], joint-limit margin [rad], qdot^T qdot [rad^2/s^2],
    peak joint speed [rad/s], contact moments (2, 3) [N m], angular momentum (3,) [kg m^2/s] and CoM (3,) [m] of
    the subtree of body ``pelvis``)`` (new arrays); and the robot's swept-sphere volumes placed from
    the geoms' frames into ``vertices`` and the leading rows of ``mirror`` (another batch holding the robot's
    volumes first; ``vertices`` itself when there is none): a capsule's segment along its local z, a sphere's
    point.

    ``torso_xmat`` is the torso's row-major rotation (9,); a contact moment is the ankle site's rotation times
    the negated torque sensor (the foot's load on the shank in the world frame).
    """
    tilt = math.acos(min(max(torso_xmat[8], -1.0), 1.0))
    n = lower.shape[0]
    margin = np.inf
    for j in range(n):
        q = qpos[7 + j]
        margin = min(margin, min(q - lower[j], upper[j] - q))
    energy = 0.0
    peak = 0.0
    for j in range(6, qvel.shape[0]):
        v = qvel[j]
        energy += v * v
        peak = max(peak, abs(v))
    moments = np.empty((2, 3))
    for k in range(2):
        s = ankle_sites[k]
        a = torque_adr[k]
        for r in range(3):
            moments[k, r] = (
                site_xmat[s, 3 * r] * -sensordata[a]
                + site_xmat[s, 3 * r + 1] * -sensordata[a + 1]
                + site_xmat[s, 3 * r + 2] * -sensordata[a + 2]
            )
    for i in range(ssv_geoms.shape[0]):
        g = ssv_geoms[i]
        h = half_length[i]
        for c in range(3):
            offset = geom_xmat[g, 3 * c + 2] * h
            vertices[i, 0, c] = geom_xpos[g, c] - offset
            vertices[i, 1, c] = geom_xpos[g, c] + offset
            vertices[i, 2, c] = vertices[i, 1, c]
            for r in range(3):
                mirror[i, r, c] = vertices[i, r, c]
    angmom = subtree_angmom[pelvis].copy()
    com = subtree_com[pelvis].copy()
    return tilt, margin, energy, peak, moments, angmom, com


@njit(**JIT_EXACT)
def biped_observation(qpos, qvel, sensordata, sensors, command, time, tail):  # noqa: ANN001, ANN201
    """The observation without noise (a new array): ``qpos``, ``qvel``, the ``sensors`` entries of
    ``sensordata``, then ``command`` [m/s], ``time`` [s] and the entries of ``tail``."""
    nq, nv, ns = qpos.shape[0], qvel.shape[0], sensors.shape[0]
    obs = np.empty(nq + nv + ns + 2 + tail.shape[0])
    obs[nq + nv + ns + 2 :] = tail
    obs[:nq] = qpos
    obs[nq : nq + nv] = qvel
    for k in range(ns):
        obs[nq + nv + k] = sensordata[sensors[k]]
    obs[nq + nv + ns] = command
    obs[nq + nv + ns + 1] = time
    return obs


@njit(**JIT_EXACT)
def biped_metrics(  # noqa: ANN201
    state,  # noqa: ANN001
    contacts,  # noqa: ANN001
    volumes,  # noqa: ANN001
):
    """Every number of the biped's step metrics in one call: :func:`biped_state_numerics` on ``state`` (its
    arguments), the feet's contact pressure (:func:`~redundancy_gym.envs.contact_pressure.contact_pressure_kernel`
    on ``contacts``) and the smallest distances of the robot's pair batch and of the batch mirroring its volumes
    (``volumes``: header address, moving volumes, frames address and first margin [m] of each, the second header
    0 without one; :func:`~redundancy_gym.geometry.ssv_kernels.smallest_pair_at`).

    Returns ``(tilt, margin, qdot^T qdot, peak speed, moments, angular momentum, CoM, cop, cop_valid, zmp,
    zmp_valid, normal, self clearance [m], mirror clearance [m] (+inf without one))``.
    """
    tilt, margin, energy, peak, moments, angmom, com = biped_state_numerics(*state)
    cop, cop_valid, zmp, zmp_valid, normal = contact_pressure_kernel(*contacts)
    own_header, own_moving, own_frames, own_margin, other_header, other_moving, other_frames, other_margin = volumes
    own = smallest_pair_at(own_header, own_margin, own_moving, own_frames)
    other = np.inf
    if other_header != 0:
        other = smallest_pair_at(other_header, other_margin, other_moving, other_frames)
    return tilt, margin, energy, peak, moments, angmom, com, cop, cop_valid, zmp, zmp_valid, normal, own, other
