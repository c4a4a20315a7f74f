"""Timing as part of intensity: each cycle's duration and the hips' travel over it, mapped by
intensity like the pose coefficients, and a motion retimed to the mapped timing.

The cycles are time-normalised before the basis is fitted, so the pose alone cannot say that a
livelier walk is quicker with longer strides. Two features per cycle do: ``log`` of its duration
(seconds) and ``log`` of the hips' horizontal travel over it in actor heights (floored at
:data:`IN_PLACE` heights, so an action done in place has a constant travel feature). Logs make a
change a ratio: the edit multiplies the motion's own duration and travel by ``exp(g(k1) -
g(k0))``. A feature is applied only when it follows the intensity (its correlation with the
intensity over every training cycle, averaged over people, at least :data:`PREDICTABLE`), as only
the key DOFs of the pose are.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..body.body import Body
from ..body.roles import JointRoles, path_joint
from ..body.take import Take
from ..motion import Motion
from ..ops import forward_kinematics
from ..rotations import quat
from .cycles import Cycle

TIMING_NAMES = ("duration", "travel")
# Below this travel per cycle (actor heights) an action is done in place: its travel is not scaled.
IN_PLACE = 0.05
# A timing feature is applied when its mean |correlation| with the intensity reaches this.
PREDICTABLE = 0.5


def cycle_timing(take: Take, cycles: Sequence[Cycle]) -> np.ndarray:
    """``[C, 2]``: per cycle, log of its duration (seconds) and log of the hips' horizontal travel
    from its first to its last frame in actor heights (at least :data:`IN_PLACE`)."""
    motion, roles, positions, height = take.motion, take.body.roles, take.positions, take.body.actor_height
    out = np.empty((len(cycles), 2))
    for i, c in enumerate(cycles):
        travel = positions[c.end, roles.hips, [0, 2]] - positions[c.start, roles.hips, [0, 2]]
        distance = max(float(np.linalg.norm(travel)) / height, IN_PLACE)
        out[i] = np.log((c.end - c.start) * motion.frame_time), np.log(distance)
    return out


def _correlation(values: np.ndarray, levels: np.ndarray) -> np.ndarray:
    """Pearson correlation of ``values [N, 2]`` with ``levels [N]`` per column (0 where constant)."""
    dv, dk = values - values.mean(axis=0), levels - levels.mean()
    denominator = np.sqrt((dv * dv).sum(axis=0) * (dk * dk).sum())
    return np.where(denominator > 1e-12, (dv * dk[:, None]).sum(axis=0) / np.maximum(denominator, 1e-300), 0.0)


@dataclass(frozen=True)
class TimingFit:
    """``performances [P, K, 2]`` (the mean of each performance's cycles), ``mappings [2, degree
    + 1]`` (a polynomial in k per feature, highest power first, averaged over people) and
    ``predictability [2]`` (mean over people of the |correlation| of every cycle's feature with
    its intensity)."""

    performances: np.ndarray
    mappings: np.ndarray
    predictability: np.ndarray


def fit_timing(cycles: np.ndarray, owners: np.ndarray, levels: np.ndarray) -> TimingFit:
    """Fit the timing features of every training cycle ``cycles [N, 2]`` (``owners [N, 2]``: the
    person and intensity index of each) at ``levels [K]``: the people's mean performance at each
    level, ``mappings [2, K]``, followed from level to level by :func:`mapped_timing`.

    Not a line, as the pose coefficients' mappings are: timing is not a straight line of
    intensity (the dataset-2 walks' cadence barely moves from exhausted to normal and jumps to
    active; a line through the three carried half of the normal-to-active change). Not a
    polynomial through the levels either: beyond them it turns back (diminishing sped a walk up)."""
    P, K = int(owners[:, 0].max()) + 1, len(levels)
    performances = np.zeros((P, K, 2))
    for p in range(P):
        for k in range(K):
            performances[p, k] = cycles[(owners[:, 0] == p) & (owners[:, 1] == k)].mean(axis=0)
    mappings = performances.mean(axis=0).T
    rho = [np.abs(_correlation(cycles[owners[:, 0] == p], levels[owners[owners[:, 0] == p, 1]])) for p in range(P)]
    return TimingFit(performances, mappings, np.mean(rho, axis=0))


def mapped_timing(mappings: np.ndarray, levels: np.ndarray, k: float) -> np.ndarray:
    """``g(k) [2]``: the timing at intensity ``k`` from the level means ``mappings [2, K]`` at
    ``levels [K]``: straight between neighbouring levels; beyond the ends, on from the end level
    at the slope of the line through all of them (the last step between levels alone, the
    steepest, made exaggerated walks outrun their locked feet)."""
    levels = np.asarray(levels, dtype=np.float64)
    k = float(k)
    if levels[0] <= k <= levels[-1]:
        i = int(np.clip(np.searchsorted(levels, k) - 1, 0, len(levels) - 2))
        share = (k - levels[i]) / (levels[i + 1] - levels[i])
        return mappings[:, i] + share * (mappings[:, i + 1] - mappings[:, i])
    slope = np.polyfit(levels, mappings.T, 1)[0]
    end = 0 if k < levels[0] else -1
    return mappings[:, end] + slope * (k - levels[end])


@dataclass(frozen=True)
class Timing:
    """What the edit did to the timing: the factors the cycles' ``duration`` and the hips'
    ``travel`` over each were multiplied by, whether the training range (+ margin) ``clamped``
    them, and the motion's mean ``before`` and ``after`` as (cycle seconds, travel per cycle in
    file units); ``warp [F']`` the input frame (fractional) of each output frame and ``span`` the
    input frames whose travel was scaled (:func:`retime_like` retimes another motion alike)."""

    duration: float
    travel: float
    clamped: bool
    before: tuple[float, float]
    after: tuple[float, float]
    warp: np.ndarray
    span: tuple[int, int]

    def text(self, unit: str = "file units") -> str:
        (d0, t0), (d1, t1) = self.before, self.after
        clamped = ", clamped to the training range (+margin)" if self.clamped else ""
        return (
            f"timing: cycle duration x{self.duration:.3f} ({d0:.3f} -> {d1:.3f} s, cadence "
            f"{2 / d0:.2f} -> {2 / d1:.2f} steps/s), travel per cycle x{self.travel:.3f} (speed "
            f"{t0 / d0:.3g} -> {t1 / d1:.3g} {unit}/s){clamped}"
        )


def timing_factors(
    change: np.ndarray, own: np.ndarray, lower: np.ndarray, upper: np.ndarray, margin: float
) -> tuple[np.ndarray, bool]:
    """The factors ``[2]`` the motion's duration and travel are multiplied by for a mapped change
    ``change [2]`` (in the log features) of its own mean features ``own [2]``: the new features
    kept within the training range ``lower, upper [2]`` widened by ``margin`` x its width (never
    tighter than the motion's own), travel left alone for an action done in place."""
    width = upper - lower
    low, high = np.minimum(lower - margin * width, own), np.maximum(upper + margin * width, own)
    new = np.clip(own + change, low, high)
    clamped = bool(np.any(np.abs(new - (own + change)) > 1e-12))
    if own[1] <= np.log(IN_PLACE) + 1e-12:
        new[1] = own[1]
    return np.exp(new - own), clamped


def time_warp(n_frames: int, cycles: Sequence[Cycle], duration: float) -> np.ndarray:
    """Fractional input frames ``[F']`` at each output frame when the motion lasts ``duration``
    times as long: its partial cycles before the first whole one and after the last take the new
    tempo too (kept at the input's, they left a jump in tempo at the first and last footstrike of
    the span, and the edit short of the cycle duration it maps to: 0.95 of the dataset-2 training
    people's active cadence instead of 1.0). ``cycles``: the edited cycles (only their presence
    matters; the hips' travel is scaled over their span alone, see :func:`retime`)."""
    t = np.arange(int(np.floor((n_frames - 1) * duration + 1e-9)) + 1, dtype=np.float64)
    return np.clip(t / duration, 0.0, n_frames - 1)


def retime(
    motion: Motion, roles: JointRoles, warp: np.ndarray, span: tuple[int, int], travel: float
) -> tuple[Motion, np.ndarray]:
    """``motion`` sampled at the fractional frames ``warp [F']`` (slerp, linear), the hips'
    horizontal travel over the input frames ``span`` multiplied by ``travel`` (after it, the path
    goes on from where the longer or shorter travel left it); with the world shift ``[F', 3]``
    the travel added to every joint."""
    rotations = quat.resample(motion.rotations, warp)
    translations = quat.resample(motion.translations, warp, rotations=False)
    shift = np.zeros((len(warp), 3))
    if travel != 1.0:
        hips = forward_kinematics(motion.rotations, motion.translations, motion.skeleton.parents)[1][:, roles.hips]
        along = quat.resample(hips, np.clip(warp, *span), rotations=False)
        shift = (travel - 1.0) * (along - hips[span[0]])  # the extra travel so far, kept after the span
        shift[:, 1] = 0.0
        mover = path_joint(motion.translations, motion.skeleton, roles)
        parent = motion.skeleton.parents[mover]
        local = shift
        if parent >= 0:
            world = forward_kinematics(rotations, translations, motion.skeleton.parents)[0][:, parent]
            local = quat.rotate(quat.conjugate(world), shift)
        translations[:, mover] += local
    return Motion(motion.skeleton, rotations, translations, motion.frame_time), shift


def retime_like(motion: Motion, timing: Timing) -> Motion:
    """``motion`` (of as many frames as the edited one, on any skeleton) retimed as an edit was:
    what an edit of it carried onto another skeleton is laid back on."""
    return retime(motion, Body.of(motion.skeleton).roles, timing.warp, timing.span, timing.travel)[0]


def warped_contacts(contacts: np.ndarray, warp: np.ndarray) -> np.ndarray:
    """Contacts ``[F, 2]`` at the fractional frames ``warp``: those of the nearest input frame."""
    return np.asarray(contacts, dtype=bool)[np.rint(warp).astype(int)]


def _run_means(values: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """Per frame, the mean of ``values [F, 3]`` over the nearest run of ``contact [F]`` (none: its own value)."""
    edges = np.diff(np.r_[0, contact.astype(np.int8), 0])
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    if not len(starts):
        return values.copy()
    run = np.full(len(values), -1)
    for k, (a, b) in enumerate(zip(starts, ends)):
        run[a:b] = k
    means = np.array([values[a:b].mean(axis=0) for a, b in zip(starts, ends)])
    centres = (starts + ends - 1) / 2
    nearest = np.abs(np.arange(len(values))[:, None] - centres[None]).argmin(axis=1)
    return np.where((run >= 0)[:, None], means[np.maximum(run, 0)], means[nearest])


def held_still(
    motion: Motion, contacts: np.ndarray, roles: JointRoles, timing: Timing
) -> tuple[Motion, np.ndarray, np.ndarray]:
    """What an edit's foot lock holds at ``timing``: ``motion`` (the input, on any skeleton of
    ``roles``) retimed alike, its ``contacts [F, 2]`` at the new frames, and its ankles held still
    through them (:func:`planted_ankles`): a retimed input's own feet slide where its travel
    was stretched."""
    retimed, shift = retime(motion, roles, timing.warp, timing.span, timing.travel)
    new_contacts = warped_contacts(contacts, timing.warp)
    return retimed, new_contacts, planted_ankles(retimed, new_contacts, roles, shift)


def planted_ankles(motion: Motion, contacts: np.ndarray, roles: JointRoles, shift: np.ndarray) -> np.ndarray:
    """``[F, 2, 3]``: the ankles of the retimed input ``motion`` without the part of the travel's
    ``shift [F, 3]`` that grows during each run of ``contacts`` (held at its mean over the run):
    each stance foot rolls as in the input, where the longer or shorter path would slide it."""
    positions = motion.positions()
    held = [_run_means(shift, contacts[:, s]) - shift for s in (0, 1)]
    return np.stack([positions[:, roles.feet[s]] + held[s] for s in (0, 1)], axis=1)


__all__ = [
    "IN_PLACE",
    "PREDICTABLE",
    "TIMING_NAMES",
    "Timing",
    "TimingFit",
    "cycle_timing",
    "fit_timing",
    "held_still",
    "mapped_timing",
    "planted_ankles",
    "retime",
    "retime_like",
    "time_warp",
    "timing_factors",
    "warped_contacts",
]
