"""Blending real clips (Bandai-Namco-Research-Motiondataset, CC BY-NC 4.0) keeps the hips' path
continuous and the heading: the second motion is turned to face the first and placed where it
is, whatever its file's root does; the command says how it placed it."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.roles import JointRoles, facing_yaw
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.decoupling.edits import blend
from expressive_mocap.rotations import quat

WALK, WAVE = "dataset-2_walk_normal_001.bvh", "dataset-2_wave-right-hand_normal_001.bvh"


@pytest.fixture(scope="module")
def body_model():
    return BodyModel.load()


@pytest.fixture(scope="module")
def walk_and_wave(bandai2_dir):
    return em.read_bvh(bandai2_dir / WALK), em.read_bvh(bandai2_dir / WAVE)


def hips_steps(motion: em.Motion) -> np.ndarray:
    """Horizontal distance the hips travel from frame to frame (file units)."""
    hips = motion.positions()[:, JointRoles.find(motion.skeleton).hips]
    return np.linalg.norm(np.diff(hips[:, [0, 2]], axis=0), axis=1)


def turned_and_moved(motion: em.Motion, degrees: float, shift) -> em.Motion:
    """The whole motion turned about the vertical through the origin and shifted, by giving the
    (otherwise still) Bandai ``joint_Root`` a constant rotation and translation: its child, the
    hips, then has a parent that is not the identity."""
    rotations, translations = motion.rotations.copy(), motion.translations.copy()
    rotations[:, 0] = quat.mul(quat.about("Y", degrees), rotations[:, 0])
    translations[:, 0] += shift
    return em.Motion(motion.skeleton, rotations, translations, motion.frame_time)


# README's example: blend walk.bvh wave.bvh --body-window 30:60 --expressive-window 60:75
CASES = [pytest.param(True, (30, 60), (60, 75), id="decoupled"), pytest.param(False, (30, 60), None, id="naive")]


@pytest.mark.parametrize("decoupled, body_window, expressive_window", CASES)
def test_blend_hips_never_jump(walk_and_wave, body_model, decoupled, body_window, expressive_window):
    """Before: the root joint (joint_Root, still in Bandai files) was aligned instead of the hips,
    so the hips slid 5 m over the window, up to 24.6 cm a frame."""
    walk, wave = walk_and_wave
    out = blend(walk, wave, body_model if decoupled else None, body_window, expressive_window)
    steps = hips_steps(out)
    largest_input = max(hips_steps(walk).max(), hips_steps(wave).max())  # 5.9 cm (the walk)
    assert steps.max() <= largest_input + 0.1, steps.max()
    assert steps.max() < 5.0  # cm a frame at 30 fps; measured 4.4
    # The hips are where the walk has them up to the anchor, then stay put (the wave stands still).
    hips = JointRoles.find(walk.skeleton).hips
    np.testing.assert_allclose(out.positions()[:31, hips], walk.positions()[:31, hips], atol=1e-6)


@pytest.mark.parametrize("decoupled, body_window, expressive_window", CASES)
def test_blend_turns_the_second_motion_to_face_the_first(
    walk_and_wave, body_model, decoupled, body_window, expressive_window
):
    """Where the second motion stands and which way it faces in its file does not matter: turned
    90 degrees and moved 3 m (through a root that is not the identity), it blends into the same
    world motion. Before: it kept its own heading (the blend turned the body by 90 degrees) and
    the root's rotation was ignored."""
    walk, wave = walk_and_wave
    model = body_model if decoupled else None
    plain = blend(walk, wave, model, body_window, expressive_window)
    turned = blend(walk, turned_and_moved(wave, 90.0, [300.0, 0.0, -150.0]), model, body_window, expressive_window)
    np.testing.assert_allclose(turned.positions()[:, 1], plain.positions()[:, 1], atol=1e-6)  # the hips, everywhere
    after = slice(body_window[1], None)  # within the window the root's own turn is being slerped in
    np.testing.assert_allclose(
        turned.positions()[after, 1:], plain.positions()[after, 1:], atol=1e-4
    )  # the body (the root was moved)


def test_blend_heading_is_continuous_at_the_anchor(bandai2_dir, body_model):
    """Blending into a clip that faces the other way: the body faces the same way just before and
    just after the anchor and walks on the same way (measured: 3.5 and 9 degrees apart). Before:
    92 degrees off."""
    walk = em.read_bvh(bandai2_dir / WALK)
    other = turned_and_moved(em.read_bvh(bandai2_dir / "dataset-2_walk_active_001.bvh"), 90.0, [0.0, 0.0, 0.0])
    out = blend(walk, other, body_model, (30, 45), (45, 60))
    roles = JointRoles.find(walk.skeleton)
    positions = out.positions()
    before, after = facing_yaw(positions[15:31], roles), facing_yaw(positions[45:61], roles)
    assert abs((after - before + 180) % 360 - 180) < 15.0, (before, after)
    # And it keeps walking the way it was walking (the travel direction of the hips).
    travel = positions[[20, 30], roles.hips], positions[[60, 90], roles.hips]
    directions = [np.degrees(np.arctan2(*(b - a)[[0, 2]])) for a, b in travel]
    assert abs((directions[1] - directions[0] + 180) % 360 - 180) < 15.0, directions
    assert hips_steps(out).max() <= max(hips_steps(walk).max(), hips_steps(other).max()) + 0.1


def test_blend_command_says_how_the_second_motion_was_placed(bandai2_dir, tmp_path, capsys):
    """The README's example on real clips: the hips continue (no step over 5 cm a frame; before:
    24.6 cm), and the command says which joint carries the path and how the wave was placed."""
    from expressive_mocap.cli import main

    out = tmp_path / "blend.bvh"
    args = [
        str(bandai2_dir / WALK),
        str(bandai2_dir / WAVE),
        "--body-window",
        "30:60",
        "--expressive-window",
        "60:75",
        "-o",
        str(out),
    ]
    assert main(["blend", *args]) == 0
    assert "continues the path of Hips from frame 30: turned" in capsys.readouterr().out
    assert hips_steps(em.read_bvh(out)).max() < 5.0


def test_blend_aligns_a_moving_root(tmp_path):
    """On a skeleton whose root is the hips (CMU-style), the root carries the path: a second walk
    heading +X, blended into one heading +Z, walks on along +Z without a jump. Before: it turned
    90 degrees over the window (its path kept its own heading)."""
    from conftest import stick_walker

    frames = np.arange(60)
    hips = np.stack([np.zeros(60), np.full(60, 90.0), 4.0 * frames], axis=1)  # 4 cm a frame along +Z
    feet = [hips + [side, -85.0, 0.0] for side in (10.0, -10.0)]
    first = stick_walker(hips, *feet)
    second = turned_and_moved_root(stick_walker(hips * [1, 1, 0.5], *(f * [1, 1, 0.5] for f in feet)), 90.0)
    out = blend(first, second, None, (20, 30))
    path = out.positions()[:, 0]
    steps = np.diff(path, axis=0)
    assert np.linalg.norm(steps[:, [0, 2]], axis=1).max() <= 4.0 + 1e-9
    np.testing.assert_allclose(steps[35:, 0], 0.0, atol=1e-9)  # still along +Z, at the second's 2 cm a frame
    np.testing.assert_allclose(steps[35:, 2], 2.0, atol=1e-9)


def turned_and_moved_root(motion: em.Motion, degrees: float) -> em.Motion:
    """The whole motion turned about the vertical through the origin (its root turned and its path
    rotated with it)."""
    rotations, translations = motion.rotations.copy(), motion.translations.copy()
    turn = quat.about("Y", degrees)
    rotations[:, 0] = quat.mul(turn, rotations[:, 0])
    translations[:, 0] = quat.rotate(np.broadcast_to(turn, (motion.n_frames, 4)), translations[:, 0])
    return em.Motion(motion.skeleton, rotations, translations, motion.frame_time)
