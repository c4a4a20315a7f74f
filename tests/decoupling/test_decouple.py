"""Decoupling algebra and its applications: the invariants of METHODS.md section 3 that need
no trained model (any body-mechanics predictor must satisfy them), and Rust/NumPy parity."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from expressive_mocap import decoupling as dc
from expressive_mocap import reference
from expressive_mocap.decoupling import edits
from expressive_mocap.errors import ArgumentError
from expressive_mocap.ops import compose_rotations, decouple_rotations
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.rotations import quat


class SmoothingModel:
    """A stand-in body-mechanics model: each joint's rotation averaged over +-5 frames (leaves
    the slow part as 'body mechanics', the fast residue as 'expressive'); root and hips copied."""

    def predict(self, motion):
        # Each joint on the hemisphere of its first frame, so the rotations can be averaged.
        rotations = motion.rotations * np.where(
            np.sum(motion.rotations * motion.rotations[:1], axis=-1, keepdims=True) < 0, -1.0, 1.0
        )
        kernel = np.ones(11) / 11
        padded = np.pad(rotations, ((5, 5), (0, 0), (0, 0)), mode="edge")
        smooth = np.apply_along_axis(lambda x: np.convolve(x, kernel, mode="valid"), 0, padded)
        smooth = quat.normalize(smooth)
        smooth[:, :2] = motion.rotations[:, :2]
        return smooth


MODEL = SmoothingModel()


def same_rotation(a, b):
    return np.abs(np.sum(a * b, axis=-1))


@pytest.fixture(scope="module")
def walk():
    return procedural_walk(seconds=2.0)


def test_compose_of_decompose_is_the_original(backend, walk):
    parts = dc.decompose(walk, MODEL)
    np.testing.assert_allclose(same_rotation(parts.recompose(1.0).rotations, walk.rotations), 1.0, atol=1e-12)
    np.testing.assert_allclose(parts.recompose(1.0).positions(), walk.positions(), atol=1e-6)
    assert parts.activity.min() >= 0.0 and parts.activity.max() <= 1.0
    # Root and hips belong to the body mechanics: no expressive rotation there.
    np.testing.assert_allclose(parts.expressive[:, :2, 3], 1.0)


def test_modulation_by_one_is_identity_and_by_zero_the_body(backend, walk):
    np.testing.assert_allclose(same_rotation(dc.modulate(walk, 1.0, MODEL).rotations, walk.rotations), 1.0, atol=1e-12)
    parts = dc.decompose(walk, MODEL)
    # The algebra alone (the stance feet not planted back, no hinge limits):
    zero = dc.modulate(walk, 0.0, MODEL, plant_feet=False, hinges=False)
    np.testing.assert_allclose(same_rotation(zero.rotations, parts.body), 1.0, atol=1e-12)
    # 150% expressiveness turns each joint 1.5 times as far from the body mechanics (the method
    # itself: without the hinge limits, which straighten a knee pushed past straight here).
    more = dc.modulate(walk, 1.5, MODEL, plant_feet=False, hinges=False).rotations
    e_more = quat.mul(more, quat.conjugate(parts.body))
    np.testing.assert_allclose(quat.angle(e_more), 1.5 * quat.angle(parts.expressive), atol=1e-9)


def test_mixing_a_motion_with_itself_is_the_identity(backend, walk):
    for align in ["index", "resample"]:
        mixed = dc.mix(walk, walk, MODEL, align=align)
        np.testing.assert_allclose(same_rotation(mixed.rotations, walk.rotations), 1.0, atol=1e-12)
        np.testing.assert_array_equal(mixed.translations, walk.translations)


def test_blend_with_empty_windows_is_a_cut(walk):
    other = procedural_walk(seconds=1.5, speed=0.6)
    for model, windows in [(MODEL, ((20, 20), (20, 20))), (None, ((20, 20), None))]:
        out = dc.blend(walk, other, model, *windows)
        assert out.n_frames == 20 + other.n_frames
        np.testing.assert_allclose(same_rotation(out.rotations[:20], walk.rotations[:20]), 1.0, atol=1e-12)
        # Every joint but the hips (which carry the path: turned to the first's heading) is the second's.
        np.testing.assert_allclose(same_rotation(out.rotations[20:, 2:], other.rotations[:, 2:]), 1.0, atol=1e-12)
        turn = quat.mul(out.rotations[20:, 1], quat.conjugate(other.rotations[:, 1]))  # one turn about Y
        np.testing.assert_allclose(np.abs(turn[:, [0, 2]]), 0.0, atol=1e-9)
        np.testing.assert_allclose(same_rotation(turn, turn[:1]), 1.0, atol=1e-9)
    # The second motion's hips continue the first's at the cut (on the floor plane).
    np.testing.assert_allclose(out.positions()[20, 1, [0, 2]], walk.positions()[20, 1, [0, 2]], atol=1e-9)


def test_asynchronous_blend_moves_each_component_in_its_own_window(walk):
    other = procedural_walk(seconds=1.5, speed=0.6)
    out = dc.blend(walk, other, MODEL, body_window=(10, 30), expressive_window=(40, 50), plant_feet=False)
    a, b = dc.decompose(walk, MODEL), dc.decompose(other, MODEL)
    frames = np.arange(out.n_frames)
    i, j = np.minimum(frames, walk.n_frames - 1), np.clip(frames - 10, 0, other.n_frames - 1)
    body = quat.slerp(a.body[i], b.body[j], edits._weights(out.n_frames, (10, 30))[:, None])
    expressive = quat.mul(out.rotations, quat.conjugate(body))[:, 2:]  # the hips, turned by the blend, have none
    # The expressive part is the first motion's until its window opens, the second's after it closes.
    np.testing.assert_allclose(same_rotation(expressive[:40], a.expressive[i[:40], 2:]), 1.0, atol=1e-9)
    np.testing.assert_allclose(same_rotation(expressive[50:], b.expressive[j[50:], 2:]), 1.0, atol=1e-9)


def test_mix_refuses_other_skeletons(walk, mixed_path):
    with pytest.raises(ArgumentError, match="different skeletons"):
        dc.mix(walk, em.read_bvh(mixed_path), MODEL)


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
def test_rust_matches_numpy_twin():
    from expressive_mocap import _core

    original = Rotation.random(3000, random_state=3).as_quat().reshape(150, 20, 4)
    noise = Rotation.from_rotvec(np.random.default_rng(4).normal(scale=0.4, size=(3000, 3)))
    body = (Rotation.from_quat(original.reshape(-1, 4)) * noise).as_quat().reshape(150, 20, 4)
    for rust, twin in zip(
        _core.decouple_rotations(original, body, 2.0, 4.0), reference.decouple_rotations(original, body, 2.0, 4.0)
    ):
        np.testing.assert_allclose(rust, twin, atol=1e-12)
    np.testing.assert_allclose(
        _core.compose_rotations(original, body, 0.7), reference.compose_rotations(original, body, 0.7), atol=1e-12
    )
    # A clip's smoothed split, against the twin's SciPy Gaussians, with per-joint thresholds.
    scale = np.random.default_rng(5).uniform(1.0, 2.0, 20)
    for sigmas in ((1.5, 3.0), (6.0, 12.0), (0.0, 0.0)):
        rust = _core.split_rotations(original, body, 2.0, 4.0, scale, *sigmas)
        twin = reference.split_rotations(original, body, 2.0, 4.0, scale, *sigmas)
        for a, b in zip(rust[:2], twin[:2]):  # quaternions: either sign is the rotation
            np.testing.assert_allclose(np.abs(np.sum(a * b, axis=-1)), 1.0, atol=1e-12)
        np.testing.assert_allclose(rust[2], twin[2], atol=1e-12)
        np.testing.assert_allclose(np.abs(np.sum(quat.mul(rust[0], rust[1]) * original, axis=-1)), 1.0, atol=1e-12)
    # The trunk read as one chain (three joints, a slanted trunk line).
    trunk = ([4, 5, 6], [(0.0, 1.0, 0.1), (0.3, 2.0, 0.0), (0.2, 1.0, -0.1)], 0.4)
    rust = _core.split_rotations(original, body, 2.0, 4.0, scale, 1.5, 3.0, *trunk)
    twin = reference.split_rotations(original, body, 2.0, 4.0, scale, 1.5, 3.0, *trunk)
    plain = reference.split_rotations(original, body, 2.0, 4.0, scale, 1.5, 3.0)
    np.testing.assert_allclose(rust[2], twin[2], atol=1e-12)
    assert np.all(twin[2] >= plain[2] - 1e-12) and np.abs(twin[2][:, 4:7] - plain[2][:, 4:7]).max() > 0.1
    np.testing.assert_array_equal(twin[2][:, :4], plain[2][:, :4])


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
def test_many_clips_split_in_one_call_as_clip_by_clip():
    """The batched split (clips in parallel, as preprocess --model runs it) gives each clip what
    its own call gives, bit for bit in Rust and within 1e-12 of the NumPy twin: each clip with its
    own smoothing widths, none leaking into its neighbours."""
    from expressive_mocap import _core

    rng = np.random.default_rng(6)
    lengths, sigmas = [40, 1, 73, 12], [(1.5, 3.0), (0.0, 0.0), (6.0, 12.0), (0.5, 1.0)]
    originals = [Rotation.random(n * 5, random_state=n).as_quat().reshape(n, 5, 4) for n in lengths]
    bodies = [
        (Rotation.from_quat(o.reshape(-1, 4)) * Rotation.from_rotvec(rng.normal(scale=0.4, size=(o.size // 4, 3))))
        .as_quat()
        .reshape(o.shape)
        for o in originals
    ]
    scale = rng.uniform(1.0, 2.0, 5)
    # the trunk read as a chain, and the arms filtered in world axes
    trunk = ([1, 2], [(0.0, 1.0, 0.1), (0.3, 2.0, 0.0)], 0.4, [-1, 0, 1, 2, 3], [3, 4])
    body_sigmas, activity_sigmas = [s[0] for s in sigmas], [s[1] for s in sigmas]
    many = _core.split_rotations_many(originals, bodies, 2.0, 4.0, scale, body_sigmas, activity_sigmas, *trunk)
    twins = reference.split_rotations_many(originals, bodies, 2.0, 4.0, scale, body_sigmas, activity_sigmas, *trunk)
    assert len(many) == len(twins) == len(originals)
    for o, b, (bs, a_s), got, twin in zip(originals, bodies, sigmas, many, twins):
        alone = _core.split_rotations(o, b, 2.0, 4.0, scale, bs, a_s, *trunk)
        for a, c in zip(got, alone):
            np.testing.assert_array_equal(a, c)
        for a, c in zip(got[:2], twin[:2]):
            np.testing.assert_allclose(np.abs(np.sum(a * c, axis=-1)), 1.0, atol=1e-12)
        np.testing.assert_allclose(got[2], twin[2], atol=1e-12)
    with pytest.raises(em.errors.ArgumentError, match="body_sigmas"):
        _core.split_rotations_many(originals, bodies, 2.0, 4.0, scale, body_sigmas[:2], activity_sigmas)
    with pytest.raises(em.errors.ArgumentError, match="bodies"):
        _core.split_rotations_many(originals, [bodies[0], bodies[0], *bodies[2:]], 2.0, 4.0, scale, body_sigmas,
                                   activity_sigmas)  # fmt: skip


def test_the_smoothed_split_holds_a_steady_prediction_and_removes_a_pop(backend):
    """B smoothed over frames: a prediction that is steady stays (away from the held ends, the
    split is the unsmoothed one), and one frame's 20-degree jump shrinks to a fifth or less."""
    from expressive_mocap.ops import split_rotations

    steady = np.tile(Rotation.from_euler("x", 40, degrees=True).as_quat(), (30, 2, 1))
    original = Rotation.from_euler("x", np.linspace(30, 60, 60)[:, None], degrees=True).as_quat().reshape(30, 2, 4)
    plain = split_rotations(original, steady, 2.0, 4.0)
    smooth = split_rotations(original, steady, 2.0, 4.0, None, 1.5, 0.0)
    np.testing.assert_allclose(np.abs(np.sum(plain[1] * smooth[1], axis=-1)), 1.0, atol=1e-12)
    popped = steady.copy()
    popped[15, 0] = Rotation.from_euler("x", 60, degrees=True).as_quat()
    body = split_rotations(original, popped, 2.0, 4.0, None, 1.5, 0.0)[1]
    jump = np.degrees(quat.angle(quat.mul(body[1:, 0], quat.conjugate(body[:-1, 0])))).max()
    assert jump < 4.0, jump


def test_activity_index_formula(backend):
    # E = rotation by a about an axis: A = clip((tanh(a) * g)^b, 0, 1).
    angles = np.radians([0.0, 5.0, 15.0, 30.0, 90.0])
    original = Rotation.from_rotvec(np.outer(angles, [0, 0, 1])).as_quat()[None]
    body = np.tile([0.0, 0, 0, 1], (1, 5, 1))
    expressive, recovered, activity = decouple_rotations(original, body, 2.0, 4.0)
    np.testing.assert_allclose(activity[0], np.clip((np.tanh(angles) * 2) ** 4, 0, 1), atol=1e-12)
    np.testing.assert_allclose(quat.angle(expressive[0]), angles * activity[0], atol=1e-12)
    np.testing.assert_allclose(same_rotation(compose_rotations(expressive, recovered), original), 1.0, atol=1e-12)


def test_bad_arguments(backend):
    q = np.tile([0.0, 0, 0, 1], (2, 3, 1))
    with pytest.raises(em.errors.ArgumentError, match="body"):
        decouple_rotations(q, q[:1], 2.0, 4.0)
    with pytest.raises(em.errors.ArgumentError, match="gain"):
        decouple_rotations(q, q, gain=-1.0, exponent=4.0)
    with pytest.raises(em.errors.ArgumentError, match="scale"):
        compose_rotations(q, q, scale=np.inf)
