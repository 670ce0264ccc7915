"""The control step of :class:`~redundancy_gym.policies.grasp_clik_policy.GraspClikPolicy` with the compiled
backend as one kernel call: the configuration and time read from the observation, the :class:`GraspPath`
sampled, the fused CLIK step (:func:`~redundancy_gym.controllers.clik.clik_kernels.clik_step`) and the normalized
action, with no Python in between (what ``bench ik`` times; the separate NumPy and Python calls cost more than
the CLIK itself).

numba's on-disk cache keys :func:`grasp_clik_action` on this file only, while the code it was compiled with
comes from ``controllers/clik_kernels.py`` and what that calls (``collision_kernels.py``,
``model/chain_kernels.py``, ``geometry/ssv_kernels.py``, ``geometry/grasp_path.py``): after editing one of
them, delete the ``*.nbi``/``*.nbc`` files here too (``make clean`` deletes all of them).
"""

from __future__ import annotations

from numba import njit

from ..controllers.clik.clik_kernels import OK, clik_fields, clik_step
from ..geometry.grasp_path import sample_grasp_path
from ..kernel_options import BORROW_EXACT

__all__ = ["BAD_OBSERVATION", "grasp_clik_action"]

BAD_OBSERVATION = -1
"""Return code of :func:`grasp_clik_action` for an observation too short for the configuration or time index."""


# no fast-math here: the action must be the NumPy ``clip(qdot / speeds, -1, 1)`` to the last bit (a reciprocal
# multiplication could differ by one unit in the last place); the CLIK step keeps its own flags. It only borrows
# arrays: no reference counting (BORROW_EXACT)
@njit(**BORROW_EXACT)
def grasp_clik_action(f, i, obs, q_start, time_index, path, speeds, action, result):  # pragma: no cover - compiled
    """One step of the grasp CLIK policy on the :class:`~redundancy_gym.controllers.CompiledClik` buffers
    ``f``, ``i`` (a :class:`FrameAxisTask`, so the target is ``[p, a]`` and its velocity ``[v, omega]``).

    Reads the configuration ``obs[q_start:q_start + nq]`` and the time ``obs[time_index]`` [s], samples the
    path (its constants ``path``:
    :attr:`GraspPath.params <redundancy_gym.geometry.grasp_path.GraspPath.params>`) into the step's
    target and target velocity, runs :func:`clik_step` and, when it succeeds, writes ``clip(qdot / speeds, -1,
    1)`` (``speeds`` [rad/s or m/s]) into the float32 ``action`` (nv) and a copy of the step's outputs into
    ``result`` (for the :class:`~redundancy_gym.controllers.ClikResult`). Returns ``clik_step``'s code, or
    :data:`BAD_OBSERVATION`; on any code but ``OK`` the action is not written."""
    inputs, outputs, nq, nv, _ = clik_fields(f, i)
    if q_start < 0 or q_start + nq > obs.shape[0] or time_index < 0 or time_index >= obs.shape[0]:
        return BAD_OBSERVATION
    for k in range(nq):
        inputs[k] = obs[q_start + k]
    sample_grasp_path(path, obs[time_index], inputs[nq : nq + 12])  # [p, a, v, omega]: the target, then its velocity
    code = clik_step(f, i, True, False)
    if code != OK:
        return code
    for k in range(nv):
        action[k] = min(max(outputs[k] / speeds[k], -1.0), 1.0)
    for k in range(outputs.shape[0]):
        result[k] = outputs[k]
    return OK
