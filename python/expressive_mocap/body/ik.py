"""Two-bone inverse kinematics (a leg: upper leg, lower leg, foot), on arrays of frames.

Used by the demo to plant its feet on a footstep plan, by the exaggeration's foot locking to
keep a stance foot where the input had it, and by retargeting to plant the feet.
"""

from __future__ import annotations

import numpy as np

from .. import ops
from ..reference.ik import REACH  # the kernels' constant (rust/ik.rs has the same)


def two_bone_ik(
    root: np.ndarray,
    upper: np.ndarray,
    lower: np.ndarray,
    upper_bone: np.ndarray,
    lower_bone: np.ndarray,
    target: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """World rotations of a two-bone chain turned so that its end reaches ``target``.

    Args:
        root: float[F, 3], the chain's first joint (the hip) in world space.
        upper, lower: float[F, 4] (x, y, z, w), world rotations of the first joint (thigh) and the
            second (shin).
        upper_bone: float[3] or [F, 3], the second joint's offset in the first joint's frame (the
            knee's local translation).
        lower_bone: float[3] or [F, 3], the end's offset in the second joint's frame (the ankle's
            local translation).
        target: float[F, 3], where the end should be.

    Returns:
        The new world rotations ``(upper, lower)``, each ``[F, 4]``. The chain bends in its own
        current plane (after D. Holden's two-joint IK) and then turns about the root to aim at the
        target; each bone keeps its twist. A target out of reach is approached as closely as
        ``REACH`` x the chain's length allows, or the chain's own reach when it is straighter
        already (so a target where its end is moves nothing); a target nearer than the bones'
        difference, as that.
        One kernel call (``two_bone_ik``), frames in parallel.
    """
    return ops.two_bone_ik(root, upper, lower, upper_bone, lower_bone, target)


__all__ = ["REACH", "two_bone_ik"]
