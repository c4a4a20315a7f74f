"""Ground truth on many skeletons: the demo's procedural walk (optionally waving) written on
synthetic skeletons built after the conventions met in practice, each with the joint map and
conventions it was built with, so that what the package reads from them can be checked.

===========  ============================================================  ====  ======  ====  ======
rig          names and structure                                           rest  unit    up    fps
===========  ============================================================  ====  ======  ====  ======
``bandai``   the demo's own Bandai-Namco skeleton (bones along local X)    other cm      +Y    30
``cmu``      CMU: zero-length LHipJoint/LowerBack/Neck/LeftShoulder,       T     inches  +Y    120
             fingers, ZYX 3-channel joints, hanging from the origin
``mixamo``   ``mixamorig:`` names, three spine joints, fingers, Toe_End     T     cm      +Y    30
``smpl``     SMPL's 24 joints (``left_hip`` ... ``left_foot`` = toes)       A     m       +Z    60
``game``     game rig: root, pelvis, spine_01-03, clavicle_l, twist bones  A     cm      +Z    30
``lafan``    LAFAN1 names (Hips, LeftUpLeg, ..., LeftToe)                   T     cm      +Y    30
===========  ============================================================  ====  ======  ====  ======

Every rig but ``bandai`` is built from one canonical T-pose (metres, Y up, facing +Z) whose legs
have the Bandai skeleton's proportions, so the walk keeps its feet planted on all of them; the
motion on each is the Bandai walk carried over by :func:`~.retargeting.retarget_rigs` with the
rig's known map and conventions (not the ones the package would read).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..body.body import Body
from ..body.conventions import UNITS, Conventions, _frame_rotation
from ..motion import Motion, Skeleton
from ..procedural import procedural_walk
from ..rotations import quat
from .retargeting import retarget_rigs
from .rig import Rig

RIGS = ("bandai", "cmu", "mixamo", "smpl", "game", "lafan")

# Canonical T-pose landmarks of the left side (metres, Y up, facing +Z, left is +X); the legs are
# the Bandai skeleton's (thigh 39.08 cm, shank 40.99 cm, its standing foot), standing on y = 0.
_ANKLE_HEIGHT = 0.0435 + 0.0744
_L = {
    "hips": (0.0, 0.93, 0.0),
    "hip": (0.0647, 0.9081, 0.0),
    "knee": (0.0647, 0.9081 - 0.3908, 0.0),
    "ankle": (0.0647, _ANKLE_HEIGHT, 0.0),
    "toes": (0.0647, 0.0435, 0.0896),
    "toe_end": (0.0647, 0.02, 0.15),
    "chest": (0.0, 1.30, 0.0),
    "neck": (0.0, 1.42, 0.0),
    "head": (0.0, 1.50, 0.01),
    "head_top": (0.0, 1.66, 0.01),
    "clavicle": (0.02, 1.38, 0.01),
    "shoulder": (0.17, 1.40, 0.0),
    "elbow": (0.44, 1.40, 0.0),
    "wrist": (0.68, 1.40, 0.0),
    "knuckle": (0.76, 1.40, 0.0),
    "finger_end": (0.84, 1.40, 0.0),
    "thumb": (0.71, 1.40, 0.04),
}
_ARM_POINTS = ("elbow", "wrist", "knuckle", "finger_end", "thumb")


class RigSpec(NamedTuple):
    """How a synthetic rig is written: ``joints`` (name, parent name, landmark or a point),
    the ground-truth map, its conventions, its channels and frame rate."""

    joints: list
    truth: dict
    up: str
    facing: str
    unit: str
    rest_pose: str
    fps: float
    root_channels: tuple[str, ...]
    channels: tuple[str, ...]
    hanging: bool = False


def _point(name: str, side: str, a_pose: bool) -> np.ndarray:
    """A landmark of ``side`` ("L", "R" or "" for the centre), with the arm lowered 45 degrees
    about the forward axis at the shoulder in an A pose."""
    x, y, z = _L[name]
    p = np.array([x if side != "R" else -x, y, z])
    if a_pose and name in _ARM_POINTS:
        shoulder = _point("shoulder", side, False)
        turn = quat.about("Z", np.array([-45.0 if side != "R" else 45.0]))[0]
        p = shoulder + quat.rotate(turn, p - shoulder)
    return p


def _spec(rig: str) -> RigSpec:
    joints: list[tuple]
    six_zxy = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
    if rig == "cmu":
        joints = [("Hips", None, "hips"), ("LowerBack", "Hips", "hips")]
        joints += [("Spine", "LowerBack", ("hips", "chest", 0.5)), ("Spine1", "Spine", "chest")]
        joints += [("Neck", "Spine1", "chest"), ("Neck1", "Neck", "neck"), ("Head", "Neck1", "head")]
        for s, S in (("L", "Left"), ("R", "Right")):
            joints += [
                (f"{s}HipJoint", "Hips", "hips"),
                (f"{S}UpLeg", f"{s}HipJoint", f"{s}:hip"),
                (f"{S}Leg", f"{S}UpLeg", f"{s}:knee"),
                (f"{S}Foot", f"{S}Leg", f"{s}:ankle"),
                (f"{S}ToeBase", f"{S}Foot", f"{s}:toes"),
                (f"{S}Shoulder", "Spine1", "chest"),
                (f"{S}Arm", f"{S}Shoulder", f"{s}:shoulder"),
                (f"{S}ForeArm", f"{S}Arm", f"{s}:elbow"),
                (f"{S}Hand", f"{S}ForeArm", f"{s}:wrist"),
                (f"{S}FingerBase", f"{S}Hand", f"{s}:wrist"),
                (f"{S}HandIndex1", f"{S}FingerBase", f"{s}:knuckle"),
                (f"{s}Thumb", f"{S}Hand", f"{s}:thumb"),
            ]
        truth = _names(
            "Hips",
            "Spine1",
            "Neck",
            "Head",
            ("Shoulder", "Arm", "ForeArm", "Hand"),
            ("UpLeg", "Leg", "Foot", "ToeBase"),
        )
        zyx = ("Zrotation", "Yrotation", "Xrotation")
        return RigSpec(
            joints, truth, "+Y", "+Z", "in", "T", 120.0, ("Xposition", "Yposition", "Zposition") + zyx, zyx, True
        )
    if rig in ("mixamo", "lafan"):
        p = "mixamorig:" if rig == "mixamo" else ""
        spine = ["Spine", "Spine1", "Spine2"]
        joints = [(p + "Hips", None, "hips"), (p + "Spine", p + "Hips", ("hips", "chest", 0.25))]
        joints += [(p + "Spine1", p + "Spine", ("hips", "chest", 0.6)), (p + "Spine2", p + "Spine1", "chest")]
        joints += [(p + "Neck", p + "Spine2", "neck"), (p + "Head", p + "Neck", "head")]
        if rig == "mixamo":
            joints += [(p + "HeadTop_End", p + "Head", "head_top")]
        toe = "ToeBase" if rig == "mixamo" else "Toe"
        for s, S in (("L", "Left"), ("R", "Right")):
            joints += [
                (f"{p}{S}UpLeg", p + "Hips", f"{s}:hip"),
                (f"{p}{S}Leg", f"{p}{S}UpLeg", f"{s}:knee"),
                (f"{p}{S}Foot", f"{p}{S}Leg", f"{s}:ankle"),
                (f"{p}{S}{toe}", f"{p}{S}Foot", f"{s}:toes"),
                (f"{p}{S}Shoulder", p + "Spine2", f"{s}:clavicle"),
                (f"{p}{S}Arm", f"{p}{S}Shoulder", f"{s}:shoulder"),
                (f"{p}{S}ForeArm", f"{p}{S}Arm", f"{s}:elbow"),
                (f"{p}{S}Hand", f"{p}{S}ForeArm", f"{s}:wrist"),
            ]
            if rig == "mixamo":
                joints += [
                    (f"{p}{S}Toe_End", f"{p}{S}{toe}", f"{s}:toe_end"),
                    (f"{p}{S}HandIndex1", f"{p}{S}Hand", f"{s}:knuckle"),
                    (f"{p}{S}HandIndex2", f"{p}{S}HandIndex1", f"{s}:finger_end"),
                    (f"{p}{S}HandThumb1", f"{p}{S}Hand", f"{s}:thumb"),
                ]
        truth = _names(
            p + "Hips",
            p + spine[-1],
            p + "Neck",
            p + "Head",
            ("Shoulder", "Arm", "ForeArm", "Hand"),
            ("UpLeg", "Leg", "Foot", toe),
            prefix=p,
        )
        three = ("Zrotation", "Xrotation", "Yrotation")
        return RigSpec(joints, truth, "+Y", "+Z", "cm", "T", 30.0, six_zxy[:3] + three, three)
    if rig == "smpl":
        joints = [("pelvis", None, "hips")]
        for side, s in (("left", "L"), ("right", "R")):
            joints += [
                (f"{side}_hip", "pelvis", f"{s}:hip"),
                (f"{side}_knee", f"{side}_hip", f"{s}:knee"),
                (f"{side}_ankle", f"{side}_knee", f"{s}:ankle"),
                (f"{side}_foot", f"{side}_ankle", f"{s}:toes"),
            ]
        joints += [("spine1", "pelvis", ("hips", "chest", 0.3)), ("spine2", "spine1", ("hips", "chest", 0.65))]
        joints += [("spine3", "spine2", "chest"), ("neck", "spine3", "neck"), ("head", "neck", "head")]
        for side, s in (("left", "L"), ("right", "R")):
            joints += [
                (f"{side}_collar", "spine3", f"{s}:clavicle"),
                (f"{side}_shoulder", f"{side}_collar", f"{s}:shoulder"),
                (f"{side}_elbow", f"{side}_shoulder", f"{s}:elbow"),
                (f"{side}_wrist", f"{side}_elbow", f"{s}:wrist"),
                (f"{side}_hand", f"{side}_wrist", f"{s}:knuckle"),
            ]
        truth = {"hips": "pelvis", "chest": "spine3", "neck": "neck", "head": "head"}
        for side in ("left", "right"):
            for role, part in zip(
                ("clavicle", "upper_arm", "forearm", "hand", "upper_leg", "lower_leg", "foot", "toes"),
                ("collar", "shoulder", "elbow", "wrist", "hip", "knee", "ankle", "foot"),
            ):
                truth[f"{side}_{role}"] = f"{side}_{part}"
        xyz = ("Xrotation", "Yrotation", "Zrotation")
        return RigSpec(joints, truth, "+Z", "-Y", "m", "A", 60.0, six_zxy[:3] + xyz, xyz)
    if rig == "game":
        joints = [("root", None, "floor"), ("pelvis", "root", "hips")]
        joints += [("spine_01", "pelvis", ("hips", "chest", 0.3)), ("spine_02", "spine_01", ("hips", "chest", 0.65))]
        joints += [("spine_03", "spine_02", "chest"), ("neck_01", "spine_03", "neck"), ("head", "neck_01", "head")]
        for s, x in (("L", "l"), ("R", "r")):
            joints += [
                (f"clavicle_{x}", "spine_03", f"{s}:clavicle"),
                (f"upperarm_{x}", f"clavicle_{x}", f"{s}:shoulder"),
                (f"upperarm_twist_01_{x}", f"upperarm_{x}", (f"{s}:shoulder", f"{s}:elbow", 0.5)),
                (f"lowerarm_{x}", f"upperarm_{x}", f"{s}:elbow"),
                (f"lowerarm_twist_01_{x}", f"lowerarm_{x}", (f"{s}:elbow", f"{s}:wrist", 0.5)),
                (f"hand_{x}", f"lowerarm_{x}", f"{s}:wrist"),
                (f"index_01_{x}", f"hand_{x}", f"{s}:knuckle"),
                (f"thumb_01_{x}", f"hand_{x}", f"{s}:thumb"),
            ]
        for s, x in (("L", "l"), ("R", "r")):
            joints += [
                (f"thigh_{x}", "pelvis", f"{s}:hip"),
                (f"thigh_twist_01_{x}", f"thigh_{x}", (f"{s}:hip", f"{s}:knee", 0.5)),
                (f"calf_{x}", f"thigh_{x}", f"{s}:knee"),
                (f"calf_twist_01_{x}", f"calf_{x}", (f"{s}:knee", f"{s}:ankle", 0.5)),
                (f"foot_{x}", f"calf_{x}", f"{s}:ankle"),
                (f"ball_{x}", f"foot_{x}", f"{s}:toes"),
            ]
        truth = {"hips": "pelvis", "chest": "spine_03", "neck": "neck_01", "head": "head"}
        for side, x in (("left", "l"), ("right", "r")):
            for role, part in zip(
                ("clavicle", "upper_arm", "forearm", "hand", "upper_leg", "lower_leg", "foot", "toes"),
                ("clavicle", "upperarm", "lowerarm", "hand", "thigh", "calf", "foot", "ball"),
            ):
                truth[f"{side}_{role}"] = f"{part}_{x}"
        yxz = ("Yrotation", "Xrotation", "Zrotation")
        return RigSpec(joints, truth, "+Z", "+Y", "cm", "A", 30.0, six_zxy[:3] + yxz, yxz)
    raise ValueError(f"unknown synthetic rig {rig!r}; rigs are {', '.join(RIGS)}")


def _names(hips, chest, neck, head, arm, leg, prefix: str = "") -> dict:
    out = {"hips": hips, "chest": chest, "neck": neck, "head": head}
    for side, S in (("left", "Left"), ("right", "Right")):
        for role, part in zip(("clavicle", "upper_arm", "forearm", "hand"), arm):
            out[f"{side}_{role}"] = f"{prefix}{S}{part}"
        for role, part in zip(("upper_leg", "lower_leg", "foot", "toes"), leg):
            out[f"{side}_{role}"] = f"{prefix}{S}{part}"
    return out


def _landmark(where, a_pose: bool) -> np.ndarray:
    if isinstance(where, tuple):
        a, b, share = where
        return (1 - share) * _landmark(a, a_pose) + share * _landmark(b, a_pose)
    if where == "floor":
        return np.zeros(3)
    side, _, name = where.rpartition(":")
    return _point(name, side, a_pose)


def synthetic_skeleton(rig: str) -> tuple[Skeleton, Conventions, dict]:
    """The rig's skeleton, the conventions it was built with and its ground-truth joint map
    (role -> joint name)."""
    if rig == "bandai":
        from ..body.canonical import bandai_like_skeleton

        skeleton = bandai_like_skeleton()
        truth = Body.of(skeleton).joint_map.as_names()
        truth.pop("spine")
        conventions = Conventions("+Y", "+Z", "cm", 0.01, 163.07, "other", 30.0, _SURE)
        return skeleton, conventions, truth
    spec = _spec(rig)
    names = [name for name, _, _ in spec.joints]
    canonical = np.array([_landmark(where, spec.rest_pose == "A") for _, _, where in spec.joints])
    if spec.hanging:
        canonical -= canonical[0]
    turn = _frame_rotation(spec.up, spec.facing)
    metres = UNITS[spec.unit]
    positions = quat.rotate(quat.conjugate(turn), canonical) / metres
    parents = [-1 if parent is None else names.index(parent) for _, parent, _ in spec.joints]
    order = _depth_first(parents)
    names = [names[j] for j in order]
    positions = positions[order]
    parents = [-1 if parents[j] < 0 else order.index(parents[j]) for j in order]
    offsets = np.array([positions[j] - (positions[p] if p >= 0 else 0.0) for j, p in enumerate(parents)])
    channels = tuple(
        spec.root_channels if p < 0 or names[j] == spec.truth["hips"] else spec.channels for j, p in enumerate(parents)
    )
    leaves = [j for j in range(len(names)) if j not in parents]
    skeleton = Skeleton(tuple(names), np.array(parents), offsets, channels, tuple((j, (0.0, 0.0, 0.0)) for j in leaves))
    height = (1.66 + 0.02) / metres
    conventions = Conventions(spec.up, spec.facing, spec.unit, metres, height, spec.rest_pose, spec.fps, _SURE)
    return skeleton, conventions, dict(spec.truth)


_SURE = {"up": 1.0, "facing": 1.0, "unit": 1.0, "rest_pose": 1.0}


def _depth_first(parents: list[int]) -> list[int]:
    """Joint order with every joint after its parent, depth first (the order a BVH file keeps)."""
    children: dict[int, list[int]] = {}
    for j, p in enumerate(parents):
        children.setdefault(p, []).append(j)
    order, stack = [], list(reversed(children[-1]))
    while stack:
        j = stack.pop()
        order.append(j)
        stack.extend(reversed(children.get(j, [])))
    return order


class Synthetic(NamedTuple):
    """A synthetic rig's walk: ``motion``, the ``conventions`` and ground-truth ``truth`` map
    (role -> joint name) it was built with."""

    motion: Motion
    conventions: Conventions
    truth: dict


def synthetic_walk(rig: str, *, wave: str | None = None, seconds: float = 4.0) -> Synthetic:
    """The demo's walk (waving the ``wave`` arm, if given) on the synthetic ``rig`` (:data:`RIGS`),
    at the rig's frame rate."""
    walk = procedural_walk(seconds, wave=wave)
    skeleton, conventions, truth = synthetic_skeleton(rig)
    if rig == "bandai":
        return Synthetic(walk, conventions, truth)
    source = Rig.of(walk)
    jmap = Body.of(skeleton, truth).joint_map
    floor = _L["toes"][1] / conventions.metres_per_unit  # the toe joint's height on a flat foot
    target = Rig(skeleton, jmap, conventions, floor, user_map=truth)
    motion = retarget_rigs(walk, source, target, plant_feet=False)
    if conventions.fps != walk.fps:
        motion = motion.resample(fps=conventions.fps)
    return Synthetic(motion, conventions, truth)


__all__ = ["RIGS", "Synthetic", "synthetic_skeleton", "synthetic_walk"]
