"""The 19 dynamic features: cases by hand, heading invariance, causality, Rust/NumPy parity and
real Bandai-Namco walks."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from conftest import straight_walker
from expressive_mocap import ops, reference
from expressive_mocap.body import actor_height
from expressive_mocap.body.canonical import bandai_like_skeleton
from expressive_mocap.body.contacts import default_floor
from expressive_mocap.body.roles import JointRoles
from expressive_mocap.decoupling.features import FEATURE_NAMES, dynamic_features
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.rotations import quat
from expressive_mocap.rotations.quat import mean_rotation

ATOL = 1e-9  # Rust vs NumPy and invariances, on features of order 1 (measured ~1e-15)
V, V_MEAN, CONTACT, AIR, H, THIGHS = slice(0, 3), slice(3, 6), slice(6, 8), slice(8, 10), 10, slice(11, 19)


def turned(motion, degrees, shift=(0.0, 0.0, 0.0)):
    """The same motion turned about the vertical through the origin, then moved by ``shift``."""
    q = quat.about("Y", degrees)
    rotations, translations = motion.rotations.copy(), motion.translations.copy()
    rotations[:, 0] = quat.mul(q, rotations[:, 0])
    translations[:, 0] = quat.rotate(q, translations[:, 0]) + shift
    return em.Motion(motion.skeleton, rotations, translations, motion.frame_time)


# -- features by hand ---------------------------------------------------------------------


def test_feature_names():
    assert len(FEATURE_NAMES) == 19 == len(set(FEATURE_NAMES))


def test_constant_hips_velocity(backend):
    walker = straight_walker(frames=40)  # 140 cm/s forward = 1 actor height a second
    f = dynamic_features(walker, floor=0.0)
    assert f.shape == (40, 19)
    np.testing.assert_allclose(f[0, V], 0.0)
    np.testing.assert_allclose(f[1:, V], np.tile([0.0, 0.0, 1.0], (39, 1)), atol=1e-12)
    # The mean over the last 10 frames (a third of a second) ramps up from frame 0's zero.
    np.testing.assert_allclose(f[:10, 5], np.arange(10) / np.arange(1, 11), atol=1e-12)
    np.testing.assert_allclose(f[10:, V_MEAN], np.tile([0.0, 0.0, 1.0], (30, 1)), atol=1e-12)
    np.testing.assert_allclose(f[:, H], 1.0)  # hips 90 cm above the floor, 90 cm at rest
    # Moving sideways to the left (+X while facing +Z) at 70 cm/s, and upwards.
    f = dynamic_features(straight_walker(frames=5, velocity=(70.0, 14.0, 0.0)), floor=0.0)
    np.testing.assert_allclose(f[1:, V], np.tile([0.5, 0.1, 0.0], (4, 1)), atol=1e-12)


def test_hips_height_is_above_the_floor_over_the_rest_height(backend):
    walker = straight_walker(frames=5)
    f = dynamic_features(walker, floor=-9.0)
    np.testing.assert_allclose(f[:, H], 99.0 / 90.0)


@pytest.mark.parametrize("degrees", [90.0, -137.0])
def test_turning_the_motion_changes_nothing(backend, degrees):
    walk = procedural_walk(seconds=2.0)
    for causal in (True, False):
        original = dynamic_features(walk, causal=causal)
        np.testing.assert_allclose(
            dynamic_features(turned(walk, degrees, shift=(300.0, 0.0, -50.0)), causal=causal), original, atol=ATOL
        )
    # The heading frame's +Z is forward, +X left.
    assert original[1:, 5].mean() > 0.5 and abs(original[1:, 3].mean()) < 0.05


def test_thighs_follow_the_reference_hemisphere(backend):
    walk = procedural_walk(seconds=1.0)
    thighs = walk.rotations[:, [14, 18]]
    default = dynamic_features(walk)[:, THIGHS].reshape(-1, 2, 4)
    np.testing.assert_allclose(np.abs(default), np.abs(thighs), atol=1e-15)
    assert (np.sum(default * thighs[:1], axis=-1) >= 0).all()  # causal default: the first frame
    flipped = dynamic_features(walk, thigh_reference=-thighs[0])[:, THIGHS].reshape(-1, 2, 4)
    np.testing.assert_allclose(flipped, -default, atol=1e-15)
    offline = dynamic_features(walk, causal=False)[:, THIGHS].reshape(-1, 2, 4)
    means = np.stack([mean_rotation(thighs[:, 0]), mean_rotation(thighs[:, 1])])
    assert (np.sum(offline * means, axis=-1) >= 0).all()


# -- causality ----------------------------------------------------------------------------


@pytest.mark.real_data
def test_causal_features_do_not_look_ahead(backend, bandai2_dir):
    walk = em.read_bvh(bandai2_dir / "dataset-2_walk_normal_001.bvh")
    other = em.read_bvh(bandai2_dir / "dataset-2_walk_exhausted_001.bvh")
    full = dynamic_features(walk)
    for k in (1, 2, 3, 11, 57, 150):
        np.testing.assert_allclose(dynamic_features(walk[:k]), full[:k], atol=1e-12, err_msg=f"truncated to {k} frames")
        # Other frames after k (a different walk, shifted to start where this one is): same first k rows.
        spliced = em.Motion(
            walk.skeleton,
            np.concatenate([walk.rotations[:k], other.rotations[k:]]),
            np.concatenate([walk.translations[:k], other.translations[k:]]),
            walk.frame_time,
        )
        np.testing.assert_allclose(
            dynamic_features(spliced)[:k], full[:k], atol=1e-12, err_msg=f"changed after frame {k}"
        )


# -- Rust vs NumPy ------------------------------------------------------------------------


def random_feature_inputs(rng, frames):
    points = rng.normal(scale=50.0, size=(frames, 3, 3))
    points[::7, 2] = points[::7, 1] + [0.0, 3.0, 0.0]  # upper legs one above the other: no heading
    points[0, 2] = points[0, 1] + [0.0, -2.0, 0.0]
    thighs = Rotation.random(frames * 2, random_state=frames).as_quat().reshape(frames, 2, 4)
    contacts = rng.random((frames, 2)) < 0.5
    ref = Rotation.random(2, random_state=1).as_quat()
    return points, thighs, contacts, ref


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
@pytest.mark.parametrize("frames, window", [(1, 10), (7, 1), (7, 30), (3000, 10)])
def test_rust_matches_numpy_twin(frames, window):
    from expressive_mocap import _core

    rng = np.random.default_rng(frames + window)
    args = (*random_feature_inputs(rng, frames), 1 / 30, 140.0, 93.0, 4.0, window)
    rust, numpy = _core.dynamic_features(*args), reference.dynamic_features(*args)
    assert rust.shape == numpy.shape == (frames, 19)
    np.testing.assert_allclose(rust, numpy, rtol=0, atol=ATOL * max(1.0, np.abs(numpy).max()))


@pytest.mark.real_data
def test_real_walk_parity_through_the_public_api(bandai2_dir):
    if not em.rust_available():
        pytest.skip("the Rust extension is not built")
    walk = em.read_bvh(bandai2_dir / "dataset-2_walk-turn-right_active_001.bvh")
    results = []
    for name in ("rust", "numpy"):
        with em.use_backend(name):
            results.append([dynamic_features(walk), dynamic_features(walk, causal=False)])
    for rust, numpy in zip(*results):
        np.testing.assert_allclose(rust, numpy, rtol=0, atol=ATOL)


# -- real walks ---------------------------------------------------------------------------


@pytest.mark.real_data
@pytest.mark.parametrize("style", ["normal", "exhausted", "youthful"])
def test_real_walk_features_are_sane(backend, bandai2_dir, style):
    walk = em.read_bvh(bandai2_dir / f"dataset-2_walk_{style}_001.bvh")
    f = dynamic_features(walk)
    assert f.shape == (walk.n_frames, 19) and np.isfinite(f).all()
    speed = f[1:, 5].mean() * actor_height(walk.skeleton)
    assert 40 < speed < 250, f"{style}: mean forward hips speed {speed:.0f} cm/s in the heading frame"
    assert abs(f[1:, 3].mean()) < 0.1 * f[1:, 5].mean(), "walks go forward, not sideways"
    assert 0.85 < np.median(f[:, H]) < 1.05, np.median(f[:, H])
    # Bandai thighs sit near 180 degrees (w ~ 0): the hemisphere rule must not flip them frame to frame.
    thighs = f[:, THIGHS].reshape(-1, 2, 4)
    assert (np.sum(thighs[1:] * thighs[:-1], axis=-1) > 0.9).all()
    assert set(np.unique(f[:, CONTACT])) == {0.0, 1.0}
    assert (f[:, AIR][f[:, CONTACT] == 1] == 0).all() and f[:, AIR].max() < 1.0


def test_demo_walk_features(backend):
    f = dynamic_features(procedural_walk(seconds=3.0, speed=1.2))
    assert np.isfinite(f).all()
    # 120 cm/s over an actor of 137 cm: about 0.88 heights a second, straight ahead.
    assert f[15:, 5].mean() == pytest.approx(120 / actor_height(bandai_like_skeleton()), rel=0.05)
    assert f[:, CONTACT].any(axis=0).all()


# -- errors -------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "options, name",
    [
        (dict(thigh_reference=[0, 0, 0, 1]), "thigh_reference"),
        (dict(floor=float("nan")), "floor"),
        (dict(speed_threshold=0), "speed_threshold"),
    ],
)
def test_argument_errors_name_the_argument(backend, options, name):
    with pytest.raises(em.MocapError, match=f"`{name}`"):
        dynamic_features(straight_walker(frames=3), **options)


@pytest.mark.parametrize(
    "name", ["points", "thighs", "contacts", "reference", "frame_time", "height", "hips_rest_height", "window"]
)
def test_kernel_errors_name_the_argument(backend, name):
    points, thighs, contacts, ref = random_feature_inputs(np.random.default_rng(0), 5)
    arguments = dict(
        points=points,
        thighs=thighs,
        contacts=contacts,
        reference=ref,
        frame_time=0.1,
        height=1.0,
        hips_rest_height=1.0,
        floor=0.0,
        window=3,
    )
    arguments[name] = {
        "points": points[:, :2],
        "thighs": thighs[:4],
        "contacts": contacts[:, :1],
        "reference": ref[:1],
        "frame_time": 0.0,
        "height": -1.0,
        "hips_rest_height": float("nan"),
        "window": 0,
    }[name]
    with pytest.raises(em.errors.ArgumentError, match=f"`{name}`"):
        ops.dynamic_features(*arguments.values())


# -- many clips at once (what preprocess uses) ----------------------------------------------


def _gait_one_by_one(motions, floor=0.0, thigh_reference=None):
    out = []
    for m in motions:
        f = dynamic_features(
            m,
            floor=default_floor(m.positions(), JointRoles.find(m.skeleton)) if floor is None else floor,
            thigh_reference=thigh_reference,
        )
        out.append((f, em.foot_contacts(m)))
    return out


def _gait_clips():
    """Walks of different lengths, speeds and frame rates, one a single frame, one of another actor size."""
    small = procedural_walk(seconds=2.0, speed=0.8)
    small = em.Motion(small.skeleton.scaled(0.8), small.rotations, small.translations * 0.8, small.frame_time)
    return [
        procedural_walk(seconds=3.0, speed=1.2),
        procedural_walk(seconds=1.5, fps=60.0, speed=1.6),
        procedural_walk(seconds=2.0)[:1],
        small,
    ]


@pytest.mark.parametrize("floor, reference", [(0.0, None), (None, "given")])
def test_gait_many_equals_the_one_clip_functions(backend, floor, reference):
    clips = _gait_clips()
    thigh_reference = clips[0].rotations[5][list(JointRoles.find(clips[0].skeleton).upper_legs)] if reference else None
    many = em.gait_many(clips, floor=floor, thigh_reference=thigh_reference)
    for (f, c), (f1, c1) in zip(many, _gait_one_by_one(clips, floor, thigh_reference)):
        np.testing.assert_allclose(f, f1, rtol=0, atol=ATOL)
        np.testing.assert_array_equal(c, c1)
    assert [len(f) for f, _ in many] == [m.n_frames for m in clips]


def test_gait_many_rust_matches_numpy_twin():
    if not em.rust_available():
        pytest.skip("the Rust extension is not built")
    # One clip with a NaN toe position in one frame: NaN propagates alike (the floor of that clip is NaN).
    broken = procedural_walk(seconds=1.0)
    rotations = broken.rotations.copy()
    rotations[7, JointRoles.find(broken.skeleton).feet[1]] = np.nan  # moves the toe
    broken = em.Motion(broken.skeleton, rotations, broken.translations, broken.frame_time)
    results = []
    for name in ("rust", "numpy"):
        with em.use_backend(name), np.errstate(invalid="ignore"):
            results.append(em.gait_many([*_gait_clips(), broken], floor=None))
    for (f, c), (f1, c1) in zip(*results):
        np.testing.assert_allclose(f, f1, rtol=0, atol=ATOL)
        np.testing.assert_array_equal(c, c1)
    assert np.isnan(results[0][-1][0][:, 10]).all()  # hips height above a NaN floor


def test_gait_many_asks_only_for_what_is_wanted_and_names_bad_input(backend):
    walk = procedural_walk(seconds=1.0)
    ((features, contacts),) = em.gait_many([walk], features=False)
    assert features is None and contacts.shape == (walk.n_frames, 2)
    ((features, contacts),) = em.gait_many([walk], contacts=False)
    assert contacts is None and features.shape == (walk.n_frames, 19)
    assert em.gait_many([]) == []
    with pytest.raises(em.MocapError, match="`motions`"):
        em.gait_many([walk, straight_walker(frames=3)])
    with pytest.raises(em.MocapError, match="`fk`"):
        em.gait_many([walk], fk=[])
    with pytest.raises(em.MocapError, match="`thigh_reference`"):
        em.gait_many([walk], thigh_reference=np.zeros(4))
    with pytest.raises(em.errors.ArgumentError, match="`roles`"):
        ops.clip_gait_many([], [0, 1], ops.GaitSettings(0.05, 0.5, 0.1, 5.0), features=True, contacts=True)
    positions = walk.positions()
    with pytest.raises(em.errors.ArgumentError, match="clip 0"):
        ops.clip_gait_many(
            [(positions, walk.rotations[:, :3], walk.frame_time, 140.0, 90.0)],
            [0] * 7,
            ops.GaitSettings(0.05, 0.5, 0.1, 5.0),
            features=True,
            contacts=True,
        )
    if em.get_backend() == "rust":  # a strided array is named, as by every Rust kernel (the twin takes it)
        with pytest.raises(TypeError, match="`clips`"):
            ops.clip_gait_many(
                [(np.asfortranarray(positions), walk.rotations, walk.frame_time, 140.0, 90.0)],
                [0] * 7,
                ops.GaitSettings(0.05, 0.5, 0.1, 5.0),
                features=True,
                contacts=True,
            )
    with pytest.raises(em.errors.ArgumentError, match="clip 0.*`toes`"):
        ops.clip_gait_many(
            [(positions, walk.rotations, walk.frame_time, 140.0, 90.0)],
            [0, 1, 2, 3, 4, 5, 99],
            ops.GaitSettings(0.05, 0.5, 0.1, 5.0),
            features=True,
            contacts=True,
        )


def test_percentiles_by_clip_are_numpys_clip_by_clip():
    from expressive_mocap.body.contacts import percentiles_by_clip

    rng = np.random.default_rng(5)
    for trial in range(60):
        lengths = rng.integers(1, 50, size=rng.integers(1, 6))
        bounds = np.r_[0, np.cumsum(lengths)]
        values = rng.normal(size=(bounds[-1], 2)) * 100
        values = np.round(values, 1) if trial % 2 else values  # ties too
        for q in (0, 5, 37.5, 50, 95, 100):
            want = [np.percentile(values[a:b], q) for a, b in zip(bounds[:-1], bounds[1:])]
            np.testing.assert_array_equal(percentiles_by_clip(values, bounds, q), want)
