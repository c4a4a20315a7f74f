"""Decoupling a motion one frame at a time, as it arrives (e.g. from a live capture)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..motion import Motion
from ..rotations import quat
from .algebra import EXPONENT, GAIN, split_from_features
from .pelvis import mean_posture


class StreamingDecoupler:
    """Decouples a motion one frame at a time, as it arrives (e.g. from a live capture).

    The features are causal, so frame ``t`` needs only the frames before it: the decoupler keeps
    the last ``history`` seconds (enough for the velocity mean, the contact filter and the air
    time of any step) and returns, for each new frame, its body-mechanics rotations, filtered
    expressive rotations and activity per joint. The floor is given (default 0), not estimated.
    Each frame is split on its own: without the offline split's smoothing in time (of the
    prediction and of the activity), which needs the frames after; the pelvis posture the model
    carries the spine onto is the window's mean (offline: the clip's).

    A ``skeleton`` other than the model's (any humanoid one; ``joint_map`` as for
    :func:`~expressive_mocap.body.find_joint_map`) is read from the first frame (its
    conventions, and its floor: the lowest foot joint then, instead of ``floor``; its bones'
    twists are taken from the rotations, which one frame cannot judge); each frame is
    retargeted onto the model's body, decoupled there, and its body mechanics carried back onto
    the frame as per-joint changes of world orientation. The rotations returned are then the
    skeleton's (the expressive component as ``O B^-1`` per joint), the activity the model's joints'.
    """

    def __init__(
        self,
        model,
        skeleton,
        frame_time: float,
        floor: float = 0.0,
        history: float = 2.0,
        gain: float = GAIN,
        exponent: float = EXPONENT,
        joint_map: dict | None = None,
    ):
        self.model, self.skeleton, self.frame_time = model, skeleton, float(frame_time)
        self.floor, self.gain, self.exponent = float(floor), gain, exponent
        self.capacity = max(2, int(round(history / self.frame_time)))
        self._rotations: list[np.ndarray] = []
        self._translations: list[np.ndarray] = []
        self._own = tuple(skeleton.names) == tuple(model.joint_names)
        self._joint_map = joint_map
        self._source: Any = None  # another skeleton's Rig, read from the first frame

    def push(self, rotations, translations) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One frame in (local ``rotations [J, 4]``, ``translations [J, 3]``); its body mechanics
        ``[J, 4]``, expressive component ``[J, 4]`` and activity (per joint of the model) out."""
        frame = Motion(
            self.skeleton,
            np.asarray(rotations, dtype=np.float64)[None],
            np.asarray(translations, dtype=np.float64)[None],
            self.frame_time,
        )
        if self._own:
            body, expressive, activity = self._step(frame, self.floor)
            return body, expressive, activity
        from ..skeletons.canonical import Carried
        from ..skeletons.rig import Rig

        if self._source is None:
            # A live stream's twists are taken from its rotations: one frame cannot tell a capture
            # that twists bones arbitrarily (measured: the demo's waving arm reads so on frame 0).
            self._source = Rig.of(frame, self._joint_map)._replace(untrusted=frozenset())
        carried = Carried(frame, target=None, source=self._source, stand=False)
        body, _, activity = self._step(carried.body, 0.0)  # the canonical body stands on 0
        on_body = carried.body
        # The body mechanics of one frame, not an edit: no hinge limits (one frame tells no axes).
        back = carried.back(Motion(on_body.skeleton, body[None], on_body.translations, self.frame_time), hinges=False)
        mine = back.rotations[0]
        return mine, quat.mul(frame.rotations[0], quat.conjugate(mine)), activity

    def _step(self, frame: Motion, floor: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The newest frame of the window (on the model's skeleton) decoupled."""
        self._rotations.append(frame.rotations[0])
        self._translations.append(frame.translations[0])
        del self._rotations[: -self.capacity], self._translations[: -self.capacity]
        skeleton = frame.skeleton
        window = Motion(skeleton, np.stack(self._rotations), np.stack(self._translations), self.frame_time)
        features = self.model.features(window, floor=floor)[-1:]
        pelvis = getattr(self.model, "pelvis", None)
        posture = None if pelvis is None else mean_posture(window.rotations, pelvis.path)  # the window's
        expressive, recovered, activity = split_from_features(
            window.rotations[-1:], features, self.model, self.gain, self.exponent, posture
        )
        return recovered[0], expressive[0], activity[0]


__all__ = ["StreamingDecoupler"]
