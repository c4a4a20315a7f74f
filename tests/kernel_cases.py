"""Arguments for every kernel, shared by the misuse and thread tests: ``CORE[name](frames)``
gives the arguments of ``_core.name`` (and of its NumPy twin) for that many frames, with the
names of its array arguments."""

import numpy as np
from scipy.spatial.transform import Rotation

from expressive_mocap import ops

RNG = np.random.default_rng(7)


def quats(*shape):
    return Rotation.random(int(np.prod(shape)), random_state=3).as_quat().reshape(*shape, 4)


def layout(joints):
    """Decode layout of ``joints`` joints with three rotation channels each (and positions on the root)."""
    rotation_columns = np.arange(3, 3 + 3 * joints).reshape(joints, 3)
    position_columns = np.full((joints, 3), -1)
    position_columns[0] = [0, 1, 2]
    return (
        rotation_columns,
        np.tile(np.array([2, 0, 1], np.uint8), (joints, 1)),
        position_columns,
        RNG.normal(size=(joints, 3)),
    )


def mlp_args(frames, inputs=5):
    return (
        RNG.normal(size=(frames, inputs)),
        [RNG.normal(size=(inputs, 4)), RNG.normal(size=(4, 3))],
        [RNG.normal(size=4), RNG.normal(size=3)],
        ["tanh", "linear"],
    )


def contacts_args(frames, feet=2, points=2):
    return (RNG.normal(size=(frames, feet, points, 3)), 1 / 30, 0.0, 0.1, 1.0, 3, False)


def features_args(frames):
    return (
        RNG.normal(size=(frames, 3, 3)),
        quats(frames, 2),
        RNG.random((frames, 2)) > 0.5,
        quats(1, 2)[0],
        1 / 30,
        1.7,
        0.9,
        0.0,
        10,
    )


def gait_args(frames, joints=7):
    clip = (RNG.normal(size=(frames, joints, 3)), quats(frames, joints), 1 / 30, 1.7, 0.9)
    return ([clip, clip], list(range(joints)), 0.05, 0.5, 0.1, 5.0, True, True)


def pipeline_args(frames, joints=3):
    """Two clips of ``frames`` frames (MOTION text with positions on the root), every output asked for."""
    rotation_columns, orders, position_columns, offsets = layout(joints)
    block = b"".join(
        b" ".join(b"%.4f" % v for v in RNG.normal(scale=20, size=3 + 3 * joints)) + b"\n" for _ in range(frames)
    )
    channels = ops.ChannelLayout(3 + 3 * joints, rotation_columns, orders, position_columns, offsets)
    clip = ops.ClipInput(block, 0, frames, channels, 1 / 30, 1.7, 0.9)
    requests = (ops.FeatureRequest(0.0), ops.FeatureRequest(None, quats(2)))
    outputs = ops.PipelineOutputs(positions=True, rotations=True, features=requests, contacts=True)
    return ([clip, clip], np.arange(joints) - 1, [0, 1, 2, 1, 2, 2, 1], ops.GaitSettings(0.05, 0.5, 0.1, 5.0), outputs)


def transfer_args(frames):
    """A retargeting transfer from 3 source joints onto 5 target joints: three roles (one swung),
    a shared spine joint, a held joint, a turned reference pose; turned axes on both sides."""
    plan = ops.TransferPlan.of(
        [0, 1, 2], [0, 1, 3], quats(3), [1], [1], [2], RNG.normal(size=(1, 3)),
        [2], [1], [3], [0.5], [4], [0], quats(5), [-1, 0, 1, 2, 0], quats(1)[0], quats(1)[0],
    )  # fmt: skip
    return (quats(frames, 3), RNG.normal(size=(frames, 3, 3)), plan)


# Name -> (arguments for F frames, names of the array arguments by position; None: not an array).
CORE = {
    "parse_motion_block": (lambda f: (b"1 2 3\n" * f, 0, f, 3), []),
    "check_motion_block": (lambda f: (b"1 2 3\n" * f, 0, f, 3), []),
    "format_motion_block": (lambda f: (RNG.normal(size=(f, 3)),), ["values"]),
    "decode_channels": (
        lambda f: (RNG.normal(size=(f, 12)), *layout(3)),
        ["values", "rotation_columns", "orders", "position_columns", "offsets"],
    ),
    "read_motion_blocks": (
        lambda f: (
            [ops.MotionBlock(b"1 2 3\n" * f, 0, f, ops.ChannelLayout(3, np.array([[0, 1, 2]]), *layout(1)[1:]))],
        ),
        [],
    ),
    # The headers of files (this one, twice) read as repeating a header: not BVH, read in full.
    "repeated_headers": (lambda f: ([__file__] * 2, b"HIERARCHY\nMOTION\n", 3, 64), []),
    "euler_to_quat": (
        lambda f: (RNG.normal(size=(f, 3, 3)), np.tile(np.array([0, 1, 2], np.uint8), (3, 1))),
        ["angles", "orders"],
    ),
    "quat_to_euler": (lambda f: (quats(f, 3), np.tile(np.array([0, 1, 2], np.uint8), (3, 1))), ["quats", "orders"]),
    "forward_kinematics": (
        lambda f: (quats(f, 3), RNG.normal(size=(f, 3, 3)), np.array([-1, 0, 1])),
        ["rotations", "translations", "parents"],
    ),
    "forward_kinematics_many": (lambda f: ([(quats(f, 3), RNG.normal(size=(f, 3, 3)), np.array([-1, 0, 1]))] * 2,), []),
    "foot_contacts": (contacts_args, ["feet"]),
    "air_time": (lambda f: (RNG.random((f, 2)) > 0.5, 1 / 30), ["contacts"]),
    "dynamic_features": (features_args, ["points", "thighs", "contacts", "reference"]),
    "clip_gait_many": (gait_args, []),
    "clip_pipeline_many": (pipeline_args, [None, "parents"]),
    "mlp_forward": (lambda f: mlp_args(f), ["x"]),
    "decouple_rotations": (
        lambda f: (quats(f, 3), quats(3, f).transpose(1, 0, 2).copy(), 2.0, 4.0),
        ["original", "body"],
    ),
    "split_rotations": (
        lambda f: (quats(f, 3), quats(3, f).transpose(1, 0, 2).copy(), 2.0, 4.0, np.ones(3), 1.5, 3.0),
        ["original", "body", None, None, "scale", None, None],
    ),
    "split_rotations_many": (
        lambda f: (
            [quats(f, 3), quats(f + 1, 3)],
            [quats(3, f).transpose(1, 0, 2).copy(), quats(3, f + 1).transpose(1, 0, 2).copy()],
            2.0,
            4.0,
            np.ones(3),
            [1.5, 0.0],
            [3.0, 1.0],
        ),
        [None, None, None, None, "scale"],
    ),
    "compose_rotations": (lambda f: (quats(f, 3), quats(3, f).transpose(1, 0, 2).copy(), 1.5), ["expressive", "body"]),
    "retarget_transfer": (transfer_args, ["world", "positions", None]),
    "plant_feet": (
        lambda f: (
            quats(f, 4),
            RNG.normal(size=(f, 4, 3)),
            np.array([-1, 0, 1, 2]),
            np.array([[1, 2, 3], [-1, -1, -1]]),
            RNG.random((f, 2)) > 0.5,
            RNG.normal(size=(f, 2, 3)),
            np.array([0, f // 2, f]),
            3,
        ),  # fmt: skip
        ["rotations", "translations", "parents", "legs", "contacts", "guide", "starts", None],
    ),
    "matrix_columns": (lambda f: (quats(f), 2), ["quats", None]),
    "clip_gradient": (
        lambda f: (RNG.normal(size=(f, 6)), np.array([0, f // 2]), np.full(f, 1 / 30)),
        ["values", "starts", "frame_time"],
    ),
    "column_totals": (lambda f: ([RNG.normal(size=(f, 4)).astype(np.float32)] * 2, 4), []),
    "two_bone_ik": (
        lambda f: (RNG.normal(size=(f, 3)), quats(f), quats(f), RNG.normal(size=(f, 3)), *RNG.normal(size=(2, f, 3))),
        ["root", "upper", "lower", "upper_bone", "lower_bone", "target"],
    ),
}
