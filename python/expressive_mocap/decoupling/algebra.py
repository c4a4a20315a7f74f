"""The decomposition of the decoupling method (Boehs, Vieira & Pereira, "Decoupling
Expressiveness and Body-Mechanics in Human Motion"): original rotations ``O`` and the
body-mechanics model's prediction ``B`` give filtered expressive rotations ``E*``,
body-mechanics rotations ``B'`` and a per-joint activity ``A``, with ``E* B' = O`` exactly.

:func:`split` is that step given the predicted rotations; :func:`split_from_features` runs
"features -> body model -> split" for any number of frames, and is what :func:`decompose`
(one motion), :func:`decompose_many` (many clips, one network call) and the streaming
decoupler (one frame at a time) share.

A body-mechanics model is anything with ``predict(motion) -> rotations [F, J, 4]``: the local
rotations a neutral performer would have at each frame given the motion's dynamics (root and
hips copied from the motion). The shipped one is
:class:`expressive_mocap.decoupling.body_model.BodyModel`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from ..body.take import Take
from ..errors import ModelError
from ..motion import Motion
from ..ops import Arms, Trunk, compose_rotations, split_rotations, split_rotations_many
from ..rotations import quat
from .pelvis import mean_postures

GAIN = 2.0  # g of the activity index A = clip((tanh(a) g)^b, 0, 1)
EXPONENT = 4.0  # b
# The network reads each frame on its own, and its pose jumps where a binary feature (a foot
# contact) flips: up to 20 degrees between two frames at 30 and at 120 fps alike. The activity
# index is steep (0.03 to 1 over 13 to 32 degrees): a wave's elbow crossing it in two frames made
# E* jump 27 degrees. Edits carried both into the output as pops (a mixed wave's hand peaked at
# 2.6x the source's speed at 30 fps, 9x at 120 fps); smoothed in time (Gaussians, in seconds so
# that every frame rate gets the same), the hand's peak is 1.2x the source's.
BODY_SMOOTHING = 0.05  # s, sigma of the Gaussian on the predicted body mechanics B
ACTIVITY_SMOOTHING = 0.1  # s, sigma of the Gaussian on the activity A
# A joint active (activity above HELD_ACTIVITY) in at least HELD_SHARE of a clip's frames holds a
# posture the model reads as expressive: a held style (a feminine walk's arms), or the actor's own
# habit where the model is not calibrated to them (the shared folder's 21-joint neutral walks:
# trunk and right upper arm; none of dataset-2's neutral walks has one).
HELD_ACTIVITY = 0.5
HELD_SHARE = 0.75


class BodyMechanicsModel(Protocol):
    def predict(self, motion: Motion) -> np.ndarray:
        """Body-mechanics local rotations ``[F, J, 4]`` for ``motion``."""


class FeatureModel(Protocol):
    def predict_from_features(
        self, rotations: np.ndarray, features: np.ndarray, posture: np.ndarray | None = None
    ) -> np.ndarray:
        """Body-mechanics local rotations ``[F, J, 4]`` from ``features [F, 19]`` and the motion's
        ``rotations`` (``posture``: the pelvis posture to carry the spine onto, per frame or one)."""


def split(
    original: np.ndarray,
    predicted: np.ndarray,
    gain: float = GAIN,
    exponent: float = EXPONENT,
    activity_scale: np.ndarray | None = None,
    fps: float | None = None,
    trunk: Trunk | None = None,
    arms: Arms | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(expressive E*, body B', activity A)`` of ``original [F, J, 4]`` given the model's
    ``predicted [F, J, 4]`` (:class:`~expressive_mocap.errors.ModelError` if their shapes differ).
    ``activity_scale [J]``: per joint, the angle of ``E`` is divided by it before the activity
    index reads it (a calibrated model's threshold; None: 1 everywhere). ``fps``: the frames are
    one clip's at that rate, and ``B`` and ``A`` are smoothed in time (BODY_SMOOTHING,
    ACTIVITY_SMOOTHING); None: each frame on its own (a stream's newest frame). ``trunk``, ``arms``:
    the model's chains read as wholes (:mod:`.trunk`, :mod:`.arms`)."""
    predicted = np.asarray(predicted, dtype=np.float64)
    if predicted.shape != np.shape(original):
        raise ModelError(
            f"the model predicted rotations {list(predicted.shape)} for a motion of {list(np.shape(original))}"
        )
    sigmas = (0.0, 0.0) if fps is None else (BODY_SMOOTHING * fps, ACTIVITY_SMOOTHING * fps)
    return split_rotations(original, predicted, gain, exponent, activity_scale, *sigmas, trunk, arms)


def split_from_features(
    rotations: np.ndarray,
    features: np.ndarray,
    model: FeatureModel,
    gain: float = GAIN,
    exponent: float = EXPONENT,
    posture: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`split` of ``rotations [F, J, 4]`` with the model's prediction from ``features [F, 19]``
    (``posture``: the pelvis posture the model carries the spine onto; None: ``rotations``')."""
    predicted = model.predict_from_features(rotations, features, posture)
    scale, trunk = getattr(model, "activity_scale", None), getattr(model, "trunk", None)
    return split(rotations, predicted, gain, exponent, scale, trunk=trunk, arms=getattr(model, "arms", None))


@dataclass(frozen=True)
class Decomposition:
    """``original`` split into filtered expressive rotations ``expressive`` (E*, ``[F, J, 4]``,
    identity where nothing expressive happens) and body-mechanics rotations ``body`` (B'), with
    the per-joint ``activity`` ``[F, J]`` in [0, 1]; ``E* * B' = O`` exactly."""

    original: Motion
    expressive: np.ndarray
    body: np.ndarray
    activity: np.ndarray

    def body_motion(self) -> Motion:
        """The body-mechanics component as a motion (translations and root trajectory of the original)."""
        return self._with_rotations(self.body)

    def expressive_motion(self) -> Motion:
        """The expressive component made visible: E* laid on the clip's mean body-mechanics
        pose (a neutral stance), root and hips following the original."""
        mean_body = quat.mean_rotation(self.body)
        return self._with_rotations(quat.mul(self.expressive, mean_body[None]))

    def recompose(self, scale: float = 1.0) -> Motion:
        """``E*^scale * B'``: 1 gives back the original (exactly: its own rotations, not their
        product's rounding), 0 the body mechanics, 1.5 150% expressiveness."""
        if scale == 1.0:
            return self._with_rotations(self.original.rotations.copy())
        return self._with_rotations(compose_rotations(self.expressive, self.body, scale))

    def held_joints(self) -> list[str]:
        """The joints active through most of the clip (:data:`HELD_ACTIVITY`, :data:`HELD_SHARE`):
        postures held throughout, which a model not calibrated to the actor cannot tell from
        the actor's habit."""
        share = np.mean(self.activity > HELD_ACTIVITY, axis=0)
        return [name for name, held in zip(self.original.skeleton.names, share >= HELD_SHARE) if held]

    def _with_rotations(self, rotations: np.ndarray) -> Motion:
        o = self.original
        return Motion(o.skeleton, rotations, o.translations, o.frame_time)


def decompose(
    motion: Motion | Take, model: BodyMechanicsModel, gain: float = GAIN, exponent: float = EXPONENT
) -> Decomposition:
    """Split ``motion`` (or a take of it) into expressive and body-mechanics components with
    ``model`` (a :class:`~expressive_mocap.decoupling.BodyModel` reads the take's positions and
    contacts instead of computing them again)."""
    take = Take.of(motion)
    scale = getattr(model, "activity_scale", None)
    predict_take = getattr(model, "predict_take", None)
    predicted = predict_take(take) if predict_take is not None else model.predict(take.motion)
    trunk, arms = getattr(model, "trunk", None), getattr(model, "arms", None)
    expressive, body, activity = split(
        take.motion.rotations, predicted, gain, exponent, scale, take.motion.fps, trunk, arms
    )
    return Decomposition(take.motion, expressive, body, activity)


def decompose_many(
    rotations: list[np.ndarray],
    features: list[np.ndarray],
    model: FeatureModel,
    fps: list[float],
    float32: bool = False,
) -> list[dict[str, np.ndarray]]:
    """``decompose`` of many clips at once, from each clip's local ``rotations [F, J, 4]``, model
    ``features [F, 19]`` and frame rate: one network call for all their frames (the network works
    frame by frame, so this is the per-clip result, with one kernel call that the Rust MLP
    spreads over its threads instead of a small call per clip), then each clip split on its own
    (smoothed in its own time, so a clip's result never depends on the clips beside it).
    Returns per clip ``activity [F, J]``, ``body`` and ``expressive [F, J, 4]`` (float64).
    ``float32``: run the network in float32, about 2x faster (on 12,689 Bandai frames: activity
    within 2e-5, body rotations within 3e-6 of the float64 result)."""
    if not rotations:
        return []
    inputs, every = np.concatenate(features), np.concatenate(rotations)
    lengths = [len(r) for r in rotations]
    # Each clip's spine carried onto its own pelvis posture, whatever clips share the call.
    pelvis = getattr(model, "pelvis", None)
    posture = None if pelvis is None else np.repeat(mean_postures(every, lengths, pelvis.path), lengths, axis=0)
    predicted = model.predict_from_features(every, inputs.astype(np.float32) if float32 else inputs, posture)
    cuts = np.cumsum(lengths)[:-1]
    # Every clip split in one kernel call, clips in parallel (clip by clip, the splits were a
    # fifth of a --model run's time on one core whatever the cores).
    parts = split_rotations_many(
        rotations,
        np.split(predicted, cuts),
        GAIN,
        EXPONENT,
        getattr(model, "activity_scale", None),
        [BODY_SMOOTHING * rate for rate in fps],
        [ACTIVITY_SMOOTHING * rate for rate in fps],
        getattr(model, "trunk", None),
        getattr(model, "arms", None),
    )
    return [{"activity": activity, "body": body, "expressive": expressive} for expressive, body, activity in parts]


__all__ = [
    "EXPONENT",
    "GAIN",
    "HELD_ACTIVITY",
    "HELD_SHARE",
    "BodyMechanicsModel",
    "Decomposition",
    "FeatureModel",
    "decompose",
    "decompose_many",
    "split",
    "split_from_features",
]
