"""The dynamic features per frame of the decoupling method (Boehs et al.): the hips' velocity in
the heading frame and its running mean, foot contacts and air time, the hips' height and the
thighs' rotations.

Python does forward kinematics, joint roles and defaults; the per-frame loops (speeds, contact
filter, heading frame, running mean) run in the kernels (Rust, or the NumPy twins in
``expressive_mocap.reference``). Y is up; thresholds are fractions of the actor's height, speeds
per second (see :mod:`expressive_mocap.body.contacts`).
"""

from __future__ import annotations

import numpy as np

from .. import ops
from ..body.contacts import (
    FLOOR_PERCENTILE,
    HEIGHT_THRESHOLD,
    MIN_DURATION,
    SPEED_THRESHOLD,
    _floor,
    foot_contacts,
    take_of,
)
from ..body.take import Take
from ..errors import ArgumentError
from ..motion import Motion
from ..rotations.quat import mean_rotation

FEATURE_NAMES = (
    "velocity_x",  # hips velocity in the heading frame (x = left, y = up, z = forward) / height, per s
    "velocity_y",
    "velocity_z",
    "mean_velocity_x",  # the same, averaged over the last third of a second
    "mean_velocity_y",
    "mean_velocity_z",
    "contact_left",  # 1 in contact, 0 in flight
    "contact_right",
    "air_time_left",  # seconds since the foot last left contact
    "air_time_right",
    "hips_height",  # (hips height - floor) / hips rest height
    "thigh_left_x",  # local rotation of the upper legs (x, y, z, w)
    "thigh_left_y",
    "thigh_left_z",
    "thigh_left_w",
    "thigh_right_x",
    "thigh_right_y",
    "thigh_right_z",
    "thigh_right_w",
)


def _thigh_reference(thigh_reference, thighs: np.ndarray | None, causal: bool) -> np.ndarray:
    if thigh_reference is None:
        if thighs is None:
            raise ArgumentError("argument `thigh_reference`: needed where no thigh rotations are given")
        # Causal: the first frame (the only one every frame may look at); offline: the clip's mean.
        return thighs[0].copy() if causal else mean_rotation(thighs)
    reference = np.asarray(thigh_reference, dtype=np.float64)
    if reference.shape != (2, 4) or not np.isfinite(reference).all():
        raise ArgumentError(
            "argument `thigh_reference`: expected finite quaternions [2, 4] "
            f"(left, right; x, y, z, w), got shape {list(reference.shape)}"
        )
    return np.ascontiguousarray(reference)


def dynamic_features(
    motion: Motion | Take,
    *,
    floor: float | None = None,
    thigh_reference=None,
    causal: bool = True,
    height_threshold: float = HEIGHT_THRESHOLD,
    speed_threshold: float = SPEED_THRESHOLD,
    min_duration: float = MIN_DURATION,
) -> np.ndarray:
    """The 19 features of every frame, ``float64 [F, 19]``, columns named in :data:`FEATURE_NAMES`.

    Frame ``t`` uses frames ``<= t`` only (with the defaults ``causal=True``): hips velocity
    ``(x_t - x_{t-1}) / dt / height`` in the heading frame (yaw removed; heading from the line
    between the upper legs; 0 at frame 0), its mean over the last ``round(fps / 3)`` frames,
    foot contacts (causal hold filter), air time, hips height above the floor / hips rest height,
    and each upper leg's local rotation kept on the hemisphere of ``thigh_reference [2, 4]``
    (default: the first frame's thigh rotations; a trained model passes its own).
    ``causal=False`` uses the offline contact filter, the 5th percentile of toe heights as the
    default floor (0 when causal) and the clip's mean thigh rotations as the default reference.
    Other arguments as in :func:`~expressive_mocap.body.contacts.foot_contacts`.
    """
    take = take_of(motion)
    motion, roles, body = take.motion, take.body.roles, take.body
    floor = _floor(floor, take, causal)
    contacts = foot_contacts(
        take,
        floor=floor,
        causal=causal,
        height_threshold=height_threshold,
        speed_threshold=speed_threshold,
        min_duration=min_duration,
    )
    points = np.ascontiguousarray(take.positions[:, [roles.hips, *roles.upper_legs]])
    thighs = np.ascontiguousarray(motion.rotations[:, list(roles.upper_legs)])
    reference = _thigh_reference(thigh_reference, thighs, causal)
    window = max(1, int(round(motion.fps / 3)))
    return ops.dynamic_features(
        points,
        thighs,
        contacts,
        reference,
        motion.frame_time,
        body.actor_height,
        body.hips_rest_height,
        floor,
        window,
    )


def gait_many(
    motions,
    *,
    features: bool = True,
    contacts: bool = True,
    floor: float | None = 0.0,
    thigh_reference=None,
    fk=None,
) -> list[tuple[np.ndarray | None, np.ndarray | None]]:
    """:func:`dynamic_features` and :func:`~expressive_mocap.body.contacts.foot_contacts` of many
    motions (or takes) in one kernel call (clips in parallel with the Rust kernels: the way to run
    them over an archive).

    Per motion ``(features [F, 19] or None, contacts bool [F, 2] or None)``: the features are
    causal, on ``floor`` (None: the 5th percentile of toe heights) with ``thigh_reference``
    (default: the first frame's thighs), i.e. ``dynamic_features(m, floor=floor,
    thigh_reference=thigh_reference)``; the contacts are ``foot_contacts(m)`` (offline, default
    floor). All motions share one hierarchy (joint names), whose roles the first one's Body
    gives; each clip has its own actor height; thresholds are the defaults. ``fk``: each motion's
    ``(world rotations, world positions)`` if already computed (a take's are used otherwise)."""
    takes = [take_of(m) for m in motions]
    if not takes:
        return []
    names = takes[0].motion.skeleton.names
    other = next((t.motion for t in takes if t.motion.skeleton.names != names), None)
    if other is not None:
        raise ArgumentError(
            f"argument `motions`: every motion needs the same joints; {len(other.skeleton.names)} joints "
            f"({', '.join(other.skeleton.names[:3])}, ...) differ from the first motion's"
        )
    roles = takes[0].body.roles
    if floor is not None and not np.isfinite(float(floor)):
        raise ArgumentError(f"argument `floor`: must be a finite height or None, got {floor}")
    if thigh_reference is not None:
        thigh_reference = _thigh_reference(thigh_reference, None, True)
    if fk is None:
        fk = [t.fk for t in takes]
    elif len(fk) != len(takes):
        raise ArgumentError(f"argument `fk`: {len(fk)} results for {len(takes)} motions")
    clips = [
        (positions, t.motion.rotations, t.motion.frame_time, t.body.actor_height, t.body.hips_rest_height)
        for t, (_, positions) in zip(takes, fk)
    ]
    return ops.clip_gait_many(
        clips,
        roles.gait_joints,
        ops.GaitSettings(HEIGHT_THRESHOLD, SPEED_THRESHOLD, MIN_DURATION, FLOOR_PERCENTILE),
        features=features,
        contacts=contacts,
        feature_floor=None if floor is None else float(floor),
        thigh_reference=thigh_reference,
    )


__all__ = ["FEATURE_NAMES", "dynamic_features", "gait_many"]
