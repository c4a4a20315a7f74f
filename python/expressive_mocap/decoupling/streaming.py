"""Decoupling a motion one frame at a time, as it arrives (e.g. from a live capture)."""

from __future__ import annotations

import numpy as np

from ..motion import Motion
from .algebra import EXPONENT, GAIN, split_from_features


class StreamingDecoupler:
    """Decouples a motion one frame at a time, as it arrives (e.g. from a live capture).

    The features are causal, so frame ``t`` needs only the frames before it: the decoupler keeps
    the last ``history`` seconds (enough for the velocity mean, the contact filter and the air
    time of any step) and returns, for each new frame, its body-mechanics rotations, filtered
    expressive rotations and activity per joint. The floor is given (default 0), not estimated.
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
    ):
        self.model, self.skeleton, self.frame_time = model, skeleton, float(frame_time)
        self.floor, self.gain, self.exponent = float(floor), gain, exponent
        self.capacity = max(2, int(round(history / self.frame_time)))
        self._rotations: list[np.ndarray] = []
        self._translations: list[np.ndarray] = []

    def push(self, rotations, translations) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One frame in (local ``rotations [J, 4]``, ``translations [J, 3]``); its body mechanics
        ``[J, 4]``, expressive component ``[J, 4]`` and activity ``[J]`` out."""
        self._rotations.append(np.asarray(rotations, dtype=np.float64))
        self._translations.append(np.asarray(translations, dtype=np.float64))
        del self._rotations[: -self.capacity], self._translations[: -self.capacity]
        window = Motion(self.skeleton, np.stack(self._rotations), np.stack(self._translations), self.frame_time)
        features = self.model.features(window, floor=self.floor)[-1:]
        expressive, recovered, activity = split_from_features(
            window.rotations[-1:], features, self.model, self.gain, self.exponent
        )
        return recovered[0], expressive[0], activity[0]


__all__ = ["StreamingDecoupler"]
