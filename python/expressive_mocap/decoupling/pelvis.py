"""The pelvis posture a body-mechanics model predicts the spine for.

The network predicts the spine relative to the pelvis; but a neutral trunk stands upright in the
world whatever the pelvis does. An old walk tilts its pelvis 6 degrees forward and the prediction
leaned with it; another session's actor holds the pelvis 5 degrees otherwise, and its neutral walks
read as leaning. So the model learns and predicts the spine as if the pelvis held the posture of
the training clips (:class:`Pelvis`): each clip's first trunk joint is carried by
``C = P^-1 R`` (``P`` the clip's mean pelvis posture, ``R`` the training clips'), as a target
``C^-1 O`` in training and a prediction ``C B`` after.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from ..body.roles import JointRoles
from ..motion import Skeleton
from ..rotations import quat


class Pelvis(NamedTuple):
    """Where a model reads the pelvis posture: ``path``, the joints from the root to the hips
    (their local rotations compose the hips' world rotation); ``spine``, the joint above the hips
    that carries the trunk onto it; ``reference [4]``, the training clips' mean posture (the hips'
    world rotation, its yaw about the up axis Y removed)."""

    path: tuple[int, ...]
    spine: int
    reference: np.ndarray


def find_pelvis(skeleton: Skeleton, roles: JointRoles, neutral: Sequence[np.ndarray]) -> Pelvis | None:
    """The pelvis of ``skeleton``, its reference the mean posture over all frames of the
    ``neutral`` clips' local rotations; None without a trunk joint above the hips."""
    spine = roles.spine[1] if len(roles.spine) > 3 else None  # a joint between the hips and the neck
    if spine is None or not neutral:
        return None
    path = pelvis_path(skeleton, roles)
    reference = quat.mean_rotation(np.concatenate([postures(r, path) for r in neutral]))
    return Pelvis(path, int(spine), reference)


def carried(rotations: np.ndarray, pelvis: Pelvis | None, inverse: bool = False) -> np.ndarray:
    """A clip's local ``rotations [F, J, 4]`` with the spine carried by ``C`` (:func:`upright`
    of the clip's mean posture), or by ``C^-1`` (``inverse``: a training target); as they are
    without a ``pelvis``."""
    if pelvis is None:
        return rotations
    c = upright(mean_posture(rotations, pelvis.path), pelvis)
    out = np.array(rotations, dtype=np.float64, copy=True)
    out[:, pelvis.spine] = quat.mul((quat.conjugate(c) if inverse else c)[None], out[:, pelvis.spine])
    return out


def pelvis_path(skeleton: Skeleton, roles: JointRoles) -> tuple[int, ...]:
    """The joints from the root down to the hips, in that order."""
    path = [roles.hips]
    while skeleton.parents[path[-1]] >= 0:
        path.append(int(skeleton.parents[path[-1]]))
    return tuple(reversed(path))


def postures(rotations: np.ndarray, path: Sequence[int]) -> np.ndarray:
    """Per frame ``[F, 4]``: the hips' world rotation (the local ``rotations [F, J, 4]`` along
    ``path``) with its yaw about the up axis removed (what stays when the actor turns)."""
    world = rotations[:, path[0]]
    for j in path[1:]:
        world = quat.mul(world, rotations[:, j])
    yaw = np.zeros_like(world)
    yaw[:, 1], yaw[:, 3] = world[:, 1], world[:, 3]
    # A world rotation is yaw * (rotation about a level axis): yaw = (0, y, 0, w) normalised.
    return quat.mul(quat.conjugate(quat.normalize(yaw)), world)


def mean_posture(rotations: np.ndarray, path: Sequence[int]) -> np.ndarray:
    """The mean over frames of :func:`postures` ``[4]``."""
    return mean_postures(rotations, [len(rotations)], path)[0]


def mean_postures(rotations: np.ndarray, lengths: Sequence[int], path: Sequence[int]) -> np.ndarray:
    """:func:`mean_posture` ``[C, 4]`` of each of the clips whose local rotations follow each other
    in ``rotations [sum(lengths), J, 4]`` (a clip without frames: the identity), for them all at
    once (:func:`~expressive_mocap.rotations.quat.mean_rotations`)."""
    return quat.mean_rotations(postures(rotations, path), lengths)


def upright(posture: np.ndarray, pelvis: Pelvis) -> np.ndarray:
    """``C = P^-1 R`` ``[..., 4]``: what carries a spine predicted for the reference posture ``R``
    onto a pelvis of mean ``posture`` ``P`` (``[4]``, or one per frame ``[F, 4]``)."""
    return quat.mul(quat.conjugate(posture), np.broadcast_to(pelvis.reference, np.shape(posture)))


__all__ = ["Pelvis", "carried", "find_pelvis", "mean_posture", "mean_postures", "pelvis_path", "postures", "upright"]
