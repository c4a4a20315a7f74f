"""Plausible decoupling edits: stance feet kept where the body-mechanics source has them
(modulate, mix, blend) and the expressive component taken from chosen joint groups only.
Feet are measured on the written files with the tests' own SciPy forward kinematics."""

import numpy as np
import pytest

import expressive_mocap as em
from conftest import bvh_values, scipy_positions
from expressive_mocap.body.canonical import canonical_skeleton
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.body.roles import JointRoles
from expressive_mocap.cli import main
from expressive_mocap.decoupling import BodyModel
from expressive_mocap.decoupling.edits import blend, mix, modulate
from expressive_mocap.decoupling.feet import default_mask, joint_mask
from expressive_mocap.errors import ArgumentError
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons.synthetic import synthetic_skeleton

LEGS = ["UpperLeg_L", "LowerLeg_L", "Foot_L", "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R"]
ARMS = [f"{part}_{side}" for side in "LR" for part in ("Shoulder", "UpperArm", "LowerArm", "Hand")]


@pytest.fixture(scope="module")
def model():
    return BodyModel.load()


def stance_speed(path, contacts) -> float:
    """Mean horizontal speed of the ankles and toes of the file ``path`` between two consecutive
    frames where ``contacts [F, 2]`` has their foot down (SciPy positions of the written file)."""
    motion = em.read_bvh(path)
    roles = JointRoles.find(motion.skeleton)
    positions = scipy_positions(motion.skeleton, bvh_values(path))
    speeds = []
    for side in (0, 1):
        for joint in (roles.feet[side], roles.toes[side]):
            v = np.linalg.norm(np.diff(positions[:, joint][:, [0, 2]], axis=0), axis=1) / motion.frame_time
            speeds.append(v[contacts[1:, side] & contacts[:-1, side]])
    return float(np.concatenate(speeds).mean())


def speeds(tmp_path, source: em.Motion, edited: em.Motion) -> tuple[float, float]:
    """Stance-foot speed of ``source`` and of ``edited`` over ``source``'s contacts."""
    contacts = foot_contacts(source)
    em.write_bvh(source, tmp_path / "source.bvh")
    em.write_bvh(edited, tmp_path / "edited.bvh")
    return stance_speed(tmp_path / "source.bvh", contacts), stance_speed(tmp_path / "edited.bvh", contacts)


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
    legs = {f"{side}{part}" for side in ("Left", "Right") for part in ("UpLeg", "Leg", "Foot", "ToeBase")}
    assert names(skeleton, "legs") == legs


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
    forearm = walk.skeleton.index("LowerArm_R")
    turn = quat.mul(out.rotations[:, forearm], quat.conjugate(walk.rotations[:, forearm]))
    assert np.degrees(quat.angle(turn)).max() > 30


def test_by_default_a_standing_clips_legs_are_not_laid_on_a_walk(clips, model):
    walk, wave = clips["walk"], clips["wave"]
    legs = joint_mask(walk.skeleton, "legs")
    assert not default_mask(walk, wave)[legs].any() and not default_mask(wave, walk)[legs].any()
    assert default_mask(walk, clips["walk1"]).all()  # two walks: every joint
    out = mix(walk, wave, model, plant_feet=False)
    np.testing.assert_array_equal(out.rotations[:, legs], walk.rotations[:, legs])


def test_modulate_keeps_the_stance_feet_of_a_stooped_walk(clips, model, tmp_path):
    old = clips["old"]
    before, after = speeds(tmp_path, old, modulate(old, 0.0, model))
    assert after <= 1.2 * before
    # Without the locking the straightened walk's stance feet slide several times as fast.
    assert speeds(tmp_path, old, modulate(old, 0.0, model, plant_feet=False))[1] > 3 * before


@pytest.mark.parametrize("body, expressive", [("walk1", "bye1"), ("bye1", "walk1")])
def test_mix_keeps_the_body_sources_stance_feet(clips, model, tmp_path, body, expressive):
    a, b = clips[body], clips[expressive]
    for joints in (None, "all"):
        before, after = speeds(tmp_path, a, mix(a, b, model, joints=joints))
        assert after <= 1.2 * before, joints


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
    naive = ["blend", str(walk), str(wave), "--body-window", "30:40", "--naive", "--joints", "arms", "-o", str(out)]
    assert main(naive) != 0
    assert "--joints: the naive blend takes whole poses" in capsys.readouterr().err


@pytest.mark.parametrize("windows", [((30, 40), (150, 160)), ((150, 160), (30, 40))])
def test_blend_keeps_the_stance_feet_where_the_bodies_are_blended(clips, model, tmp_path, windows):
    # Between the windows one clip's expression rides on the other's body: a walk's leg swing on
    # a standing gesture, or the reverse, when every joint's expression is taken.
    for first, second in (("old", "bye1"), ("bye1", "old")):
        a, b = clips[first], clips[second]
        naive = blend(a, b, None, *windows)  # its feet: the first's, then the second's
        before, after = speeds(tmp_path, naive, blend(a, b, model, *windows, joints="all"))
        assert after <= 1.2 * before
        # Neither planted nor limited (the hinge limits alone straighten some sliding knees): the
        # feet slide 2.8x and more.
        unlocked = blend(a, b, model, *windows, joints="all", plant_feet=False, hinges=False)
        assert speeds(tmp_path, naive, unlocked)[1] > 2 * before


def test_modulate_plants_the_feet_of_another_skeleton(other_dir, tmp_path):
    # A Xia-style walk goes through the canonical body and back: its own feet stay planted.
    source = other_dir / "dme_comp_3d_2.bvh"
    contacts = foot_contacts(em.read_bvh(source))
    speeds = []
    for extra in ([], ["--no-foot-lock"]):
        out = tmp_path / f"out{len(extra)}.bvh"
        assert main(["modulate", str(source), "--scale", "0", *extra, "-o", str(out)]) == 0
        speeds.append(stance_speed(out, contacts))
    before = stance_speed(source, contacts)
    assert speeds[0] <= 1.2 * before
    assert speeds[1] > 3 * before  # unlocked, the straightened legs slide


def test_planted_puts_the_stance_feet_back_and_eases_the_swing():
    """On the demo's walk (no data needed): bend both knees (bones lie along X) and turn a foot;
    through the contacts the ankles and feet are the walk's again, and the swing gets no jump."""
    from expressive_mocap.decoupling.feet import planted
    from expressive_mocap.procedural import procedural_walk

    walk = procedural_walk(seconds=3.0)
    skeleton = walk.skeleton
    rotations = walk.rotations.copy()
    for name, axis, degrees in (("LowerLeg_L", "Z", 25.0), ("LowerLeg_R", "Z", -15.0), ("Foot_L", "Y", 20.0)):
        j = skeleton.index(name)
        rotations[:, j] = quat.mul(rotations[:, j], quat.about(axis, degrees)[None])
    edited = em.Motion(skeleton, rotations, walk.translations, walk.frame_time)
    out, contacts = planted(walk, edited)
    world_in, pos_in = walk.fk()
    world_out, pos_out = out.fk()
    moved = edited.positions()
    for side, (foot, toe) in enumerate((("Foot_L", "Toes_L"), ("Foot_R", "Toes_R"))):
        f, t = skeleton.index(foot), skeleton.index(toe)
        down = contacts[:, side]
        assert down.any() and not down.all()
        np.testing.assert_allclose(pos_out[down, f], pos_in[down, f], atol=1e-6)
        np.testing.assert_allclose(pos_out[down, t], pos_in[down, t], atol=1e-6)  # the foot's rotation too
        assert np.abs(moved[down, f] - pos_in[down, f]).max() > 1.0  # the edit had moved them (cm)
        # No frame-to-frame step of the ankle longer than the walk's or the edit's own largest.
        steps = [np.linalg.norm(np.diff(p[:, f], axis=0), axis=1).max() for p in (pos_in, moved, pos_out)]
        assert steps[2] <= 1.05 * max(steps[:2])
    # Arms and spine are the edit's.
    upper = [skeleton.index(n) for n in ARMS + ["Spine", "Chest", "Head"]]
    np.testing.assert_array_equal(out.rotations[:, upper], edited.rotations[:, upper])


def test_an_edit_that_changes_nothing_changes_nothing(model, tmp_path):
    """modulate --scale 1 returns its input exactly: the recomposition is the input's own
    rotations, and the feet, planted where the input has them, stay (planting bent a straight
    stance leg: a knee moved 0.56 cm on a standing wave). A scale a hair from 1 moves nothing a
    viewer could see."""
    from expressive_mocap.procedural import walk_and_wave

    wave = walk_and_wave(seconds=2.0).waving
    assert np.array_equal(modulate(wave, 1.0, model).rotations, wave.rotations)
    near = modulate(wave, 1.0 + 1e-9, model)
    assert np.linalg.norm(near.positions() - wave.positions(), axis=-1).max() < 1e-4  # cm
    src, out = tmp_path / "wave.bvh", tmp_path / "same.bvh"
    em.write_bvh(wave, src)
    assert main(["modulate", str(src), "--scale", "1", "-o", str(out)]) == 0
    np.testing.assert_allclose(bvh_values(out), bvh_values(src), rtol=0, atol=1e-9)  # Euler round trips: 3e-13


@pytest.mark.real_data
def test_a_standing_wave_modulated_by_one_keeps_its_knees(model, bandai1_dir):
    bye = em.read_bvh(bandai1_dir / "dataset-1_bye_normal_001.bvh")
    for scale in (1.0, 1.0 + 1e-9):
        out = modulate(bye, scale, model)
        assert np.linalg.norm(out.positions() - bye.positions(), axis=-1).max() < 1e-4  # cm (was 0.57)
