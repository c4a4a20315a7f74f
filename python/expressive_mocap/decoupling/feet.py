"""Plausible decoupling edits: the stance feet kept where the body-mechanics source has them, and
the expressive component taken from chosen groups of joints only.

An edit that changes the legs' rotations (a stooped walk straightened by ``modulate --scale 0``, a
standing clip's foot turn laid on a walk by ``mix``) moves the feet in the frames where they
should rest on the floor. :func:`planted` puts each stance foot back where the motion that gives
the body mechanics has it, during that motion's contacts, with two-bone leg IK, the correction
spread over the swing between contacts.
"""

from __future__ import annotations

import numpy as np

from ..body.body import Body
from ..body.contacts import foot_contacts
from ..body.ik import two_bone_ik
from ..body.jointmap import JointMap
from ..body.names import ARM_ROLES, LEG_ROLES
from ..body.take import Take
from ..errors import ArgumentError
from ..motion import Motion, Skeleton
from ..rotations import quat

JOINT_GROUPS = ("all", "arms", "upper-body", "head", "legs")
# Both feet on the floor in at least this share of the frames: a clip that stands. Measured on the
# Bandai-Namco takes 001: walks 0.01-0.47, runs and dashes 0-0.09, gestures and bows 0.89-1.
STANDING_SHARE = 0.8
# The feet are held through each contact and this long either side of it: the contact detector
# starts a contact once the foot is slow, a frame or two after it lands.
GROW_SECONDS = 0.07


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


def joint_mask(skeleton: Skeleton, groups) -> np.ndarray:
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
    parts = _parts(skeleton, Body.of(skeleton).joint_map)
    return np.array([p in wanted for p in parts])


def stands(motion: Motion | Take) -> bool:
    """Whether ``motion`` stands: both feet on the floor in at least :data:`STANDING_SHARE` of its frames."""
    contacts = foot_contacts(motion)
    return bool(len(contacts)) and float(contacts.all(axis=1).mean()) >= STANDING_SHARE


def default_mask(body_source: Motion | Take, expressive_source: Motion | Take) -> np.ndarray:
    """The joints whose expressive component a mix or blend takes by default: all (the activity
    index decides how much), but not the legs when one source stands and the other does not (a
    standing clip's leg expression is a way of standing, not of walking, and the reverse)."""
    skeleton = Take.of(body_source).motion.skeleton
    if stands(body_source) != stands(expressive_source):
        return ~joint_mask(skeleton, "legs")
    return joint_mask(skeleton, "all")


def chosen_joints(joints, body_source: Motion | Take, expressive_source: Motion | Take) -> np.ndarray:
    """``bool [J]`` from ``joints``: None for :func:`default_mask`, group names
    (:func:`joint_mask`) or a boolean mask over the skeleton's joints."""
    if joints is None:
        return default_mask(body_source, expressive_source)
    skeleton = Take.of(body_source).motion.skeleton
    if isinstance(joints, np.ndarray) and joints.dtype == bool:
        if joints.shape != (skeleton.n_joints,):
            raise ArgumentError(
                f"joints: expected a mask of {skeleton.n_joints} joints, got shape {list(joints.shape)}"
            )
        return joints
    return joint_mask(skeleton, joints)


def _grown(contact: np.ndarray, frames: int) -> np.ndarray:
    """``contact bool [F]`` with each run grown by ``frames`` frames at both ends."""
    out = contact.copy()
    for i in range(1, frames + 1):
        out[i:] |= contact[:-i]
        out[:-i] |= contact[i:]
    return out


def _between_contacts(contact: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per frame of ``contact bool [F]``: the last contact frame at or before it, the first at or
    after it, and the smoothstep share ``s`` of the way from the one to the other (in a contact:
    the frame itself, s = 0; before the first contact or after the last, both are the nearest)."""
    frames = np.arange(len(contact))
    down = np.flatnonzero(contact)
    after = down[np.clip(np.searchsorted(down, frames), 0, len(down) - 1)]
    before = down[np.clip(np.searchsorted(down, frames, side="right") - 1, 0, len(down) - 1)]
    before = np.where(before > frames, after, before)
    after = np.where(after < frames, before, after)
    x = np.where(after > before, (frames - before) / np.maximum(after - before, 1), 0.0)
    return before, after, x * x * (3 - 2 * x)


def planted(guide: Motion | Take, edited: Motion, contacts: np.ndarray | None = None) -> tuple[Motion, np.ndarray]:
    """``edited`` with each stance foot put back where ``guide`` (the source of the body
    mechanics, on the same timeline, its hips where ``edited`` has them) has it: through each of
    ``guide``'s foot contacts the ankle goes where ``guide``'s is and the foot takes its world
    rotation, by two-bone leg IK; between two contacts the correction (of the ankle's place and
    of the foot's rotation) eases from the one at the end of the first to the one at the start of
    the next, so the swing carries the foot from where the edit would put it to where it lands
    without a jump. Returns it and ``guide``'s contacts ``bool [F, 2]``. A leg whose foot is not
    two joints below the upper leg is an :class:`~expressive_mocap.errors.ArgumentError`.
    ``contacts``: ``guide``'s, where read otherwise (Y up: a Z-up file's are read from it upright)."""
    take = Take.of(guide)
    guide, roles = take.motion, take.body.roles
    contacts = foot_contacts(take) if contacts is None else contacts
    parents = guide.skeleton.parents
    world_in, pos_in = take.fk
    world_out, pos_out = edited.fk()
    rotations = edited.rotations.copy()
    for s in (0, 1):
        hip, foot, toe = roles.upper_legs[s], roles.feet[s], roles.toes[s]
        knee = parents[foot]
        if knee < 0 or parents[knee] != hip:
            names = guide.skeleton.names
            raise ArgumentError(
                f"planting the feet needs a two-bone leg: {names[foot]} is not the grandchild of {names[hip]}; "
                "pass plant_feet=False (--no-foot-lock)"
            )
        # A foot the edit left where it was (its leg untouched: an arms-only mix) is left alone.
        if not contacts[:, s].any() or np.array_equal(pos_in[:, [foot, toe]], pos_out[:, [foot, toe]]):
            continue
        before, after, x = _between_contacts(_grown(contacts[:, s], int(round(GROW_SECONDS / guide.frame_time))))
        shift = pos_in[:, foot] - pos_out[:, foot]
        turn = quat.mul(world_in[:, foot], quat.conjugate(world_out[:, foot]))
        shift = (1 - x[:, None]) * shift[before] + x[:, None] * shift[after]
        turn = quat.slerp(turn[before], turn[after], x)
        t = edited.translations
        upper, lower = two_bone_ik(
            pos_out[:, hip], world_out[:, hip], world_out[:, knee], t[:, knee], t[:, foot], pos_out[:, foot] + shift
        )
        parent = parents[hip]
        rotations[:, hip] = quat.mul(quat.conjugate(world_out[:, parent]), upper) if parent >= 0 else upper
        rotations[:, knee] = quat.mul(quat.conjugate(upper), lower)
        rotations[:, foot] = quat.mul(quat.conjugate(lower), quat.mul(turn, world_out[:, foot]))
    return Motion(edited.skeleton, rotations, edited.translations, edited.frame_time), contacts


__all__ = [
    "JOINT_GROUPS",
    "STANDING_SHARE",
    "chosen_joints",
    "default_mask",
    "joint_mask",
    "planted",
    "stands",
]
