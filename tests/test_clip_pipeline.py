"""The whole per-clip work of preprocessing in one kernel call (``clip_pipeline_many``, Rust
``rust/clip.rs`` and its NumPy twin), and headers read from a file's beginning
(``bvh.read_header``), which the Rust kernel then reads whole."""

import dataclasses
import errno
import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import expressive_mocap as em
from expressive_mocap import bvh, ops, reference
from expressive_mocap.body.contacts import FLOOR_PERCENTILE, HEIGHT_THRESHOLD, MIN_DURATION, SPEED_THRESHOLD
from expressive_mocap.body.roles import JointRoles, actor_height, hips_rest_height
from expressive_mocap.bvh import header as bvh_header
from expressive_mocap.procedural import procedural_walk

GAIT = ops.GaitSettings(HEIGHT_THRESHOLD, SPEED_THRESHOLD, MIN_DURATION, FLOOR_PERCENTILE)


def pipeline_input(source, data: bytes):
    """``clip_pipeline_many``'s per-clip input, parents and gait joints for a clip whose text is ``data``."""
    header = bvh.parse_header(data, "clip")
    skeleton = header.skeleton
    roles = JointRoles.find(skeleton)
    clip = ops.ClipInput.of(source, header, actor_height(skeleton, roles), hips_rest_height(skeleton, roles))
    return clip, np.ascontiguousarray(skeleton.parents, dtype=np.int64), roles.gait_joints


@pytest.fixture(scope="module")
def walks(tmp_path_factory):
    """Two procedural walks (one waving) as files: (path, bytes) each."""
    folder = tmp_path_factory.mktemp("walks")
    out = []
    for name, motion in (
        ("plain", procedural_walk(seconds=1.5)),
        ("wave", procedural_walk(seconds=1.2, speed=1.2, wave="left")),
    ):
        path = folder / f"{name}.bvh"
        em.write_bvh(motion, path)
        out.append((path, path.read_bytes()))
    return out


def run(module, walks, float32=False, by_path=True):
    clips = []
    for path, data in walks:
        clip, parents, joints = pipeline_input(str(path) if by_path else data, data)
        clips.append(clip)
    requests = (ops.FeatureRequest(0.0), ops.FeatureRequest(None, np.array([[0, 0, 0, 1.0], [0, 0, 0, 1.0]])))
    outputs = ops.PipelineOutputs(positions=True, rotations=True, features=requests, contacts=True, float32=float32)
    return module.clip_pipeline_many(clips, parents, joints, gait=GAIT, outputs=outputs)


def test_the_numpy_twin_is_the_package_per_clip(walks):
    # The twin is the composition of the per-clip functions the rest of the package uses: the
    # NumPy ones, reading included (a Rust-read Motion's rotations differ from the twin's by up
    # to 2.8e-16, its own sine/cosine; Rust vs twin is the next test's, at 1e-12).
    for (path, _), (positions, rotations, features, contacts, _) in zip(walks, run(reference, walks)):
        with em.use_backend("numpy"):
            motion = em.read_bvh(path)
            np.testing.assert_allclose(positions, motion.positions(), atol=1e-9)
            np.testing.assert_array_equal(rotations, motion.rotations)
            np.testing.assert_allclose(features[0], em.dynamic_features(motion, floor=0.0), atol=1e-9)
            np.testing.assert_array_equal(contacts, em.foot_contacts(motion))


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
@pytest.mark.parametrize("by_path", [True, False])
@pytest.mark.parametrize("float32", [False, True])
def test_rust_matches_its_twin_and_the_kernels_one_by_one(walks, by_path, float32):
    from expressive_mocap import _core as core

    rust, twin = run(core, walks, float32, by_path), run(reference, walks, float32, by_path)
    dtype = np.float32 if float32 else np.float64
    for (_path, data), got, expected in zip(walks, rust, twin):
        assert got[0].dtype == got[1].dtype == got[2][0].dtype == dtype and got[3].dtype == bool
        np.testing.assert_allclose(got[0], expected[0], atol=2e-5 if float32 else 1e-9)  # float32 positions ~100 cm
        np.testing.assert_allclose(got[1], expected[1], atol=1e-7 if float32 else 1e-12)
        for ours, theirs in zip(got[2], expected[2]):
            np.testing.assert_allclose(ours, theirs, atol=1e-6 if float32 else 1e-9)
        np.testing.assert_array_equal(got[3], expected[3])
        if not float32:  # the same Rust kernels called one by one: the same numbers, bit for bit
            clip, parents, joints = pipeline_input(data, data)
            ((local, translations),) = core.read_motion_blocks(
                [ops.MotionBlock(data, clip.start, clip.frames, clip.layout)]
            )
            ((_, world),) = core.forward_kinematics_many([(local, translations, parents)])
            gait = core.clip_gait_many(
                [(world, local, clip.frame_time, clip.height, clip.hips_rest_height)], joints, *GAIT, True, True, 0.0
            )
            np.testing.assert_array_equal(got[0], world)
            np.testing.assert_array_equal(got[1], local)
            np.testing.assert_array_equal(got[2][0], gait[0][0])
            np.testing.assert_array_equal(got[3], gait[0][1])


@pytest.mark.parametrize("columns", [2, 3])
def test_stored_forms_are_the_forms_kernels_of_the_clips_arrays(walks, columns, backend):
    # The pipeline's 6D / matrix rotations and velocities: the kernels' matrix_columns of its
    # quaternions and clip_gradient of its positions, bit for bit (float64 first, rounded once).
    plain = run(ops, walks)
    clips, parents, joints = zip(*(pipeline_input(path, data) for path, data in walks))
    formed = ops.PipelineOutputs(
        positions=True, rotations=True, float32=True, rotation_columns=columns, velocities=True
    )
    got = ops.clip_pipeline_many(list(clips), parents[0], joints[0], GAIT, formed)
    for clip, (positions, quats, *_), (world32, matrices, _, _, velocities) in zip(clips, plain, got):
        assert matrices.shape == quats.shape[:-1] + (3 * columns,) and matrices.dtype == np.float32
        np.testing.assert_array_equal(matrices, ops.matrix_columns(quats, columns))
        frame_time = np.full(len(positions), clip.frame_time)
        np.testing.assert_array_equal(velocities, ops.clip_gradient(positions, [0], frame_time).astype(np.float32))
        np.testing.assert_array_equal(world32, positions.astype(np.float32))
    with pytest.raises(em.ArgumentError, match="rotation_columns"):
        ops.clip_pipeline_many(list(clips), parents[0], joints[0], GAIT, ops.PipelineOutputs(rotation_columns=1))


def test_a_bad_block_and_a_missing_file_are_that_clips_result(walks, tmp_path, backend):
    path, data = walks[0]
    clip, parents, joints = pipeline_input(data, data)
    block = data[clip.start :].split(b"\n")
    block[2] = block[2].replace(b" ", b" x ", 1)  # the third frame line: not a number
    broken = dataclasses.replace(clip, source=data[: clip.start] + b"\n".join(block))
    missing = dataclasses.replace(clip, source=str(tmp_path / "gone.bvh"))
    outputs = ops.PipelineOutputs(positions=True, contacts=True, float32=True)
    good, bad, gone = ops.clip_pipeline_many([clip, broken, missing], parents, joints, GAIT, outputs)
    assert isinstance(good, tuple) and good[1] is None and good[2] == []
    assert isinstance(bad, em.errors.ParseError) and bad.args == ("'x' is not a number", 2)
    assert isinstance(gone, OSError) and (gone.errno, gone.strerror) == (errno.ENOENT, os.strerror(errno.ENOENT))


def test_the_body_scale_and_roles_must_fit_the_skeleton(walks, backend):
    path, data = walks[0]
    clip, parents, joints = pipeline_input(data, data)
    outputs = ops.PipelineOutputs(positions=True, contacts=True)
    with pytest.raises(em.errors.ArgumentError, match="`toes`"):
        ops.clip_pipeline_many([clip], parents, joints[:6] + [99], GAIT, outputs)
    with pytest.raises(em.errors.ArgumentError, match="`roles`"):
        ops.clip_pipeline_many([clip], parents, joints[:6], GAIT, outputs)


# ----------------------------------------------------------------------------- read_header


def header_fields(header):
    return (
        header.skeleton.names,
        header.skeleton.offsets.tolist(),
        header.frames,
        header.frame_time,
        header.block_start,
        header.block_line,
    )


def padded_clip(pad: int) -> bytes:
    """A walk whose OFFSET line of the root carries ``pad`` extra spaces: moves the MOTION,
    Frames and Frame Time lines across the boundary of what read_header reads first (HEADER_PREFIX)."""
    text = em.bvh_bytes(procedural_walk(seconds=0.5))
    return text.replace(b"OFFSET", b"OFFSET" + b" " * pad, 1)


def test_read_header_takes_the_beginning_only_when_the_header_fits(tmp_path):
    base = padded_clip(0)
    motion_at = base.index(b"MOTION")
    block_at = bvh.parse_header(base, "x").block_start
    # Cuts at that boundary through the MOTION line, the Frames line, the Frame Time line
    # (number cut short: 0.0333 read as 0.03 would be wrong), its newline, and just after.
    for cut in sorted({motion_at + 3, motion_at + 12, block_at - 4, block_at - 1, block_at, block_at + 1}):
        data = padded_clip(bvh.HEADER_PREFIX - cut)
        path = tmp_path / f"cut{cut}.bvh"
        path.write_bytes(data)
        header, whole = bvh.read_header(path)
        assert header_fields(header) == header_fields(bvh.parse_header(data, str(path)))
        starts_in_beginning = header.block_start < bvh.HEADER_PREFIX
        assert (whole is None) == starts_in_beginning and (whole is None or whole == data)
    assert bvh.HEADER_PREFIX - (block_at - 1) < 1 << 20  # the cases above did cross the boundary


def test_read_header_errors_are_read_bvh_errors(tmp_path):
    big = padded_clip(bvh.HEADER_PREFIX)  # a header longer than the beginning
    path = tmp_path / "big.bvh"
    path.write_bytes(big)
    header, whole = bvh.read_header(path)
    assert whole == big and header.frames == em.read_bvh(path).n_frames
    # A clip whose frame count is only plausible for the whole file's size (frames x joints
    # above 65,536 and above a third of the beginning's bytes): read from the beginning.
    long = em.bvh_bytes(procedural_walk(seconds=120))
    path = tmp_path / "long.bvh"
    path.write_bytes(long)
    header, whole = bvh.read_header(path)
    assert whole is None and header.frames == em.read_bvh(path).n_frames
    assert header.frames * header.skeleton.n_joints > max(bvh.HEADER_PREFIX // 3, 65536)
    # Errors: a Frames count the file cannot hold (small and large files), blank beginnings.
    frames = f"Frames: {header.frames}".encode()
    claims = long.replace(frames, b"Frames: 99999999", 1)
    short = padded_clip(0)
    short = short.replace(short[short.index(b"Frames:") :].split(b"\n", 1)[0], b"Frames: 9999", 1)
    cases = (
        ("claims.bvh", claims),
        ("short.bvh", short),
        ("empty.bvh", b" " * (bvh.HEADER_PREFIX + 10)),
        ("late.bvh", b"\n" * bvh.HEADER_PREFIX + short),
    )
    for name, data in cases:
        path = tmp_path / name
        path.write_bytes(data)
        with pytest.raises(em.BVHError) as expected:
            em.read_bvh(path)
        with pytest.raises(em.BVHError) as got:
            bvh.read_header(path)
        assert str(got.value) == str(expected.value)
    with pytest.raises(em.BVHError, match="cannot read the file"):
        bvh.read_header(tmp_path / "missing.bvh")


@settings(max_examples=3000, deadline=None, derandomize=True)
@given(
    st.lists(
        st.sampled_from(
            [b"MOTION", b"motion", b"MoTiOn", b"MOTIONS", b" ", b"\t", b"\n", b"\r", b"\r\n", b"x", b"Mot", b"ion"]
        ),
        max_size=16,
    ),
    st.integers(0, 5000),
)
def test_the_motion_line_is_found_as_the_regex_finds_it(pieces, padding):
    # Padding moves the candidates across the first 4 KB window when there is no upper-case MOTION.
    for data in (b"".join(pieces), b"x" * padding + b"".join(pieces), b"\n" * padding + b"".join(pieces)):
        expected, found = bvh_header._MOTION.search(data), bvh_header._find_motion_line(data)
        assert (found is None) == (expected is None) and (found is None or found.span() == expected.span())


def test_finding_the_motion_line_stays_linear_on_hostile_headers():
    # Millions of candidates on one line, or one line each: each line is matched once.
    for data in (b"motion" * 600_000, b" " * 2_000_000 + b"motion" * 300_000, b"\n motion x" * 400_000):
        assert bvh_header._find_motion_line(data) is None and bvh_header._MOTION.search(data) is None
