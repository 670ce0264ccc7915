"""The deterministic action of a plain-MLP stable-baselines3 policy, computed from the network's weights in one
compiled kernel call (:class:`MlpInference`), without torch.

SB3's ``predict`` spends 95-130 us per call on a 2x64 MLP, nearly all of it per-call overhead (tensor conversion,
``no_grad``, the distribution object, the clipping in NumPy) rather than the 6000 multiply-adds of the network; the
kernel here does those multiply-adds and the same pre- and post-processing in a few microseconds.

What :func:`~redundancy_gym.policies.sb3_policy.mlp_inference_from_sb3` builds from a loaded model (that module
imports stable-baselines3 and torch; this one needs neither) reproduces of
``model.predict(observation, deterministic=True)`` (stable-baselines3 2.x, ``BasePolicy.predict``):

* the observation cast to float32 (``preprocess_obs`` of a non-image ``Box``), flattened (``FlattenExtractor``);
* PPO / A2C (``ActorCriticPolicy``): ``action_net(mlp_extractor.policy_net(obs))``, the mean of the diagonal
  Gaussian, clipped to the action space's bounds;
* SAC (``SACPolicy``): ``tanh(mu(latent_pi(obs)))``, the mode of the squashed Gaussian, unscaled from [-1, 1] to
  the bounds (``low + 0.5 (a + 1) (high - low)``);
* TD3 / DDPG (``TD3Policy``): ``mu(obs)`` (a ``Tanh`` ends it), unscaled likewise.

The weights stay float32 and the observation is rounded to float32 as torch's input is; from there the kernel
computes in float64 (each product of two float32 numbers is exact in it) and rounds the action to float32 once: it
is the network's exact value to half a float32 unit (the tests hold it to 1e-7 of the network in float64).
torch's float32 matrix products round every partial sum and differ from that by their own error: under 1e-6 for
most shipped models, up to 1.4e-5 where observations reach 2000 (BipedObstacles' 193 inputs), so SB3's and this
path's actions agree to within torch's own rounding, and to 1e-6 where that is smaller.

Anything else is not a plain MLP here and keeps SB3's ``predict``: a non-``Box`` (e.g. ``Dict``) or image
observation, another features extractor (a CNN, a custom one), a layer or activation other than ``Linear``,
``Tanh``, ``ReLU``, state-dependent exploration (gSDE), a non-Gaussian action distribution, a policy class of its
own; ``mlp_inference_from_sb3`` then says which.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ..kernel_options import BORROW, BORROW_EXACT
from .exceptions import PolicyError

__all__ = ["ACTIVATIONS", "CLIP", "UNSCALE", "MlpInference", "mlp_forward", "tanh64"]

ACTIVATIONS: tuple[str, ...] = ("identity", "tanh", "relu")
"""The activations a layer of :class:`MlpInference` may have (the kernel's codes are their indices)."""
_IDENTITY, _TANH, _RELU = range(3)
CLIP = 0
"""Output mode of :func:`mlp_forward`: clip the network's output to the bounds (SB3 without ``squash_output``)."""
UNSCALE = 1
"""Output mode of :func:`mlp_forward`: map the network's output from [-1, 1] to the bounds (``squash_output``)."""

_FLOAT_CHARS = "fd"  # float32, float64: the dtypes the kernel takes as they are


_TANH_CLAMP = 40.0
# tanh(x) is 1 in float64 for |x| >= 20 (1 - tanh(20) = 8.5e-18, under half the float64 spacing below 1), so 2|x|
# stops there; e^40 = 2.4e17 is far from overflow. (Hidden units of the shipped networks reach |x| = 30.)
_TANH_HALVINGS = 10  # 2|x| / 2^10 <= 0.039, where seven Taylor terms of expm1 leave 1.3e-16 relative


# tanh without a library call, so that the loop over a layer vectorizes (glibc's tanhf cost 26 ns a value, 3.4 us
# of the 2x64 network's 4.5): expm1(2|x|) from seven Taylor terms of expm1 at 2|x| / 1024, squared back up with
# expm1(2y) = m (m + 2) (multiplications only: the relative error grows by a few float64 units a step), then
# tanh = m / (m + 2): within 2e-15 relative of NumPy's tanh (measured on [-25, 25] and near 0).
@njit(**BORROW_EXACT)
def tanh64(x):  # pragma: no cover - compiled
    """``tanh`` of ``x`` to a few float64 units (2e-15 relative; NaN gives NaN)."""
    a = 2.0 * abs(x)
    if a > _TANH_CLAMP:  # NaN passes
        a = _TANH_CLAMP
    y = a * (1.0 / 1024.0)
    m = y * (1.0 + y * (1.0 / 2 + y * (1.0 / 6 + y * (1.0 / 24 + y * (1.0 / 120 + y * (1.0 / 720 + y / 5040.0))))))
    for _ in range(_TANH_HALVINGS):
        m = m * (m + 2.0)
    t = m / (m + 2.0)
    return -t if x < 0.0 else t


# The weights are stored transposed and the loops run over a layer's outputs innermost, so they vectorize without
# reordering a sum (each output: its bias plus the products in input order, in float64). Four inputs per pass keep
# an output in a register across four products: a quarter of the loads and stores. Fused multiply-adds (BORROW's
# fast-math subset) make a float64 multiply-add one instruction; products of float32 numbers are exact either way.
# The 530 x 64 first layer of AgriReach streams its 136 kB of weights from L2 per call: about 5 us on AMD EPYC
# (Zen), what bounds that network. Borrowing only: no reference counting.
@njit(**BORROW)
def _dense(x, params, layout, k, y):  # pragma: no cover - compiled
    """Layer ``k`` of :func:`mlp_forward`: ``y = act(W x + b)``."""
    n_in, width, w0, b0, act = layout[k, 0], layout[k, 1], layout[k, 2], layout[k, 3], layout[k, 4]
    for i in range(width):
        y[i] = params[b0 + i]
    # a row of W^T as a slice: indexing params[w0 + j * width + i] directly did not vectorize (numba's wraparound
    # of a possibly negative index stays in the loop), at 0.8 ns instead of 0.15 ns a multiply-add
    j = 0
    while j + 4 <= n_in:
        x0, x1, x2, x3 = x[j], x[j + 1], x[j + 2], x[j + 3]
        r = w0 + j * width
        w_0 = params[r : r + width]
        w_1 = params[r + width : r + 2 * width]
        w_2 = params[r + 2 * width : r + 3 * width]
        w_3 = params[r + 3 * width : r + 4 * width]
        for i in range(width):
            y[i] = (((y[i] + x0 * w_0[i]) + x1 * w_1[i]) + x2 * w_2[i]) + x3 * w_3[i]
        j += 4
    while j < n_in:
        xj = x[j]
        r = w0 + j * width
        w_j = params[r : r + width]
        for i in range(width):
            y[i] += xj * w_j[i]
        j += 1
    if act == _TANH:
        for i in range(width):
            y[i] = tanh64(y[i])
    elif act == _RELU:
        for i in range(width):
            if y[i] < 0.0:  # NaN passes, as in torch
                y[i] = 0.0


# No fast math (BORROW_EXACT): the clipping and the unscaling are NumPy's float32 operations in NumPy's order.
@njit(**BORROW_EXACT)
def mlp_forward(obs, params, layout, squash, mode, bounds, hidden, out):  # pragma: no cover - compiled
    """The actions of a batch: ``out[r] = post(squash(f(obs[r])))`` for the MLP ``f``.

    Args:
        obs: (n, inputs) observations, float32 or float64; rounded to float32 first, as SB3's preprocessing does.
        params: float32, every layer's (inputs, outputs) weight matrix (torch's transposed, row-major) and its
            biases.
        layout: int64 (layers, 5): inputs, outputs, offset of the weights and of the biases into ``params``,
            activation (an index of :data:`ACTIVATIONS`).
        squash: 1 where a ``tanh`` follows the last layer (a squashed Gaussian's mode), else 0.
        mode: :data:`CLIP` or :data:`UNSCALE`; bounds: (2, actions) low and high (the action space's dtype).
        hidden: float64 (2, widest layer) scratch: one layer's input and output.
        out: (n, actions) result, the dtype of ``float32`` combined with the bounds'.
    """
    # fewer array arguments, less dispatch: each costs numba about 0.1 us a call to unbox
    low, high = bounds[0], bounds[1]
    half, one = np.float32(0.5), np.float32(1.0)  # SB3 unscales float32 actions with Python floats: float32 math
    n_layers = layout.shape[0]
    n_out = layout[n_layers - 1, 1]
    first, second = hidden[0], hidden[1]
    for r in range(obs.shape[0]):
        for j in range(layout[0, 0]):
            first[j] = np.float32(obs[r, j])
        for k in range(n_layers):
            if k % 2 == 0:
                _dense(first, params, layout, k, second)
            else:
                _dense(second, params, layout, k, first)
        last = second if n_layers % 2 == 1 else first
        for i in range(n_out):
            a = np.float32(tanh64(last[i]) if squash else last[i])
            if mode == UNSCALE:
                out[r, i] = low[i] + half * (a + one) * (high[i] - low[i])
            elif a < low[i]:  # np.clip: NaN passes
                out[r, i] = low[i]
            elif a > high[i]:
                out[r, i] = high[i]
            else:
                out[r, i] = a


class MlpInference:
    """A fully connected network with its action post-processing, evaluated by :func:`mlp_forward`.

    Calls share one scratch buffer: an instance is for one thread at a time.

    Args:
        layers: ``(weight, bias, activation)`` per layer, input first: weight (outputs, inputs) as torch stores
            it, bias (outputs,), activation a name of :data:`ACTIVATIONS`; cast to float32.
        observation_shape: the shape of one observation (flattened into the first layer's inputs).
        low, high: the action space's bounds (its shape: the action's).
        squash: a ``tanh`` after the last layer (the mode of a squashed Gaussian, SAC's).
        unscale: map the output from [-1, 1] to ``[low, high]`` (SB3's ``squash_output``); else clip to them.
        description: what the network is, for messages (:attr:`description`).

    Raises:
        PolicyError: no layers, layers whose sizes do not chain (the first's inputs: the observation's size), an
            unknown activation, bounds of another size than the last layer's outputs or of a dtype other than
            float32 and float64.
    """

    def __init__(
        self,
        layers: Sequence[tuple[NDArray[np.floating], NDArray[np.floating], str]],
        observation_shape: tuple[int, ...],
        low: NDArray[np.floating],
        high: NDArray[np.floating],
        *,
        squash: bool = False,
        unscale: bool = False,
        description: str = "",
    ) -> None:
        if not layers:
            raise PolicyError("layers must hold at least one (weight, bias, activation); got none")
        self.observation_shape = tuple(int(d) for d in observation_shape)
        self.action_shape: tuple[int, ...] = tuple(np.shape(low))
        rows = []
        n_in = int(np.prod(self.observation_shape, dtype=np.int64))
        w_off = b_off = 0
        weights, biases = [], []
        for k, (weight, bias, activation) in enumerate(layers):
            w = np.asarray(weight, dtype=np.float32)
            b = np.asarray(bias, dtype=np.float32).reshape(-1)
            if activation not in ACTIVATIONS:
                raise PolicyError(f"layer {k}: activation={activation!r}; valid: {', '.join(ACTIVATIONS)}")
            if w.ndim != 2 or w.shape[1] != n_in or b.shape != (w.shape[0],):
                raise PolicyError(
                    f"layer {k}: weight of shape {w.shape} and bias of shape {b.shape} do not take {n_in} inputs "
                    "(valid: weight (outputs, inputs) with the previous layer's outputs as inputs, bias (outputs,))"
                )
            rows.append((n_in, w.shape[0], w_off, b_off, ACTIVATIONS.index(activation)))
            weights.append(np.ascontiguousarray(w.T).reshape(-1))  # (inputs, outputs): the kernel's axpy order
            biases.append(b)
            w_off += w.size
            b_off += b.size
            n_in = w.shape[0]
        bounds = np.broadcast_arrays(np.asarray(low), np.asarray(high))
        if bounds[0].size != n_in:
            raise PolicyError(f"low and high of shape {bounds[0].shape} do not match the last layer's {n_in} outputs")
        if any(x.dtype not in (np.float32, np.float64) for x in bounds):
            raise PolicyError(
                f"low and high of dtype {bounds[0].dtype}, {bounds[1].dtype}; valid: float32, float64 (a Box's)"
            )
        layout = np.asarray(rows, dtype=np.int64)
        layout[:, 3] += w_off  # the biases follow the weights in one array
        self._params = np.concatenate(weights + biases)
        self._layout = layout
        # np.clip and the unscaling of float32 actions with the bounds give the bounds' dtype when it is wider
        self.dtype = np.result_type(np.float32, bounds[0].dtype, bounds[1].dtype)
        self._bounds = np.stack([b.reshape(-1) for b in bounds]).astype(np.result_type(*bounds))
        self._squash = int(squash)
        self._mode = UNSCALE if unscale else CLIP
        self._hidden = np.zeros((2, int(layout[:, :2].max())), dtype=np.float64)
        self._n_in = int(layout[0, 0])
        self._single = (1, int(layout[-1, 1]))
        self.squash = bool(squash)
        self.unscale = bool(unscale)
        self.description = description or self._describe()

    @property
    def widths(self) -> tuple[int, ...]:
        """The inputs, then each layer's outputs."""
        return (int(self._layout[0, 0]), *(int(w) for w in self._layout[:, 1]))

    def _describe(self) -> str:
        acts = sorted({ACTIVATIONS[int(a)] for a in self._layout[:-1, 4]} - {"identity"})
        hidden = "x".join(str(w) for w in self.widths[1:-1]) or "no hidden layer"
        return f"MLP {self.widths[0]} -> {hidden} -> {self.widths[-1]}" + (f" ({', '.join(acts)})" if acts else "")

    def __call__(self, observation: Any) -> NDArray[np.floating]:
        """The actions of one observation (shape :attr:`observation_shape`; the action's shape) or of a batch
        (``(n, *observation_shape)``; ``(n, *action_shape)``), as SB3's ``predict(..., deterministic=True)``.

        Raises:
            PolicyError: an observation of neither shape.
        """
        # a few NumPy calls only: each costs 0.1-0.2 us, as much as the 2x64 network's first layer
        obs = observation if isinstance(observation, np.ndarray) else np.asarray(observation)
        if obs.dtype.char not in _FLOAT_CHARS:
            obs = obs.astype(np.float32)  # as torch's .float(): one rounding of the original values
        shape = obs.shape
        if shape == self.observation_shape:
            out = np.empty(self._single, dtype=self.dtype)
            mlp_forward(
                obs.reshape(1, self._n_in), self._params, self._layout, self._squash, self._mode, self._bounds,
                self._hidden, out,
            )  # fmt: skip
            return out.reshape(self.action_shape)
        if shape[1:] != self.observation_shape or len(shape) != len(self.observation_shape) + 1:
            raise PolicyError(
                f"observation of shape {shape} is neither the model's {self.observation_shape} nor a batch "
                f"(n, {', '.join(map(str, self.observation_shape))})"
            )
        out = np.empty((shape[0], self._single[1]), dtype=self.dtype)
        mlp_forward(
            obs.reshape(shape[0], self._n_in), self._params, self._layout, self._squash, self._mode, self._bounds,
            self._hidden, out,
        )  # fmt: skip
        return out.reshape((shape[0], *self.action_shape))
