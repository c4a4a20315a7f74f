"""Anatomical limits of the hinge joints (elbows and knees): a flexion range in the limb's own
frame that every edit is kept within.

A hinge's flexion is the angle its lower segment turns from the upper one's line about the
hinge's axis, measured in the upper segment's frame (the upper arm's, the thigh's), so neither
the body's heading nor the upper segment's swing changes it: 0 is straight, positive is bent the
way the joint bends, negative is bent backwards (hyperextended). The axis is the mean normal of
the two segments over the frames where the limb is clearly bent, learnt from real motion; the
range is from straight (never past it) to the most the data shows plus a margin. Only the
flexion is limited: a corrected joint turns about the hinge's axis alone, so the limb keeps its
plane and its twist.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..errors import ArgumentError, MocapError
from ..motion import Motion, spread_frames
from ..ops import forward_kinematics
from ..rotations import quat
from .body import Body
from .canonical import canonical_shape, canonical_skeleton
from .take import Take

# Each hinge (the joint map's role of its middle joint) with its limb: upper, middle, end.
LIMBS = {"forearm": ("upper_arm", "forearm", "hand"), "lower_leg": ("upper_leg", "lower_leg", "foot")}
HINGES = tuple(f"{side}_{part}" for part in LIMBS for side in ("left", "right"))
BENT = 25.0  # degrees: a limb bent this far tells its hinge's axis clearly
MARGIN = 0.1  # the room above the most flexion seen: this share of the range seen
# The canonical body's hinges as the Bandai-Namco dataset-2 neutral locomotion shows them (CC BY-NC
# 4.0; the 145 {walk,walk-turn-left,walk-turn-right,run}_normal clips the shipped body-mechanics
# model learnt from; experiments/hinge_limits.py measures them): the most flexion (degrees; the limit
# before the margin, on any skeleton whose own data does not tell it) and the axis in the upper
# joint's frame (the rest pose's bones lie along X there).
NEUTRAL_MOST = {"left_forearm": 125.9, "right_forearm": 123.7, "left_lower_leg": 138.5, "right_lower_leg": 137.6}
CANONICAL_AXES = {
    "left_forearm": (0.0, -1.0, 0.0),
    "right_forearm": (0.0, -1.0, 0.0),
    "left_lower_leg": (0.0, 1.0, 0.0),
    "right_lower_leg": (0.0, 1.0, 0.0),
}


@dataclass(frozen=True)
class Hinge:
    """One hinge: its ``role``, its limb's joints ``upper``, ``middle``, ``end`` (indices), the
    ``axis [3]`` it bends about in the upper joint's frame, and the most flexion allowed
    (``high``, degrees)."""

    role: str
    upper: int
    middle: int
    end: int
    axis: np.ndarray
    high: float


@dataclass(frozen=True)
class HingeLimits:
    """The hinges of one skeleton (by its joint names) and their limits."""

    names: tuple[str, ...]
    hinges: tuple[Hinge, ...]

    def flexion(self, rotations: np.ndarray, translations: np.ndarray, parents: np.ndarray) -> np.ndarray:
        """Each hinge's flexion ``[F, H]`` (degrees; negative: bent backwards) over local
        ``rotations [F, J, 4]`` and ``translations [F, J, 3]``."""
        world, positions = forward_kinematics(rotations, translations, parents)
        return (
            np.stack([_flexion(world, positions, h) for h in self.hinges], axis=1)
            if self.hinges
            else np.zeros((len(rotations), 0))
        )

    def of(self, motion: Motion) -> np.ndarray:
        """:meth:`flexion` of ``motion``."""
        self._check(motion)
        return self.flexion(motion.rotations, motion.translations, motion.skeleton.parents)

    def _check(self, motion: Motion) -> None:
        if tuple(motion.skeleton.names) != self.names:
            raise ArgumentError(
                f"hinge limits of a {len(self.names)}-joint skeleton ({', '.join(self.names[:3])}, ...) do not "
                f"fit a motion of {motion.skeleton.n_joints} joints ({', '.join(motion.skeleton.names[:3])}, ...)"
            )

    def table(self) -> dict[str, tuple[float, float]]:
        """Joint name -> allowed flexion (low, high), degrees."""
        return {self.names[h.middle]: (0.0, h.high) for h in self.hinges}


def _flexion(world: np.ndarray, positions: np.ndarray, hinge: Hinge) -> np.ndarray:
    """The signed flexion ``[F]`` (degrees) of ``hinge`` from world rotations and positions."""
    inverse = quat.conjugate(world[:, hinge.upper])
    upper = quat.rotate(inverse, positions[:, hinge.middle] - positions[:, hinge.upper])
    lower = quat.rotate(inverse, positions[:, hinge.end] - positions[:, hinge.middle])
    lower = lower - np.outer(lower @ hinge.axis, hinge.axis)  # in the hinge's plane
    sine = np.cross(upper, lower) @ hinge.axis
    cosine = np.sum(upper * lower, axis=-1)
    return np.degrees(np.arctan2(sine, cosine))  # both scaled by the two lengths


def _limbs(body: Body) -> list[tuple[str, int, int, int]]:
    """The hinges the body's joint map knows: (role, upper, middle, end) joint indices."""
    try:
        jmap = body.joint_map
    except MocapError:  # no limbs to tell: no hinges
        return []
    out = []
    for role in HINGES:
        side, part = role.split("_", 1)
        upper, middle, end = (jmap.get(f"{side}_{p}") for p in LIMBS[part])
        if upper is not None and middle is not None and end is not None:
            out.append((role, upper, middle, end))
    return out


def learn_hinge_limits(
    motions: Sequence[Motion | Take], margin: float = MARGIN, most: dict[str, float] | None = None
) -> HingeLimits:
    """Hinge limits learnt from real ``motions`` (one skeleton): each hinge's axis, the mean
    normal of its two segments in the upper joint's frame over the frames bent at least
    :data:`BENT` degrees; its most flexion, the most the motions show (or ``most[role]``, e.g.
    ``most["left_forearm"]``, where given) plus ``margin`` x the range they show. A hinge never
    bent that far in the motions is left without limits. The limbs are those of the first
    motion's Body (a take's, where given: a Body read with a user's joint map)."""
    if not motions:
        raise ArgumentError("hinge limits need at least one motion to learn from")
    takes = [Take.of(m) for m in motions]
    body = takes[0].body
    names = tuple(body.skeleton.names)
    if any(tuple(t.motion.skeleton.names) != names for t in takes):
        raise ArgumentError("hinge limits are learnt from motions of one skeleton")
    rotations = np.concatenate([t.motion.rotations for t in takes])
    translations = np.concatenate([t.motion.translations for t in takes])
    return _learnt(body, rotations, translations, margin, most)


def _learnt(
    body: Body, rotations: np.ndarray, translations: np.ndarray, margin: float, most: dict[str, float] | None
) -> HingeLimits:
    skeleton = body.skeleton
    names = tuple(skeleton.names)
    world, positions = forward_kinematics(rotations, translations, skeleton.parents)
    hinges = []
    for role, upper, middle, end in _limbs(body):
        inverse = quat.conjugate(world[:, upper])
        a = quat.rotate(inverse, positions[:, middle] - positions[:, upper])
        b = quat.rotate(inverse, positions[:, end] - positions[:, middle])
        normal = np.cross(a, b)
        sine = np.linalg.norm(normal, axis=-1)
        bent = np.degrees(np.arctan2(sine, np.sum(a * b, axis=-1))) >= BENT
        if bent.sum() < 3:
            continue
        axis = (normal[bent] / sine[bent, None]).mean(axis=0)
        line = a.mean(axis=0) / np.linalg.norm(a.mean(axis=0))
        axis = axis - line * (axis @ line)  # square to the upper segment
        axis /= np.linalg.norm(axis)
        hinge = Hinge(role, upper, middle, end, axis, 0.0)
        angles = _flexion(world, positions, hinge)
        top = most[role] if most is not None else float(angles.max())
        high = top + margin * (top - min(0.0, float(angles.min())))
        hinges.append(Hinge(role, upper, middle, end, axis, high))
    return HingeLimits(names, tuple(hinges))


@dataclass
class HingeReport:
    """What :func:`limit_hinges` changed: per joint the frames limited and the largest change
    (degrees), as ``{joint: (frames, degrees)}``; and the hyperextension and flexion left."""

    limited: dict[str, tuple[int, float]]
    most_backwards: float
    most_flexion: float

    def text(self) -> str:
        if not self.limited:
            return f"hinges within their limits (most flexion {self.most_flexion:.1f} deg)"
        worst = sorted(self.limited.items(), key=lambda kv: -kv[1][1])
        return f"hinges kept from straight to the most the data shows (+margin), {len(worst)} joint(s): " + ", ".join(
            f"{j} ({n} frames, by up to {v:.1f} deg)" for j, (n, v) in worst
        )


def limit_hinges(motion: Motion, limits: HingeLimits, allow: Sequence[np.ndarray] = ()) -> tuple[Motion, HingeReport]:
    """``motion`` with every hinge's flexion kept within ``limits``: from straight to the limit's
    most, each frame widened to what the rotations in ``allow`` (``[F, J, 4]`` each, on the
    motion's skeleton: an edit's inputs) already have there, so an edit never makes a pose less
    plausible than its input but never more either. A hinge past its range turns back about its
    axis (the joint's own rotation; what hangs below follows)."""
    limits._check(motion)
    if not limits.hinges:
        return motion, HingeReport({}, 0.0, 0.0)
    parents = motion.skeleton.parents
    world, positions = forward_kinematics(motion.rotations, motion.translations, parents)
    angles = np.stack([_flexion(world, positions, h) for h in limits.hinges], axis=1)
    low = np.zeros_like(angles)
    high = np.broadcast_to([h.high for h in limits.hinges], angles.shape).copy()
    for rotations in allow:
        if rotations.shape != motion.rotations.shape:
            raise ArgumentError(f"an allowance of shape {rotations.shape} for a motion of {motion.rotations.shape}")
        theirs = limits.flexion(rotations, motion.translations, parents)
        low, high = np.minimum(low, theirs), np.maximum(high, theirs)
    target = np.clip(angles, low, high)
    change = target - angles
    out = motion.rotations.copy()
    limited = {}
    for k, h in enumerate(limits.hinges):
        frames = np.abs(change[:, k]) > 1e-9
        if not frames.any():
            continue
        limited[motion.skeleton.names[h.middle]] = (int(frames.sum()), float(np.abs(change[:, k]).max()))
        axis = quat.rotate(world[frames, h.upper], np.broadcast_to(h.axis, (int(frames.sum()), 3)))
        turn = quat.exp(axis * np.radians(change[frames, k])[:, None])
        new_world = quat.mul(turn, world[frames, h.middle])
        parent = parents[h.middle]
        out[frames, h.middle] = quat.mul(quat.conjugate(world[frames, parent]), new_world)
    result = Motion(motion.skeleton, out, motion.translations, motion.frame_time)
    after = limits.of(result) if limited else angles
    return result, HingeReport(limited, float(max(0.0, -after.min())), float(after.max()))


@lru_cache(maxsize=1)
def canonical_hinge_limits() -> HingeLimits:
    """The canonical body's hinge limits: its axes and most flexion measured on the Bandai-Namco
    neutral locomotion (:data:`CANONICAL_AXES`, :data:`NEUTRAL_MOST`), plus :data:`MARGIN`."""
    skeleton = canonical_skeleton()
    names = tuple(skeleton.names)
    hinges = []
    for role, upper, middle, end in _limbs(Body.of(skeleton)):
        axis = np.asarray(CANONICAL_AXES[role], dtype=np.float64)
        hinges.append(Hinge(role, upper, middle, end, axis, NEUTRAL_MOST[role] * (1 + MARGIN)))
    return HingeLimits(names, tuple(hinges))


_AXIS_FRAMES = 240  # frames of each motion a skeleton's hinge axes are learnt from, at most


def hinge_limits_for(motions: Sequence[Motion]) -> HingeLimits:
    """The limits for edits of ``motions`` (one skeleton) without a model's own: the canonical
    body's on it, else the axes learnt from the motions themselves with the canonical most
    flexion of each hinge (the same human body) plus the margin."""
    if tuple(motions[0].skeleton.names) == canonical_shape()[0]:
        return canonical_hinge_limits()
    # The axes from evenly spread frames: a clip's hinges turn about the same lines throughout,
    # and an edit carried back to its skeleton should not cost a pass over every frame.
    spread = [m[spread_frames(m.n_frames, _AXIS_FRAMES)] for m in motions]
    return learn_hinge_limits(spread, most=NEUTRAL_MOST)


__all__ = [
    "HINGES",
    "Hinge",
    "HingeLimits",
    "HingeReport",
    "canonical_hinge_limits",
    "hinge_limits_for",
    "learn_hinge_limits",
    "limit_hinges",
]
