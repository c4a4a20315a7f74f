"""Which way a bone faces about itself, read from joint positions.

A bone's direction shows in the positions of its two ends, its twist does not: it is carried by
the rotations. Most captures twist their bones as a body does (a knee bends about a line across
the leg), but some files twist them arbitrarily, such as the output of a network trained on
positions, which may turn a thigh 100 degrees about itself and the shin back. For the limbs the
positions still tell how each bone faces: the plane an elbow or knee bends in, the way the foot
points, the chest's forward. :func:`facing` gives that direction for the roles it can read, the
same way in a reference pose and frame by frame, and :func:`twist_angles` how far a motion's
rotations turn each bone from it (about 10-20 degrees on a real capture, 60-180 on those files).
"""

from __future__ import annotations

import numpy as np

from ..body.jointmap import JointMap
from ..rotations import quat

# A limb's three joints, by the part of each segment.
_ARM, _LEG = ("upper_arm", "forearm", "hand"), ("upper_leg", "lower_leg", "foot")
LIMBS = {"upper_arm": _ARM, "forearm": _ARM, "hand": _ARM, "upper_leg": _LEG, "lower_leg": _LEG}
# The parts :func:`facing` reads (a forearm's or hand's facing is its elbow's plane, blind to its
# pronation; a foot's and the toes' where the shin rises, blind to the foot's roll; the neck's and
# head's the chest's forward, blind to their turn): what positions can tell of a twist. READABLE:
# those whose twist is taken from the positions where the rotations disagree too much (TRUSTED).
FACING = ("neck", "head", "clavicle", "upper_arm", "forearm", "hand", "upper_leg", "lower_leg", "foot", "toes")
READABLE = FACING
# How far a motion's rotations may twist a bone from the way its positions say it faces before the
# positions are taken instead (median over the frames that tell: :func:`telling`). Measured on
# real captures (the Bandai-Namco clips, the CMU file): legs, spine, neck and clavicles 0-20
# degrees, upper arms up to 50, forearms and wrists up to 80 (they turn about themselves; 3 of the
# 3,076 Bandai-Namco clips, stylised walks, pass 90), a head looking aside through a whole clip 51;
# on the demo's waving arm an upper arm 43 and a forearm 60; on files of arbitrary twists 50-170
# (heads 93, thighs 87-131).
TRUSTED = {
    "upper_arm": np.radians(60.0),
    "forearm": np.radians(90.0),
    "hand": np.radians(90.0),
    "head": np.radians(80.0),
}
TRUSTED_ELSE = np.radians(45.0)
_STRAIGHT, _BENT = np.radians(10.0), np.radians(25.0)  # a limb's bend that tells its plane fully


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _square_to(v: np.ndarray, bone: np.ndarray) -> np.ndarray:
    """``v`` made square to ``bone`` (both ``[..., 3]``), unit length."""
    b = _unit(bone)
    return _unit(v - b * np.sum(v * b, axis=-1, keepdims=True))


def chest_forward(points: np.ndarray, jmap: JointMap) -> np.ndarray:
    """The chest's forward ``[..., 3]`` from joint positions ``[..., J, 3]``: left (across the
    upper arms, else the hips) times up (from the chest to the head)."""
    arm = "upper_arm" if "left_upper_arm" in jmap else "upper_leg"
    left = points[..., jmap[f"left_{arm}"], :] - points[..., jmap[f"right_{arm}"], :]
    up = points[..., jmap["head"], :] - points[..., jmap["chest"], :]
    return _unit(quat.cross(left, _square_to(up, left)))


def _hinge(points: np.ndarray, jmap: JointMap, side: str, limb: tuple[str, str, str]) -> tuple[np.ndarray, np.ndarray]:
    """The line ``[..., 3]`` a limb's elbow or knee bends about (its two segments' normal, signed
    so that the normal times a segment is where that segment faces: forward for an arm, for a leg
    forward too, its knee bending back), and how much it can be trusted (0 when the limb is
    nearly straight, 1 from 25 degrees of bend)."""
    top, middle, end = (points[..., jmap[f"{side}_{p}"], :] for p in limb)
    upper, lower = _unit(middle - top), _unit(end - middle)
    angle = np.arccos(np.clip(np.sum(upper * lower, axis=-1), -1.0, 1.0))
    sure = np.clip((angle - _STRAIGHT) / (_BENT - _STRAIGHT), 0.0, 1.0)[..., None]
    normal = _unit(quat.cross(upper, lower))
    return (normal if limb is _ARM else -normal), sure


def facing(
    points: np.ndarray, jmap: JointMap, role: str, bone: np.ndarray, forward: np.ndarray | None = None
) -> np.ndarray:
    """The direction ``[..., 3]`` square to ``role``'s ``bone`` that the positions ``[..., J, 3]``
    say it faces: for an upper arm or forearm where the elbow bends (the chest's forward when the
    arm is straight), for a thigh where the knee bends (where the foot points when the leg is
    straight), for a shin where the foot points, for a foot where the shin rises, for a clavicle
    the chest's forward, and so for the neck. ``role``'s part is one of :data:`FACING`, its joints
    mapped (:func:`readable`). ``forward``: :func:`chest_forward`, when already known."""
    forward = chest_forward(points, jmap) if forward is None else forward
    if role in ("neck", "head"):
        return _square_to(forward, bone)
    side, part = role.split("_", 1)
    if part == "clavicle":
        return _square_to(forward, bone)
    ankle, toes = (points[..., jmap[f"{side}_{p}"], :] for p in ("foot", "toes"))
    if part == "lower_leg":
        return _square_to(toes - ankle, bone)
    if part in ("foot", "toes"):
        return _square_to(points[..., jmap[f"{side}_lower_leg"], :] - ankle, bone)
    hinge, sure = _hinge(points, jmap, side, LIMBS[part])
    straight = _square_to(toes - ankle if LIMBS[part] is _LEG else forward, bone)
    return _unit(sure * _square_to(quat.cross(hinge, bone), bone) + (1.0 - sure) * straight)


def telling(points: np.ndarray, jmap: JointMap, role: str) -> np.ndarray:
    """Where :func:`facing` reads ``role`` from the positions ``[..., J, 3]`` alone (``[...]``
    booleans): for an arm, where its elbow is bent (a straight arm raised forward overhead faces
    back, raised sideways forward: the chest cannot tell which); for any other role, everywhere."""
    if role.split("_", 1)[-1] in ("upper_arm", "forearm", "hand"):
        return _hinge(points, jmap, role.split("_", 1)[0], _ARM)[1][..., 0] > 0.5
    return np.ones(points.shape[:-2], dtype=bool)


def readable(jmap: JointMap, role: str, parts: tuple[str, ...] = FACING) -> bool:
    """Whether :func:`facing` can read ``role`` (one of ``parts``) in a skeleton of map ``jmap``."""
    chest = ["chest", "head", "left_upper_arm", "right_upper_arm"]  # the chest's forward
    if role in ("neck", "head"):
        return role in parts and all(r in jmap for r in [role, *chest])
    if not role.startswith(("left_", "right_")) or role.split("_", 1)[1] not in parts:
        return False
    side, part = role.split("_", 1)
    needed = [f"{side}_{p}" for p in ("upper_leg", "lower_leg", "foot", "toes")]
    if part in ("clavicle", "upper_arm", "forearm", "hand"):
        needed += [f"{side}_{p}" for p in _ARM] + chest
    return all(r in jmap for r in needed)


def trusted(role: str) -> float:
    """The largest median twist (radians) of ``role``'s rotations from its facing still trusted."""
    return TRUSTED.get(role.split("_", 1)[-1], TRUSTED_ELSE)


def twist_angles(bones: np.ndarray, seconds: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """Signed angles ``[...]`` about each unit ``bone`` from ``seconds`` (where the rotations put a
    bone's second axis) to ``wanted`` (where the positions say it faces), both square to it."""
    return np.arctan2(np.sum(bones * quat.cross(seconds, wanted), axis=-1), np.sum(seconds * wanted, axis=-1))


__all__ = [
    "FACING",
    "LIMBS",
    "READABLE",
    "TRUSTED",
    "TRUSTED_ELSE",
    "trusted",
    "chest_forward",
    "facing",
    "readable",
    "twist_angles",
]
