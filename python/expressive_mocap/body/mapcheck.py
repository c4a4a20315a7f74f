"""A joint map checked as a whole, so that it cannot put a chest on a toe or a left arm on a right
shoulder (which retargeted whole bodies 1-2 heights off, or to NaN, without a word).

:func:`check_joint_map`, whenever a map is found or given: each role on a joint of its own, every
chain of roles connected in the hierarchy (hips -> spine -> chest -> neck -> head, chest ->
clavicle -> upper arm -> forearm -> hand, hips -> upper leg -> lower leg -> foot -> toes), each
side's limbs apart from the other's, the legs off the trunk above the hips, the head off the arms.
:func:`check_posed_map`, whenever a motion's conventions are read: in most of its frames, the feet
on the other side of the hips from the head, the left arm on the left leg's side and, where the
map file gave a side's roles, the toes pointing forwards. A rest pose cannot tell these
(Bandai-Namco's lays every bone along X), a motion's frames can. A map that fails is refused with
one line naming the role and the joint.

Every map the package finds passes: those of all 3,076 Bandai-Namco clips, the files on other
rigs and the synthetic rigs (tests/body/test_mapcheck.py).
"""

from __future__ import annotations

import numpy as np

from .._utils.tokens import listed, shown
from ..errors import MocapError
from .names import ARM_ROLES, LEG_ROLES

# Each role's nearest role up its chain, in order of preference (the first mapped one).
_UP_THE_CHAIN = {
    "chest": ("hips",),
    "neck": ("chest",),
    "head": ("neck", "chest"),
    "clavicle": ("chest",),
    "upper_arm": ("clavicle", "chest"),
    "forearm": ("upper_arm",),
    "hand": ("forearm",),
    "upper_leg": ("hips",),
    "lower_leg": ("upper_leg",),
    "foot": ("lower_leg",),
    "toes": ("foot",),
}


def check_joint_map(skeleton, joints: dict[str, int], spine: tuple[int, ...]) -> None:
    """Raise MocapError (one line, naming the role and the joint) when the map ``joints`` (role ->
    joint index) with ``spine`` (hips-side first, the chest last) is not one body in the
    hierarchy of ``skeleton``."""
    names, parents = skeleton.names, skeleton.parents

    def called(role: str) -> str:
        return f"{role.replace('_', ' ')} {shown(names[joints[role]])}"

    by_joint: dict[int, str] = {}
    for role, joint in joints.items():
        if joint in by_joint:
            raise _refused(
                f"{shown(names[joint])} plays two roles, {by_joint[joint]} and {role}; each role needs its own joint"
            )
        by_joint[joint] = role
    above = {role: _ancestors(parents, joint) for role, joint in joints.items()}
    for role in joints:
        part = role.split("_", 1)[1] if role.startswith(("left_", "right_")) else role
        side = role[: len(role) - len(part)]
        wanted = [side + r if r not in ("hips", "chest") else r for r in _UP_THE_CHAIN.get(part, ())]
        parent_role = next((r for r in wanted if r in joints), None)
        if parent_role is not None and joints[parent_role] not in above[role]:
            raise _refused(f"the {called(role)} does not hang below the {called(parent_role)} in the hierarchy")
    _check_apart(joints, above, called)
    check_spine(skeleton, joints["hips"], spine)
    if spine and joints["chest"] not in spine:
        raise _refused(f"the spine ({listed(names[j] for j in spine)}) does not reach the {called('chest')}")


def check_spine(skeleton, hips: int, spine: tuple[int, ...]) -> None:
    """Raise MocapError unless each joint of ``spine`` hangs below the one before (the first below
    the ``hips``)."""
    for k, joint in enumerate(spine):
        below = spine[k - 1] if k else hips
        if below not in _ancestors(skeleton.parents, joint):
            what = "the hips" if below == hips else shown(skeleton.names[below])
            raise _refused(
                f"the spine's joint {shown(skeleton.names[joint])} does not hang below {what} in the hierarchy"
            )


def _ancestors(parents, joint: int) -> set[int]:
    out, j = set(), int(parents[joint])
    while j >= 0 and j not in out:  # a cycle cannot be built, but never loop
        out.add(j)
        j = int(parents[j])
    return out


def _check_apart(joints: dict, above: dict, called) -> None:
    """Each side's limbs apart from the other side's, the legs off the trunk above the hips, and
    the head off the arms."""
    limbs = {
        side: [f"{side}_{r}" for r in ARM_ROLES + LEG_ROLES if f"{side}_{r}" in joints] for side in ("left", "right")
    }
    for side, other in (("left", "right"), ("right", "left")):
        for role in limbs[side]:
            crossed = next((r for r in limbs[other] if joints[r] in above[role]), None)
            if crossed is not None:
                raise _refused(f"the {called(role)} hangs below the {called(crossed)}, on the other side")
            if role.endswith(LEG_ROLES) and joints["chest"] in above[role]:
                raise _refused(f"the {called(role)} hangs below the {called('chest')}: legs leave the hips")
    for role in ("neck", "head"):
        if role in joints:
            arm = next((r for s in limbs for r in limbs[s] if joints[r] in above[role]), None)
            if arm is not None:
                raise _refused(f"the {called(role)} hangs below the {called(arm)}")


def check_posed_map(jmap, positions: np.ndarray) -> None:
    """Raise MocapError when the map ``jmap`` disagrees with the body in most of the posed frames
    ``positions [F, J, 3]`` (a rest pose can tell nothing: Bandai-Namco's lays every bone along
    X): the feet on the head's side of the hips, the left upper arm on the right upper leg's
    side; and, when the map file gave a side's roles, the toes pointing backwards (left and right
    swapped whole)."""
    if not len(positions):  # a clip of no frames shows nothing to check
        return
    joints = jmap.joints
    names = jmap.names

    def called(role: str) -> str:
        return f"{role.replace('_', ' ')} {shown(names[joints[role]])}"

    def mostly(values: np.ndarray) -> bool:
        return bool(np.mean(values) > 0.5)

    hips = positions[:, joints["hips"]]
    up = positions[:, joints["head"]] - hips
    left = positions[:, joints["left_upper_leg"]] - positions[:, joints["right_upper_leg"]]
    size = float(np.median(np.linalg.norm(up, axis=-1)))
    if not size > 0:
        raise _refused(f"the {called('head')} is at the {called('hips')} in most frames: the body has no height")
    if float(np.median(np.linalg.norm(left, axis=-1))) < 1e-3 * size:
        raise _refused(
            f"the {called('left_upper_leg')} and {called('right_upper_leg')} are at one place in most frames: "
            "left cannot be told from right"
        )
    for side in ("left", "right"):
        foot = f"{side}_foot"
        if mostly(np.sum((positions[:, joints[foot]] - hips) * up, axis=-1) > 0):
            raise _refused(f"the {called(foot)} is on the head's side of the {called('hips')} in most frames")
    if "left_upper_arm" in joints and "right_upper_arm" in joints:
        arms = positions[:, joints["left_upper_arm"]] - positions[:, joints["right_upper_arm"]]
        if mostly(np.sum(arms * left, axis=-1) < 0):
            raise _refused(
                f"left and right disagree: the {called('left_upper_arm')} is on the side of the "
                f"{called('right_upper_leg')} in most frames"
            )
    given = any(jmap.how.get(role) == "map" for role in joints if role.startswith(("left_", "right_")))
    if given and all(f"{side}_toes" in joints for side in ("left", "right")):
        forward = np.cross(left, up)  # left x up, as everywhere in the package
        toes = sum(positions[:, joints[f"{s}_toes"]] - positions[:, joints[f"{s}_foot"]] for s in ("left", "right"))
        if mostly(np.sum(toes * forward, axis=-1) < 0):
            raise _refused(
                f"left and right look swapped: with the {called('left_upper_leg')} as the left, the toes point "
                "backwards in most frames"
            )


def four_legged(jmap, positions: np.ndarray, up: np.ndarray) -> bool:
    """Whether the body mapped by ``jmap`` moves on four legs in most frames ``[F, J, 3]`` (world
    ``up`` ``[3]``): its trunk (hips to chest) within 30 degrees of level and its hands as low as
    its feet (within a fifth of the leg's length)."""
    joints = jmap.joints
    if not len(positions) or not all(f"{side}_hand" in joints for side in ("left", "right")):
        return False
    trunk = positions[:, joints["chest"]] - positions[:, joints["hips"]]
    level = np.abs(trunk @ up) < 0.5 * np.linalg.norm(trunk, axis=-1)
    height = positions @ up  # [F, J]
    leg = float(np.median(height[:, joints["hips"]] - height[:, joints["left_foot"]]))
    feet = np.minimum(height[:, joints["left_foot"]], height[:, joints["right_foot"]])
    hands = np.maximum(height[:, joints["left_hand"]], height[:, joints["right_hand"]])
    return bool(leg > 0 and np.mean(level & (hands - feet < 0.2 * leg)) > 0.5)


def _refused(what: str) -> MocapError:
    return MocapError(f"joint map refused: {what}")


__all__ = ["check_joint_map", "check_posed_map", "check_spine", "four_legged"]
