"""Twin of ``rust/fk.rs``: forward kinematics, one loop over joints vectorised over frames."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..rotations import quat


def forward_kinematics(
    rotations: np.ndarray, translations: np.ndarray, parents: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """World rotations ``[F, J, 4]`` and positions ``[F, J, 3]`` from local ones and ``parents [J]``."""
    parents = np.asarray(parents)
    joints = len(parents)
    for j, p in enumerate(parents.tolist()):
        if not -1 <= p < j:
            raise ArgumentError(
                f"argument `parents`: joint {j} has parent {p}: parents must be -1 (root) or an earlier joint"
            )
    if rotations.ndim != 3 or rotations.shape[1:] != (joints, 4):
        raise ArgumentError(f"argument `rotations`: expected shape [F, {joints}, 4], got {list(rotations.shape)}")
    if translations.shape != rotations.shape[:2] + (3,):
        raise ArgumentError(
            f"argument `translations`: expected shape [{rotations.shape[0]}, {joints}, 3], got "
            f"{list(translations.shape)}"
        )
    world_rot = np.empty_like(rotations, dtype=np.float64)
    world_pos = np.empty_like(translations, dtype=np.float64)
    for j, p in enumerate(parents.tolist()):
        if p < 0:
            world_rot[:, j] = rotations[:, j]
            world_pos[:, j] = translations[:, j]
        else:
            world_rot[:, j] = quat.mul(world_rot[:, p], rotations[:, j])
            world_pos[:, j] = world_pos[:, p] + quat.rotate(world_rot[:, p], translations[:, j])
    return world_rot, world_pos


def forward_kinematics_many(clips: list) -> list:
    """:func:`forward_kinematics` of each ``(rotations, translations, parents)`` triple."""
    return [forward_kinematics(*clip) for clip in clips]


__all__ = [
    "forward_kinematics",
    "forward_kinematics_many",
]
