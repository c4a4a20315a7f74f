"""The only code that calls the kernels: one wrapper per kernel family, which checks and
coerces its arguments (an :class:`~expressive_mocap.errors.ArgumentError` naming the bad one),
builds the kernel's argument objects (:class:`ChannelLayout`, :class:`MotionBlock`,
:class:`ClipInput`, :class:`GaitSettings`, :class:`PipelineOutputs`) and calls the backend in
use: the Rust kernel or its NumPy twin (see :mod:`expressive_mocap.backend`), which take the
same arguments and raise the same exceptions. Leading batch dimensions are folded into frames.

Arrays written by another thread during a call: the Rust kernels run without the GIL, so
other Python threads run meanwhile. Index arrays (``parents``, channel columns, gait joints)
and bool flags are copied before the GIL is released, so a write to them during a call has no
effect on it: it is computed from the values at the call, or refused with an ArgumentError. Float
arrays are read in place (copying them would cost as much as some kernels): a write to one
during a call gives results computed from a mix of its old and new values, and nothing worse
(no crash, no error). Don't write to a kernel's inputs while it runs if you need its result.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._utils.lazy import lazy_exports

# Each wrapper loads on first use (PEP 562): most import NumPy, which a command that needs none
# (`info` with the Rust kernels: its block is checked by ``check_motion_block``) should not pay for.
_LAZY = {
    "ACTIVATIONS": "mlp",
    "Arms": "rotations",
    "ChannelLayout": "bvh_text",
    "ClipArrays": "arrays",
    "ClipInput": "gait",
    "FeatureRequest": "gait",
    "GaitSettings": "gait",
    "MotionBlock": "bvh_text",
    "PipelineOutputs": "gait",
    "TransferPlan": "posing",
    "Trunk": "rotations",
    "air_time": "gait",
    "arrays_pipeline_many": "arrays",
    "channel_layout": "bvh_text",
    "check_motion_block": "blocks",
    "clip_gait_many": "gait",
    "clip_gradient": "gait",
    "clip_pipeline_many": "gait",
    "column_totals": "gait",
    "compose_rotations": "rotations",
    "decode_channels": "rotations",
    "decouple_rotations": "rotations",
    "dynamic_features": "gait",
    "euler_to_quat": "rotations",
    "foot_contacts": "gait",
    "format_motion_block": "bvh_text",
    "forward_kinematics": "rotations",
    "forward_kinematics_many": "rotations",
    "matrix_columns": "rotations",
    "mlp_forward": "mlp",
    "plant_feet": "posing",
    "quat_to_euler": "rotations",
    "read_motion_blocks": "bvh_text",
    "repeated_headers": "bvh_text",
    "retarget_transfer": "posing",
    "split_rotations": "rotations",
    "split_rotations_many": "rotations",
    "stored_rotations": "arrays",
    "two_bone_ik": "posing",
}

if TYPE_CHECKING:  # what the names are, for type checkers and editors
    from .arrays import ClipArrays, arrays_pipeline_many, stored_rotations
    from .blocks import check_motion_block
    from .bvh_text import (
        ChannelLayout,
        MotionBlock,
        channel_layout,
        format_motion_block,
        read_motion_blocks,
        repeated_headers,
    )
    from .gait import (
        ClipInput,
        FeatureRequest,
        GaitSettings,
        PipelineOutputs,
        air_time,
        clip_gait_many,
        clip_gradient,
        clip_pipeline_many,
        column_totals,
        dynamic_features,
        foot_contacts,
    )
    from .mlp import ACTIVATIONS, mlp_forward
    from .posing import TransferPlan, plant_feet, retarget_transfer, two_bone_ik
    from .rotations import (
        Arms,
        Trunk,
        compose_rotations,
        decode_channels,
        decouple_rotations,
        euler_to_quat,
        forward_kinematics,
        forward_kinematics_many,
        matrix_columns,
        quat_to_euler,
        split_rotations,
        split_rotations_many,
    )

__getattr__, __dir__ = lazy_exports(__name__, _LAZY, globals())

__all__ = [
    "ACTIVATIONS",
    "Arms",
    "ChannelLayout",
    "ClipArrays",
    "ClipInput",
    "FeatureRequest",
    "GaitSettings",
    "MotionBlock",
    "PipelineOutputs",
    "TransferPlan",
    "Trunk",
    "air_time",
    "arrays_pipeline_many",
    "channel_layout",
    "check_motion_block",
    "clip_gait_many",
    "clip_gradient",
    "clip_pipeline_many",
    "column_totals",
    "compose_rotations",
    "decode_channels",
    "decouple_rotations",
    "dynamic_features",
    "euler_to_quat",
    "foot_contacts",
    "format_motion_block",
    "forward_kinematics",
    "forward_kinematics_many",
    "matrix_columns",
    "mlp_forward",
    "plant_feet",
    "quat_to_euler",
    "read_motion_blocks",
    "repeated_headers",
    "retarget_transfer",
    "split_rotations",
    "split_rotations_many",
    "stored_rotations",
    "two_bone_ik",
]
