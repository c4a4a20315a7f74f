"""The procedural walk: the Bandai-Namco skeleton, an upright walk at the speed asked for with
planted, alternating feet, a wave that touches one arm only, and local rotations inside the
range of a real Bandai neutral walk."""

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.canonical import BANDAI_CHANNELS, bandai_like_skeleton
from expressive_mocap.body.contacts import cadence, contact_intervals, foot_contacts, footstrikes
from expressive_mocap.body.roles import JointRoles
from expressive_mocap.procedural import WAVE_RAISE, procedural_walk, strides_per_second, walk_and_wave
from expressive_mocap.rotations import quat
from expressive_mocap.rotations.quat import mean_rotation

BANDAI_NAMES = (
    "joint_Root", "Hips", "Spine", "Chest", "Neck", "Head",
    "Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L", "Shoulder_R", "UpperArm_R", "LowerArm_R", "Hand_R",
    "UpperLeg_L", "LowerLeg_L", "Foot_L", "Toes_L", "UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R",
)  # fmt: skip
BANDAI_PARENTS = [-1, 0, 1, 2, 3, 4, 3, 6, 7, 8, 3, 10, 11, 12, 1, 14, 15, 16, 1, 18, 19, 20]
ARM = {"left": [7, 8, 9], "right": [11, 12, 13]}  # upper arm, forearm, hand
SPEEDS = [0.6, 1.2, 1.5]
REAL_CLIP = "dataset-2_walk_normal_001.bvh"  # 1.11 m/s along +Z, the clip the skeleton was taken from


@pytest.fixture(scope="module")
def pair():
    return walk_and_wave(seconds=4.0, speed=1.2, side="right")


def bone(motion, joint, child):
    """World direction ``[F, 3]`` of the bone from ``joint`` to ``child``."""
    positions = motion.positions()
    d = positions[:, child] - positions[:, joint]
    return d / np.linalg.norm(d, axis=1, keepdims=True)


# -- skeleton ------------------------------------------------------------------------------


def test_skeleton_has_the_bandai_names_hierarchy_and_channels():
    skeleton = bandai_like_skeleton()
    assert skeleton.names == BANDAI_NAMES
    assert skeleton.parents.tolist() == BANDAI_PARENTS
    assert skeleton.channels == (BANDAI_CHANNELS,) * 22
    assert [skeleton.rotation_order(j) for j in range(22)] == ["ZXY"] * 22
    assert [skeleton.names[j] for j, _ in skeleton.end_sites] == ["Head", "Hand_L", "Hand_R", "Toes_L", "Toes_R"]
    # Not upright: bones lie along local X (the legs along -X on the right side).
    assert skeleton.offsets[15, 0] == pytest.approx(39.0811) and skeleton.offsets[19, 0] == pytest.approx(-39.0811)


@pytest.mark.real_data
def test_skeleton_equals_the_real_files(bandai2_dir):
    # The table holds the file's numbers as written: equal within 1e-6 cm. The Hips offset is
    # each clip's own (normal_001's here); every other offset is the same in every clip.
    ours = bandai_like_skeleton()
    for name in [REAL_CLIP, "dataset-2_walk_active_001.bvh", "dataset-2_walk_feminine_002.bvh"]:
        real = em.read_bvh(bandai2_dir / name).skeleton
        assert (
            real.names == ours.names
            and real.parents.tolist() == ours.parents.tolist()
            and real.channels == ours.channels
        )
        assert [(j, off) for j, off in real.end_sites] == [(j, off) for j, off in ours.end_sites]
        others = np.arange(22) != 1
        np.testing.assert_allclose(ours.offsets[others], real.offsets[others], atol=1e-6)
        if name == REAL_CLIP:
            np.testing.assert_allclose(ours.offsets[1], real.offsets[1], atol=1e-6)
            assert ours.rest_height() == pytest.approx(real.rest_height(), abs=1e-6)


# -- the walk ------------------------------------------------------------------------------


@pytest.mark.parametrize("speed", SPEEDS)
@pytest.mark.parametrize("wave", [None, "left"])
def test_upright_every_frame(speed, wave):
    walk = procedural_walk(seconds=3.0, speed=speed, wave=wave)
    y = walk.positions()[..., 1]
    feet = y[:, [16, 17, 20, 21]]
    assert (y[:, 5] > y[:, 1] + 40).all(), "head well above the hips"
    assert (y[:, 1] > feet.max(axis=1) + 50).all(), "hips well above both feet"
    assert feet.min() == pytest.approx(4.35)  # toe joints touch down at their real height


@pytest.mark.parametrize("speed", SPEEDS)
def test_travels_forward_at_the_speed_asked_facing_the_way_it_goes(speed):
    walk = procedural_walk(seconds=4.0, speed=speed)
    positions = walk.positions()
    hips = positions[:, 1]
    travelled = hips[-1] - hips[0]
    assert travelled[2] / walk.duration == pytest.approx(100 * speed, rel=0.05)
    assert abs(travelled[0]) < 0.02 * travelled[2]
    # Facing +Z (the heading of features.py: left upper leg - right upper leg, x up) in every frame.
    facing = np.cross(positions[:, 14] - positions[:, 18], [0.0, 1.0, 0.0])
    heading = np.degrees(np.arctan2(facing[:, 0], facing[:, 2]))
    assert np.abs(heading).max() < 10.0


@pytest.mark.parametrize("speed", SPEEDS)
def test_feet_take_turns_and_stay_planted(speed):
    walk = procedural_walk(seconds=6.0, speed=speed)
    contacts = foot_contacts(walk)
    strikes = footstrikes(contacts)
    assert len(strikes) >= 6
    assert (np.diff(strikes[:, 1]) != 0).all(), "left and right footstrikes alternate"
    steps = cadence(contacts, walk.frame_time)
    assert 1.3 < steps < 2.5, "steps a second of a walk"
    assert steps == pytest.approx(2 * strides_per_second(speed), rel=0.05)
    # Each whole contact lasts a walking stance (over 0.3 s) and its toe joint stays put (the real
    # clip's toes drift 1.7-2.9 cm in a contact, as the foot rolls).
    positions = walk.positions()
    for toe, intervals in zip([17, 21], contact_intervals(contacts, walk.frame_time)):
        for interval in intervals[1:-1]:
            assert interval.seconds > 0.3
            toe_path = positions[interval.start : interval.end + 1, toe][:, [0, 2]]
            assert np.ptp(toe_path, axis=0).max() < 2.0


def test_cadence_and_stride_follow_speed():
    assert 2 * strides_per_second(1.1) == pytest.approx(1.8, abs=0.02)  # Bandai neutral walks: 1.8 steps/s at 1.1 m/s
    assert strides_per_second(0.6) < strides_per_second(1.2) < strides_per_second(1.5)
    swing = []
    for speed in (0.6, 1.5):
        upper_arm = procedural_walk(seconds=2.0, speed=speed).rotations[:, 7]
        swing.append(np.degrees(quat.angle(quat.mul(quat.conjugate(mean_rotation(upper_arm)), upper_arm))).max())
    assert swing[1] > swing[0] + 5, "arms swing further when walking faster"


# -- the wave ------------------------------------------------------------------------------


@pytest.mark.parametrize("side", ["left", "right"])
def test_wave_changes_the_waving_arm_and_nothing_else(side):
    walk, waving = walk_and_wave(seconds=3.0, speed=1.2, side=side)
    others = [j for j in range(22) if j not in ARM[side]]
    np.testing.assert_array_equal(waving.rotations[:, others], walk.rotations[:, others])
    np.testing.assert_array_equal(waving.translations, walk.translations)
    changed = np.degrees(
        quat.angle(quat.mul(waving.rotations[:, ARM[side]], quat.conjugate(walk.rotations[:, ARM[side]])))
    )
    assert (changed.max(axis=0) > 5.0).all()
    # The same walks come from procedural_walk.
    np.testing.assert_array_equal(procedural_walk(seconds=3.0, speed=1.2).rotations, walk.rotations)
    np.testing.assert_array_equal(procedural_walk(seconds=3.0, speed=1.2, wave=side).rotations, waving.rotations)


def test_wave_raises_the_arm_and_swings_the_forearm_at_its_frequency(pair):
    walk, waving = pair
    upper, fore, hand = ARM["right"]
    # The upper arm points up and out: 120-160 degrees from hanging straight down.
    from_down = np.degrees(np.arccos(-bone(waving, upper, fore)[:, 1]))
    assert 120 < from_down.min() and from_down.max() < 160
    # What was laid on, seen in local rotations: E = O_wave O_walk^-1 turns the upper arm by the
    # raise, the forearm by the elbow bend +- the amplitude, at the wave's frequency.
    laid = quat.angle(quat.mul(waving.rotations, quat.conjugate(walk.rotations)))
    np.testing.assert_allclose(np.degrees(laid[:, upper]), WAVE_RAISE, atol=1e-6)
    forearm = np.degrees(laid[:, fore])
    assert np.ptp(forearm) == pytest.approx(60.0, abs=1.0)
    spectrum = np.abs(np.fft.rfft(forearm - forearm.mean()))
    frequencies = np.fft.rfftfreq(len(forearm), walk.frame_time)
    assert frequencies[spectrum.argmax()] == pytest.approx(2.0, abs=0.3)


def test_wave_options():
    slow = procedural_walk(seconds=2.0, wave="left", wave_frequency=1.0, wave_amplitude=10.0)
    walk = procedural_walk(seconds=2.0)
    laid = np.degrees(quat.angle(quat.mul(slow.rotations, quat.conjugate(walk.rotations))))[:, 8]
    assert np.ptp(laid) == pytest.approx(20.0, abs=0.5)
    with pytest.raises(em.MocapError, match="wave"):
        procedural_walk(wave="up")
    with pytest.raises(em.MocapError, match="speed"):
        procedural_walk(speed=0.0)


# -- against real data ---------------------------------------------------------------------


@pytest.mark.real_data
def test_local_rotations_stay_in_a_real_walks_range(bandai2_dir):
    # For each joint: the angle of every frame's local rotation from the real clip's mean local
    # rotation must stay below the largest such angle in the real clip itself, plus 10 degrees.
    # The demo walks at the clip's speed and, like it, along +Z (the Hips rotation holds the heading).
    real = em.read_bvh(bandai2_dir / REAL_CLIP)
    mean = np.stack([mean_rotation(real.rotations[:, j]) for j in range(22)])
    real_largest = quat.angle(quat.mul(quat.conjugate(mean), real.rotations)).max(axis=0)
    for wave in [None, "right"]:
        walk = procedural_walk(seconds=4.0, speed=1.1, wave=wave)
        largest = quat.angle(quat.mul(quat.conjugate(mean), walk.rotations)).max(axis=0)
        joints = [j for j in range(22) if wave is None or j not in ARM[wave]]
        excess = np.degrees(largest - real_largest)[joints]
        assert (excess < 10.0).all(), dict(zip([real.skeleton.names[j] for j in joints], excess.round(1)))


@pytest.mark.real_data
def test_walks_like_the_real_clip(bandai2_dir):
    real = em.read_bvh(bandai2_dir / REAL_CLIP)
    walk = procedural_walk(seconds=real.duration, speed=1.1)
    for motion in (real, walk):
        assert JointRoles.find(motion.skeleton).hips == 1
    real_hips, hips = real.positions()[:, 1, 1], walk.positions()[:, 1, 1]
    # Hips height: real 87.9-93.1 cm (mean 90.4).
    assert hips.mean() == pytest.approx(real_hips.mean(), abs=1.5)
    assert hips.min() > real_hips.min() - 2 and hips.max() < real_hips.max() + 2
    real_steps = cadence(foot_contacts(real), real.frame_time)
    assert cadence(foot_contacts(walk), walk.frame_time) == pytest.approx(real_steps, rel=0.05)
