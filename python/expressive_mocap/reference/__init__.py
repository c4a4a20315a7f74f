"""Pure-NumPy twins of every Rust kernel, with the same names and signatures as
``expressive_mocap._core``. They are the fallback without the extension, the reference in
parity tests and the baseline in benchmarks: written for clarity first, vectorised over frames.

Conventions (shared with the Rust kernels): quaternions are unit, stored x, y, z, w; ``q1 * q2``
rotates by ``q2`` then ``q1``; an Euler order is three axis indices (0 = X, 1 = Y, 2 = Z) as
written in a BVH CHANNELS line, intrinsic, first channel outermost; angles in degrees.
"""

from .._utils.lazy import lazy_exports

# Each twin loads on first use: with the Rust kernels in use, none is needed to run, and importing
# all of them took a tenth of a command's start-up.
_TWINS = {
    "air_time": "footsteps",
    "check_motion_block": "motion_block",
    "clip_gait_many": "gait",
    "clip_gradient": "forms",
    "clip_pipeline_many": "clip",
    "column_totals": "forms",
    "compose_rotations": "decouple",
    "decode_channels": "motion_block",
    "decouple_rotations": "decouple",
    "dynamic_features": "features",
    "euler_to_quat": "rotations",
    "foot_contacts": "footsteps",
    "format_motion_block": "motion_block",
    "forward_kinematics": "fk",
    "forward_kinematics_many": "fk",
    "matrix_columns": "forms",
    "mlp_forward": "mlp",
    "parse_motion_block": "motion_block",
    "plant_feet": "planting",
    "quat_to_euler": "rotations",
    "read_motion_blocks": "motion_block",
    "repeated_headers": "clip",
    "split_rotations": "decouple",
    "split_rotations_many": "decouple",
    "retarget_transfer": "retarget",
    "two_bone_ik": "ik",
}

__getattr__, __dir__ = lazy_exports(__name__, _TWINS, globals())

num_threads = 1

__all__ = [*_TWINS, "num_threads"]
