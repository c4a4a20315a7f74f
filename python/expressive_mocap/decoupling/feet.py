"""Plausible decoupling edits: the expressive component taken from chosen groups of joints only
(a standing clip's leg expression is a way of standing, not of walking)."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..features import foot_contacts
from ..motion import Motion, Skeleton
from ..roles import JointRoles
from ..skeletons.jointmap import JointMap, find_joint_map
from ..skeletons.names import ARM_ROLES, LEG_ROLES

JOINT_GROUPS = ("all", "arms", "upper-body", "head", "legs")
# Both feet on the floor in at least this share of the frames: a clip that stands (a walk has both
# down in about a quarter of its frames, a run in none).
STANDING_SHARE = 0.8


def _parts(skeleton: Skeleton, jmap: JointMap) -> list[str]:
    """Each joint's part: ``"legs"``, ``"arms"``, ``"head"`` (neck and head), ``"torso"`` (the
    spine above the hips) or ``"root"`` (the hips and what is above them); joints without a role
    take their parent's part (fingers are the hand's, a toe end the foot's)."""
    part: dict[int, str] = {}
    for role, joint in jmap.joints.items():
        name = role.split("_", 1)[-1]
        if name in LEG_ROLES:
            part[joint] = "legs"
        elif name in ARM_ROLES:
            part[joint] = "arms"
        elif role in ("neck", "head"):
            part[joint] = "head"
        elif role == "chest":
            part[joint] = "torso"
        else:
            part[joint] = "root"
    for joint in jmap.spine:
        part.setdefault(joint, "torso")
    out: list[str] = []
    for j, parent in enumerate(skeleton.parents):  # parents come before their children
        out.append(part.get(j, out[parent] if parent >= 0 else "root"))
    return out


_GROUP_PARTS = {
    "arms": {"arms"},
    "head": {"head"},
    "legs": {"legs"},
    "upper-body": {"arms", "head", "torso"},
    "all": {"arms", "head", "torso", "legs", "root"},
}


def joint_mask(skeleton: Skeleton, groups, jmap: JointMap | None = None) -> np.ndarray:
    """``bool [J]``: the joints of ``skeleton`` in any of ``groups`` (names of
    :data:`JOINT_GROUPS`: ``arms`` from the clavicles to the fingers, ``head`` the neck and head,
    ``legs`` from the upper legs to the toes, ``upper-body`` the spine above the hips, arms and
    head, ``all`` every joint)."""
    groups = [groups] if isinstance(groups, str) else list(groups)
    unknown = [g for g in groups if g not in _GROUP_PARTS]
    if unknown or not groups:
        raise ArgumentError(
            f"joints: unknown group(s) {', '.join(unknown) or '(none given)'}; groups are {', '.join(JOINT_GROUPS)}"
        )
    wanted = set().union(*(_GROUP_PARTS[g] for g in groups))
    parts = _parts(skeleton, jmap or find_joint_map(skeleton))
    return np.array([p in wanted for p in parts])


def stands(motion: Motion, roles: JointRoles | None = None, contacts: np.ndarray | None = None) -> bool:
    """Whether ``motion`` stands: both feet on the floor in at least :data:`STANDING_SHARE` of its frames."""
    contacts = foot_contacts(motion, roles) if contacts is None else contacts
    return bool(len(contacts)) and float(contacts.all(axis=1).mean()) >= STANDING_SHARE


def default_mask(
    body_source: Motion, expressive_source: Motion, roles: JointRoles | None = None, jmap: JointMap | None = None
) -> np.ndarray:
    """The joints whose expressive component a mix or blend takes by default: all (the activity
    index decides how much), but not the legs when one source stands and the other does not (a
    standing clip's leg expression is a way of standing, not of walking, and the reverse)."""
    skeleton = body_source.skeleton
    if stands(body_source, roles) != stands(expressive_source, roles):
        return ~joint_mask(skeleton, "legs", jmap)
    return joint_mask(skeleton, "all", jmap)


def chosen_joints(
    joints, body_source: Motion, expressive_source: Motion, roles: JointRoles | None = None
) -> np.ndarray:
    """``bool [J]`` from ``joints``: None for :func:`default_mask`, group names
    (:func:`joint_mask`) or a boolean mask over the skeleton's joints."""
    if joints is None:
        return default_mask(body_source, expressive_source, roles)
    if isinstance(joints, np.ndarray) and joints.dtype == bool:
        if joints.shape != (body_source.skeleton.n_joints,):
            raise ArgumentError(
                f"joints: expected a mask of {body_source.skeleton.n_joints} joints, got shape {list(joints.shape)}"
            )
        return joints
    return joint_mask(body_source.skeleton, joints)


__all__ = [
    "JOINT_GROUPS",
    "STANDING_SHARE",
    "chosen_joints",
    "default_mask",
    "joint_mask",
    "stands",
]
