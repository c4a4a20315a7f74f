"""The wrapper of the model-ready arrays pipeline: decoded clips to the arrays a dataset stores."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..backend import kernels
from ._args import _array, _f64
from .gait import GaitSettings, PipelineOutputs, clip_gradient


@dataclass(frozen=True)
class ClipArrays:
    """One clip already decoded, for :func:`arrays_pipeline_many`: local ``rotations [F, J, 4]``
    and ``translations [F, J, 3]``, its ``frame_time`` and body scale (as :class:`ClipInput`)."""

    rotations: np.ndarray
    translations: np.ndarray
    frame_time: float
    height: float
    hips_rest_height: float

    @property
    def frames(self) -> int:
        return len(self.rotations)


def stored_rotations(quats: np.ndarray, columns: int) -> np.ndarray:
    """Local rotations ``[F, J, 4]`` in the form :class:`PipelineOutputs` asks for: as they are
    (``columns`` 0) or their matrices' first ``columns`` columns, in float64 (as the pipeline's)."""
    from ..reference.forms import matrix_entries  # the twin's formula: the same as the kernel's

    return quats if columns == 0 else matrix_entries(quats, columns)


def arrays_pipeline_many(
    clips: Sequence[ClipArrays], parents, roles, gait: GaitSettings, outputs: PipelineOutputs
) -> list[tuple]:
    """What :func:`clip_pipeline_many` gives of clips whose frames are arrays already (a
    retargeted clip): FK, features and contacts, the same kernels clips in parallel, per clip
    ``(positions or None, rotations or None, [features per request], contacts or None,
    velocities or None)``."""
    parents = _array("parents", parents, np.int64, "iu")
    local = [(_f64("rotations", c.rotations, 4), _f64("translations", c.translations, 3), parents) for c in clips]
    kinematics = kernels().forward_kinematics_many(local)
    gait_clips = [
        (p, r, c.frame_time, c.height, c.hips_rest_height) for c, (r, _, _), (_, p) in zip(clips, local, kinematics)
    ]
    roles = [int(r) for r in roles]
    contacts: list = [None] * len(clips)
    features: list[list] = [[] for _ in clips]
    for number, request in enumerate(outputs.features):  # the contacts come with the first request
        with_contacts = outputs.contacts and number == 0
        reference = None if request.thigh_reference is None else _f64("thigh_reference", request.thigh_reference, 4)
        found = kernels().clip_gait_many(
            gait_clips, roles, *gait, True, with_contacts, request.floor, reference
        )  # fmt: skip
        for k, (f, c) in enumerate(found):
            features[k].append(f)
            contacts[k] = c if with_contacts else contacts[k]
    if outputs.contacts and not outputs.features:
        contacts = [c for _, c in kernels().clip_gait_many(gait_clips, roles, *gait, False, True)]
    dtype = np.float32 if outputs.float32 else np.float64
    return [
        (
            p.astype(dtype, copy=False) if outputs.positions else None,
            stored_rotations(r, outputs.rotation_columns).astype(dtype, copy=False) if outputs.rotations else None,
            [f.astype(dtype, copy=False) for f in found],
            contact,
            clip_gradient(p, [0], np.full(len(p), c.frame_time)).astype(dtype, copy=False)
            if outputs.velocities
            else None,
        )
        for c, (r, _, _), (_, p), found, contact in zip(clips, local, kinematics, features, contacts)
    ]


__all__ = ["ClipArrays", "arrays_pipeline_many", "stored_rotations"]
