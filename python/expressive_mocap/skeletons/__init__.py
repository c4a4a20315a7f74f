"""Any humanoid skeleton:

- :mod:`.jointmap`: which joint plays which part (:func:`find_joint_map`, by names, topology or
  a user's map file, :func:`read_joint_map`);
- :mod:`.conventions`: the axes, unit, actor height and rest pose a file was captured in
  (:func:`read_conventions`), and the change to the canonical frame and back;
- :mod:`.retargeting`: a motion moved onto another skeleton (:func:`retarget`);
- :mod:`.twist`: how a bone faces about itself, read from joint positions;
- :mod:`.mirror`: a motion mirrored left for right (:func:`mirror`);
- :mod:`.synthetic`: the demo's walk on six synthetic skeletons, with their ground truth.
"""

from __future__ import annotations

from ..lazy import lazy_exports

_LAZY = {
    "ROLES": "jointmap",
    "JointMap": "jointmap",
    "find_joint_map": "jointmap",
    "read_joint_map": "jointmap",
    "Conventions": "conventions",
    "read_conventions": "conventions",
    "to_canonical": "conventions",
    "from_canonical": "conventions",
    "Rig": "retargeting",
    "retarget": "retargeting",
    "mirror": "mirror",
    "RIGS": "synthetic",
    "synthetic_skeleton": "synthetic",
    "synthetic_walk": "synthetic",
}

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

__all__ = [
    "RIGS",
    "ROLES",
    "Conventions",
    "JointMap",
    "Rig",
    "find_joint_map",
    "from_canonical",
    "read_conventions",
    "mirror",
    "read_joint_map",
    "retarget",
    "synthetic_skeleton",
    "synthetic_walk",
    "to_canonical",
]
