"""The canonical body's skeleton: the one of the Bandai-Namco dataset-2 files (22 joints, their
names, hierarchy, rest offsets in cm with Y up, six channels a joint in Z X Y rotation order,
End Sites at the hand, toe and head joints), and the upright pose its bones' twists are measured
from. The shipped body model, the procedural walks and retargeting onto the canonical body all
stand on it.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ..motion import Skeleton
from ..rotations import quat

BANDAI_CHANNELS = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")

# From Bandai-Namco-Research-Motiondataset-2 (CC BY-NC 4.0), dataset-2_walk_normal_001.bvh:
# name, parent, rest offset (cm; the Hips offset is that clip's own), and W, the joint's world
# rotation (x, y, z, w) averaged over the clip with its heading removed (facing +Z); for the feet
# and toes, averaged over the frames where that foot is flat on the floor.
_BANDAI = [
    ("joint_Root", None, (0.0, 0.0, 0.0), (0.0000, 0.0000, 0.0000, 1.0000)),
    ("Hips", "joint_Root", (-0.726466, 93.3139, -2.00062), (-0.0199, 0.0202, 0.7003, 0.7133)),
    ("Spine", "Hips", (15.7357, 0.0, 0.0), (0.5131, 0.4912, 0.5042, 0.4911)),
    ("Chest", "Spine", (8.98455, -0.406207, 0.0), (0.5243, 0.4880, 0.5163, 0.4693)),
    ("Neck", "Chest", (16.3773, 0.0, 0.0), (0.5101, 0.4855, 0.5409, 0.4599)),
    ("Head", "Neck", (6.45672, 0.0, 0.0), (0.5401, 0.4513, 0.5408, 0.4607)),
    ("Shoulder_L", "Chest", (12.9942, -0.242716, 4.98039), (0.0425, 0.1788, 0.0230, 0.9827)),
    ("UpperArm_L", "Shoulder_L", (5.34809, 0.0, 0.0), (0.0758, -0.0614, -0.5861, 0.8043)),
    ("LowerArm_L", "UpperArm_L", (24.3286, 1.87007e-05, 0.0), (0.0369, -0.2878, -0.5808, 0.7606)),
    ("Hand_L", "LowerArm_L", (22.2916, 0.0, 0.0), (0.0303, -0.3505, -0.5200, 0.7784)),
    ("Shoulder_R", "Chest", (12.9945, -0.242716, -4.98039), (-0.9875, -0.0616, -0.1410, 0.0334)),
    ("UpperArm_R", "Shoulder_R", (-5.34813, 0.0, 0.0), (-0.7826, -0.6082, 0.0996, 0.0875)),
    ("LowerArm_R", "UpperArm_R", (-24.3289, 0.000322201, 0.0), (-0.7375, -0.6044, 0.2965, 0.0532)),
    ("Hand_R", "LowerArm_R", (-22.2915, -0.000108084, 0.0), (-0.7824, -0.5208, 0.3378, 0.0507)),
    ("UpperLeg_L", "Hips", (-2.19248, -6.46944, 0.0), (-0.1241, -0.0198, -0.6911, 0.7117)),
    ("LowerLeg_L", "UpperLeg_L", (39.0811, 0.0, -1.23785e-05), (0.0702, 0.1782, -0.6980, 0.6900)),
    ("Foot_L", "LowerLeg_L", (40.9854, 0.0, -1.26872e-05), (-0.3466, -0.2558, -0.6062, 0.6686)),
    ("Toes_L", "Foot_L", (11.7543, 0.0, 0.0), (-0.4348, -0.3536, -0.5472, 0.6217)),
    ("UpperLeg_R", "Hips", (-2.19251, 6.46944, 0.0), (0.7060, 0.6926, -0.0081, 0.1480)),
    ("LowerLeg_R", "UpperLeg_R", (-39.0811, -0.00228153, -0.0401928), (-0.6859, -0.7039, -0.1809, 0.0362)),
    ("Foot_R", "LowerLeg_R", (-40.9854, 0.0, 0.0), (0.6841, 0.5896, -0.2352, 0.3592)),
    ("Toes_R", "Foot_R", (-11.7543, 0.0, 0.0), (0.6306, 0.5155, -0.3539, 0.4598)),
]
_END_SITES = ("Head", "Hand_L", "Hand_R", "Toes_L", "Toes_R")  # all at their joint (zero offset)
BANDAI_JOINTS = tuple(n for n, _, _, _ in _BANDAI)
_J = {n: j for j, n in enumerate(BANDAI_JOINTS)}
_PARENTS = np.array([-1 if p is None else BANDAI_JOINTS.index(p) for _, p, _, _ in _BANDAI])
_STANDING = quat.normalize(np.array([w for _, _, _, w in _BANDAI]))  # W_j


def bandai_standing_pose() -> np.ndarray:
    """``W``, the Bandai-Namco skeleton's world rotations ``[22, 4]`` (x, y, z, w) in a real neutral
    walk's average pose, facing +Z: the upright pose its bones' twists are measured from (its rest
    pose, every bone along its joint's X axis, is no human pose)."""
    return _STANDING.copy()


def bandai_like_skeleton() -> Skeleton:
    """The Bandai-Namco dataset-2 skeleton: joint names, hierarchy, rest offsets and channels
    as in ``dataset-2_walk_normal_001.bvh`` (the Hips offset is that clip's)."""
    return Skeleton(
        names=BANDAI_JOINTS,
        parents=_PARENTS,
        offsets=np.array([o for _, _, o, _ in _BANDAI]),
        channels=(BANDAI_CHANNELS,) * len(BANDAI_JOINTS),
        end_sites=tuple((_J[n], (0.0, 0.0, 0.0)) for n in _END_SITES),
    )


@lru_cache(maxsize=1)
def canonical_skeleton() -> Skeleton:
    """The canonical body's skeleton (:func:`bandai_like_skeleton`), one object for the process."""
    return bandai_like_skeleton()


def canonical_shape() -> tuple[tuple[str, ...], tuple[int, ...]]:
    """The canonical skeleton's joint names and parents (what tells a clip already on it)."""
    skeleton = canonical_skeleton()
    return tuple(skeleton.names), tuple(int(p) for p in skeleton.parents)


__all__ = [
    "BANDAI_CHANNELS",
    "BANDAI_JOINTS",
    "bandai_like_skeleton",
    "bandai_standing_pose",
    "canonical_shape",
    "canonical_skeleton",
]
