"""The trunk read as one chain by the decomposition.

A hunched or leaning walk bends the spine a few degrees at each of its joints. The activity index
is steep (13 to 32 degrees on one joint take it from 0.05 to 1), so read joint by joint such a
lean is nothing, and the body mechanics kept it whole: an old walk leaning 15 degrees came out of
``modulate --scale 0`` leaning 15. Read as the chain's (the angle between the trunk line, hips to
neck, of the motion and of the body mechanics), it counts; a twist about that line, which
sidesteps and turns show in neutral movement, does not.

The chain's threshold is the model's own: the lean it leaves on its held-out neutral clips, at
the NEUTRAL_PERCENTILE-th percentile, reads as NEUTRAL_LEAN degrees (activity 0.01).

The pelvis the spine is predicted for: :mod:`.pelvis`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from ..body.body import Body
from ..body.roles import JointRoles
from ..motion import Motion, Skeleton
from ..ops import Trunk
from ..reference.decouple import trunk_lean
from ..rotations import quat
from .algebra import BODY_SMOOTHING

if TYPE_CHECKING:
    from .body_model import BodyModel

NEUTRAL_PERCENTILE = 95.0
NEUTRAL_LEAN = 10.0  # degrees


Bones = tuple[tuple[float, float, float], ...]


def trunk_chain(skeleton: Skeleton, roles: JointRoles) -> tuple[tuple[int, ...], Bones] | None:
    """The trunk's joints (above the hips, below the neck: the spine-to-head chain less the hips,
    the neck and the head) and the bone each carries (the next one's rest offset, the last one's
    the neck's), so that the trunk line runs from the first of them to the neck; None for a
    skeleton with no joint between hips and neck, or a trunk of no length."""
    joints = tuple(int(j) for j in roles.spine[1:-2])
    if not joints:
        return None
    bones = tuple(tuple(float(v) for v in skeleton.offsets[j]) for j in roles.spine[2:-1])
    if np.linalg.norm(np.sum(bones, axis=0)) < 1e-9:
        return None
    return joints, bones  # type: ignore[return-value]


def trunk_threshold(
    chain: tuple[tuple[int, ...], Bones],
    originals: Sequence[np.ndarray],
    predictions: Sequence[np.ndarray],
    body_sigmas: Sequence[float],
    percentile: float = NEUTRAL_PERCENTILE,
    degrees: float = NEUTRAL_LEAN,
) -> Trunk:
    """The trunk of ``chain`` with its threshold read from neutral clips: their rotations
    ``originals`` and the model's ``predictions`` (each ``[F, J, 4]``), the predictions smoothed
    over ``body_sigmas`` frames as the decomposition smooths them; the lean left at the
    ``percentile`` reads as ``degrees``."""
    joints, bones = chain
    leans = []
    for original, predicted, sigma in zip(originals, predictions, body_sigmas):
        body = quat.smooth(predicted, sigma) if sigma > 0 and len(predicted) > 1 else predicted
        leans.append(trunk_lean(original, body, list(joints), np.asarray(bones)))
    lean = np.degrees(np.percentile(np.concatenate(leans), percentile))
    return Trunk(joints, bones, float(max(lean, 1e-3) / degrees))


def with_trunk(model: BodyModel, skeleton: Skeleton, held_out: Sequence[Motion]) -> BodyModel:
    """``model`` reading its trunk as one chain, the threshold set by the lean it leaves on the
    ``held_out`` neutral clips (what ``train`` does); unchanged for a skeleton with no joint
    between hips and neck."""
    chain = trunk_chain(skeleton, Body.of(skeleton).roles)
    if chain is None or not held_out:
        return model
    predictions = [model.predict(m) for m in held_out]
    sigmas = [BODY_SMOOTHING * m.fps for m in held_out]
    return replace(model, trunk=trunk_threshold(chain, [m.rotations for m in held_out], predictions, sigmas))


__all__ = ["NEUTRAL_LEAN", "NEUTRAL_PERCENTILE", "trunk_chain", "trunk_threshold", "with_trunk"]
