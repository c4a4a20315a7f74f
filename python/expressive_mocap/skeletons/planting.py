"""Planted feet after retargeting: through each of the source's contacts, each ankle follows the
source's (carried onto the target: still where the source's is still), with two-bone leg IK
(the foot keeps its world rotation), eased in and out."""

from __future__ import annotations

import numpy as np

from .. import quat
from ..exaggeration.footlock import contact_weights
from ..features import foot_contacts
from ..ik import two_bone_ik
from ..motion import Motion
from ..roles import JointRoles
from .jointmap import JointMap

BLEND_FRAMES = 3


def plant_feet(
    motion: Motion,
    jmap: JointMap,
    contacts: np.ndarray,
    guide: np.ndarray,
    blend_frames: int = BLEND_FRAMES,
    starts=None,
) -> Motion:
    """``motion`` with each ankle, through each contact run of ``contacts bool [F, 2]`` (left,
    right), moving as ``guide [F, 2, 3]`` (the source's ankles in this motion's world) does, from
    where this motion has it on average over the run. Legs whose knee is not the foot's parent
    and the upper leg's child (a twist bone in the chain) are left as they are. ``starts``: where
    clips laid end to end begin and the last one ends (runs and easing stop there)."""
    skeleton = motion.skeleton
    parents = skeleton.parents
    world, positions = motion.fk()
    contacts = np.asarray(contacts, dtype=bool)
    bounds = [0, motion.n_frames] if starts is None else [int(b) for b in starts]
    pieces = list(zip(bounds[:-1], bounds[1:]))
    weights = np.concatenate([contact_weights(contacts[a:b], blend_frames) for a, b in pieces])
    rotations = motion.rotations.copy()
    for s, side in enumerate(("left", "right")):
        hip, knee, foot = (jmap[f"{side}_{r}"] for r in ("upper_leg", "lower_leg", "foot"))
        if parents[foot] != knee or parents[knee] != hip:
            continue
        frames = np.flatnonzero(weights[:, s] > 0)
        if not len(frames):
            continue
        gap = positions[:, foot] - guide[:, s]
        offsets = np.concatenate([_run_offsets(gap[a:b], contacts[a:b, s]) for a, b in pieces])
        w = weights[frames, s, None]
        target = (1 - w) * positions[frames, foot] + w * (guide[frames, s] + offsets[frames])
        t = motion.translations[frames]
        upper, lower = two_bone_ik(
            positions[frames, hip], world[frames, hip], world[frames, knee], t[:, knee], t[:, foot], target
        )
        parent = parents[hip]
        rotations[frames, hip] = quat.mul(quat.conjugate(world[frames, parent]), upper) if parent >= 0 else upper
        rotations[frames, knee] = quat.mul(quat.conjugate(upper), lower)
        rotations[frames, foot] = quat.mul(quat.conjugate(lower), world[frames, foot])
    return Motion(skeleton, rotations, motion.translations, motion.frame_time)


def _run_offsets(ankle: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """Per frame, the mean of ``ankle [F, 3]`` over the nearest contact run (none: its own value)."""
    out = ankle.copy()
    edges = np.diff(np.r_[0, contact.astype(np.int8), 0])
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    if not len(starts):
        return out
    run = np.full(len(ankle), -1)
    for k, (a, b) in enumerate(zip(starts, ends)):
        run[a:b] = k
    means = np.array([ankle[a:b].mean(axis=0) for a, b in zip(starts, ends)])
    centres = (starts + ends - 1) / 2
    nearest = np.abs(np.arange(len(ankle))[:, None] - centres[None]).argmin(axis=1)
    return np.where((run >= 0)[:, None], means[np.maximum(run, 0)], means[nearest])


def source_contacts(motion: Motion, rig, upright_positions: np.ndarray) -> np.ndarray:
    """Contacts ``bool [F, 2]`` of ``motion`` (of the rig ``rig``) from its world positions turned
    to the canonical axes (Y up, file units)."""
    return foot_contacts(motion, JointRoles.from_map(motion.skeleton, rig.jmap), positions=upright_positions)


__all__ = ["BLEND_FRAMES", "plant_feet", "source_contacts"]
