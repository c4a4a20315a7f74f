"""Heading frames: each frame of a motion seen from the body's own place and facing on the floor.

A motion's world is first *harmonised*: turned so that its up axis is +Y and the skeleton's
facing axis +Z (:func:`~expressive_mocap.body.conventions.up_and_facing`, read from the data).
A frame's **heading frame** then has its origin on the floor under the hips (the file's ground
plane, up coordinate 0), Y up, +Z the body's facing projected on the floor and +X the body's left.
The facing is read from the hips line and the shoulder line (left minus right joint, each
projected on the floor and made unit, summed; forward = left x up). Its **yaw** is the angle about
+Y from the harmonised +Z to that facing, in radians.

``world -> heading``: ``p_h = R_y(-yaw) (T p - origin)``, with ``T`` the harmonising turn and
``origin`` the hips in harmonised axes with their up coordinate set to 0;
:func:`to_heading` and :func:`from_heading` are each other's inverse.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..body.body import Body
from ..body.conventions import AXES, facing_of, frame_rotation, up_of
from ..motion import Skeleton
from ..rotations import quat


@dataclass(frozen=True)
class HeadingFrame:
    """What heading frames of a skeleton's motion need: the harmonising ``turn`` (quaternion)
    and its ``matrix``, the file's ``up`` axis ``[3]``, the ``hips`` joint and the (left, right)
    joint ``pairs`` whose lines give the facing (upper legs, then upper arms when present)."""

    turn: np.ndarray
    matrix: np.ndarray
    up: tuple[float, float, float]
    hips: int
    pairs: tuple[tuple[int, int], ...]

    @classmethod
    def of(cls, skeleton: Skeleton, positions: np.ndarray) -> HeadingFrame:
        """The heading frame of ``skeleton`` whose world positions ``[F, J, 3]`` (a sample of
        frames is enough) show its up axis. Raises MocapError when its hips, legs or head are
        not found (:func:`~expressive_mocap.body.jointmap.find_joint_map`)."""
        return cls.for_up(skeleton, up_of(Body.of(skeleton).joint_map, positions)[0])

    @classmethod
    def for_up(cls, skeleton: Skeleton, up: str) -> HeadingFrame:
        """The heading frame of ``skeleton`` whose up axis is ``up`` (an axis name, ``"+Y"``)."""
        jmap = Body.of(skeleton).joint_map
        facing, _ = facing_of(skeleton, jmap, up)
        turn = frame_rotation(up, facing)
        pairs = [("left_upper_leg", "right_upper_leg"), ("left_upper_arm", "right_upper_arm")]
        found = tuple((jmap[a], jmap[b]) for a, b in pairs if a in jmap.joints and b in jmap.joints)
        up_axis = tuple(float(v) for v in AXES[up])
        return cls(turn, quat.to_matrix(turn), up_axis, jmap["hips"], found)  # type: ignore[arg-type]

    def harmonised(self, points: np.ndarray) -> np.ndarray:
        """Points or directions ``[..., 3]`` in harmonised axes (Y up, +Z the skeleton's facing)."""
        if np.array_equal(self.matrix, np.eye(3)):  # Y up and facing +Z already
            return points
        return points @ self.matrix.T

    def yaw(self, positions: np.ndarray) -> np.ndarray:
        """Each frame's yaw ``[F]`` (radians, see the module's notes) from world positions ``[F, J, 3]``."""
        left = np.zeros(positions.shape[:1] + (2,))
        for a, b in self.pairs:
            line = self.harmonised(positions[:, a] - positions[:, b])[:, [0, 2]]
            length = np.linalg.norm(line, axis=-1, keepdims=True)
            left += line / np.where(length > 1e-12, length, 1.0)
        return np.arctan2(-left[:, 1], left[:, 0])  # forward = left x up = (-left_z, 0, left_x)

    def origin(self, positions: np.ndarray) -> np.ndarray:
        """Each frame's heading origin ``[F, 3]`` in harmonised axes: the hips on the floor."""
        origin = np.array(self.harmonised(positions[:, self.hips]))
        origin[:, 1] = 0.0
        return origin


def turn_by_yaw(vectors: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """Vectors ``[F, ..., 3]`` turned about +Y by ``yaw [F]`` radians (``R_y(yaw) v``)."""
    shape = (-1,) + (1,) * (vectors.ndim - 2)
    cos, sin = np.cos(yaw).reshape(shape), np.sin(yaw).reshape(shape)
    x, z = vectors[..., 0], vectors[..., 2]
    out = np.empty(np.broadcast_shapes(vectors.shape, cos.shape + (3,)))
    out[..., 0] = cos * x + sin * z
    out[..., 1] = vectors[..., 1]
    out[..., 2] = cos * z - sin * x
    return out


def to_heading(points: np.ndarray, frame: HeadingFrame, yaw: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """World points ``[F, ..., 3]`` in each frame's heading frame (``yaw [F]``, ``origin [F, 3]``)."""
    shape = origin.shape[:1] + (1,) * (points.ndim - 2) + (3,)
    return turn_by_yaw(frame.harmonised(points) - origin.reshape(shape), -yaw)


def from_heading(points: np.ndarray, frame: HeadingFrame, yaw: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """The inverse of :func:`to_heading`: heading-frame points ``[F, ..., 3]`` back in world axes."""
    shape = origin.shape[:1] + (1,) * (points.ndim - 2) + (3,)
    return (turn_by_yaw(points, yaw) + origin.reshape(shape)) @ frame.matrix


def heading_rotation(frame: HeadingFrame, yaw: np.ndarray) -> np.ndarray:
    """Each frame's world -> heading rotation as quaternions ``[F, 4]`` (``R_y(-yaw) T``)."""
    return quat.mul(quat.about("Y", -np.degrees(yaw)), frame.turn)


__all__ = ["HeadingFrame", "from_heading", "heading_rotation", "to_heading", "turn_by_yaw"]
