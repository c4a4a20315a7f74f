"""The per-clip input of ``clip_pipeline_many`` for a clip's text, and the package's gait settings:
shared by the pipeline kernel's tests (ops/test_clip_pipeline.py) and the input side of
preprocess (dataset/test_preprocess_inputs.py)."""

import numpy as np

from expressive_mocap import bvh, ops
from expressive_mocap.body import Body
from expressive_mocap.body.contacts import FLOOR_PERCENTILE, HEIGHT_THRESHOLD, MIN_DURATION, SPEED_THRESHOLD

GAIT = ops.GaitSettings(HEIGHT_THRESHOLD, SPEED_THRESHOLD, MIN_DURATION, FLOOR_PERCENTILE)


def pipeline_input(source, data: bytes):
    """``clip_pipeline_many``'s per-clip input, parents and gait joints for a clip whose text is ``data``."""
    header = bvh.parse_header(data, "clip")
    skeleton = header.skeleton
    body = Body.of(skeleton)
    roles = body.roles
    clip = ops.ClipInput.of(source, header, body.actor_height, body.hips_rest_height)
    return clip, np.ascontiguousarray(skeleton.parents, dtype=np.int64), roles.gait_joints
