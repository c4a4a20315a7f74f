"""Plausible decoupling edits: the expressive component taken from chosen joint groups only."""

import numpy as np
import pytest

import expressive_mocap as em
from conftest import bvh_values
from expressive_mocap.cli import main
from expressive_mocap.decoupling import BodyModel
from expressive_mocap.decoupling.edits import mix
from expressive_mocap.decoupling.feet import default_mask, joint_mask
from expressive_mocap.errors import ArgumentError
from expressive_mocap.skeletons.canonical import canonical_skeleton
from expressive_mocap.skeletons.synthetic import synthetic_skeleton

LEGS = ["UpperLeg_L", "LowerLeg_L", "Foot_L", "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R"]
ARMS = [f"{part}_{side}" for side in "LR" for part in ("Shoulder", "UpperArm", "LowerArm", "Hand")]


@pytest.fixture(scope="module")
def model():
    return BodyModel.load()


# Groups of joints ---------------------------------------------------------------------------


def names(skeleton, groups):
    return {n for n, chosen in zip(skeleton.names, joint_mask(skeleton, groups)) if chosen}


def test_joint_groups_on_the_canonical_body():
    skeleton = canonical_skeleton()
    assert names(skeleton, "arms") == set(ARMS)
    assert names(skeleton, "legs") == set(LEGS)
    assert names(skeleton, "head") == {"Neck", "Head"}
    assert names(skeleton, "upper-body") == set(ARMS) | {"Spine", "Chest", "Neck", "Head"}
    assert names(skeleton, ["arms", "legs"]) == set(ARMS) | set(LEGS)
    assert names(skeleton, "all") == set(skeleton.names)


def test_joint_groups_on_another_skeleton_take_the_fingers_with_the_hand():
    skeleton = synthetic_skeleton("cmu")[0]
    arms = names(skeleton, "arms")
    assert {"LeftShoulder", "LeftHand", "LeftHandIndex1", "LThumb", "RightForeArm"} <= arms
    assert not arms & {"Hips", "Spine1", "Head", "LeftUpLeg"}
    assert names(skeleton, "legs") == {
        f"{s}{p}" for s in ("Left", "Right") for p in ("UpLeg", "Leg", "Foot", "ToeBase")
    }


def test_an_unknown_group_is_a_clear_error():
    with pytest.raises(ArgumentError, match="unknown group.*hands.*groups are all, arms"):
        joint_mask(canonical_skeleton(), ["arms", "hands"])


# Real clips ----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def clips(bandai1_dir, bandai2_dir):
    read = em.read_bvh
    return {
        "walk": read(bandai2_dir / "dataset-2_walk_normal_001.bvh"),
        "wave": read(bandai2_dir / "dataset-2_wave-right-hand_normal_001.bvh"),
        "old": read(bandai1_dir / "dataset-1_walk_old_001.bvh"),
        "walk1": read(bandai1_dir / "dataset-1_walk_normal_001.bvh"),
        "bye1": read(bandai1_dir / "dataset-1_bye_normal_001.bvh"),
    }


def test_mixing_the_arms_only_leaves_every_other_joint_bit_for_bit(clips, model):
    walk, wave = clips["walk"], clips["wave"]
    out = mix(walk, wave, model, joints="arms")
    arms = [walk.skeleton.index(n) for n in ARMS]
    others = [j for j in range(walk.skeleton.n_joints) if j not in arms]
    np.testing.assert_array_equal(out.rotations[:, others], walk.rotations[:, others])
    np.testing.assert_array_equal(out.translations, walk.translations)
    # ... and the arms do take the wave's expression: the right arm moves off the walk's.
    hand = walk.skeleton.index("LowerArm_R")
    assert (
        np.degrees(em.quat.angle(em.quat.mul(out.rotations[:, hand], em.quat.conjugate(walk.rotations[:, hand])))).max()
        > 30
    )


def test_by_default_a_standing_clips_legs_are_not_laid_on_a_walk(clips, model):
    walk, wave = clips["walk"], clips["wave"]
    legs = joint_mask(walk.skeleton, "legs")
    assert not default_mask(walk, wave)[legs].any() and not default_mask(wave, walk)[legs].any()
    assert default_mask(walk, clips["walk1"]).all()  # two walks: every joint
    out = mix(walk, wave, model)
    np.testing.assert_array_equal(out.rotations[:, legs], walk.rotations[:, legs])


def test_mix_takes_joint_groups(bandai2_dir, tmp_path, capsys):
    walk, wave = bandai2_dir / "dataset-2_walk_normal_001.bvh", bandai2_dir / "dataset-2_wave-right-hand_normal_001.bvh"
    out = tmp_path / "mixed.bvh"
    assert main(["mix", "--body", str(walk), "--expressive", str(wave), "--joints", "arms", "-o", str(out)]) == 0
    skeleton = em.read_bvh(walk).skeleton
    columns = np.cumsum([0] + [len(c) for c in skeleton.channels])
    arms = {skeleton.index(n) for n in ARMS}
    kept = np.concatenate([np.arange(columns[j], columns[j + 1]) for j in range(skeleton.n_joints) if j not in arms])
    np.testing.assert_allclose(bvh_values(out)[:, kept], bvh_values(walk)[:, kept], atol=1e-6)
    assert np.abs(bvh_values(out) - bvh_values(walk)).max() > 10  # the arms did change
    with pytest.raises(SystemExit):
        main(["mix", "--body", str(walk), "--expressive", str(wave), "--joints", "hands", "-o", str(out)])
    assert "invalid choice: 'hands'" in capsys.readouterr().err
