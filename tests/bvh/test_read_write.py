"""BVH reading and writing: every source kind, layouts, round trips, editing operations, and
what write_bvh says when given something other than a Motion."""

import io
import os

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from conftest import bvh_values
from expressive_mocap.decoupling.algebra import decompose
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.procedural import procedural_walk


def same_rotation(q1, q2):
    return np.abs(np.sum(q1 * q2, axis=-1))


def assert_same_motion(a: em.Motion, b: em.Motion, rtol=1e-12):
    """Same skeleton layout, same rotations (as rotations) and translations to ``rtol`` of their scale."""
    assert a.skeleton.names == b.skeleton.names
    assert a.skeleton.channels == b.skeleton.channels
    np.testing.assert_array_equal(a.skeleton.parents, b.skeleton.parents)
    scale = max(np.abs(a.translations).max(), np.abs(a.skeleton.offsets).max(), 1.0)
    np.testing.assert_allclose(a.skeleton.offsets, b.skeleton.offsets, rtol=0, atol=rtol * scale)
    assert a.frame_time == pytest.approx(b.frame_time, rel=rtol)
    np.testing.assert_allclose(same_rotation(a.rotations, b.rotations), 1.0, atol=max(rtol, 1e-12))
    np.testing.assert_allclose(a.translations, b.translations, rtol=0, atol=rtol * scale)


def test_reads_the_hand_written_layout(mixed_path):
    motion = em.read_bvh(mixed_path)
    sk = motion.skeleton
    assert sk.names == ("mixamorig:Hips", "Spine Lower", "Chest", "Head", "Arm_L", "Hand_L", "Leg_R", "Foot_R", "Toe_R")
    assert sk.parents.tolist() == [-1, 0, 1, 2, 2, 4, 0, 6, 7]
    assert [sk.rotation_order(j) for j in range(4)] == ["YXZ", "ZXY", "YZX", "ZYX"]
    assert sk.rotation_order(5) == "ZXY"  # one Z channel; missing axes follow in X, Y order
    assert sk.channels[7] == ("Yposition", "Xrotation") and sk.channels[8] == ()
    assert [j for j, _ in sk.end_sites] == [3, 5, 8]
    assert motion.n_frames == 4 and motion.fps == pytest.approx(30.0, rel=1e-5)
    np.testing.assert_allclose(sk.offsets[1], [0.0, 10.5, 0.1])
    # Position channels replace the offset components they name; others keep the offset.
    np.testing.assert_allclose(motion.translations[0, 0], [1.5, 91.0, -2.0])
    np.testing.assert_allclose(motion.translations[0, 4], [14.0, 5.5, 0.25])
    np.testing.assert_allclose(motion.translations[0, 7], [0.0, -78.5, 0.0])
    np.testing.assert_allclose(motion.translations[:, 8], np.tile([0.0, -5.0, 12.0], (4, 1)))
    # Hand_L's single Z channel is its whole rotation.
    expected = Rotation.from_euler("Z", [[80.0], [-80.0], [0.0], [135.0]], degrees=True).as_quat()
    np.testing.assert_allclose(same_rotation(motion.rotations[:, 5], expected), 1.0, atol=1e-12)


def test_every_source_kind_and_whitespace_style(mixed_path, backend):
    reference = em.read_bvh(mixed_path)
    text = mixed_path.read_bytes()
    crlf_tabs = text.replace(b"\n", b"\r\n").replace(b" ", b" \t ")
    for source in [str(mixed_path), mixed_path, text, bytearray(text), io.BytesIO(crlf_tabs), crlf_tabs + b"\r\n\r\n"]:
        assert_same_motion(em.read_bvh(source), reference)


def test_text_mode_file_object_is_refused(mixed_path):
    with open(mixed_path) as handle, pytest.raises(em.BVHError, match="text mode"):
        em.read_bvh(handle)


def test_exact_round_trip(tmp_path, mixed_path, backend):
    motion = em.read_bvh(mixed_path)
    em.write_bvh(motion, tmp_path / "out.bvh")
    again = em.read_bvh(tmp_path / "out.bvh")
    assert_same_motion(again, motion)
    # Channel values come back too: positions exactly, angles as the same rotations.
    np.testing.assert_allclose(again.channel_values()[:, :3], bvh_values(mixed_path)[:, :3], rtol=0, atol=0)
    assert list(tmp_path.iterdir()) == [tmp_path / "out.bvh"]  # no temporary file left behind
    umask = os.umask(0)
    os.umask(umask)
    assert (tmp_path / "out.bvh").stat().st_mode & 0o777 == 0o666 & ~umask  # as open() would make it


def test_fixed_decimals_round_trip_within_1e6_relative(tmp_path, mixed_path):
    motion = em.read_bvh(mixed_path)
    text = em.bvh_bytes(motion, decimals=6)
    assert b"0.250000" in text
    assert_same_motion(em.read_bvh(text), motion, rtol=1e-6)


def test_read_many_matches_read_one_and_reports_bad_files(mixed_path, backend):
    good = mixed_path.read_bytes()
    bad = good.replace(b"4.5 94.0", b"4.5 oops")
    results = em.read_bvh_many([good, bad, mixed_path], errors="return")
    assert_same_motion(results[0], em.read_bvh(good))
    assert isinstance(results[1], em.BVHError) and results[1].line == 65  # the last frame line of the file
    assert_same_motion(results[2], results[0])
    with pytest.raises(em.BVHError):
        em.read_bvh_many([good, bad])


def test_slicing_resampling_and_euler_views(mixed_path):
    motion = em.read_bvh(mixed_path)
    assert motion[1:3].n_frames == 2 and motion[2].n_frames == 1
    np.testing.assert_array_equal(motion[::2].rotations, motion.rotations[::2])
    # Resampling to twice the rate keeps the original frames and puts slerp midpoints between.
    double = motion.resample(fps=2 * motion.fps)
    assert double.n_frames == 2 * motion.n_frames - 1
    np.testing.assert_allclose(same_rotation(double.rotations[::2], motion.rotations), 1.0, atol=1e-12)
    a, b, mid = motion.rotations[0], motion.rotations[1], double.rotations[1]
    halfway = (Rotation.from_quat(a).inv() * Rotation.from_quat(b)).as_rotvec() / 2
    expected = (Rotation.from_quat(a) * Rotation.from_rotvec(halfway)).as_quat()
    np.testing.assert_allclose(same_rotation(mid, expected), 1.0, atol=1e-12)
    np.testing.assert_allclose(double.translations[1], (motion.translations[0] + motion.translations[1]) / 2)
    assert motion.resample(n_frames=10).n_frames == 10
    assert motion.resample(n_frames=10).duration == pytest.approx(motion.duration)
    # Euler views in the joints' own orders rebuild the same motion.
    rebuilt = em.Motion.from_euler(motion.skeleton, motion.to_euler(), motion.translations, motion.frame_time)
    assert_same_motion(rebuilt, motion)


def test_changing_order_and_scale_keeps_the_world_pose(mixed_path, backend):
    motion = em.read_bvh(mixed_path)
    for order in ["XYZ", "ZYX"]:
        converted = em.read_bvh(em.bvh_bytes(motion.with_rotation_order(order)))
        rotating = [j for j, cs in enumerate(converted.skeleton.channels) if any(c.endswith("rotation") for c in cs)]
        assert {converted.skeleton.rotation_order(j) for j in rotating} == {order}
        np.testing.assert_allclose(converted.positions(), motion.positions(), atol=1e-9)
    scaled = em.read_bvh(em.bvh_bytes(motion.scaled(0.01)))
    np.testing.assert_allclose(scaled.positions(), motion.positions() * 0.01, atol=1e-11)
    assert scaled.skeleton.rest_height() == pytest.approx(motion.skeleton.rest_height() * 0.01)


@pytest.mark.real_data
def test_real_clips_round_trip(tmp_path, bandai2_dir, bandai1_dir, backend):
    paths = (
        sorted(bandai2_dir.glob("dataset-2_walk-turn-left_*.bvh"))[:3]
        + sorted(bandai1_dir.glob("dataset-1_dance*.bvh"))[:2]
    )
    for path in paths:
        motion = em.read_bvh(path)
        assert motion.skeleton.n_joints == 22 and motion.fps == pytest.approx(30.0, rel=1e-4)
        for decimals, rtol in [(None, 1e-12), (6, 1e-6)]:
            again = em.read_bvh(em.bvh_bytes(motion, decimals))
            assert_same_motion(again, motion, rtol)
        # Every position channel of the file reads back (angles are compared as rotations above).
        values = bvh_values(path)
        position_columns = [
            i for i, c in enumerate(c for cs in motion.skeleton.channels for c in cs) if c.endswith("position")
        ]
        np.testing.assert_allclose(
            motion.channel_values()[:, position_columns], values[:, position_columns], rtol=1e-12, atol=1e-12
        )


def test_files_sharing_a_hierarchy_shape_keep_their_own_offsets(mixed_path, backend):
    # The second file differs only in OFFSET numbers: it reuses the cached shape.
    text = mixed_path.read_bytes()
    other = text.replace(b"OFFSET 0.0 12.0 0.0", b"OFFSET 0.5 13.0 -1.0").replace(
        b"OFFSET 8.0 0.0 0.0", b"OFFSET 7.0 1.0 0.0"
    )
    first, second = em.read_bvh(text), em.read_bvh(other)
    np.testing.assert_array_equal(second.skeleton.offsets[2], [0.5, 13.0, -1.0])
    assert second.skeleton.end_sites[1] == (5, (7.0, 1.0, 0.0))
    np.testing.assert_array_equal(first.skeleton.offsets[2], [0.0, 12.0, 0.0])
    assert first.skeleton.end_sites[1] == (5, (8.0, 0.0, 0.0))
    # A bad number in a cached shape still gets the full parser's error and line.
    with pytest.raises(em.BVHError, match="line 12: expected an OFFSET value"):
        em.read_bvh(text.replace(b"OFFSET 0.0 12.0 0.0", b"OFFSET 0.0 nan 0.0"))


# ----------------------------------------------------------------------------- write_bvh


def test_write_bvh_of_a_decompositions_array_names_the_call_to_make(tmp_path):
    walk = procedural_walk(seconds=0.5)
    parts = decompose(walk, BodyModel.load())
    # Failed before with AttributeError: 'numpy.ndarray' object has no attribute 'skeleton'.
    with pytest.raises(em.MocapError) as raised:
        em.write_bvh(parts.body, tmp_path / "body.bvh")
    message = str(raised.value)
    assert "\n" not in message and "needs a Motion" in message and "parts.body_motion()" in message
    assert f"array {list(parts.body.shape)}" in message
    with pytest.raises(em.MocapError, match="got a Decomposition"):
        em.write_bvh(parts, tmp_path / "body.bvh")
    assert not (tmp_path / "body.bvh").exists()
    em.write_bvh(parts.body_motion(), tmp_path / "body.bvh")  # the call the message names works
    np.testing.assert_allclose(
        em.read_bvh(tmp_path / "body.bvh").positions(), parts.body_motion().positions(), atol=1e-6
    )
