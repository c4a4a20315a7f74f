"""Every method is unit-free (Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0): the same clips in
centimetres and in metres give the same exaggeration, decoupling, features and leg IK."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.rotations import quat

WAVE = "dataset-2_wave-right-hand_normal_001.bvh"


@pytest.fixture(scope="module")
def body_model():
    return BodyModel.load()


def assert_same_up_to_scale(cm: em.Motion, m: em.Motion, what: str, tolerance: float = 1e-9) -> None:
    """Rotations equal (to ``tolerance`` degrees), world positions equal after scaling (to ``tolerance`` cm)."""
    turn = np.degrees(quat.angle(quat.mul(quat.conjugate(cm.rotations), m.rotations)))
    assert turn.max() < tolerance, f"{what}: rotations differ by up to {turn.max():.3g} degrees"
    np.testing.assert_allclose(m.positions() * 100.0, cm.positions(), atol=tolerance, err_msg=what)


# The edits that plant the feet with leg IK: its arccos of a nearly straight knee rounds differently
# in centimetres and metres (measured: up to 1.2e-6 degrees).
IK = 1e-5


@pytest.fixture(scope="module")
def clips_cm_and_m(bandai2_dir):
    walk = em.read_bvh(bandai2_dir / "dataset-2_walk_normal_012.bvh")
    wave = em.read_bvh(bandai2_dir / WAVE)
    return (walk, wave), (walk.scaled(0.01), wave.scaled(0.01))


def real_walk_people(data, takes):
    """dataset-2's walks, take ``p`` of each style as person ``p``, styles in intensity order 1, 2, 3."""
    return [
        [em.read_bvh(data / f"dataset-2_walk_{style}_{p:03d}.bvh") for style in ("exhausted", "normal", "active")]
        for p in takes
    ]


def test_exaggeration_is_unit_free(bandai2_dir, clips_cm_and_m):
    """A model trained in centimetres exaggerates a walk in metres as it does the same walk in
    centimetres, and a model trained in metres is the same model. Before: the walk's hips height
    was divided by the model's actor height (139 cm): this test failed with rotations 33.9 degrees
    apart; on walk_normal_001 in metres (--to 3.5) the hips rose from 0.90 m to 1.45 m on average
    and foot locking reported 'out of reach by up to 2.52' (m)."""
    from expressive_mocap.exaggeration import exaggerate, train

    people = real_walk_people(bandai2_dir, (1, 2))
    model = train(people, [1, 2, 3])
    (walk, _), (walk_m, _) = clips_cm_and_m
    out, report = exaggerate(model, walk, 4.0)
    out_m, report_m = exaggerate(model, walk_m, 4.0)
    # Retimed and with the feet locked by leg IK: the same rounding as the decoupling edits (IK).
    assert_same_up_to_scale(out, out_m, "exaggerate", IK)
    assert report_m.k0 == pytest.approx(report.k0, abs=1e-9)
    assert report_m.foot_residual * 100 == pytest.approx(report.foot_residual, abs=1e-6)
    assert report_m.clamped.keys() == report.clamped.keys()
    # Trained in metres: the same ranking and mappings (weights are bone lengths: all scaled alike).
    model_m = train([[m.scaled(0.01) for m in p] for p in people], [1, 2, 3])
    np.testing.assert_array_equal(model_m.key, model.key)
    np.testing.assert_allclose(model_m.mappings, model.mappings, atol=1e-9)
    np.testing.assert_allclose(model_m.overall, model.overall, atol=1e-12)


def test_decoupling_and_features_are_unit_free(clips_cm_and_m, body_model):
    """Each method of the decoupling part, on the same clips in centimetres and in metres."""
    from expressive_mocap import decoupling as dc
    from expressive_mocap.body.contacts import foot_contacts
    from expressive_mocap.decoupling.features import dynamic_features

    (walk, wave), (walk_m, wave_m) = clips_cm_and_m
    assert_same_up_to_scale(
        dc.decompose(walk, body_model).body_motion(), dc.decompose(walk_m, body_model).body_motion(), "decompose"
    )
    assert_same_up_to_scale(dc.modulate(wave, 1.5, body_model), dc.modulate(wave_m, 1.5, body_model), "modulate", IK)
    assert_same_up_to_scale(dc.mix(walk, wave, body_model), dc.mix(walk_m, wave_m, body_model), "mix", IK)
    assert_same_up_to_scale(
        dc.blend(walk, wave, body_model, (30, 60), (60, 75)),
        dc.blend(walk_m, wave_m, body_model, (30, 60), (60, 75)),
        "blend",
        IK,
    )
    assert_same_up_to_scale(
        dc.blend(walk, wave, None, (30, 60)), dc.blend(walk_m, wave_m, None, (30, 60)), "naive blend"
    )
    np.testing.assert_array_equal(foot_contacts(walk_m), foot_contacts(walk))
    np.testing.assert_allclose(dynamic_features(walk_m), dynamic_features(walk), atol=1e-12)
    np.testing.assert_allclose(dynamic_features(walk_m, causal=False), dynamic_features(walk, causal=False), atol=1e-12)
    np.testing.assert_allclose(
        body_model.calibrated([walk_m]).calibration, body_model.calibrated([walk]).calibration, atol=1e-12
    )
    streams = [dc.StreamingDecoupler(body_model, m.skeleton, m.frame_time) for m in (walk, walk_m)]
    for t in range(45):
        cm, m = (s.push(x.rotations[t], x.translations[t]) for s, x in zip(streams, (walk, walk_m)))
        for a, b in zip(cm, m):
            np.testing.assert_allclose(np.abs(b), np.abs(a), atol=1e-12)


def test_leg_ik_is_unit_free():
    """Two-bone IK with a target nearer than the bones' difference gives the same pose in any
    units. Before: that bound was 1e-3 file units, 1 mm in metres but 0.01 mm in centimetres."""
    from expressive_mocap.body.ik import two_bone_ik

    identity = np.tile([0.0, 0.0, 0.0, 1.0], (1, 1))
    thigh, shin = np.array([0.0, -45.0, 0.0]), np.array([0.0, -40.0, 0.0])
    target = np.array([[0.0, -4.0, 0.5]])  # 4 cm from the hip: closer than 45 - 40 cm
    solved = [two_bone_ik(np.zeros((1, 3)), identity, identity, thigh * s, shin * s, target * s) for s in (1.0, 0.01)]
    for a, b in zip(*solved):
        np.testing.assert_allclose(np.abs(b), np.abs(a), atol=1e-12)
