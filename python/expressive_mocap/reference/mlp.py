"""Twin of ``rust/mlp.rs``: batched forward pass of a dense network, ``x @ W + b`` then tanh."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError

# The activations this twin implements (the package's list is ``expressive_mocap.ops.ACTIVATIONS``).
_APPLY = {"tanh": lambda h: np.tanh(h, out=h), "linear": lambda h: h}


def check_layers(x: np.ndarray, weights: list, biases: list, activations: list) -> None:
    """Raise ``ArgumentError`` naming the argument and layer when the layers do not chain."""
    n = len(weights)
    if len(biases) != n or len(activations) != n:
        raise ArgumentError(
            f"arguments `weights`, `biases`, `activations`: one of each a layer, got {n}, "
            f"{len(biases)} and {len(activations)}"
        )
    if n == 0:
        raise ArgumentError("argument `weights`: a network needs at least one layer")
    if x.ndim != 2:
        raise ArgumentError(f"argument `x`: expected shape [N, in], got {list(x.shape)}")
    if weights[0].ndim == 2 and x.shape[1] != weights[0].shape[0]:
        raise ArgumentError(
            f"argument `x`: expected shape [N, {weights[0].shape[0]}] (the inputs of layer 0), got {list(x.shape)}"
        )
    previous = x.shape[1]
    for i, (w, b, act) in enumerate(zip(weights, biases, activations)):
        if w.ndim != 2:
            raise ArgumentError(f"argument `weights`: layer {i} must be 2-D [in, out], got shape {list(w.shape)}")
        if min(w.shape) == 0:
            raise ArgumentError(
                f"argument `weights`: layer {i} has shape {list(w.shape)}: every layer needs at least "
                "one input and one output"
            )
        if w.shape[0] != previous:
            raise ArgumentError(
                f"argument `weights`: layer {i} takes {w.shape[0]} inputs but layer {i - 1} has {previous} outputs"
            )
        if b.shape != (w.shape[1],):
            raise ArgumentError(f"argument `biases`: layer {i}: expected shape [{w.shape[1]}], got {list(b.shape)}")
        if w.dtype != x.dtype or b.dtype != x.dtype:
            raise TypeError(
                f"arguments `weights`, `biases`: layer {i} must be {x.dtype} like `x`, got {w.dtype} and {b.dtype}"
            )
        if act not in _APPLY:
            raise ArgumentError(
                f'argument `activations`: layer {i}: unknown activation {act!r} (expected "tanh" or "linear")'
            )
        previous = w.shape[1]


def mlp_forward(x: np.ndarray, weights: list, biases: list, activations: list) -> np.ndarray:
    """Outputs ``[N, out]`` of the network for ``x [N, in]`` (float32 or float64, kept).

    ``weights[i] [in_i, out_i]``, ``biases[i] [out_i]``, ``activations[i]`` "tanh" or "linear".
    """
    check_layers(x, weights, biases, activations)
    h = x
    for w, b, act in zip(weights, biases, activations):
        h = _APPLY[act](h @ w + b)
    return h


__all__ = [
    "check_layers",
    "mlp_forward",
]
