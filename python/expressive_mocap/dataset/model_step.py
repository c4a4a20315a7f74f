"""The last step of a batch's work (:func:`run_model`): the body-mechanics model on all its clips,
then each clip's sums for the normalisation statistics. A stage of its own in the pipeline
(:mod:`.pipeline`): its NumPy parts hold one core, and in a thread of their own they overlap the
next batch's clip kernels on the others instead of keeping them waiting."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..decoupling.algebra import decompose_many
from .forms import add_sums

if TYPE_CHECKING:
    from .work import Outcome


@dataclass
class Ran:
    """A batch after its clips' kernels (:func:`.work.run_clips`): the ``outcomes``; ``kept``, of
    each clip and mirror image the model reads, (values to update, local rotations, model
    features, fps); ``finished``, of each clip and mirror image that succeeded, (its outcome,
    its values); the seconds :func:`.work.prepare` took and those the kernels took."""

    outcomes: list[Outcome]
    kept: list
    finished: list
    prepare_seconds: float
    seconds: float


def run_model(ran: Ran, keep: tuple[str, ...], model, model_float32: bool) -> tuple[list[Outcome], float, float]:
    """The model's kinds of every kept clip (one network call and one split call for the whole
    batch), then the sums: the outcomes, the seconds of :func:`.work.prepare` and those of the
    kernels and this step together."""
    start = time.perf_counter()
    if ran.kept:
        parts = decompose_many(
            [rotations for _, rotations, _, _ in ran.kept],
            [features for _, _, features, _ in ran.kept],
            model,
            [fps for *_, fps in ran.kept],
            model_float32,
        )
        for (values, *_), clip_parts in zip(ran.kept, parts):
            values.update({kind: v.astype(np.float32) for kind, v in clip_parts.items() if kind in keep})
    add_sums(ran.finished, keep)
    return ran.outcomes, ran.prepare_seconds, ran.seconds + time.perf_counter() - start


__all__ = ["Ran", "run_model"]
