"""A walk's lean belongs to its trunk's expressive component, on real walks (Bandai-Namco
datasets 1 and 2, CC BY-NC 4.0): leaning styles read active in spine and chest, and the body
mechanics (modulation 0) stands them up. Lean measured with SciPy forward kinematics."""

from __future__ import annotations

from dataclasses import replace

import pytest

import expressive_mocap as em
from conftest import forward_lean
from expressive_mocap.decoupling import BodyModel, decompose

TRUNK = ["Spine", "Chest"]


@pytest.fixture(scope="module")
def model() -> BodyModel:
    return BodyModel.load()


def lean(motion: em.Motion) -> float:
    """Mean angle of the hips-to-neck line from vertical, towards the facing direction, degrees."""
    return forward_lean(motion, "Neck", ("UpperLeg_L", "UpperLeg_R"))


def trunk_reading(motion: em.Motion, model: BodyModel) -> tuple[float, float]:
    """Spine and chest activity (mean) and the lean at modulation 0."""
    parts = decompose(motion, model)
    joints = [motion.skeleton.index(n) for n in TRUNK]
    return float(parts.activity[:, joints].mean()), lean(parts.recompose(0.0))


def test_the_training_sessions_elderly_walks_lean_in_the_expressive_component(model, bandai2_dir):
    # Held-out takes (9-11) of dataset-2's walks. Measured: elderly lean 8.2 degrees, trunk
    # activity 0.43 (0.002 joint by joint), 6.1 at modulation 0; normal 0.3, 0.001, unchanged.
    def walks(style):
        return [em.read_bvh(bandai2_dir / f"dataset-2_walk_{style}_{k:03d}.bvh") for k in (9, 10, 11)]

    for walk in walks("normal"):
        activity, upright = trunk_reading(walk, model)
        assert activity < 0.01 and abs(upright - lean(walk)) < 0.5, (activity, upright, lean(walk))
    for walk in walks("elderly"):
        activity, upright = trunk_reading(walk, model)
        joint_by_joint, _ = trunk_reading(walk, replace(model, trunk=None))
        assert activity > 0.15 and joint_by_joint < 0.02, (activity, joint_by_joint)
        assert upright < lean(walk) - 1.0, (upright, lean(walk))


def test_another_sessions_leaning_walks_stand_up_when_calibrated(model, bandai1_dir):
    # Dataset-1's sidesteps, the model calibrated on that session's three normal ones. Measured
    # (walk-left): normal activity 0.008; tired 0.70, not-confident 1.00, and at modulation 0
    # their lean 9.4 -> 0.6 and 20.3 -> 2.0 (normal -1.2).
    def clip(move, style):
        return em.read_bvh(bandai1_dir / f"dataset-1_{move}_{style}_001.bvh")

    calibrated = model.calibrated([clip(m, "normal") for m in ("walk-left", "walk-right", "walk-back")])
    normal = clip("walk-left", "normal")
    normal_activity, _ = trunk_reading(normal, calibrated)
    for style in ("tired", "not-confident"):
        walk = clip("walk-left", style)
        activity, upright = trunk_reading(walk, calibrated)
        assert activity > max(2 * normal_activity, 0.3), (style, activity, normal_activity)
        halfway = (lean(walk) + lean(normal)) / 2
        assert upright < halfway, (style, upright, halfway)
