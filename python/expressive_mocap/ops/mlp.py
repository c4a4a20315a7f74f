"""The wrapper of the batched dense-network kernel (the body model's forward pass)."""

from __future__ import annotations

import numpy as np

from ..backend import kernels
from ..errors import ArgumentError
from ._args import _array, _float

ACTIVATIONS = ("tanh", "linear")  # of a dense layer (mlp_forward); the kernels implement these


def mlp_forward(x, weights, biases, activations) -> np.ndarray:
    """Batched forward pass of a dense network: ``h = act_i(h @ weights[i] + biases[i])``.

    ``x [..., in]`` float32 or float64 (kept; other dtypes become float64), leading dimensions
    folded into rows; ``weights[i] [in_i, out_i]``, ``biases[i] [out_i]`` (cast to the dtype of
    ``x``), ``activations[i]`` ``"tanh"`` or ``"linear"``. Returns ``[..., out]``.
    """
    x = _float("x", x)
    if x.ndim < 1:
        raise ArgumentError(f"argument `x`: expected shape [..., in], got {list(x.shape)}")
    weights, biases, activations = list(weights), list(biases), [str(a) for a in activations]
    for i, activation in enumerate(activations):
        if activation not in ACTIVATIONS:
            raise ArgumentError(
                f"argument `activations`: layer {i}: unknown activation {activation!r} (expected one of {ACTIVATIONS})"
            )
    for name, items in (("biases", biases), ("activations", activations)):
        if len(items) != len(weights):
            raise ArgumentError(
                f"argument `{name}`: expected one for each of the {len(weights)} layers, got {len(items)}"
            )
    for i, (w, b) in enumerate(zip(weights, biases)):
        if np.ndim(w) != 2:
            raise ArgumentError(f"argument `weights`: layer {i} must be 2-D [in, out], got shape {list(np.shape(w))}")
        if np.ndim(b) != 1:
            raise ArgumentError(f"argument `biases`: layer {i} must be 1-D [out], got shape {list(np.shape(b))}")
    weights = [_array("weights", w, x.dtype) for w in weights]
    biases = [_array("biases", b, x.dtype) for b in biases]
    batch = x.shape[:-1]
    flat = x.reshape(-1, x.shape[-1])
    out = kernels().mlp_forward(flat, weights, biases, activations)
    return out.reshape(*batch, out.shape[-1])


__all__ = ["ACTIVATIONS", "mlp_forward"]
