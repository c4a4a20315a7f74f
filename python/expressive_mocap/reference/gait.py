"""Twin of ``rust/gait.rs``: dynamic features and foot contacts of whole clips from their
forward kinematics, by gathering the joints and calling the two kernels' twins clip by clip."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from .features import dynamic_features
from .footsteps import foot_contacts

GAIT_ROLES = "[hips, left upper leg, right upper leg, left foot, right foot, left toe, right toe]"


def _at_least_one_frame(x: float) -> int:
    return max(1, int(round(x)))


def clip_gait_many(
    clips,
    roles,
    height_threshold: float,
    speed_threshold: float,
    min_duration: float,
    floor_percentile: float,
    features: bool,
    contacts: bool,
    feature_floor: float | None = None,
    thigh_reference: np.ndarray | None = None,
) -> list[tuple[np.ndarray | None, np.ndarray | None]]:
    """Per clip ``(positions [F, J, 3] world, rotations [F, J, 4] local, frame_time, height,
    hips_rest_height)`` (file units): causal
    features ``[F, 19]`` on ``feature_floor`` (None: the ``floor_percentile`` of both toes'
    heights) with ``thigh_reference [2, 4]`` (None: the first frame's thighs), and offline
    contacts ``bool [F, 2]`` on the toe-percentile floor; each None unless asked for."""
    roles = [int(r) for r in roles]
    if len(roles) != 7:
        raise ArgumentError(f"argument `roles`: expected 7 joint indices {GAIT_ROLES}, got {len(roles)}")
    hips, left_leg, right_leg, left_foot, right_foot, left_toe, right_toe = roles
    if thigh_reference is not None and np.shape(thigh_reference) != (2, 4):
        raise ArgumentError(f"argument `thigh_reference`: expected shape [2, 4], got {list(np.shape(thigh_reference))}")
    out = []
    for index, (positions, rotations, frame_time, height, hips_rest_height) in enumerate(clips):
        positions, rotations = np.asarray(positions, dtype=np.float64), np.asarray(rotations, dtype=np.float64)
        if positions.ndim != 3 or positions.shape[2] != 3 or rotations.shape != (*positions.shape[:2], 4):
            raise ArgumentError(
                f"argument `clips`: clip {index} has positions {list(positions.shape)} and rotations "
                f"{list(rotations.shape)}, expected [F, J, 3] and [F, J, 4]"
            )
        try:
            out.append(
                _clip(
                    positions,
                    rotations,
                    float(frame_time),
                    roles,
                    float(height),
                    float(hips_rest_height),
                    height_threshold,
                    speed_threshold,
                    min_duration,
                    floor_percentile,
                    features,
                    contacts,
                    feature_floor,
                    thigh_reference,
                )
            )
        except (ValueError, IndexError) as error:
            raise ArgumentError(f"clip {index}: {error}") from None
    return out


def _clip(
    positions,
    rotations,
    frame_time,
    roles,
    height,
    hips_rest_height,
    height_threshold,
    speed_threshold,
    min_duration,
    floor_percentile,
    want_features,
    want_contacts,
    feature_floor,
    thigh_reference,
):
    frames, joints = positions.shape[:2]
    for name, index in zip(("hips", "upper_legs", "upper_legs", "feet", "feet", "toes", "toes"), roles):
        if not 0 <= index < joints:
            raise ArgumentError(f"argument `{name}`: joint {index} out of range for {joints} joints")
    if not (np.isfinite(frame_time) and frame_time > 0):
        raise ArgumentError(f"argument `frame_time`: must be a positive number of seconds, got {frame_time}")
    if frames == 0:
        return (np.zeros((0, 19)) if want_features else None), (np.zeros((0, 2), bool) if want_contacts else None)
    hips, left_leg, right_leg, left_foot, right_foot, left_toe, right_toe = roles
    toe_floor = float(np.percentile(positions[:, [left_toe, right_toe], 1], floor_percentile))
    feet = np.ascontiguousarray(positions[:, [[left_foot, left_toe], [right_foot, right_toe]]])
    min_frames = _at_least_one_frame(min_duration * (1.0 / frame_time))

    def contacts_on(floor, causal):
        return foot_contacts(
            feet, frame_time, floor, height_threshold * height, speed_threshold * height, min_frames, causal
        )

    features = None
    if want_features:
        floor = toe_floor if feature_floor is None else float(feature_floor)
        thighs = np.ascontiguousarray(rotations[:, [left_leg, right_leg]])
        reference = thighs[0] if thigh_reference is None else np.asarray(thigh_reference, dtype=np.float64)
        points = np.ascontiguousarray(positions[:, [hips, left_leg, right_leg]])
        window = _at_least_one_frame(1.0 / frame_time / 3.0)
        features = dynamic_features(
            points, thighs, contacts_on(floor, True), reference, frame_time, height, hips_rest_height, floor, window
        )
    return features, (contacts_on(toe_floor, False) if want_contacts else None)


__all__ = [
    "GAIT_ROLES",
    "clip_gait_many",
]
