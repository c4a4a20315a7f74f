"""Names of Euler orders. An order is written as in a BVH CHANNELS line, e.g. ``"ZXY"``:
intrinsic rotations, the first channel outermost, i.e. ``R = Rz(a) @ Rx(b) @ Ry(c)``
(SciPy: ``Rotation.from_euler("ZXY", [a, b, c], degrees=True)``)."""

from __future__ import annotations

from .errors import MocapError

AXES = "XYZ"
ORDERS = ("XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX")


def axes_of(order: str) -> tuple[int, int, int]:
    """``"ZXY"`` -> ``(2, 0, 1)``."""
    upper = order.upper()
    if upper not in ORDERS:
        raise MocapError(f"rotation order must be one of {', '.join(ORDERS)}, got {order!r}")
    return tuple(AXES.index(a) for a in upper)


def order_name(axes) -> str:
    """``(2, 0, 1)`` -> ``"ZXY"``."""
    return "".join(AXES[int(a)] for a in axes)
