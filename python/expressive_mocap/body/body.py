"""A :class:`Body`: what the package knows about one skeleton, found once.

Telling which joint is which and how tall the actor stands reads names, topology and bone
lengths. A Body holds those answers for one skeleton, and one Body is kept per skeleton
*content*: two clips of one rig share it, whatever objects they were read into, so each finder
runs once per rig in a command, however many clips and steps ask.

The actor's height has one definition, :attr:`Body.actor_height`: the hips' height standing
(:attr:`Body.hips_rest_height`) plus the bone lengths of the spine up to the head joint, about
141 cm on the Bandai-Namco skeleton. Contact thresholds, speeds and feature scales are fractions
of it. The stature that :class:`~expressive_mocap.body.Conventions` reads (the standing height
to the top of the head, estimated from the leg bones: about 163 cm there) only tells the unit.
"""

from __future__ import annotations

from collections.abc import Mapping
from functools import cached_property

from .._utils.kept import Kept
from ..errors import ArgumentError, MocapError
from ..motion import Motion, Skeleton
from .jointmap import JointMap, find_joint_map
from .roles import JointRoles, rest_heights

KEPT = 256  # bodies kept, the most recently asked for: an archive holds a handful of rigs


class Body:
    """One skeleton's joint map and roles (one vocabulary: the roles are the map's gait joints),
    and actor height, each found on first use and kept.

    Get one with :meth:`Body.of` (kept per skeleton content and user map), or :meth:`Body.of_motion`.
    ``user_map``: role -> joint name (as :func:`~expressive_mocap.body.read_joint_map` reads a
    map file), which the joint map and the roles then follow.
    """

    def __init__(self, skeleton: Skeleton, user_map: Mapping[str, object] | None = None):
        if not isinstance(skeleton, Skeleton):
            raise ArgumentError(f"argument `skeleton`: expected a Skeleton, got {type(skeleton).__name__}")
        self.skeleton = skeleton
        self.user_map = dict(user_map) if user_map else None

    @classmethod
    def of(cls, skeleton: Skeleton, user_map: Mapping[str, object] | None = None) -> Body:
        """The Body of ``skeleton`` (read with ``user_map``), the same object for every skeleton of
        the same content."""
        if not isinstance(skeleton, Skeleton):
            raise ArgumentError(f"argument `skeleton`: expected a Skeleton, got {type(skeleton).__name__}")
        return _BODIES.get((skeleton.content_key, _frozen(user_map)), lambda: cls(skeleton, user_map))

    @classmethod
    def of_motion(cls, motion: Motion, user_map: Mapping[str, object] | None = None) -> Body:
        """:meth:`of` ``motion``'s skeleton."""
        if not isinstance(motion, Motion):
            raise ArgumentError(f"argument `motion`: expected a Motion, got {type(motion).__name__}")
        return cls.of(motion.skeleton, user_map)

    @cached_property
    def joint_map(self) -> JointMap:
        """Which joint plays which part (:func:`~expressive_mocap.body.find_joint_map`)."""
        return find_joint_map(self.skeleton, self.user_map)

    @cached_property
    def roles(self) -> JointRoles:
        """The joints the gait features read, in the joint map's terms: those a user's map gives;
        else those the names tell (cheap, and the same joints wherever the names are plain), else
        the joint map's (names missing or ambiguous: SMPL's "left_foot" is a toe)."""
        if self.user_map:
            return JointRoles.from_map(self.skeleton, self.joint_map)
        try:
            return JointRoles.by_names(self.skeleton)
        except MocapError as named:
            try:
                return JointRoles.from_map(self.skeleton, self.joint_map)
            except MocapError:
                raise named from None

    @cached_property
    def _heights(self) -> tuple[float, float]:
        return rest_heights(self.skeleton, self.roles)

    @property
    def hips_rest_height(self) -> float:
        """The hips' height above the floor standing, in file units
        (:func:`~expressive_mocap.body.roles.rest_heights`)."""
        return self._heights[0]

    @property
    def actor_height(self) -> float:
        """The actor's height in file units: :attr:`hips_rest_height` plus the spine-to-head bones."""
        return self._heights[1]

    def __repr__(self) -> str:
        return f"Body({self.skeleton.n_joints} joints, root {self.skeleton.names[0]!r})"


def actor_height(skeleton: Skeleton) -> float:
    """The actor's height in file units (:attr:`Body.actor_height` of ``skeleton``'s Body)."""
    return Body.of(skeleton).actor_height


def _frozen(user_map: Mapping[str, object] | None) -> tuple[tuple[str, object], ...]:
    """A user map as a hashable key (a spine given as a list of names included)."""
    if not user_map:
        return ()
    return tuple(sorted((k, tuple(v) if isinstance(v, (list, tuple)) else v) for k, v in user_map.items()))


_BODIES: Kept[Body] = Kept(KEPT)


__all__ = ["KEPT", "Body", "actor_height"]
