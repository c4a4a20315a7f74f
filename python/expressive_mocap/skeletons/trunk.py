"""The trunk's lean and curve kept through a retarget.

The transfer (:mod:`.retargeting`) gives each mapped joint the source's world rotation (through
the reference poses' alignments), so every mapped bone points where the source's does. The line
from the hips to the chest, and from the chest to the head, also depend on the joints between
them and on each rig's own offsets: on walks of other rigs retargeted onto the Bandai-Namco body
they leaned 2-16 degrees (mean) away from the source's. Here the chain's first joint above its
start is turned, frame by frame, so that its end lies on the source's line from its start (in the
target's axes; lengths stay the target's), and the end joint's local rotation takes the turn back:
its world rotation, and so everything above it (arms, neck, head), is as the transfer left it.
The chain's first joint is a spine segment (no role: every mapped bone still points where the
source's does) or, for the head, the neck: its bone then turns by what the two rigs' proportions
differ (2-5 degrees on the synthetic rigs), so that the head sits where the source's does.
"""

from __future__ import annotations

import numpy as np

from .. import ops
from ..motion import Motion
from ..rotations import quat

# The trunk's lines kept: (start role, end role).
CHAINS = (("hips", "chest"), ("chest", "head"))


def keep_trunk(out: Motion, source_points: np.ndarray, source_jmap, target_jmap, turn: np.ndarray) -> Motion:
    """``out`` (a retarget) with its lines of :data:`CHAINS` those of the source (world positions
    ``source_points [F, J, 3]`` of a rig mapped by ``source_jmap``; ``turn``: the rotation from the
    source's axes into the target's). A chain with no joint between its two roles, or a role
    either map lacks, is left as it is."""
    rotations = out.rotations.copy()
    parents = out.skeleton.parents
    # One forward kinematics for both chains: the first keeps its end's (the chest's) world
    # rotation, so everything above it only moves with it, and the second chain's own geometry
    # (lines, world rotations) is as it was.
    world, points = ops.forward_kinematics(rotations, out.translations, parents)
    for start_role, end_role in CHAINS:
        if not all(r in m for r in (start_role, end_role) for m in (source_jmap, target_jmap)):
            continue
        start, end = target_jmap[start_role], target_jmap[end_role]
        base = _first_below(parents, start, end)
        if base is None:
            continue
        wanted = quat.rotate(turn, source_points[:, source_jmap[end_role]] - source_points[:, source_jmap[start_role]])
        swing = _swing(points[:, start], points[:, base], points[:, end], wanted)
        parent = parents[base]
        rotations[:, base] = quat.mul(quat.conjugate(world[:, parent]), quat.mul(swing, world[:, base]))
        # The end keeps its world rotation: its local one takes the swing back.
        above = quat.mul(swing, world[:, parents[end]])
        rotations[:, end] = quat.mul(quat.conjugate(above), world[:, end])
    return Motion(out.skeleton, rotations, out.translations, out.frame_time)


def _first_below(parents: np.ndarray, start: int, end: int) -> int | None:
    """The joint just below ``start`` on the way to ``end`` (None: ``end`` is ``start``'s child,
    or not below it)."""
    chain = [end]
    while chain[-1] >= 0 and parents[chain[-1]] != start:
        chain.append(int(parents[chain[-1]]))
    if chain[-1] < 0 or len(chain) < 2:
        return None
    return chain[-1]


def _swing(start: np.ndarray, base: np.ndarray, end: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """Rotations ``[F, 4]`` about ``base`` taking ``end`` onto the ray from ``start`` along
    ``wanted`` (each ``[F, 3]``), its distance from ``base`` kept; the identity where the ray
    passes out of its reach or ``wanted`` is zero."""
    direction = wanted / np.maximum(np.linalg.norm(wanted, axis=-1, keepdims=True), 1e-12)
    offset = base - start
    length = np.linalg.norm(end - base, axis=-1)
    along = np.sum(direction * offset, axis=-1)
    # |start + t d - base| = length: t^2 - 2 t (d . offset) + |offset|^2 - length^2 = 0, the far root.
    disc = along**2 - np.sum(offset * offset, axis=-1) + length**2
    ok = (disc >= 0) & (np.linalg.norm(wanted, axis=-1) > 0)
    t = along + np.sqrt(np.where(ok, disc, 0.0))
    target = start + t[:, None] * direction
    swing = quat.between(end - base, target - base)
    return np.where(ok[:, None], swing, [0.0, 0.0, 0.0, 1.0])


__all__ = ["CHAINS", "keep_trunk"]
