"""Pure-NumPy twins of every Rust kernel, with the same names and signatures as
``expressive_mocap._core``. They are the fallback without the extension, the reference in
parity tests and the baseline in benchmarks: written for clarity first, vectorised over frames.

Conventions (shared with the Rust kernels): quaternions are unit, stored x, y, z, w; ``q1 * q2``
rotates by ``q2`` then ``q1``; an Euler order is three axis indices (0 = X, 1 = Y, 2 = Z) as
written in a BVH CHANNELS line, intrinsic, first channel outermost; angles in degrees.
"""

from .clip import clip_pipeline_many
from .decouple import compose_rotations, decouple_rotations
from .features import dynamic_features
from .fk import forward_kinematics, forward_kinematics_many
from .footsteps import air_time, foot_contacts
from .forms import clip_gradient, column_totals, matrix_columns
from .gait import clip_gait_many
from .ik import two_bone_ik
from .mlp import mlp_forward
from .motion_block import decode_channels, format_motion_block, parse_motion_block, read_motion_blocks
from .planting import plant_feet
from .retarget import retarget_transfer
from .rotations import euler_to_quat, quat_to_euler

num_threads = 1

__all__ = [
    "air_time",
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
    "num_threads",
    "parse_motion_block",
    "plant_feet",
    "read_motion_blocks",
    "quat_to_euler",
    "retarget_transfer",
    "two_bone_ik",
]
