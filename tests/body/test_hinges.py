"""Hinge limits: no elbow or knee bent backwards (past straight) after any edit.

The real-data tests measure independently of the package: the edited motion is written to BVH,
its numbers read with NumPy, composed with SciPy (world rotations and positions), and each
hinge's signed flexion taken about the axis the input itself bends it about (learnt here, from
the input's frames bent 25 degrees or more)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import expressive_mocap as em
from conftest import bvh_values, scipy_fk
from expressive_mocap.body.hinges import canonical_hinge_limits, learn_hinge_limits, limit_hinges
from expressive_mocap.decoupling.body_model import BodyModel
from expressive_mocap.decoupling.edits import blend, mix, modulate
from expressive_mocap.errors import ArgumentError
from expressive_mocap.exaggeration import exaggerate
from expressive_mocap.procedural import procedural_walk
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons.canonical import carried_for
from expressive_mocap.skeletons.synthetic import synthetic_walk

TOLERANCE = 0.5  # degrees past straight an edit may leave (real walks show 0-0.4)
# Each hinge's limb by joint names: upper, hinge, end.
BANDAI = {
    f"{side} {hinge}": tuple(f"{part}_{side}" for part in parts)
    for hinge, parts in {"elbow": ("UpperArm", "LowerArm", "Hand"), "knee": ("UpperLeg", "LowerLeg", "Foot")}.items()
    for side in "LR"
}
CMU = {
    f"{side} {hinge}": tuple(part.format(side) for part in parts)
    for hinge, parts in {"elbow": ("{}Shoulder", "{}Elbow", "{}Wrist"), "knee": ("{}Hip", "{}Knee", "{}Ankle")}.items()
    for side in ("Left", "Right")
}


def limb_vectors(motion: em.Motion, limb: tuple[int, int, int], tmp_path) -> tuple[np.ndarray, np.ndarray]:
    """The upper and lower segment ``[F, 3]`` of a limb in the upper joint's frame, by SciPy."""
    path = tmp_path / "measured.bvh"
    em.write_bvh(motion, path)
    skeleton = em.read_bvh(path).skeleton
    rotations, positions = scipy_fk(skeleton, bvh_values(path))
    top, middle, end = limb
    inverse = rotations[top].inv()
    return (
        inverse.apply(positions[:, middle] - positions[:, top]),
        inverse.apply(positions[:, end] - positions[:, middle]),
    )


def bend_axis(upper: np.ndarray, lower: np.ndarray) -> np.ndarray:
    """The mean normal of the two segments over the frames bent 25 degrees or more."""
    normal = np.cross(upper, lower)
    cos = np.sum(upper * lower, 1) / np.linalg.norm(upper, axis=1) / np.linalg.norm(lower, axis=1)
    bent = np.degrees(np.arccos(np.clip(cos, -1, 1))) >= 25
    axis = (normal[bent] / np.linalg.norm(normal[bent], axis=1, keepdims=True)).mean(axis=0)
    return axis / np.linalg.norm(axis)


def signed_flexion(upper: np.ndarray, lower: np.ndarray, axis: np.ndarray) -> np.ndarray:
    """Degrees the lower segment turns from the upper one's line about ``axis`` (< 0: backwards)."""
    lower = lower - np.outer(lower @ axis, axis)
    return np.degrees(np.arctan2(np.cross(upper, lower) @ axis, np.sum(upper * lower, 1)))


def most_backwards(edited: em.Motion, original: em.Motion, tmp_path, names: dict = BANDAI) -> dict[str, float]:
    """Per hinge the most degrees ``edited`` bends it backwards (about the axis ``original`` bends it
    about), independently measured."""
    out = {}
    for hinge, joints in names.items():
        limb = tuple(original.skeleton.index(n) for n in joints)
        axis = bend_axis(*limb_vectors(original, limb, tmp_path))
        out[hinge] = float(max(0.0, -signed_flexion(*limb_vectors(edited, limb, tmp_path), axis).min()))
    return out


def test_a_hinge_bent_backwards_is_straightened_and_nothing_else_moves():
    """The demo's walk with its left elbow bent 20 degrees backwards in a stretch of frames: the
    limits bring it back to straight (the two segments in line) by turning the elbow alone,
    and report it; allowed the bent rotations, they change nothing."""
    walk = procedural_walk(seconds=2.0)
    limits = canonical_hinge_limits()
    elbow = walk.skeleton.index("LowerArm_L")
    hinge = next(h for h in limits.hinges if h.middle == elbow)
    flexion = limits.of(walk)[:, limits.hinges.index(hinge)]
    frames = slice(10, 30)
    rotations = walk.rotations.copy()
    back = quat.exp(
        hinge.axis * -np.radians(flexion[frames] + 20.0)[:, None]
    )  # about the axis, in the upper arm's frame
    rotations[frames, elbow] = quat.mul(back, rotations[frames, elbow])
    bent = em.Motion(walk.skeleton, rotations, walk.translations, walk.frame_time)
    assert limits.of(bent)[frames, limits.hinges.index(hinge)] == pytest.approx(-20.0, abs=1e-6)

    fixed, report = limit_hinges(bent, limits)
    p = fixed.positions()
    upper = p[frames, elbow] - p[frames, walk.skeleton.index("UpperArm_L")]
    lower = p[frames, walk.skeleton.index("Hand_L")] - p[frames, elbow]
    cos = np.sum(upper * lower, 1) / np.linalg.norm(upper, axis=1) / np.linalg.norm(lower, axis=1)
    assert np.degrees(np.arccos(np.clip(cos, -1, 1))).max() < 3.0  # straight but for the demo's turn out of plane
    assert list(report.limited) == ["LowerArm_L"] and report.limited["LowerArm_L"] == (20, pytest.approx(20.0))
    others = np.delete(np.arange(walk.skeleton.n_joints), elbow)
    np.testing.assert_array_equal(fixed.rotations[:, others], bent.rotations[:, others])
    np.testing.assert_array_equal(fixed.rotations[:10], bent.rotations[:10])  # frames never bent: untouched
    assert "LowerArm_L (20 frames" in report.text()
    same, allowed = limit_hinges(bent, limits, allow=(bent.rotations,))
    assert allowed.limited == {}
    np.testing.assert_array_equal(same.rotations, bent.rotations)


def test_limits_are_learnt_about_the_way_each_hinge_bends():
    """Learnt from the demo's walk on the canonical body: each hinge's axis is the canonical one
    (the data says which way it bends), and its most flexion is the walk's plus the margin."""
    walk = procedural_walk(seconds=4.0)
    learnt = learn_hinge_limits([walk], margin=0.1)
    canonical = canonical_hinge_limits()
    assert [h.role for h in learnt.hinges] == [h.role for h in canonical.hinges]
    for ours, theirs in zip(learnt.hinges, canonical.hinges):
        assert float(ours.axis @ theirs.axis) > 0.95, ours.role
    flexion = learnt.of(walk)
    assert flexion.min() > -1e-6  # the demo never bends a hinge backwards
    for k, h in enumerate(learnt.hinges):
        top = flexion[:, k].max()
        assert h.high == pytest.approx(top + 0.1 * (top - min(0.0, flexion[:, k].min())))


def test_modulating_the_demo_walk_keeps_its_knees_from_bending_backwards():
    """The demo walk's expressiveness scaled by 2 and 3 with the shipped model bends its knees
    12-28 degrees backwards without the limits; with them no hinge passes straight, and the
    hinges the edit left within range are as the bare method makes them."""
    walk = procedural_walk(seconds=4.0)
    model = BodyModel.load()
    limits = canonical_hinge_limits()
    knees = [k for k, h in enumerate(limits.hinges) if "lower_leg" in h.role]
    for scale in (2.0, 3.0):
        # The limits alone (planting the feet also unbends some knees, through the leg IK):
        loose = modulate(walk, scale, model, hinges=False, plant_feet=False)
        limited = modulate(walk, scale, model, plant_feet=False)
        assert limits.of(loose)[:, knees].min() < -10.0
        assert limits.of(limited).min() >= -1e-9
        assert limits.of(modulate(walk, scale, model)).min() >= -1e-9  # both, as the command runs
        elbows = [h.middle for h in limits.hinges if "forearm" in h.role]
        np.testing.assert_array_equal(limited.rotations[:, elbows], loose.rotations[:, elbows])


def test_limits_name_the_skeleton_they_do_not_fit():
    with pytest.raises(ArgumentError, match="hinge limits of a 22-joint skeleton"):
        canonical_hinge_limits().of(synthetic_walk("cmu").motion)
    with pytest.raises(ArgumentError, match="at least one motion"):
        learn_hinge_limits([])


# Walks whose edits bent elbows or knees backwards before the limits (up to 15 and 8 degrees).
REAL_WALKS = ("normal_012", "normal_003", "masculine_016", "elderly_005", "youthful_027", "active_013")


@pytest.mark.parametrize("name", REAL_WALKS)
def test_no_hinge_past_straight_after_exaggerating_real_walks(bandai2_dir, walks_model, name, tmp_path):
    walk = em.read_bvh(bandai2_dir / f"dataset-2_walk_{name}.bvh")
    for level in (0.0, 1.0, 2.0, 3.0, 4.0):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # an estimate outside the trained range
            out, report = exaggerate(walks_model, walk, level)
            _, loose = exaggerate(walks_model, walk, level, hinges=False)
        worst = most_backwards(out, walk, tmp_path)
        assert max(worst.values()) <= TOLERANCE, (level, worst)
        # The limits come before the feet are locked: the stance feet move no faster than without them.
        assert report.stance_speed_output <= 1.01 * loose.stance_speed_output + 1e-9
        assert report.hinges is not None and report.hinges.most_backwards <= TOLERANCE


def test_no_hinge_past_straight_after_decoupling_edits(bandai2_dir, tmp_path):
    """modulate, mix and blend with the shipped model on real clips: an active walk's
    expressiveness doubled (elbows flipped fully backwards without the limits), a wave's tripled,
    a walk mixed with a wave either way round and blended into one."""
    model = BodyModel.load()
    walk = em.read_bvh(bandai2_dir / "dataset-2_walk_active_001.bvh")
    old = em.read_bvh(bandai2_dir / "dataset-2_walk_elderly_005.bvh")
    wave = em.read_bvh(bandai2_dir / "dataset-2_wave-right-hand_active_001.bvh")
    edits = {
        "modulate walk x2": (modulate(walk, 2.0, model), walk),
        "modulate wave x3": (modulate(wave, 3.0, model), wave),
        "mix walk + wave": (mix(walk, wave, model), walk),
        "mix wave + walk": (mix(wave, old, model), wave),
        "blend walk -> wave": (blend(old, wave, model, (60, 90), (40, 120)), old),
    }
    unlimited = modulate(walk, 2.0, model, hinges=False)
    assert max(most_backwards(unlimited, walk, tmp_path).values()) > 90  # what the limits prevent
    for what, (out, source) in edits.items():
        worst = most_backwards(out, source, tmp_path)
        assert max(worst.values()) <= TOLERANCE, (what, worst)


def test_no_hinge_past_straight_after_a_retargeted_edit(other_dir, tmp_path):
    """A CMU walk edited on the canonical body and carried back: its own elbows and knees, about
    the axes it bends them about, stay on the right side of straight."""
    model = BodyModel.load()
    motion = em.read_bvh(other_dir / "cmu_scaled_131_03.bvh")
    carried = carried_for(motion, model)
    assert carried is not None
    for scale in (2.0, 3.0):
        out = carried.back(modulate(carried.body, scale, model))
        worst = most_backwards(out, motion, tmp_path, CMU)
        assert max(worst.values()) <= TOLERANCE, (scale, worst)
