"""Decoupling across capture sessions: the model's feature range (inputs clipped into what it was
trained on) and calibration's activity threshold (a session's neutral residue is not expressive),
on synthetic data and on a session the model never saw (Bandai-Namco dataset-1, CC BY-NC 4.0)."""

from dataclasses import replace

import numpy as np
import pytest

import expressive_mocap as em
from conftest import FixedFloor, scipy_positions
from expressive_mocap.cli import main
from expressive_mocap.decoupling.algebra import GAIN, decompose, split
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.errors import ModelError
from expressive_mocap.ops import Trunk
from expressive_mocap.procedural import walk_and_wave
from expressive_mocap.rotations import quat


@pytest.fixture(scope="module")
def model():
    return BodyModel.load()


def test_the_shipped_model_clips_features_outside_its_training_range(model):
    walk = walk_and_wave(seconds=2.0).walk
    features = model.features(walk)
    low, high = model.feature_range
    assert np.all(low <= high) and high[2] > 1.0  # forward speed: up to a run, in heights per second
    far = features.copy()
    far[:, 2] = 50.0  # a forward speed no training clip had
    edge = features.copy()
    edge[:, 2] = high[2]
    np.testing.assert_allclose(
        model.predict_from_features(walk.rotations, far), model.predict_from_features(walk.rotations, edge), atol=1e-12
    )
    # Unclipped, the network extrapolates: another pose.
    free = replace(model, feature_range=None)
    assert (
        np.abs(free.predict_from_features(walk.rotations, far) - free.predict_from_features(walk.rotations, edge)).max()
        > 0.01
    )


def test_activity_scale_reads_each_angle_divided_by_it():
    # Joint 0 turned 40 degrees, joint 1 20 degrees; with scale 2 on joint 0 both read as 20 degrees.
    original = np.stack([quat.about("X", 40.0), quat.about("X", 20.0)])[None]
    identity = np.tile([0.0, 0.0, 0.0, 1.0], (1, 2, 1))
    expressive, body, activity = split(original, identity, activity_scale=np.array([2.0, 1.0]))
    assert activity[0, 0] == pytest.approx(activity[0, 1]) and activity[0, 1] == pytest.approx(
        (np.tanh(np.radians(20.0)) * GAIN) ** 4
    )
    np.testing.assert_allclose(np.abs(np.sum(quat.mul(expressive, body) * original, axis=-1)), 1.0, atol=1e-12)
    # Scale 1 is the kernel's own decoupling.
    for a, b in zip(split(original, identity), split(original, identity, activity_scale=np.ones(2))):
        np.testing.assert_allclose(np.abs(a), np.abs(b), atol=1e-12)


def test_a_lean_spread_over_the_trunk_reads_as_the_chains_and_a_twist_does_not(backend):
    # Spine and chest each leaning 9 degrees forward: alone, activity 0.01 each; as the chain's
    # 18 degrees read with scale 0.5 (36 degrees), fully active. Twisted 20 degrees each about
    # the trunk line (X here, as on the Bandai skeleton), the chain adds nothing.
    identity = np.tile([0.0, 0.0, 0.0, 1.0], (1, 3, 1))
    trunk = Trunk((0, 1), ((0.0, 0.0, 0.0), (1.0, 0.0, 0.0)), 0.5)
    leaning = np.stack([quat.about("Z", 9.0), quat.about("Z", 9.0), quat.about("Z", 9.0)])[None]
    alone = split(leaning, identity)[2][0]
    chain = split(leaning, identity, trunk=trunk)[2][0]
    assert alone.max() < 0.02 and chain[0] == chain[1] == pytest.approx(1.0) and chain[2] == alone[2]
    twisted = np.stack([quat.about("X", 20.0), quat.about("X", 20.0), quat.about("Z", 1.0)])[None]
    np.testing.assert_array_equal(split(twisted, identity, trunk=trunk)[2], split(twisted, identity)[2])


def test_calibration_raises_thresholds_only_above_the_residue_and_saves_them(model, tmp_path):
    walks = [walk_and_wave(seconds=2.0, speed=s).walk for s in (0.8, 1.2)]
    calibrated = model.calibrated(walks)
    assert calibrated.activity_scale is not None and np.all(calibrated.activity_scale >= 1.0)
    assert model.calibrated(walks, threshold=False).activity_scale is None
    calibrated.save(tmp_path / "cal.npz")
    np.testing.assert_array_equal(BodyModel.load(tmp_path / "cal.npz").activity_scale, calibrated.activity_scale)
    # The trunk's threshold: saved, never below the model's own, and a bad one refused.
    assert calibrated.trunk.joints == model.trunk.joints and calibrated.trunk.scale >= model.trunk.scale
    assert BodyModel.load(tmp_path / "cal.npz").trunk == calibrated.trunk
    trunkless = dict(np.load(tmp_path / "cal.npz"))
    trunkless["trunk_scale"] = np.array(-1.0)
    np.savez(tmp_path / "bad_trunk.npz", **trunkless)
    with pytest.raises(ModelError, match="bad_trunk.npz: trunk_bones must make a trunk of some length and trunk_scale"):
        BodyModel.load(tmp_path / "bad_trunk.npz")
    arrays = dict(np.load(tmp_path / "cal.npz"))
    arrays["activity_scale"] = np.full(22, 0.5)
    np.savez(tmp_path / "bad.npz", **arrays)
    with pytest.raises(ModelError, match="bad.npz: activity_scale must be at least 1"):
        BodyModel.load(tmp_path / "bad.npz")


def test_the_streaming_decoupler_uses_the_calibrated_thresholds(model):
    from expressive_mocap.decoupling.streaming import StreamingDecoupler

    pair = walk_and_wave(seconds=2.0)
    calibrated = model.calibrated([walk_and_wave(seconds=2.0, speed=0.8).walk])
    calibrated = replace(calibrated, activity_scale=np.full(22, 1.5))  # raised everywhere, to tell it apart
    waving = pair.waving[:30]
    predicted = FixedFloor(calibrated, 0.0).predict_streamed(waving)
    # The stream splits frame by frame: the offline split without its smoothing in time.
    offline = split(waving.rotations, predicted, activity_scale=calibrated.activity_scale, trunk=calibrated.trunk)[2]
    assert np.abs(offline - split(waving.rotations, predicted, trunk=calibrated.trunk)[2]).max() > 0.05
    stream = StreamingDecoupler(calibrated, waving.skeleton, waving.frame_time, floor=0.0)
    for f in range(waving.n_frames):
        _, _, activity = stream.push(waving.rotations[f], waving.translations[f])
        np.testing.assert_allclose(activity, offline[f], atol=1e-9)


def test_calibrate_command_sets_thresholds_unless_told_not_to(tmp_path, capsys):
    pair = walk_and_wave(seconds=2.0)
    em.write_bvh(pair.walk, tmp_path / "walk.bvh")
    assert main(["calibrate", str(tmp_path / "walk.bvh"), "-o", str(tmp_path / "a.npz")]) == 0
    assert "activity thresholds raised" in capsys.readouterr().out
    assert main(["calibrate", str(tmp_path / "walk.bvh"), "--no-threshold", "-o", str(tmp_path / "b.npz")]) == 0
    assert BodyModel.load(tmp_path / "a.npz").activity_scale is not None
    assert BodyModel.load(tmp_path / "b.npz").activity_scale is None
    # Beside --calibrate on the commands that decouple.
    em.write_bvh(pair.waving, tmp_path / "wave.bvh")
    for flag, name in (([], "t"), (["--no-threshold"], "n")):
        argv = ["decouple", str(tmp_path / "wave.bvh"), "--calibrate", str(tmp_path / "walk.bvh"), *flag]
        assert main([*argv, "-o", str(tmp_path / name)]) == 0
    activity = [np.loadtxt(tmp_path / f"{n}_activity.csv", delimiter=",", skiprows=1) for n in ("t", "n")]
    assert np.all(activity[0] <= activity[1] + 1e-9) and activity[0].sum() < activity[1].sum()


def _hand_motion(motion: em.Motion, model, hand: str) -> float:
    """Mean over frames of the hand's world distance between modulation 0 and 1 (SciPy FK)."""
    parts = decompose(motion, model)
    j = motion.skeleton.index(hand)
    at = [scipy_positions(motion.skeleton, parts.recompose(s).channel_values())[:, j] for s in (0.0, 1.0)]
    return float(np.linalg.norm(at[0] - at[1], axis=-1).mean())


def test_another_sessions_neutral_walk_stays_out_of_the_expressive_component(model, bandai1_dir):
    # Calibrated on four neutral clips of dataset-1, the fifth (a walk to the left) against a
    # right-hand "bye" of the same session. Measured: walk's hands at most 1.2 cm, bye's waving
    # hand 28 cm, its idle hand 2.7 cm (0.4 with the network trained before the spine was learned
    # for a reference pelvis); with a constant calibration only 4.8, 39 and 15 cm.
    def clip(name):
        return em.read_bvh(bandai1_dir / f"dataset-1_{name}_001.bvh")

    neutral = [clip(f"{c}_normal") for c in ("walk-right", "walk-back", "run", "dash")]
    walk, bye = clip("walk-left_normal"), clip("bye_normal")
    for threshold in (True, False):
        calibrated = model.calibrated(neutral, threshold=threshold)
        walking = max(_hand_motion(walk, calibrated, h) for h in ("Hand_L", "Hand_R"))
        waving, idle = _hand_motion(bye, calibrated, "Hand_R"), _hand_motion(bye, calibrated, "Hand_L")
        if threshold:
            assert walking < 0.1 * waving and waving > 20.0 and idle < 3.0, (walking, waving, idle)
        else:  # what the threshold fixes
            assert walking > 0.1 * waving and idle > 3.0, (walking, waving, idle)
