"""Which joint plays which part: hips, head, the spine-to-head chain, upper legs, ankles, toes.

Found by name on the skeletons met in practice (Bandai-Namco ``UpperLeg_L``/``Foot_L``/
``Toes_L``, CMU ``LeftUpLeg``/``LeftFoot``/``LeftToeBase``, Mixamo ``mixamorig:LeftUpLeg``, and
``Left``/``L``/``_l`` spellings of them); any role can be given by the caller instead.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .._utils.tokens import listed
from ..errors import MocapError
from ..motion import Skeleton
from .jointmap import find_joint_map

_SIDES = {"left": r"(?:left|l)", "right": r"(?:right|r)"}
_PARTS = {
    "upper_leg": r"(?:upleg|upperleg|thigh|hip)",
    "foot": r"(?:foot|ankle)",
    "toe": r"(?:toes?|toebase|ball)",
}
_CENTRE = {"hips": r"(?:hips|pelvis)", "head": r"head"}


def _key(name: str) -> str:
    """``"mixamorig:Left_Up-Leg"`` -> ``"leftupleg"``: no namespace prefix, case or separators."""
    return re.sub(r"[\s_.\-]", "", name.rsplit(":", 1)[-1].lower())


def _sided(part: str, side: str) -> re.Pattern:
    s, p = _SIDES[side], _PARTS[part]
    return re.compile(rf"^(?:{s}{p}|{p}{s})$")


ROLE_NAMES = ("hips", "head", "left_upper_leg", "right_upper_leg", "left_foot", "right_foot", "left_toe", "right_toe")
_PATTERNS = {
    "hips": re.compile(rf"^{_CENTRE['hips']}$"),
    "head": re.compile(rf"^{_CENTRE['head']}$"),
    **{f"{side}_{part}": _sided(part, side) for part in _PARTS for side in _SIDES},
}


@dataclass(frozen=True)
class JointRoles:
    """Joint indices of the parts the features need. ``spine`` is the chain from the hips to the
    head, both included, in that order. Pairs are (left, right)."""

    hips: int
    head: int
    spine: tuple[int, ...]
    upper_legs: tuple[int, int]
    feet: tuple[int, int]
    toes: tuple[int, int]

    @property
    def gait_joints(self) -> list[int]:
        """The seven joints the whole-clip gait kernels read, in their order (``clip_gait_many``,
        ``clip_pipeline_many``): hips, left and right upper leg, left and right foot, left and right toe."""
        return [self.hips, *self.upper_legs, *self.feet, *self.toes]

    @classmethod
    def find(cls, skeleton: Skeleton, given: Mapping[str, int | str] | None = None) -> JointRoles:
        """Roles of ``skeleton`` by joint name, else (none ``given``) by its joint map, which
        reads the topology too. ``given``: any role (names in :data:`ROLE_NAMES`) -> a joint
        index or name, e.g. ``{"left_toe": "LeftToe_End"}``. Commands read a skeleton's roles
        once, from its :class:`~expressive_mocap.body.Body`.

        Raises :class:`MocapError` naming every role that could not be found (or was found twice).
        """
        try:
            return cls.by_names(skeleton, given)
        except MocapError as named:
            if given:
                raise
            try:
                return cls.from_map(skeleton, find_joint_map(skeleton))
            except MocapError:
                raise named from None

    @classmethod
    def by_names(cls, skeleton: Skeleton, given: Mapping[str, int | str] | None = None) -> JointRoles:
        """Roles of ``skeleton`` by joint name only (see :meth:`find`)."""
        overrides = dict(given or {})
        unknown = set(overrides) - set(ROLE_NAMES)
        if unknown:
            raise MocapError(f"unknown joint role(s) {', '.join(sorted(unknown))}; roles are {', '.join(ROLE_NAMES)}")
        keys = [_key(n) for n in skeleton.names]
        found: dict[str, int] = {}
        problems = []
        for role in ROLE_NAMES:
            if role in overrides:
                found[role] = _joint(skeleton, overrides[role], role)
                continue
            matches = [j for j, k in enumerate(keys) if _PATTERNS[role].match(k)]
            if len(matches) == 1:
                found[role] = matches[0]
            elif matches:
                problems.append(f"{role} (several candidates: {', '.join(skeleton.names[j] for j in matches)})")
            else:
                problems.append(role)
        if problems:
            raise MocapError(
                f"cannot tell which joint is the {'; '.join(problems)}: pass it by name, e.g. "
                f"JointRoles.find(skeleton, {{'{problems[0].split()[0]}': 'JointName'}}); joints are: "
                f"{listed(skeleton.names)}"
            )
        spine = _chain(skeleton, found["hips"], found["head"])
        return cls(
            hips=found["hips"],
            head=found["head"],
            spine=spine,
            upper_legs=(found["left_upper_leg"], found["right_upper_leg"]),
            feet=(found["left_foot"], found["right_foot"]),
            toes=(found["left_toe"], found["right_toe"]),
        )

    @classmethod
    def from_map(cls, skeleton: Skeleton, jmap) -> JointRoles:
        """The roles of a :class:`~expressive_mocap.body.JointMap` (a foot's own joint
        stands in for toes the map lacks)."""
        toes = tuple(jmap.get(f"{s}_toes") if f"{s}_toes" in jmap else jmap[f"{s}_foot"] for s in ("left", "right"))
        return cls(
            hips=jmap["hips"],
            head=jmap["head"],
            spine=_chain(skeleton, jmap["hips"], jmap["head"]),
            upper_legs=(jmap["left_upper_leg"], jmap["right_upper_leg"]),
            feet=(jmap["left_foot"], jmap["right_foot"]),
            toes=(toes[0], toes[1]),
        )

    def names(self, skeleton: Skeleton) -> dict[str, str]:
        """Role -> joint name, for messages."""
        pairs = {"upper_leg": self.upper_legs, "foot": self.feet, "toe": self.toes}
        out = {"hips": skeleton.names[self.hips], "head": skeleton.names[self.head]}
        for part, (left, right) in pairs.items():
            out[f"left_{part}"], out[f"right_{part}"] = skeleton.names[left], skeleton.names[right]
        return out


def _joint(skeleton: Skeleton, value: int | str, role: str) -> int:
    if isinstance(value, str):
        return skeleton.index(value)
    index = int(value)
    if not 0 <= index < skeleton.n_joints:
        raise MocapError(f"role {role}: joint index {index} out of range (the skeleton has {skeleton.n_joints} joints)")
    return index


def _chain(skeleton: Skeleton, top: int, bottom: int) -> tuple[int, ...]:
    """Joints from ``top`` down to ``bottom`` along the parents, both included."""
    chain = [bottom]
    while chain[-1] != top:
        parent = int(skeleton.parents[chain[-1]])
        if parent < 0:
            raise MocapError(f"joint {skeleton.names[bottom]!r} does not hang below the hips {skeleton.names[top]!r}")
        chain.append(parent)
    return tuple(reversed(chain))


def rest_heights(skeleton: Skeleton, roles: JointRoles) -> tuple[float, float]:
    """``(hips rest height, actor height)`` in file units; read them from a skeleton's
    :class:`~expressive_mocap.body.Body`, which finds them once.

    The hips' rest height is their rest Y above the file's origin, taken as the floor
    (Bandai-Namco, Mixamo and the demo put the origin there); where that is under half the leg's
    length (files such as CMU's hang the rest pose from the origin), the leg's length: the bone
    lengths from the hips down to the ankle, which a standing actor's hips are about that high.
    The actor's height adds the bone lengths of the spine-to-head chain (the Bandai rest pose is
    not upright, so its vertical extent is no measure; this gives about 141 cm there).
    """
    joints, _ = skeleton.rest_positions()
    bone = np.linalg.norm(skeleton.offsets, axis=1)
    leg = float(sum(bone[j] for j in _chain(skeleton, roles.hips, roles.feet[0])[1:]))
    above_origin = float(joints[roles.hips, 1])
    hips = above_origin if above_origin >= 0.5 * leg else leg
    return hips, hips + float(sum(bone[j] for j in roles.spine[1:]))


def facing_yaw(positions: np.ndarray, roles: JointRoles) -> float:
    """The yaw (degrees about Y, 0 = facing +Z) the body faces over world ``positions [N, J, 3]``:
    perpendicular to the mean line from the right to the left upper leg (the
    best heading on skeletons whose rest pose is not upright)."""
    side = np.mean(positions[:, roles.upper_legs[0]] - positions[:, roles.upper_legs[1]], axis=0)
    return float(np.degrees(np.arctan2(-side[2], side[0])))  # forward = left x up = (-z, 0, x)


def path_joint(translations: np.ndarray, skeleton: Skeleton, roles: JointRoles) -> int:
    """The joint that carries the motion's path: the first joint on the chain from the root down to
    the hips whose local translation changes over ``translations [F, J, 3]`` (the root itself on
    most skeletons; the hips on Bandai-Namco's, whose ``joint_Root`` never moves), else the hips."""
    root = int(np.flatnonzero(skeleton.parents < 0)[0])
    chain = _chain(skeleton, root, roles.hips) if roles.hips != root else (root,)
    for joint in chain:
        if np.ptp(translations[:, joint], axis=0).max(initial=0.0) > 0:
            return int(joint)
    return int(roles.hips)


__all__ = ["ROLE_NAMES", "JointRoles", "facing_yaw", "path_joint", "rest_heights"]
