"""The arms filtered in world axes by the decomposition.

A relaxed arm hangs in the world: while an actor waves with one hand, the hips and shoulders sway
with each stroke and the other arm counter-turns at the shoulder to hang as before. Filtered joint
by joint, that arm keeps the actor's local rotations (its activity is low) on the trunk the body
mechanics give it, so it swung with every difference between the two trunks: in dataset-2's
held-out one-hand gestures the body mechanics' idle hand moved about its shoulder more than the
actor's own + 0.5 cm in a quarter of the clips (active waves: 55 of 83). The upper arms and
forearms are therefore filtered between world rotations (``split_rotations``' ``arms``): their
inactive part keeps the actor's world rotation, their active part follows the network's arm where
the network puts it, not the network's arm on another trunk (a raised arm, a half turn from the
network's, is filtered joint by joint as before). The hand keeps the joint-by-joint filter.
"""

from __future__ import annotations

from ..body.body import Body
from ..errors import MocapError
from ..motion import Skeleton
from ..ops import Arms

LIMB_ROLES = ("left_upper_arm", "left_forearm", "right_upper_arm", "right_forearm")


def arm_limbs(skeleton: Skeleton) -> Arms | None:
    """The upper arms and forearms of ``skeleton`` (by its joint map) as the limbs the split
    filters in world axes, parents first; None for a skeleton whose arms are not found."""
    try:
        found = Body.of(skeleton).joint_map.joints
    except MocapError:  # a skeleton the joint map cannot read has no arms to hang
        return None
    limbs = sorted(found[role] for role in LIMB_ROLES if role in found)
    return Arms(tuple(int(p) for p in skeleton.parents), tuple(int(j) for j in limbs)) if limbs else None


__all__ = ["LIMB_ROLES", "arm_limbs"]
