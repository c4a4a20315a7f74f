"""Clavicles for positions that have none.

Positions without clavicle joints (Human3.6M's 17: the shoulders hang from the thorax) give a
target's clavicles no bone to follow: retargeted, they stay at rest, so the shoulders sit where
the rest pose puts them (centimetres from where its actor holds them) and a shrug is lost.
:func:`reach_shoulders` gives each clavicle the target's own typical pose (the mean of its
motion's; its rest when it has no motion), then swings it, frame by frame, by how the shoulder
the positions give moves about its mean place: the shrug, not the two bodies' proportions (a
Bandai-Namco shoulder reached for on a CMU skeleton would hunch it 30-40 degrees).
"""

from __future__ import annotations

import numpy as np

from ..body.jointmap import JointMap
from ..motion import Motion
from ..rotations import quat

# The most a clavicle is swung from its typical pose (degrees): a person's shoulder girdle moves
# some 30-40 degrees at most.
MOST_SWING = 40.0
# The most the shoulders' mean place turns a clavicle from the target's typical pose (degrees): on
# its own skeleton, what the fit leaves of the actor's own pose is within 8 degrees (Human3.6M's
# joints from real captures); on another, 12 to 56 (the two bodies' proportions).
MOST_MEAN = 10.0
_IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def reach_shoulders(motion: Motion, jmap: JointMap, shoulders: np.ndarray, own: np.ndarray | None) -> Motion:
    """``motion`` with each clavicle in its typical pose in ``own [F', J, 4]`` (the local
    rotations of a motion of the same skeleton: the mean of each clavicle's; None: as it is), then
    swung, frame by frame, so its bone points at the shoulder
    ``shoulders [F, 2, 3]`` gives (left, right; the motion's world and units): the swing about its
    mean, and of the mean at most :data:`MOST_MEAN` degrees, in all at most :data:`MOST_SWING`.
    The arm below keeps its world orientation. A side whose upper arm is not the clavicle's child
    is left as it is."""
    parents = motion.skeleton.parents
    world, positions = motion.fk()
    rotations = motion.rotations.copy()
    for s, name in enumerate(("left", "right")):
        clavicle, arm = jmap.joints.get(f"{name}_clavicle"), jmap.joints.get(f"{name}_upper_arm")
        if clavicle is None or arm is None or parents[arm] != clavicle:
            continue
        above = world[:, parents[clavicle]]
        typical = world[:, clavicle] if own is None else quat.mul(above, quat.mean_rotation(own[:, clavicle]))
        bone = quat.rotate(typical, motion.translations[:, arm])  # the clavicle's, in its typical pose
        with np.errstate(invalid="ignore", divide="ignore"):  # no bone, or a shoulder at the joint: no swing
            swing = quat.between(bone, shoulders[:, s] - positions[:, clavicle])
        swing[~np.isfinite(swing).all(axis=-1)] = _IDENTITY
        mean = quat.mean_rotation(swing)
        # The shrug about the mean, and of the mean itself what the actor's own pose may differ by.
        swing = _at_most(quat.mul(quat.mul(swing, quat.conjugate(mean)), _at_most(mean, MOST_MEAN)), MOST_SWING)
        turned = quat.normalize(quat.mul(swing, typical))
        rotations[:, clavicle] = quat.normalize(quat.mul(quat.conjugate(above), turned))
        rotations[:, arm] = quat.normalize(quat.mul(quat.conjugate(turned), world[:, arm]))
    return Motion(motion.skeleton, rotations, motion.translations, motion.frame_time)


def _at_most(q: np.ndarray, degrees: float) -> np.ndarray:
    """Rotations ``q [..., 4]`` shortened along their arc to at most ``degrees``."""
    angle = quat.angle(q)
    limit = np.radians(degrees)
    share = np.where(angle > limit, limit / np.maximum(angle, 1e-12), 1.0)
    return quat.slerp(np.broadcast_to(_IDENTITY, q.shape), q, share)


__all__ = ["MOST_MEAN", "MOST_SWING", "reach_shoulders"]
