"""Wrappers of the rotation kernels: Euler angles to quaternions and back, forward kinematics,
channel decoding, the decoupling algebra's per-joint products, rotation matrix columns."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..backend import kernels
from ..errors import ArgumentError
from ._args import _array, _f64, _frames, _orders


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
        raise ArgumentError(f"argument `parents`: expected shape [J], got {list(parents.shape)}")
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
        raise ArgumentError(f"argument `values`: expected shape [F, C], got {list(values.shape)}")
    rotation_columns = _array("rotation_columns", rotation_columns, np.int64, "iu")
    orders = _array("orders", orders, np.uint8, "iu")
    position_columns = _array("position_columns", position_columns, np.int64, "iu")
    offsets = _array("offsets", offsets, np.float64)
    joints = len(orders)
    for name, array in (
        ("rotation_columns", rotation_columns),
        ("orders", orders),
        ("position_columns", position_columns),
        ("offsets", offsets),
    ):
        if array.shape != (joints, 3):
            raise ArgumentError(
                f"argument `{name}`: expected shape [{joints}, 3] (one row per joint), got {list(array.shape)}"
            )
    return kernels().decode_channels(values, rotation_columns, orders, position_columns, offsets)


def decouple_rotations(original, body, gain: float, exponent: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Split local rotations ``original [F, J, 4]`` given body-mechanics rotations ``body``:
    ``E = O B^-1``; activity ``A = clip((tanh(angle(E)) * gain)^exponent, 0, 1)`` ``[F, J]``;
    filtered expressive component ``E* = E^A``; recovered body mechanics ``B' = E*^-1 O``.
    Returns ``(E*, B', A)``; ``E* * B' = O`` exactly. ``gain`` and ``exponent`` have no default
    here: the package's are ``decouple.GAIN`` and ``decouple.EXPONENT``, passed by its callers."""
    original, body = _f64("original", original, 4), _f64("body", body, 4)
    batch = original.shape[:-1]
    e, b, a = kernels().decouple_rotations(_frames(original), _frames(body), float(gain), float(exponent))
    return e.reshape(original.shape), b.reshape(original.shape), a.reshape(batch)


class Trunk(NamedTuple):
    """The trunk read as one chain by :func:`split_rotations`: ``joints`` from the hips up (each
    the parent of the next), ``bones`` the bone each carries (the next one's rest offset; the
    last one's, the neck's), so that the trunk line runs from the first to the neck; ``scale``
    the divisor of the angle between the original's and the body mechanics' trunk lines before
    the activity index reads it."""

    joints: tuple[int, ...]
    bones: tuple[tuple[float, float, float], ...]
    scale: float


class Arms(NamedTuple):
    """Limbs :func:`split_rotations` filters in world axes (a relaxed arm hangs in the world as
    the actor's does, whatever the body mechanics do to the trunk above it): ``limbs`` (parents
    before children), ``parents`` the skeleton's."""

    parents: tuple[int, ...]
    limbs: tuple[int, ...]


def split_rotations(
    original,
    body,
    gain: float,
    exponent: float,
    scale=None,
    body_sigma: float = 0.0,
    activity_sigma: float = 0.0,
    trunk: Trunk | None = None,
    arms: Arms | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One clip's :func:`decouple_rotations` (``[F, J, 4]``) with ``body`` smoothed over
    ``body_sigma`` frames and the activity, read from ``angle(E) / scale`` (``[J]``, None: 1),
    over ``activity_sigma`` frames (Gaussians, the ends held; 0: none). ``trunk``: its joints are
    at least as active as the chain's lean reads (a lean spread over several joints, a few degrees
    each, counts as the chain's); ``arms``: limbs filtered in world axes. Returns ``(E*, B', A)``."""
    original, body = _f64("original", original, 4), _f64("body", body, 4)
    if original.ndim != 3:
        raise ArgumentError(f"argument `original`: expected shape [F, J, 4] (one clip), got {list(original.shape)}")
    scale = np.ones(original.shape[1]) if scale is None else _array("scale", scale, np.float64)
    return kernels().split_rotations(
        original,
        body,
        float(gain),
        float(exponent),
        scale,
        float(body_sigma),
        float(activity_sigma),
        **_chains(trunk, arms),
    )


def split_rotations_many(
    originals: list,
    bodies: list,
    gain: float,
    exponent: float,
    scale=None,
    body_sigmas=None,
    activity_sigmas=None,
    trunk: Trunk | None = None,
    arms: Arms | None = None,
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """:func:`split_rotations` of many clips (``originals``, ``bodies``: ``[F, J, 4]`` each, the
    same joints) in one kernel call, clips in parallel, each smoothed over its own
    ``body_sigmas`` and ``activity_sigmas`` frames (None: 0 for every clip); the same results
    as clip by clip."""
    originals = [_f64("originals", o, 4) for o in originals]
    bodies = [_f64("bodies", b, 4) for b in bodies]
    for o in originals:
        if o.ndim != 3:
            raise ArgumentError(f"argument `originals`: expected clips of shape [F, J, 4], got {list(o.shape)}")
    joints = originals[0].shape[1] if originals else 0
    scale = np.ones(joints) if scale is None else _array("scale", scale, np.float64)
    zeros = [0.0] * len(originals)
    return kernels().split_rotations_many(
        originals,
        bodies,
        float(gain),
        float(exponent),
        scale,
        zeros if body_sigmas is None else [float(s) for s in body_sigmas],
        zeros if activity_sigmas is None else [float(s) for s in activity_sigmas],
        **_chains(trunk, arms),
    )


def _chains(trunk: Trunk | None, arms: Arms | None) -> dict:
    """A :class:`Trunk` and :class:`Arms` as the kernels' keyword arguments (none for None)."""
    chains: dict = {}
    if trunk is not None:
        chains["trunk_joints"] = [int(j) for j in trunk.joints]
        chains["trunk_bones"] = [tuple(float(v) for v in bone) for bone in trunk.bones]
        chains["trunk_scale"] = float(trunk.scale)
    if arms is not None:
        chains["arm_parents"] = [int(p) for p in arms.parents]
        chains["arm_joints"] = [int(j) for j in arms.limbs]
    return chains


def compose_rotations(expressive, body, scale: float = 1.0) -> np.ndarray:
    """``expressive^scale * body`` for rotations ``[F, J, 4]`` (modulation of expressiveness)."""
    expressive, body = _f64("expressive", expressive, 4), _f64("body", body, 4)
    return kernels().compose_rotations(_frames(expressive), _frames(body), float(scale)).reshape(body.shape)


def matrix_columns(quats, columns: int) -> np.ndarray:
    """Unit quaternions ``[..., 4]`` as float32 rotation matrices: ``[..., 9]`` row after row
    (``columns`` 3) or ``[..., 6]`` their first two columns, column after column (2: the 6D form)."""
    quats = _array("quats", quats, np.float64)
    if quats.shape[-1:] != (4,):
        raise ArgumentError(f"argument `quats`: expected shape [..., 4], got {list(quats.shape)}")
    flat = kernels().matrix_columns(quats.reshape(-1, 4), int(columns))
    return flat.reshape(quats.shape[:-1] + flat.shape[1:])


__all__ = [
    "Arms",
    "Trunk",
    "compose_rotations",
    "decode_channels",
    "decouple_rotations",
    "split_rotations",
    "split_rotations_many",
    "euler_to_quat",
    "forward_kinematics",
    "forward_kinematics_many",
    "matrix_columns",
    "quat_to_euler",
]
