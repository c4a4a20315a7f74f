"""What the package knows about a skeleton, found once per rig:

- :mod:`.roles`: the joints the gait features read (:class:`JointRoles`) and the actor's height;
- :mod:`.jointmap`: which joint plays which part of the body (:func:`find_joint_map`, by names,
  topology or a user's map file, :func:`read_joint_map`), and :mod:`.mapcheck`, its whole checks;
- :mod:`.names`: what a joint's name says (side and part);
- :mod:`.conventions`: the axes, unit, actor height and rest pose a file was captured in
  (:func:`read_conventions`), and the change to the canonical frame and back;
- :mod:`.hinges`: the knees' and elbows' hinge axes and limits;
- :mod:`.ik`: two-bone inverse kinematics for legs and arms.
"""

from __future__ import annotations

from .._utils.lazy import lazy_exports

_LAZY = {
    "ROLES": "jointmap",
    "JointMap": "jointmap",
    "find_joint_map": "jointmap",
    "read_joint_map": "jointmap",
    "JointRoles": "roles",
    "actor_height": "roles",
    "Conventions": "conventions",
    "read_conventions": "conventions",
    "to_canonical": "conventions",
    "from_canonical": "conventions",
}

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

__all__ = sorted(_LAZY)
