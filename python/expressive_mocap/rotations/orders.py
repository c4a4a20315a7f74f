"""Euler orders and the six BVH channel names: how a joint's CHANNELS line says which axes it
turns about, in which order."""

from __future__ import annotations

from functools import lru_cache

from .._utils.tokens import shown
from ..errors import MocapError

# Euler orders. An order is written as in a BVH CHANNELS line, e.g. "ZXY": intrinsic rotations, the
# first channel outermost, i.e. R = Rz(a) @ Rx(b) @ Ry(c) (SciPy: Rotation.from_euler("ZXY", [a, b, c],
# degrees=True)).
AXES = "XYZ"
ORDERS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")


def axes_of(order: str) -> tuple[int, int, int]:
    """``"ZXY"`` -> ``(2, 0, 1)``."""
    upper = order.upper()
    if upper not in ORDERS:
        raise MocapError(f"rotation order must be one of {', '.join(ORDERS)}, got {order!r}")
    first, second, third = (AXES.index(a) for a in upper)
    return first, second, third


def order_name(axes) -> str:
    """``(2, 0, 1)`` -> ``"ZXY"``."""
    return "".join(AXES[int(a)] for a in axes)


# The six BVH channels, by their canonical names.
POSITION_CHANNELS = tuple(f"{a}position" for a in AXES)
ROTATION_CHANNELS = tuple(f"{a}rotation" for a in AXES)
_CANONICAL = {c.lower(): c for c in POSITION_CHANNELS + ROTATION_CHANNELS}


def canonical_channel(name: str) -> str:
    """``"xROTATION"`` -> ``"Xrotation"``; raises for anything that is not one of the six BVH channels."""
    try:
        return _CANONICAL[name.lower()]
    except KeyError:
        raise MocapError(f"unknown channel {shown(name)}: expected one of {', '.join(_CANONICAL.values())}") from None


@lru_cache(maxsize=1024)
def canonical_channels(names: tuple[str, ...]) -> tuple[str, ...]:
    """:func:`canonical_channel` of each name (cached: files repeat a few channel lists)."""
    return tuple(canonical_channel(n) for n in names)


def rotation_order(channels: tuple[str, ...]) -> str:
    """The Euler order of a joint's canonical ``channels`` as written (e.g. ``"ZXY"``); axes without
    a channel follow in X, Y, Z order; ``"XYZ"`` for a joint without rotations."""
    written = [c[0] for c in channels if c in ROTATION_CHANNELS]
    return "".join(written + [a for a in AXES if a not in written])


__all__ = [
    "AXES",
    "ORDERS",
    "POSITION_CHANNELS",
    "ROTATION_CHANNELS",
    "axes_of",
    "canonical_channel",
    "canonical_channels",
    "order_name",
    "rotation_order",
]
