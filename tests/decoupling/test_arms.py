"""The arms filtered in world axes by the split: an inactive arm hangs in the world as the actor's,
whatever the body mechanics do to the trunk above it; a half-turned arm is filtered joint by joint;
the twins agree; and on real one-hand gestures the body mechanics' idle hand moves no more than
the actor's own."""

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import expressive_mocap as em
from expressive_mocap import reference
from expressive_mocap.decoupling.algebra import decompose
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.decoupling.training import split_by_group
from expressive_mocap.errors import ArgumentError, ModelError
from expressive_mocap.ops import Arms, compose_rotations, split_rotations

# root -> spine -> shoulder -> upper arm -> forearm
PARENTS = (-1, 0, 1, 2, 3)
ARMS = Arms(PARENTS, (3, 4))


def world(rotations: np.ndarray, joint: int) -> Rotation:
    """The joint's world rotations, composed with SciPy from the local quaternions ``[F, J, 4]``."""
    turn = Rotation.from_quat(rotations[:, joint])
    while PARENTS[joint] >= 0:
        joint = PARENTS[joint]
        turn = Rotation.from_quat(rotations[:, joint]) * turn
    return turn


def degrees_apart(a: Rotation, b: Rotation) -> np.ndarray:
    return np.degrees((a * b.inv()).magnitude())


def a_trunk_turned(degrees: float, frames: int = 30):
    """An actor's motion and a body-mechanics pose equal to it but for the spine, turned by
    ``degrees`` more (about an axis that moves over the clip): the arm's local rotations agree,
    so the arm is not active, yet it points elsewhere in the world."""
    original = Rotation.random(frames * 5, random_state=3).as_quat().reshape(frames, 5, 4)
    axes = np.stack([np.cos(np.linspace(0, 2, frames)), np.full(frames, 0.3), np.sin(np.linspace(0, 2, frames))], 1)
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    body = original.copy()
    body[:, 1] = (Rotation.from_quat(original[:, 1]) * Rotation.from_rotvec(np.radians(degrees) * axes)).as_quat()
    return original, body


def test_an_inactive_arm_hangs_as_the_actors_in_the_world(backend):
    original, body = a_trunk_turned(25.0)
    expressive, recovered, activity = split_rotations(original, body, 2.0, 4.0, arms=ARMS)
    assert activity[:, 1].min() > 0.2 and activity[:, 3:].max() < 1e-12  # the spine moved, the arm did not
    for limb in ARMS.limbs:
        assert degrees_apart(world(recovered, limb), world(original, limb)).max() < 1e-9
    np.testing.assert_allclose(np.abs(np.sum(compose_rotations(expressive, recovered) * original, -1)), 1.0, atol=1e-12)
    # Joint by joint, the same arm swings with the spine the body mechanics gave it.
    _, plain, _ = split_rotations(original, body, 2.0, 4.0)
    assert degrees_apart(world(plain, 3), world(original, 3)).min() > 10.0
    np.testing.assert_array_equal(plain[:, :3], recovered[:, :3])  # nothing above the arms changes


def test_a_half_turned_arm_is_filtered_joint_by_joint(backend):
    """Past WORLD_NONE a part of the world change would flip its way round as it crosses 180
    degrees: there the limb keeps the joint-by-joint filter."""
    original, body = a_trunk_turned(0.0)
    body[:, 3] = (Rotation.from_quat(original[:, 3]) * Rotation.from_rotvec([0.0, 0.0, np.radians(150.0)])).as_quat()
    got = split_rotations(original, body, 2.0, 4.0, arms=Arms(PARENTS, (3,)))
    plain = split_rotations(original, body, 2.0, 4.0)
    for a, b in zip(got, plain):
        np.testing.assert_allclose(a, b, atol=1e-12)


@pytest.mark.skipif(not em.rust_available(), reason="the Rust extension is not built")
def test_the_rust_and_numpy_arms_agree_on_smoothed_noisy_clips():
    from expressive_mocap import _core

    rng = np.random.default_rng(2)
    original = Rotation.random(60 * 5, random_state=8).as_quat().reshape(60, 5, 4)
    noise = Rotation.from_rotvec(rng.normal(scale=0.5, size=(300, 3)))
    body = (Rotation.from_quat(original.reshape(-1, 4)) * noise).as_quat().reshape(60, 5, 4)
    arguments = (original, body, 2.0, 4.0, np.ones(5), 1.5, 3.0, [], [], 1.0, list(PARENTS), [3, 4])
    for rust, twin in zip(_core.split_rotations(*arguments), reference.split_rotations(*arguments)):
        np.testing.assert_allclose(rust, twin, atol=1e-12)


@pytest.mark.parametrize(
    "parents, limbs, message",
    [((-1, 0, 1), (1,), "arm_parents"), ((-1, 0, 3, 2, 3), (3,), "arm_parents"), (PARENTS, (0,), "arm_joints"),
     (PARENTS, (5,), "arm_joints")],
)  # fmt: skip
def test_bad_arms_are_refused_naming_the_argument(backend, parents, limbs, message):
    original, body = a_trunk_turned(10.0, frames=3)
    with pytest.raises(ArgumentError, match=message):
        split_rotations(original, body, 2.0, 4.0, arms=Arms(parents, limbs))


def test_the_model_file_keeps_its_arms_and_refuses_bad_ones():
    model = BodyModel.load()
    assert model.arms is not None and len(model.arms.limbs) == 4  # the shipped model's upper arms and forearms
    again = BodyModel.load(model.to_bytes())
    assert again.arms == model.arms
    assert BodyModel.load(replace(model, arms=None).to_bytes()).arms is None  # a file from before: joint by joint
    bad = replace(model, arms=Arms((0,) + model.arms.parents[1:], model.arms.limbs))
    with pytest.raises(ModelError, match="arm_parents"):
        BodyModel.load(bad.to_bytes())


def _hand_about_shoulder(motion: em.Motion, side: str) -> float:
    """Mean distance of the hand from its mean place relative to its shoulder, in world axes
    (positions composed with SciPy): how much the arm itself moves, whatever the body does."""
    names, parents = motion.skeleton.names, motion.skeleton.parents
    rotations: list[Rotation] = []
    positions = np.zeros(motion.translations.shape)
    for j, parent in enumerate(parents):
        local = Rotation.from_quat(motion.rotations[:, j])
        if parent < 0:
            rotations.append(local)
            positions[:, j] = motion.translations[:, j]
        else:
            rotations.append(rotations[parent] * local)
            positions[:, j] = positions[:, parent] + rotations[parent].apply(motion.translations[:, j])
    hand = positions[:, names.index(f"Hand_{side}")] - positions[:, names.index(f"Shoulder_{side}")]
    return float(np.linalg.norm(hand - hand.mean(axis=0), axis=-1).mean())


def test_the_idle_hand_of_held_out_waves_moves_no_more_than_the_actors(bandai2_dir):
    """Dataset-2's held-out one-hand gestures (30 % by clip, seed 0), active style, the worst
    before: the body mechanics' idle hand moved more than the actor's own + 0.5 cm in 5 of these
    12 clips (it swung with the trunk the network gave it); now in none. The waving hand stays in
    the expressive component."""
    contents = {"wave-left-hand": "L", "wave-right-hand": "R", "raise-up-left-hand": "L", "raise-up-right-hand": "R"}
    paths = [p for c in contents for p in sorted(bandai2_dir.glob(f"dataset-2_{c}_*.bvh"))]
    _, held_out = split_by_group(np.arange(len(paths)), 0.3, 0)
    clips = [paths[k] for k in held_out if "_active_" in paths[k].name][:12]
    model, within = BodyModel.load(), 0
    for path, motion in zip(clips, em.read_bvh_many(clips)):
        waving = contents[path.stem.split("_")[1]]
        idle = "R" if waving == "L" else "L"
        body = decompose(motion, model).recompose(0.0)
        within += _hand_about_shoulder(body, idle) <= _hand_about_shoulder(motion, idle) + 0.5
        assert _hand_about_shoulder(body, waving) < 0.5 * _hand_about_shoulder(motion, waving), path.name
    assert within >= 11, f"{within} of {len(clips)}"
