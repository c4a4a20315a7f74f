"""What a joint's name says: its side and the body part it names, on the naming conventions met
in practice (Bandai-Namco ``UpperLeg_L``, CMU ``LeftUpLeg``/``LHipJoint``/``LeftHip``, Mixamo
``mixamorig:LeftForeArm``, SMPL ``left_knee``, game rigs ``thigh_l``/``upperarm_twist_01_l``,
3ds Max ``Bip01 L Thigh``).

A name is split into words (separators, camel case, digits), the namespace prefix and rig prefixes
dropped, the side word taken out; what is left, joined, is looked up in :data:`PARTS`.
"""

from __future__ import annotations

import re
from functools import lru_cache
from typing import NamedTuple

# The roles a chain can hold, in order from the body outwards.
LEG_ROLES = ("upper_leg", "lower_leg", "foot", "toes")
ARM_ROLES = ("clavicle", "upper_arm", "forearm", "hand")

# Part words -> the roles they can name. Several roles where conventions disagree: SMPL's
# "shoulder" is the upper arm and its "foot" the toes, where CMU's and Mixamo's are the clavicle
# and the ankle; the order along the chain settles it (see jointmap).
PARTS: dict[str, tuple[str, ...]] = {
    **dict.fromkeys(("hips", "pelvis"), ("hips",)),
    **dict.fromkeys(("spine", "chest", "upperchest", "torso", "lowerback", "back", "abdomen", "waist"), ("spine",)),
    **dict.fromkeys(("neck", "lowerneck", "upperneck"), ("neck",)),
    "head": ("head",),
    **dict.fromkeys(("clavicle", "collar", "collarbone"), ("clavicle",)),
    "shoulder": ("clavicle", "upper_arm"),
    **dict.fromkeys(("arm", "upperarm", "uparm", "humerus"), ("upper_arm",)),
    **dict.fromkeys(("forearm", "lowerarm", "elbow", "radius"), ("forearm",)),
    **dict.fromkeys(("hand", "wrist"), ("hand",)),
    **dict.fromkeys(("upleg", "upperleg", "thigh", "femur"), ("upper_leg",)),
    "hip": ("upper_leg", "hips"),
    **dict.fromkeys(("leg", "lowerleg", "calf", "knee", "shin", "tibia"), ("lower_leg",)),
    "ankle": ("foot",),
    "foot": ("foot", "toes"),
    **dict.fromkeys(("toe", "toes", "toebase", "ball", "forefoot"), ("toes",)),
}

# Words that make a joint a helper, never a role: ends, twist and roll bones, IK targets, fingers.
_HELPER_WORDS = frozenset(
    "end nub top site tip twist roll ik pole target helper finger fingerbase thumb index middle ring pinky "
    "little carpal metacarpal".split()
)
# Rig prefixes that say nothing about the part.
_PREFIX_WORDS = frozenset("bip biped def drv jnt bn mixamorig".split())
_SIDE_WORDS = {"left": "left", "l": "left", "right": "right", "r": "right"}
_WORDS = re.compile(r"[A-Z]+(?=[A-Z][a-z])|[A-Z]?[a-z]+|[A-Z]+|\d+")


class NameLabel(NamedTuple):
    """What a name says: ``side`` ("left", "right" or ""), ``part`` (the part words joined, side,
    digits and prefixes removed), ``roles`` (the roles the part can name; empty for helpers)."""

    side: str
    part: str
    roles: tuple[str, ...]


def words(name: str) -> list[str]:
    """``"mixamorig:LeftUpLeg"`` -> ``["left", "up", "leg"]``: no namespace, split at separators,
    case changes and digits, lower case."""
    return [w.lower() for w in _WORDS.findall(name.rsplit(":", 1)[-1])]


@lru_cache(maxsize=4096)
def label(name: str) -> NameLabel:
    """The side and candidate roles ``name`` spells (see :data:`PARTS`)."""
    found = [w for w in words(name) if w not in _PREFIX_WORDS and not w.isdigit()]
    side = ""
    kept = []
    for w in found:
        if w in _SIDE_WORDS and not side:
            side = _SIDE_WORDS[w]
        else:
            kept.append(w)
    part = "".join(kept)
    if not side:  # "lefthand", "handleft", "lhand" written as one lower-case word
        for spelled, s in (("left", "left"), ("right", "right")):
            if part.startswith(spelled) and part[len(spelled) :] in PARTS:
                side, part = s, part[len(spelled) :]
            elif part.endswith(spelled) and part[: -len(spelled)] in PARTS:
                side, part = s, part[: -len(spelled)]
    if any(w in _HELPER_WORDS for w in kept):
        return NameLabel(side, part, ())
    roles = PARTS.get(part, ())
    if side:
        roles = tuple(r for r in roles if r in LEG_ROLES + ARM_ROLES)
    else:
        roles = tuple(r for r in roles if r not in LEG_ROLES + ARM_ROLES)
    return NameLabel(side, part, roles)


__all__ = ["ARM_ROLES", "LEG_ROLES", "NameLabel", "PARTS", "label", "words"]
