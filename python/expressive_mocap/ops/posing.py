"""Wrappers of the posing kernels: two-bone IK, foot planting and retargeting's rotation transfer."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..backend import kernels
from ..errors import ArgumentError
from ._args import _array, _f64


def two_bone_ik(root, upper, lower, upper_bone, lower_bone, target) -> tuple[np.ndarray, np.ndarray]:
    """New world rotations ``(upper, lower)`` ``[F, 4]`` of two-bone chains reaching for
    ``target [F, 3]`` (see :func:`expressive_mocap.body.ik.two_bone_ik`); ``upper_bone`` and
    ``lower_bone`` ``[3]`` (every frame's) or ``[F, 3]``."""
    root = _array("root", root, np.float64)
    frames = len(root) if root.ndim else 0

    def rows(name: str, value, width: int) -> np.ndarray:
        value = _array(name, value, np.float64)
        if value.ndim == 1 and value.shape == (width,) and name.endswith("bone"):
            value = np.ascontiguousarray(np.broadcast_to(value, (frames, width)))
        if value.shape != (frames, width):
            raise ArgumentError(f"argument `{name}`: expected shape [{frames}, {width}], got {list(value.shape)}")
        return value

    return kernels().two_bone_ik(
        rows("root", root, 3),
        rows("upper", upper, 4),
        rows("lower", lower, 4),
        rows("upper_bone", upper_bone, 3),
        rows("lower_bone", lower_bone, 3),
        rows("target", target, 3),
    )


def plant_feet(rotations, translations, parents, legs, contacts, guide, starts, blend: int) -> np.ndarray:
    """The local rotations ``[F, J, 4]`` of a motion with its feet planted (see
    :func:`expressive_mocap.skeletons.planting.plant_feet`): ``legs [2, 3]`` (hip, knee, foot;
    -1s: a leg left as it is), ``contacts bool [F, 2]``, ``guide [F, 2, 3]``, ``starts`` where
    clips laid end to end begin and the last one ends, ``blend`` frames of easing."""
    return kernels().plant_feet(
        _f64("rotations", rotations, 4),
        _f64("translations", translations, 3),
        _array("parents", parents, np.int64, "iu"),
        _array("legs", legs, np.int64, "iu"),
        np.ascontiguousarray(contacts, dtype=bool),
        _f64("guide", guide, 3),
        _array("starts", starts, np.int64, "iu"),
        int(blend),
    )


class TransferPlan(NamedTuple):
    """What :func:`retarget_transfer` does in every frame, made once per pair of skeletons (see
    :mod:`expressive_mocap.skeletons.retargeting`): per role its ``source`` and ``target`` joint
    and alignment ``aligns [R, 4]``; the roles ``swung`` onto the source's bone from joint
    ``starts`` to joint ``ends`` (at rest ``rest_lines [S, 3]``, canonical axes); the target's
    spine joints ``shared`` taking the share ``shares`` of the turn from ``tops`` to
    ``bottoms``; the target joints ``held`` with ``copied``, their nearest computed ancestor
    (-1: none); both as changes from ``reference [Jt, 4]``, the target's world rotations in its
    reference pose (canonical axes; the rest pose: all the identity); the target's ``parents``;
    both skeletons' turns onto the canonical axes."""

    source: np.ndarray
    target: np.ndarray
    aligns: np.ndarray
    swung: np.ndarray
    starts: np.ndarray
    ends: np.ndarray
    rest_lines: np.ndarray
    shared: np.ndarray
    tops: np.ndarray
    bottoms: np.ndarray
    shares: np.ndarray
    held: np.ndarray
    copied: np.ndarray
    reference: np.ndarray
    parents: np.ndarray
    turn_source: tuple[float, float, float, float]
    turn_target: tuple[float, float, float, float]

    @classmethod
    def of(cls, *parts) -> TransferPlan:
        """A plan of the parts in the fields' order, each coerced: index arrays int64,
        ``aligns``, ``reference`` and ``rest_lines`` float ``[N, 4]`` and ``[N, 3]``, turns four floats."""
        fields = dict(zip(cls._fields, parts))
        for name in ("aligns", "rest_lines", "shares", "reference"):
            fields[name] = _array(name, fields[name], np.float64)
        fields["aligns"] = fields["aligns"].reshape(-1, 4)
        fields["reference"] = fields["reference"].reshape(-1, 4)
        fields["rest_lines"] = fields["rest_lines"].reshape(-1, 3)
        for name in ("source", "target", "swung", "starts", "ends", "shared", "tops", "bottoms", "held", "copied"):
            value = np.asarray(fields[name])
            value = value.astype(np.int64) if value.size == 0 else value  # [] reads as floats
            fields[name] = _array(name, value, np.int64, "iu").reshape(-1)
        fields["parents"] = _array("parents", fields["parents"], np.int64, "iu")
        for name in ("turn_source", "turn_target"):
            fields[name] = tuple(float(v) for v in np.asarray(fields[name], dtype=np.float64).reshape(4))
        return cls(**fields)


def retarget_transfer(world, positions, plan: TransferPlan) -> np.ndarray:
    """The target skeleton's local rotations ``[F, Jt, 4]`` from the source's world rotations
    ``world [F, Js, 4]`` and positions ``positions [F, Js, 3]``, along ``plan``."""
    return kernels().retarget_transfer(_f64("world", world, 4), _f64("positions", positions, 3), plan)


__all__ = ["TransferPlan", "plant_feet", "retarget_transfer", "two_bone_ik"]
