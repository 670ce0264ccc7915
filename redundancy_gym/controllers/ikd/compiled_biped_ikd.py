"""The compiled twin of :class:`~redundancy_gym.controllers.ikd.BipedIkd`: the model's terms of each step from one
numba kernel on the exported chain instead of pinocchio's passes and their Python."""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ...model import AccelerationTerms, SerialChain
from ...model.chain_kernels import chain_acceleration_terms, chain_difference, chain_integrate
from ..exceptions import ControllerError
from .biped_ikd import BipedIkd

__all__ = ["CompiledBipedIkd"]


class CompiledBipedIkd(BipedIkd):
    """:class:`BipedIkd` with the placements, Jacobians and drifts of the soles and the torso, the CoM, ``A_G`` and
    ``Adot_G qdot`` of each step computed by :func:`~redundancy_gym.model.chain_kernels.chain_acceleration_terms`
    on :meth:`RobotModel.serial_chain` (same arguments; the same accelerations to round-off, held by
    ``tests/controllers/ikd/test_compiled_biped_ikd.py``).

    Unlike :class:`BipedIkd` its step leaves the model's kinematic cache where it was (an objective other than the
    walking controller's joint limits gets the model updated at ``q`` before it is evaluated).
    """

    _kernel: tuple[tuple[NDArray[Any], ...], tuple[NDArray[np.float64], ...]] | None = None
    """The chain's arrays with the frames' attachments, and the kernel's scratch arrays (built at the first step)."""

    @cached_property
    def _chain(self) -> SerialChain:
        """The model's exported chain (:meth:`RobotModel.serial_chain`)."""
        return self.model.serial_chain()

    def _arguments(self) -> tuple[tuple[NDArray[Any], ...], tuple[NDArray[np.float64], ...]]:
        """``(chain, work)``: the kernel's leading arguments from :meth:`RobotModel.serial_chain` and
        :meth:`RobotModel.frame_attachment`, and its scratch arrays."""
        chain = self._chain
        n = chain.num_joints
        return (
            *chain.kernel_arrays(),
            *self.model.frame_attachments((*self.feet_frames, self.torso_frame)),
        ), (np.empty((n, 3, 3)), *(np.empty((n, 3)) for _ in range(6)), np.empty((n, 13)))

    def _terms(self, q: NDArray[np.float64], qdot: NDArray[np.float64]) -> AccelerationTerms:
        if self._kernel is None:
            self._kernel = self._arguments()
        chain, work = self._kernel
        k, nv = 2 + 1, self.model.nv  # the soles, then the torso
        terms = AccelerationTerms(
            np.empty((k, 3, 3)),
            np.empty((k, 3)),
            np.empty((k, 6, nv)),
            np.empty((k, 6)),
            np.empty(3),
            np.empty((6, nv)),
            np.empty(6),
        )
        chain_acceleration_terms(*chain, np.ascontiguousarray(q), np.ascontiguousarray(qdot), *work, *terms)
        return terms

    def integrate(self, q: ArrayLike, qdot: ArrayLike, dt: float) -> NDArray[np.float64]:
        """As :meth:`BipedIkd.integrate`, by :func:`~redundancy_gym.model.chain_kernels.chain_integrate`.

        Raises:
            ControllerError: ``q``, ``qdot`` or ``dt`` of the wrong shape, or a non-finite result.
        """
        chain = self._chain
        q = np.ascontiguousarray(q, dtype=np.float64)
        qdot = np.ascontiguousarray(qdot, dtype=np.float64)
        if q.shape != (chain.nq,) or qdot.shape != (chain.nv,):
            raise ControllerError(
                f"q and qdot must have shapes ({chain.nq},), ({chain.nv},); got {q.shape}, {qdot.shape}"
            )
        out = np.empty(chain.nq)
        chain_integrate(chain.joint_type, chain.q_index, chain.v_index, q, qdot, float(dt), out)
        if not math.isfinite(float(out.sum())):
            raise ControllerError(f"integrating qdot over dt = {dt!r} s gives a non-finite configuration")
        return out

    def _difference(self, q0: NDArray[np.float64], q1: NDArray[np.float64]) -> NDArray[np.float64]:
        chain = self._chain
        out = np.empty(chain.nv)
        chain_difference(chain.joint_type, chain.q_index, chain.v_index, q0, q1, out)
        return out

    def _prepare_objectives(self, q: NDArray[np.float64]) -> None:
        self.model.update(q)
