"""The whole per-clip work of preprocessing in one kernel call (``clip_pipeline_many``, Rust
``rust/clip.rs`` and its NumPy twin)."""

import dataclasses
import errno
import os

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap import ops, reference
from expressive_mocap.procedural import procedural_walk
from pipeline_inputs import GAIT, pipeline_input


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
