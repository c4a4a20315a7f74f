"""The package's canonical body: the skeleton everything it has learned lives on (the shipped
body-mechanics model, features and contacts tuned on Bandai-Namco captures), so a motion of any
other skeleton is retargeted onto it to be compared with them.

It is the Bandai-Namco dataset-2 skeleton (22 joints, centimetres, Y up, facing +Z, six channels a
joint in Z X Y order; the demo's, :func:`~expressive_mocap.demo.bandai_like_skeleton`).
"""

from __future__ import annotations

from functools import lru_cache

from ..motion import Motion, Skeleton
from .conventions import Conventions
from .jointmap import JointMap, find_joint_map
from .retargeting import Rig, retarget_clips, retarget_rigs

# The toe joint sits 4.35 cm above the floor on a flat foot (measured on dataset-2's walks).
_TOE_HEIGHT_CM = 4.35


def canonical_skeleton() -> Skeleton:
    """The canonical body's skeleton."""
    return canonical_rig().skeleton


@lru_cache(maxsize=1)
def canonical_rig() -> Rig:
    """The canonical body with its joint map, conventions and floor."""
    from ..demo import bandai_like_skeleton

    skeleton = bandai_like_skeleton()
    jmap = find_joint_map(skeleton)
    sure = {"up": 1.0, "facing": 1.0, "unit": 1.0, "rest_pose": 1.0}
    conventions = Conventions("+Y", "+Z", "cm", 0.01, 163.07, "other", 30.0, sure)
    return Rig(skeleton, jmap, conventions, _TOE_HEIGHT_CM)


def canonical_shape() -> tuple[tuple[str, ...], tuple[int, ...]]:
    """The canonical skeleton's joint names and parents (what tells a clip already on it)."""
    skeleton = canonical_skeleton()
    return tuple(skeleton.names), tuple(int(p) for p in skeleton.parents)


def onto_canonical(motion: Motion, user_map: dict | None = None, *, plant_feet: bool = True) -> tuple[Motion, JointMap]:
    """``motion`` retargeted onto the canonical body (at its own frame rate), and the joint map
    its skeleton was read with."""
    source = Rig.of(motion, user_map)
    return retarget_rigs(motion, source, canonical_rig(), plant_feet=plant_feet), source.jmap


def many_onto_canonical(motions: list[Motion], user_map: dict | None = None) -> list[tuple[Motion, JointMap]]:
    """:func:`onto_canonical` of many clips at once (feet planted; see
    :func:`~expressive_mocap.skeletons.retargeting.retarget_clips`)."""
    return retarget_clips(motions, canonical_rig(), user_map=user_map)


__all__ = ["canonical_rig", "canonical_shape", "canonical_skeleton", "many_onto_canonical", "onto_canonical"]
