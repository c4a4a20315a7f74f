"""The body-mechanics model: training end to end on small data, the file format (data only,
checked, never pickles), skeleton checks, calibration, and the streaming decoupler."""

import io
import zipfile

import numpy as np
import pytest

import expressive_mocap as em
from conftest import FixedFloor
from expressive_mocap.decoupling.algebra import Decomposition, decompose, split
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.decoupling.streaming import StreamingDecoupler
from expressive_mocap.decoupling.training import train_body_model
from expressive_mocap.errors import ModelError
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.rotations import quat


@pytest.fixture(scope="module")
def walks():
    return [procedural_walk(seconds=3.0, speed=s) for s in (0.8, 1.0, 1.2, 1.4)]


@pytest.fixture(scope="module")
def model(walks):
    return train_body_model(walks, walks[:2], hidden=12, regression_hidden=12, max_iter=25, log=None)


def test_training_reports_every_stage_and_beats_the_mean_pose(model):
    report, stages = model.report, model.report.stages()
    assert list(stages) == ["mean_pose", "autoencoder", "regression", "stack", "fine_tuned", "plain"]
    for name, stage in stages.items():
        assert stage.test_mse is not None and np.isfinite(stage.test_mse), name
    assert stages["fine_tuned"].test_mse < stages["mean_pose"].test_mse
    assert report.split is not None and report.split.train_groups >= 1 and report.split.test_groups >= 1
    # Root and hips come from the motion; every other joint is predicted.
    assert model.predicted.tolist() == list(range(2, 22))
    # The upper arms and forearms are filtered in world axes, on the skeleton's own tree.
    names = model.joint_names
    limbs = [names.index(n) for n in ("UpperArm_L", "LowerArm_L", "UpperArm_R", "LowerArm_R")]
    assert model.arms is not None and list(model.arms.limbs) == sorted(limbs)


def test_a_trained_model_keeps_the_range_of_its_training_features(model, walks, tmp_path):
    from expressive_mocap.decoupling.body_model import model_features

    low, high = model.feature_range
    every = np.concatenate([model_features(m, model.thigh_reference) for m in walks])
    # The training clips' range (the test split's clips may reach beyond it), within all clips';
    # the thigh rotations (the last 8 columns) are not limited.
    assert np.all(low[:11] >= every.min(axis=0)[:11]) and np.all(high[:11] <= every.max(axis=0)[:11])
    assert np.all(low[:11] < high[:11]) and np.all(low[11:] == -1.0) and np.all(high[11:] == 1.0)
    model.save(tmp_path / "m.npz")
    np.testing.assert_array_equal(BodyModel.load(tmp_path / "m.npz").feature_range, model.feature_range)


def test_prediction_keeps_root_and_hips_and_gives_unit_rotations(model, walks):
    body = model.predict(walks[0])
    assert body.shape == walks[0].rotations.shape
    np.testing.assert_array_equal(body[:, :2], walks[0].rotations[:, :2])
    np.testing.assert_allclose(np.linalg.norm(body, axis=-1), 1.0, atol=1e-12)


def test_file_round_trip(tmp_path, model, walks):
    model.save(tmp_path / "m.npz")
    again = BodyModel.load(tmp_path / "m.npz")
    np.testing.assert_array_equal(again.predict(walks[1]), model.predict(walks[1]))
    assert again.report == model.report and again.settings == model.settings


def test_other_skeleton_is_a_clear_error(model, mixed_path):
    with pytest.raises(ModelError, match="22-joint skeleton.*9 joints"):
        model.predict(em.read_bvh(mixed_path))


def test_damaged_and_foreign_files_are_refused(tmp_path, model):
    data = model.to_bytes()
    with pytest.raises(em.MocapError, match="not a readable model file"):
        BodyModel.load(data[: len(data) // 2])
    with pytest.raises(em.MocapError, match="not a readable model file"):
        BodyModel.load(b"hello")
    # A pickled object inside the archive: np.load(allow_pickle=False) refuses it.
    buffer = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(data)) as source, zipfile.ZipFile(buffer, "w") as target:
        for item in source.namelist():
            target.writestr(item, source.read(item))
        target.writestr("evil.npy", _pickled_npy({"run": "os.system"}))
    with pytest.raises(em.MocapError, match="not a readable model file"):
        BodyModel.load(buffer.getvalue())
    # Arrays of the wrong shape.
    arrays = dict(np.load(io.BytesIO(data), allow_pickle=False))
    arrays["hemispheres"] = arrays["hemispheres"][:3]
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    with pytest.raises(em.MocapError, match="hemispheres"):
        BodyModel.load(buffer.getvalue())


def _pickled_npy(payload) -> bytes:
    """An .npy file holding a pickled object array."""
    buffer = io.BytesIO()
    np.save(buffer, np.array([payload], dtype=object), allow_pickle=True)
    return buffer.getvalue()


def test_calibration_absorbs_a_constant_offset(model, walks):
    # The same walks with the left upper arm turned by a constant 40 degrees (another "session").
    offset = quat.about("Z", 40.0)
    arm = walks[0].skeleton.index("UpperArm_L")

    def shifted(m):
        rotations = m.rotations.copy()
        rotations[:, arm] = quat.mul(offset, rotations[:, arm])
        return em.Motion(m.skeleton, rotations, m.translations, m.frame_time)

    base, other = model.calibrated(walks), model.calibrated([shifted(m) for m in walks])
    # Left multiplication is linear, so the session's correction is the offset times the base one.
    np.testing.assert_allclose(
        np.abs(np.sum(other.calibration[arm] * quat.mul(offset, base.calibration[arm]))), 1.0, atol=1e-12
    )
    before = decompose(shifted(walks[1]), model).activity[:, arm].mean()
    after = decompose(shifted(walks[1]), other).activity[:, arm].mean()
    reference = decompose(walks[1], base).activity[:, arm].mean()
    assert before > 0.9 and after == pytest.approx(reference, abs=1e-9), (before, after, reference)


def test_streaming_matches_offline_decoupling_frame_by_frame(model, walks):
    """The stream splits each frame as it comes: the offline split without its smoothing in time
    (which needs the frames after)."""
    walk = walks[2][:45]
    predicted = FixedFloor(model, 0.0).predict_streamed(walk)
    offline = Decomposition(walk, *split(walk.rotations, predicted, trunk=model.trunk, arms=model.arms))
    stream = StreamingDecoupler(model, walk.skeleton, walk.frame_time, floor=0.0, history=2.0)
    for f in range(walk.n_frames):
        body, expressive, activity = stream.push(walk.rotations[f], walk.translations[f])
        np.testing.assert_allclose(activity, offline.activity[f], atol=1e-9)
        np.testing.assert_allclose(np.abs(np.sum(body * offline.body[f], axis=-1)), 1.0, atol=1e-9)
