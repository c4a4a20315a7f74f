"""The decomposition of many clips at once, for the model kinds of a dataset (activity, body,
expressive). Waits here until it joins the decoupling code (``decoupling/``): the lead moves it."""

from __future__ import annotations

import numpy as np

from ..decouple import EXPONENT, GAIN
from ..kernels import decouple_rotations


def decompose_many(
    rotations: list[np.ndarray], features: list[np.ndarray], model, float32: bool = False
) -> list[dict[str, np.ndarray]]:
    """``decompose`` of many clips at once, from each clip's local ``rotations [F, J, 4]`` and
    model ``features [F, 19]``: one network call for all their frames (the network and the
    decoupling work frame by frame, so this is the per-clip result, with one kernel call that
    the Rust MLP spreads over its threads instead of a small call per clip). Returns per clip
    ``activity [F, J]``, ``body`` and ``expressive [F, J, 4]`` (float64). ``float32``: run the
    network in float32, about 2x faster (on 12,689 Bandai frames: activity within 2e-5, body
    rotations within 3e-6 of the float64 result)."""
    if not rotations:
        return []
    original = np.concatenate(rotations)
    inputs = np.concatenate(features)
    body = model.predict_from_features(original, inputs.astype(np.float32) if float32 else inputs)
    expressive, recovered, activity = decouple_rotations(original, body, GAIN, EXPONENT)
    cuts = np.cumsum([len(r) for r in rotations])[:-1]
    return [
        {"activity": a, "body": b, "expressive": e}
        for a, b, e in zip(np.split(activity, cuts), np.split(recovered, cuts), np.split(expressive, cuts))
    ]


__all__ = ["decompose_many"]
