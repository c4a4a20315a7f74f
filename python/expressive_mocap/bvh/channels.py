"""The BVH channel layout: where each joint's numbers sit in a frame of the MOTION block, and
the conversion between channel values and local rotations and translations.

A frame holds ``skeleton.n_channels`` numbers, each joint's channels in file order (e.g.
``Xposition Yposition Zposition Zrotation Xrotation Yrotation``): angles in degrees, in the
joint's Euler order (:meth:`~expressive_mocap.motion.Skeleton.rotation_order`), and positions
that replace the components of the joint's rest offset.
"""

from __future__ import annotations

from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from .. import ops
from ..rotations.orders import AXES, ROTATION_CHANNELS, axes_of, rotation_order

if TYPE_CHECKING:  # the Skeleton's methods use this module
    from ..motion import Skeleton

__all__ = ["decode", "encode", "layout"]


def _frozen(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@lru_cache(maxsize=256)
def _layout(channels: tuple[tuple[str, ...], ...]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """See :func:`layout`. Cached: archives share a handful of channel layouts."""
    rot = np.full((len(channels), 3), -1, dtype=np.int64)
    pos = np.full((len(channels), 3), -1, dtype=np.int64)
    orders = np.zeros((len(channels), 3), dtype=np.uint8)
    column = 0
    for j, cs in enumerate(channels):
        order = rotation_order(cs)
        orders[j] = axes_of(order)
        for c in cs:
            if c in ROTATION_CHANNELS:
                rot[j, order.index(c[0])] = column
            else:
                pos[j, AXES.index(c[0])] = column
            column += 1
    return _frozen(rot), _frozen(orders), _frozen(pos)


def layout(skeleton: Skeleton) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where each joint's numbers sit in a frame of channel values: ``rotation_columns [J, 3]``
    (column of each angle, in the joint's order; -1 where there is no channel), ``orders [J, 3]``
    (axis indices) and ``position_columns [J, 3]`` (x, y, z; -1: none). Read-only arrays."""
    return _layout(skeleton.channels)


def decode(skeleton: Skeleton, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Channel values ``[F, C]`` -> local rotations ``[F, J, 4]`` and translations ``[F, J, 3]``."""
    return ops.decode_channels(values, *_layout(skeleton.channels), skeleton.offsets)


def encode(skeleton: Skeleton, rotations: np.ndarray, translations: np.ndarray) -> np.ndarray:
    """Local rotations and translations -> channel values ``[F, C]`` (the inverse of :func:`decode`)."""
    rot_cols, orders, pos_cols = _layout(skeleton.channels)
    angles = _prefer_written_axes(ops.quat_to_euler(rotations, orders), rot_cols >= 0)
    values = np.zeros((len(rotations), skeleton.n_channels))
    values[:, rot_cols[rot_cols >= 0]] = angles[:, rot_cols >= 0]
    values[:, pos_cols[pos_cols >= 0]] = translations[:, pos_cols >= 0]
    return values


def _prefer_written_axes(angles: np.ndarray, written: np.ndarray) -> np.ndarray:
    """Every rotation has two Tait-Bryan decompositions, (a, b, c) and (a + 180, 180 - b,
    c + 180). Where a joint has no channel for some axis, pick the one whose unwritten angles are
    nearer 0, so a rotation the channels can express is written exactly (``angles [F, J, 3]``,
    ``written [J, 3]``)."""
    missing = ~written
    if not missing.any():
        return angles
    other = angles + np.array([180.0, 0.0, 180.0])
    other[..., 1] = 180.0 - angles[..., 1]
    other = (other + 180.0) % 360.0 - 180.0
    cost = np.sum(np.abs(angles) * missing, axis=-1)
    other_cost = np.sum(np.abs(other) * missing, axis=-1)
    return np.where((other_cost < cost)[..., None], other, angles)
