"""What the package knows about a skeleton, found once per rig:

- :mod:`.body`: :class:`Body`, a skeleton's joint map, roles, actor height and stature, kept per
  skeleton content; :mod:`.take`: :class:`Take`, a motion with its Body and what is derived from
  it once (positions, floor, contacts);

- :mod:`.roles`: the joints the gait features read (:class:`JointRoles`) and the rest heights;
- :mod:`.contacts`: foot contacts, the floor, steps and cadence;
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
    "Body": "body",
    "Take": "take",
    "actor_height": "body",
    "JointRoles": "roles",
    "Conventions": "conventions",
    "read_conventions": "conventions",
    "to_canonical": "conventions",
    "from_canonical": "conventions",
}

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

__all__ = sorted(_LAZY)
