"""Twin of ``rust/planting.rs``: planted feet after retargeting, vectorised over frames."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..rotations import quat
from .fk import forward_kinematics
from .ik import two_bone_ik


def plant_feet(rotations, translations, parents, legs, contacts, guide, starts, blend: int) -> np.ndarray:
    """The local rotations ``[F, J, 4]`` with the feet planted (see ``rust/planting.rs``)."""
    from ..exaggeration.footlock import contact_weights

    frames, joints = len(rotations), len(parents)
    contacts = np.asarray(contacts)
    for name, value, shape in (
        ("contacts", contacts, (frames, 2)),
        ("guide", guide, (frames, 2, 3)),
        ("legs", legs, (2, 3)),
    ):
        if np.shape(value) != shape:
            raise ArgumentError(f"argument `{name}`: expected shape {list(shape)}, got {list(np.shape(value))}")
    bounds = [int(b) for b in starts]
    if not bounds or bounds[0] != 0 or bounds[-1] != frames or np.any(np.diff(bounds) < 0):
        raise ArgumentError(f"argument `starts`: expected rising frame indices from 0 to {frames}")
    for leg in np.asarray(legs).tolist():
        if not (all(0 <= j < joints for j in leg) or leg == [-1, -1, -1]):
            raise ArgumentError(f"argument `legs`: {leg} is not three joints below {joints} (or -1s)")
    world, positions = forward_kinematics(rotations, translations, parents)
    pieces = list(zip(bounds[:-1], bounds[1:]))
    weights = np.concatenate([contact_weights(contacts[a:b], blend) for a, b in pieces] + [np.zeros((0, 2))])
    out = np.array(rotations, dtype=np.float64)
    for s, (hip, knee, foot) in enumerate(np.asarray(legs).tolist()):
        frames_in = np.flatnonzero(weights[:, s] > 0)
        if hip < 0 or not len(frames_in):
            continue
        offsets = _run_offsets(positions[:, foot] - guide[:, s], contacts[:, s], bounds)
        w = weights[frames_in, s, None]
        target = (1 - w) * positions[frames_in, foot] + w * (guide[frames_in, s] + offsets[frames_in])
        t = translations
        upper, lower = two_bone_ik(
            positions[frames_in, hip], world[frames_in, hip], world[frames_in, knee],
            t[frames_in, knee], t[frames_in, foot], target,
        )  # fmt: skip
        parent = parents[hip]
        out[frames_in, hip] = quat.mul(quat.conjugate(world[frames_in, parent]), upper) if parent >= 0 else upper
        out[frames_in, knee] = quat.mul(quat.conjugate(upper), lower)
        out[frames_in, foot] = quat.mul(quat.conjugate(lower), world[frames_in, foot])
    return out


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


__all__ = ["plant_feet"]
