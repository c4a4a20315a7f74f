"""Planted feet after retargeting: through each of the source's contacts, each ankle follows the
source's (carried onto the target: still where the source's is still), with two-bone leg IK
(the foot keeps its world rotation), eased in and out."""

from __future__ import annotations

import numpy as np

from .. import quat
from ..exaggeration.footlock import contact_weights
from ..features import FLOOR_PERCENTILE, foot_contacts, percentiles_by_clip
from ..ik import two_bone_ik
from ..motion import Motion
from ..roles import JointRoles, actor_height
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
        offsets = _run_offsets(positions[:, foot] - guide[:, s], contacts[:, s], bounds)
        w = weights[frames, s, None]
        target = (1 - w) * positions[frames, foot] + w * (guide[frames, s] + offsets[frames])
        t = motion.translations
        upper, lower = two_bone_ik(
            positions[frames, hip], world[frames, hip], world[frames, knee], t[frames, knee], t[frames, foot], target
        )
        parent = parents[hip]
        rotations[frames, hip] = quat.mul(quat.conjugate(world[frames, parent]), upper) if parent >= 0 else upper
        rotations[frames, knee] = quat.mul(quat.conjugate(upper), lower)
        rotations[frames, foot] = quat.mul(quat.conjugate(lower), world[frames, foot])
    return Motion(skeleton, rotations, motion.translations, motion.frame_time)


def _run_offsets(ankle: np.ndarray, contact: np.ndarray, bounds) -> np.ndarray:
    """Per frame, the mean of ``ankle [F, 3]`` over the nearest contact run of its clip (clips
    laid end to end as ``bounds`` says; a clip without contact: its own value). All clips at once."""
    out = ankle.copy()
    bounds = np.asarray(bounds, dtype=np.int64)
    clip = np.repeat(np.arange(len(bounds) - 1), np.diff(bounds))
    # Runs begin where a contact begins or a clip does in contact, and end likewise.
    touching = contact.astype(bool)
    begins = touching.copy()
    begins[1:] &= ~touching[:-1] | (clip[1:] != clip[:-1])
    ends = touching.copy()
    ends[:-1] &= ~touching[1:] | (clip[1:] != clip[:-1])
    starts, stops = np.flatnonzero(begins), np.flatnonzero(ends) + 1
    if not len(starts):
        return out
    run = np.full(len(ankle), -1)
    run[starts] = np.arange(len(starts))
    run_of = np.maximum.accumulate(run)  # the last run begun at or before each frame
    inside = touching & (run_of >= 0)
    # Each run's sum in frame order (bincount adds as a run's mean does), then the means.
    counts = (stops - starts)[:, None]
    weights = ankle[inside]
    sums = np.stack([np.bincount(run_of[inside], weights[:, i], len(starts)) for i in range(3)], axis=1)
    means = sums / counts
    # Frames outside a run take the nearest run of their clip by centre (the first of a tie).
    run_clip = clip[starts]
    centres = (starts + stops - 1) / 2
    first = np.searchsorted(run_clip, clip, side="left")
    last = np.searchsorted(run_clip, clip, side="right") - 1
    has_runs = last >= first
    frames = np.arange(len(ankle))
    before = np.clip(np.searchsorted(centres, frames, side="right") - 1, first, np.maximum(last, first))
    after = np.clip(before + 1, first, np.maximum(last, first))
    nearer_after = np.abs(centres[np.minimum(after, len(centres) - 1)] - frames) < np.abs(
        centres[np.minimum(before, len(centres) - 1)] - frames
    )
    nearest = np.where(nearer_after, after, before)
    picked = np.where(inside, run_of, nearest)
    use = inside | has_runs
    out[use] = means[np.minimum(picked[use], len(means) - 1)]
    return out


def source_contacts(clips: list[Motion], rig, upright_positions: np.ndarray, bounds=None) -> np.ndarray:
    """Contacts ``bool [F, 2]`` of ``clips`` (of the rig ``rig``, laid end to end as ``bounds``
    says; None: one clip) from their world positions turned to the canonical axes (Y up, file
    units), each clip on its own floor."""
    bounds = [0, len(upright_positions)] if bounds is None else bounds
    skeleton = clips[0].skeleton
    roles = JointRoles.from_map(skeleton, rig.jmap)
    height = actor_height(skeleton, roles)  # one skeleton: the same for every clip
    floors = percentiles_by_clip(upright_positions[:, list(roles.toes), 1], bounds, FLOOR_PERCENTILE)
    pieces = zip(clips, floors, bounds[:-1], bounds[1:])
    return np.concatenate(
        [foot_contacts(c, roles, floor=f, height=height, positions=upright_positions[a:b]) for c, f, a, b in pieces]
    )


__all__ = ["BLEND_FRAMES", "plant_feet", "source_contacts"]
