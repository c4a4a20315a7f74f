"""Public entry points of the kernels: coerce arguments, then call the backend in use.

Each function runs the Rust kernel or its NumPy twin (see :mod:`expressive_mocap.backend`);
both take and return float64 arrays. Leading batch dimensions are folded into frames.

Arrays written by another thread during a call: the Rust kernels run without the GIL, so
other Python threads run meanwhile. Index arrays (``parents``, channel columns, gait joints)
and bool flags are copied before the GIL is released, so a write to them during a call has no
effect on it: it is computed from the values at the call, or refused with a ValueError. Float
arrays are read in place (copying them would cost as much as some kernels): a write to one
during a call gives results computed from a mix of its old and new values, and nothing worse
(no crash, no error). Don't write to a kernel's inputs while it runs if you need its result.
"""

from __future__ import annotations

import numpy as np

from .backend import kernels
from . import motion  # its Euler order names (a module import: motion imports this module)


def _array(name: str, value, dtype, kinds: str = "biuf") -> np.ndarray:
    """``value`` as a C-contiguous array of ``dtype``; a ValueError naming the argument when its
    dtype kind is not one of ``kinds`` (numbers; integers only where indices are expected)."""
    array = np.asarray(value)
    if array.dtype.kind not in kinds:
        wanted = "integers" if kinds == "iu" else "numbers"
        raise ValueError(f"argument `{name}`: expected an array of {wanted}, got dtype {array.dtype}")
    return np.ascontiguousarray(array, dtype=dtype)


def _f64(name: str, array, last: int) -> np.ndarray:
    array = _array(name, array, np.float64)
    if array.ndim < 2 or array.shape[-1] != last:
        raise ValueError(f"argument `{name}`: expected shape [..., J, {last}], got {list(array.shape)}")
    return array


def _orders(orders, joints: int) -> np.ndarray:
    """Orders as a ``[J, 3]`` uint8 array from one order ("ZXY") or one per joint."""
    if isinstance(orders, str):
        orders = [orders] * joints
    axes = np.array([motion.axes_of(o) if isinstance(o, str) else o for o in orders], dtype=np.uint8)
    if axes.shape != (joints, 3):
        raise ValueError(f"argument `orders`: expected one order or {joints} orders, got {axes.shape[0]}")
    return axes


def euler_to_quat(angles, orders) -> np.ndarray:
    """Euler angles ``[..., J, 3]`` in degrees -> unit quaternions ``[..., J, 4]`` (x, y, z, w).

    ``orders``: one order such as ``"ZXY"`` (the BVH channel order, intrinsic, first channel
    outermost, like SciPy's upper-case orders) or a sequence of ``J`` orders.
    """
    angles = _f64("angles", angles, 3)
    batch = angles.shape[:-2]
    flat = angles.reshape(-1, *angles.shape[-2:])
    return kernels().euler_to_quat(flat, _orders(orders, angles.shape[-2])).reshape(*batch, angles.shape[-2], 4)


def quat_to_euler(quats, orders) -> np.ndarray:
    """Unit quaternions ``[..., J, 4]`` (x, y, z, w) -> Euler angles ``[..., J, 3]`` in degrees.

    The middle angle lies in [-90, 90]; at gimbal lock the third angle is 0.
    """
    quats = _f64("quats", quats, 4)
    batch = quats.shape[:-2]
    flat = quats.reshape(-1, *quats.shape[-2:])
    return kernels().quat_to_euler(flat, _orders(orders, quats.shape[-2])).reshape(*batch, quats.shape[-2], 3)


def forward_kinematics(rotations, translations, parents) -> tuple[np.ndarray, np.ndarray]:
    """World rotations ``[F, J, 4]`` and positions ``[F, J, 3]`` from local ones.

    ``rotations [F, J, 4]`` (x, y, z, w) and ``translations [F, J, 3]`` are relative to each
    joint's parent; ``parents [J]`` lists each joint after its parent, roots as -1.
    """
    rotations = _f64("rotations", rotations, 4)
    translations = _f64("translations", translations, 3)
    parents = _array("parents", parents, np.int64, "iu")
    if parents.ndim != 1:
        raise ValueError(f"argument `parents`: expected shape [J], got {list(parents.shape)}")
    return kernels().forward_kinematics(rotations, translations, parents)


def forward_kinematics_many(motions) -> list[tuple[np.ndarray, np.ndarray]]:
    """World rotations and positions of many motions at once (in parallel across motions with
    the Rust kernels: the way to run FK over an archive of short clips)."""
    clips = [(m.rotations, m.translations, np.ascontiguousarray(m.skeleton.parents, dtype=np.int64)) for m in motions]
    return kernels().forward_kinematics_many(clips)


def decode_channels(values, rotation_columns, orders, position_columns, offsets) -> tuple[np.ndarray, np.ndarray]:
    """BVH channel values ``[F, C]`` -> local rotations ``[F, J, 4]`` and translations ``[F, J, 3]``.

    The layout arrays are those of :meth:`Skeleton.layout`; ``offsets [J, 3]`` are the rest offsets.
    """
    values = _array("values", values, np.float64)
    if values.ndim != 2:
        raise ValueError(f"argument `values`: expected shape [F, C], got {list(values.shape)}")
    rotation_columns = _array("rotation_columns", rotation_columns, np.int64, "iu")
    orders = _array("orders", orders, np.uint8, "iu")
    position_columns = _array("position_columns", position_columns, np.int64, "iu")
    offsets = _array("offsets", offsets, np.float64)
    joints = len(orders)
    for name, array in (("rotation_columns", rotation_columns), ("orders", orders), ("position_columns", position_columns), ("offsets", offsets)):
        if array.shape != (joints, 3):
            raise ValueError(f"argument `{name}`: expected shape [{joints}, 3] (one row per joint), got {list(array.shape)}")
    return kernels().decode_channels(values, rotation_columns, orders, position_columns, offsets)


def decouple_rotations(original, body, gain: float = 2.0, exponent: float = 4.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split local rotations ``original [F, J, 4]`` given body-mechanics rotations ``body``:
    ``E = O B^-1``; activity ``A = clip((tanh(angle(E)) * gain)^exponent, 0, 1)`` ``[F, J]``;
    filtered expressive component ``E* = E^A``; recovered body mechanics ``B' = E*^-1 O``.
    Returns ``(E*, B', A)``; ``E* * B' = O`` exactly."""
    original, body = _f64("original", original, 4), _f64("body", body, 4)
    batch = original.shape[:-1]
    e, b, a = kernels().decouple_rotations(_frames(original), _frames(body), float(gain), float(exponent))
    return e.reshape(original.shape), b.reshape(original.shape), a.reshape(batch)


def compose_rotations(expressive, body, scale: float = 1.0) -> np.ndarray:
    """``expressive^scale * body`` for rotations ``[F, J, 4]`` (modulation of expressiveness)."""
    expressive, body = _f64("expressive", expressive, 4), _f64("body", body, 4)
    return kernels().compose_rotations(_frames(expressive), _frames(body), float(scale)).reshape(body.shape)


def _frames(array: np.ndarray) -> np.ndarray:
    """``[..., J, k]`` as ``[F, J, k]``, all leading dimensions folded into frames."""
    return array.reshape(-1, *array.shape[-2:])


def _float(name: str, array) -> np.ndarray:
    """``array`` as a C-contiguous float32 or float64 array (float32 kept, other numbers float64)."""
    array = np.asarray(array)
    return _array(name, array, np.float32 if array.dtype == np.float32 else np.float64)


def mlp_forward(x, weights, biases, activations) -> np.ndarray:
    """Batched forward pass of a dense network: ``h = act_i(h @ weights[i] + biases[i])``.

    ``x [..., in]`` float32 or float64 (kept; other dtypes become float64), leading dimensions
    folded into rows; ``weights[i] [in_i, out_i]``, ``biases[i] [out_i]`` (cast to the dtype of
    ``x``), ``activations[i]`` ``"tanh"`` or ``"linear"``. Returns ``[..., out]``.
    """
    x = _float("x", x)
    if x.ndim < 1:
        raise ValueError(f"argument `x`: expected shape [..., in], got {list(x.shape)}")
    weights, biases, activations = list(weights), list(biases), [str(a) for a in activations]
    for name, items in (("biases", biases), ("activations", activations)):
        if len(items) != len(weights):
            raise ValueError(f"argument `{name}`: expected one for each of the {len(weights)} layers, got {len(items)}")
    for i, (w, b) in enumerate(zip(weights, biases)):
        if np.ndim(w) != 2:
            raise ValueError(f"argument `weights`: layer {i} must be 2-D [in, out], got shape {list(np.shape(w))}")
        if np.ndim(b) != 1:
            raise ValueError(f"argument `biases`: layer {i} must be 1-D [out], got shape {list(np.shape(b))}")
    weights = [_array("weights", w, x.dtype) for w in weights]
    biases = [_array("biases", b, x.dtype) for b in biases]
    batch = x.shape[:-1]
    flat = x.reshape(-1, x.shape[-1])
    out = kernels().mlp_forward(flat, weights, biases, activations)
    return out.reshape(*batch, out.shape[-1])
