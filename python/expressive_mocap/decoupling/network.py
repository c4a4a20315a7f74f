"""A small dense network (multilayer perceptron) whose inference runs in the Rust kernel.

An :class:`Mlp` is a list of :class:`Layer` s ``h = act(h @ weights + bias)``. It is what
:mod:`expressive_mocap.decoupling.training` produces, and saves to an ``.npz`` without pickle::

    np.savez(path, **net.to_arrays("body"))
    net = Mlp.from_arrays(np.load(path), "body")
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError, ModelError
from ..ops import ACTIVATIONS, mlp_forward


@dataclass(frozen=True)
class Layer:
    """One dense layer: ``weights [in, out]``, ``bias [out]`` (float64), ``activation``
    ``"tanh"`` or ``"linear"``."""

    weights: np.ndarray
    bias: np.ndarray
    activation: str = "tanh"

    def __post_init__(self):
        weights = np.array(self.weights, dtype=np.float64)  # a copy: the layer owns its values
        bias = np.array(self.bias, dtype=np.float64)
        if weights.ndim != 2 or bias.shape != weights.shape[1:]:
            raise ArgumentError(
                f"a layer needs weights [in, out] and bias [out], got {list(weights.shape)} and {list(bias.shape)}"
            )
        if self.activation not in ACTIVATIONS:
            raise ArgumentError(f"activation must be one of {ACTIVATIONS}, got {self.activation!r}")
        object.__setattr__(self, "weights", weights)
        object.__setattr__(self, "bias", bias)


class Mlp:
    """A chain of dense layers; ``forward(x [..., in]) -> [..., out]``.

    ``layers``: :class:`Layer` s or ``(weights, bias, activation)`` triples, each layer's ``in``
    equal to the previous layer's ``out``. Weights are kept in float64; float32 copies are made
    once, the first time a float32 batch comes in.
    """

    def __init__(self, layers: Iterable[Layer | tuple]):
        self.layers = tuple(layer if isinstance(layer, Layer) else Layer(*layer) for layer in layers)
        if not self.layers:
            raise ArgumentError("an Mlp needs at least one layer")
        for i in range(1, len(self.layers)):
            given, taken = self.layers[i - 1].weights.shape[1], self.layers[i].weights.shape[0]
            if given != taken:
                raise ArgumentError(f"layer {i} takes {taken} inputs but layer {i - 1} has {given} outputs")
        self._cast: dict[np.dtype, tuple[list, list]] = {}

    @property
    def n_inputs(self) -> int:
        return self.layers[0].weights.shape[0]

    @property
    def n_outputs(self) -> int:
        return self.layers[-1].weights.shape[1]

    @property
    def shape(self) -> tuple[int, ...]:
        """Widths from input to output, e.g. ``(19, 300, 300, 80)``."""
        return (self.n_inputs,) + tuple(layer.weights.shape[1] for layer in self.layers)

    def __repr__(self) -> str:
        acts = ", ".join(layer.activation for layer in self.layers)
        return f"Mlp({' -> '.join(map(str, self.shape))}; {acts})"

    def _arrays(self, dtype) -> tuple[list, list]:
        dtype = np.dtype(dtype)
        if dtype not in self._cast:
            self._cast[dtype] = (
                [layer.weights.astype(dtype) for layer in self.layers],
                [layer.bias.astype(dtype) for layer in self.layers],
            )
        return self._cast[dtype]

    def forward(self, x) -> np.ndarray:
        """Outputs ``[..., out]`` for inputs ``x [..., in]``; float32 stays float32, anything
        else runs in float64. Runs in the kernel backend in use (Rust, or the NumPy twin)."""
        x = np.asarray(x)
        dtype = np.float32 if x.dtype == np.float32 else np.float64
        weights, biases = self._arrays(dtype)
        return mlp_forward(x.astype(dtype, copy=False), weights, biases, [layer.activation for layer in self.layers])

    __call__ = forward

    def to_arrays(self, prefix: str = "mlp") -> dict[str, np.ndarray]:
        """Named arrays for ``np.savez``: ``{prefix}.{i}.weights``, ``{prefix}.{i}.bias`` and
        ``{prefix}.activations`` (a unicode array, so no pickle is needed to load it)."""
        arrays = {f"{prefix}.activations": np.array([layer.activation for layer in self.layers])}
        for i, layer in enumerate(self.layers):
            arrays[f"{prefix}.{i}.weights"] = layer.weights
            arrays[f"{prefix}.{i}.bias"] = layer.bias
        return arrays

    @classmethod
    def from_arrays(cls, arrays: Mapping[str, np.ndarray], prefix: str = "mlp") -> Mlp:
        """The network :meth:`to_arrays` described (``arrays`` may be an ``np.load`` result);
        :class:`~expressive_mocap.errors.ModelError` if arrays are missing or do not make a network."""
        key = f"{prefix}.activations"
        if key not in arrays:
            raise ModelError(f"no network under prefix {prefix!r}: {key!r} is missing")
        activations = [str(a) for a in np.asarray(arrays[key]).tolist()]
        missing = [
            k
            for i in range(len(activations))
            for k in (f"{prefix}.{i}.weights", f"{prefix}.{i}.bias")
            if k not in arrays
        ]
        if missing:
            raise ModelError(f"the network under prefix {prefix!r} lacks {', '.join(map(repr, missing))}")
        try:
            return cls(
                Layer(arrays[f"{prefix}.{i}.weights"], arrays[f"{prefix}.{i}.bias"], act)
                for i, act in enumerate(activations)
            )
        except ArgumentError as error:
            raise ModelError(f"the network under prefix {prefix!r} is invalid: {error}") from None


__all__ = ["Layer", "Mlp"]
