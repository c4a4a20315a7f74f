"""The DOF parameterisation: per joint the rotation vector of ``m_j^-1 q_j`` (or Euler angles
relative to the mean) and the hips height over the actor height, ``D = 3 J + 1`` DOFs; their
names and weights (the bone length a joint moves)."""

from __future__ import annotations

import numpy as np

from ..body.roles import JointRoles
from ..motion import Skeleton
from ..ops import euler_to_quat, quat_to_euler
from ..rotations import quat
from .cycles import SampledCycles
from .settings import TRAINING


def subtree_weights(skeleton: Skeleton) -> np.ndarray:
    """``w_j [J]``: the summed length of every bone below joint ``j`` (its children's offsets, their
    children's, ..., End Sites included): a shoulder moves the whole arm."""
    weights = np.zeros(skeleton.n_joints)
    for j, off in skeleton.end_sites:
        weights[j] += float(np.linalg.norm(off))
    for j in range(skeleton.n_joints - 1, 0, -1):  # children come after parents
        parent = skeleton.parents[j]
        weights[parent] += weights[j] + float(np.linalg.norm(skeleton.offsets[j]))
    return weights


def dof_weights(skeleton: Skeleton, roles: JointRoles, joint_weights: np.ndarray) -> np.ndarray:
    """``[D]``: each joint's weight ``joint_weights [J]`` on its three DOFs, then the hips height's:
    the root's when the hips are the root, else the hips' own."""
    w = joint_weights
    return np.append(np.repeat(w, 3), w[0] if skeleton.parents[roles.hips] < 0 else w[roles.hips])


def dof_names(skeleton: Skeleton, representation: str = TRAINING.representation) -> list[str]:
    """Names of the ``3 J + 1`` DOFs: ``Joint.rx ry rz`` (rotation vector) or ``Joint.Zrot ...`` (Euler,
    in the joint's order), then ``Hips.height``."""
    names = []
    for j, joint in enumerate(skeleton.names):
        axes = "xyz" if representation == "rotvec" else skeleton.rotation_order(j)
        names += [f"{joint}.r{a}" if representation == "rotvec" else f"{joint}.{a}rot" for a in axes]
    return names + ["Hips.height"]


def _wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def rotations_to_dofs(
    rotations: np.ndarray, reference: np.ndarray, representation: str, orders: np.ndarray
) -> np.ndarray:
    """Local rotations ``[N, J, 4]`` (heading removed) -> rotation DOFs ``[N, 3 J]`` relative to the
    ``reference [J, 4]`` (rotation vector of ``ref^-1 q``, or Euler angles minus the reference's,
    wrapped to (-pi, pi], radians)."""
    if representation == "rotvec":
        return quat.log(quat.mul(quat.conjugate(reference)[None], rotations)).reshape(len(rotations), -1)
    angles = np.radians(quat_to_euler(rotations, orders)) - np.radians(quat_to_euler(reference[None], orders))
    return _wrap(angles).reshape(len(rotations), -1)


def dofs_to_rotations(dofs: np.ndarray, reference: np.ndarray, representation: str, orders: np.ndarray) -> np.ndarray:
    """The inverse of :func:`rotations_to_dofs`: ``[N, 3 J]`` -> ``[N, J, 4]``."""
    dofs = dofs.reshape(len(dofs), -1, 3)
    if representation == "rotvec":
        return quat.mul(reference[None], quat.exp(dofs))
    angles = np.degrees(dofs + np.radians(quat_to_euler(reference[None], orders)))
    return euler_to_quat(angles, orders)


def sampled_dofs(sampled: SampledCycles, reference: np.ndarray, representation: str, orders: np.ndarray) -> np.ndarray:
    """DOFs ``[C, T, D]`` of time-normalised cycles, rotations measured from ``reference [J, 4]``."""
    C, T, J, _ = sampled.rotations.shape
    rot = rotations_to_dofs(sampled.rotations.reshape(C * T, J, 4), reference, representation, orders)
    return np.concatenate([rot.reshape(C, T, 3 * J), sampled.heights[..., None]], axis=-1)


__all__ = ["dof_names", "dof_weights", "dofs_to_rotations", "rotations_to_dofs", "sampled_dofs", "subtree_weights"]
