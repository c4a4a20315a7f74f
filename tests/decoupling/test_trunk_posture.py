"""The pelvis posture the model predicts the spine for (decoupling/pelvis.py): yaw-free, and carried
onto a clip's own posture and back exactly."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from expressive_mocap.decoupling.pelvis import Pelvis, carried, mean_posture, mean_postures, postures
from expressive_mocap.rotations import quat


def _clip(frames=40, seed=0):
    """Local rotations [F, 3, 4] of root, hips and spine: a tilted, swaying pelvis under a turning root."""
    rng = np.random.default_rng(seed)
    root = Rotation.from_euler("y", np.linspace(0, 270, frames)[:, None], degrees=True)
    hips = Rotation.from_euler(
        "xz", np.column_stack([8 + 3 * np.sin(np.arange(frames) / 3), rng.normal(0, 2, frames)]), degrees=True
    )
    spine = Rotation.from_euler("x", rng.normal(-5, 1, (frames, 1)), degrees=True)
    return np.stack([root.as_quat(), hips.as_quat(), spine.as_quat()], axis=1)


def test_the_posture_ignores_which_way_the_actor_faces():
    clip = _clip()
    turned = clip.copy()
    turned[:, 0] = quat.mul(Rotation.from_euler("y", 123, degrees=True).as_quat()[None], clip[:, 0])
    np.testing.assert_allclose(np.abs(np.sum(postures(clip, (0, 1)) * postures(turned, (0, 1)), -1)), 1.0, atol=1e-12)
    # What is left is the hips' tilt: the root's turn about the up axis is gone (the tilt's own
    # sliver of yaw, from composing two tilts, goes too: under 0.01 degrees here).
    tilt = Rotation.from_quat(postures(clip, (0, 1))).magnitude()
    np.testing.assert_allclose(tilt, Rotation.from_quat(clip[:, 1]).magnitude(), atol=2e-4)


def test_carrying_the_spine_onto_a_posture_and_back_is_exact_and_levels_the_trunk():
    clip = _clip()
    reference = Rotation.from_euler("x", 2, degrees=True).as_quat()
    pelvis = Pelvis((0, 1), 2, reference)
    there = carried(clip, pelvis, inverse=True)
    np.testing.assert_array_equal(there[:, :2], clip[:, :2])
    back = carried(there, pelvis)
    np.testing.assert_allclose(np.abs(np.sum(back * clip, -1)), 1.0, atol=1e-12)
    # As a training target, the spine's world posture is the one it has on the reference pelvis.
    held = mean_posture(clip, (0, 1))
    on_reference = quat.mul(reference, there[:, 2])
    mean_world = quat.mul(held, clip[:, 2])
    angle = np.degrees(
        quat.angle(quat.mul(quat.mean_rotation(on_reference), quat.conjugate(quat.mean_rotation(mean_world))))
    )
    assert angle == pytest.approx(0.0, abs=0.5)


def test_a_batch_of_clips_gets_each_clips_own_mean_posture():
    # The batched form gives each clip its own mean posture, whatever clips lie beside it (a clip
    # without frames included).
    clips = [_clip(frames, seed) for frames, seed in ((40, 0), (0, 1), (1, 2), (173, 3))]
    means = mean_postures(np.concatenate(clips), [len(c) for c in clips], (0, 1))
    np.testing.assert_array_equal(means[1], [0.0, 0.0, 0.0, 1.0])
    for clip, mean in zip(clips, means):
        if len(clip):
            np.testing.assert_allclose(mean, quat.mean_rotation(postures(clip, (0, 1))), atol=1e-14)
            np.testing.assert_array_equal(mean, mean_posture(clip, (0, 1)))
    assert np.degrees(quat.angle(quat.mul(means[0], quat.conjugate(means[3])))) > 0.1  # they differ
