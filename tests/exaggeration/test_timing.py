"""Timing as part of intensity: each cycle's duration and the hips' travel over it are mapped by
intensity, so an exaggerated walk walks faster with longer strides, its stance feet planted at
the new timing. Speed and cadence are measured here from SciPy forward kinematics of the
channel values, with a contact test of this file's own."""

import numpy as np
import pytest

import expressive_mocap as em
from conftest import scipy_positions
from expressive_mocap.errors import ModelError
from expressive_mocap.exaggeration import ExaggerationModel, exaggerate, timing_validation, train
from expressive_mocap.exaggeration.model import TIMING_ARRAYS
from expressive_mocap.procedural import loaded_walk, procedural_walk

LEVELS = [1.0, 2.0, 3.0]
SPEEDS = (1.0, 1.2, 1.4)  # m/s: the procedural walk's cadence and stride grow with its speed


def gait(motion: em.Motion) -> tuple[float, float, float]:
    """Speed (hips travel between the first and last footstrike over the time between them),
    cadence (footstrikes of both feet per second) and stance-foot speed (the ankles' mean
    horizontal speed while within 10% of their height range above their lowest), from SciPy FK."""
    names = motion.skeleton.names
    p = scipy_positions(motion.skeleton, motion.channel_values())
    dt = motion.frame_time
    strikes, stance = [], []
    for side in "LR":
        ankle = p[:, names.index(f"Foot_{side}")]
        low, high = np.percentile(ankle[:, 1], [2, 98])
        down = ankle[:, 1] < low + 0.1 * (high - low)
        edges = np.diff(np.r_[0, down.astype(np.int8), 0])
        starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
        strikes += [int(a) for a, b in zip(starts, ends) if b - a >= 3 and a > 0]
        v = np.linalg.norm(np.diff(ankle[:, [0, 2]], axis=0), axis=1) / dt
        stance.append(v[down[1:] & down[:-1]])
    strikes.sort()
    span = (strikes[-1] - strikes[0]) * dt
    hips = p[:, names.index("Hips")]
    travel = np.linalg.norm(hips[strikes[-1], [0, 2]] - hips[strikes[0], [0, 2]])
    return travel / span, (len(strikes) - 1) / span, float(np.concatenate(stance).mean())


def peak_ankle_speed(motion: em.Motion) -> float:
    p = scipy_positions(motion.skeleton, motion.channel_values())
    feet = [motion.skeleton.names.index(f"Foot_{side}") for side in "LR"]
    return float(np.linalg.norm(np.diff(p[:, feet][..., [0, 2]], axis=0), axis=-1).max() / motion.frame_time)


@pytest.fixture(scope="module")
def speed_model():
    """One 'person' walking at three speeds as intensities 1 < 2 < 3."""
    return train([[procedural_walk(5.0, speed=s) for s in SPEEDS]], LEVELS)


def share_of_the_way(before, after, goal) -> np.ndarray:
    """How far (0: not at all, 1: all the way) speed and cadence moved from ``before`` to ``goal``."""
    return (np.array(after[:2]) - before[:2]) / (np.array(goal[:2]) - before[:2])


def test_an_exaggerated_walk_walks_faster_with_the_faster_walks_cadence(speed_model):
    walk, faster = procedural_walk(6.0, speed=SPEEDS[1]), procedural_walk(6.0, speed=SPEEDS[2])
    before, goal = gait(walk), gait(faster)
    out, report = exaggerate(speed_model, walk, 3.0, current=2.0)
    after = gait(out)
    assert report.timing is not None and report.timing.duration < 1 < report.timing.travel
    assert out.n_frames < walk.n_frames  # the same cycles, each shorter
    assert (share_of_the_way(before, after, goal) > 0.5).all(), (before, after, goal)
    # Stance feet held at the new timing (the package's contacts), and no ankle flung faster than
    # the real faster walk's when a held foot is let go.
    assert report.stance_speed_output <= 1.2 * report.stance_speed_input
    assert peak_ankle_speed(out) <= 1.1 * peak_ankle_speed(faster)
    # Diminishing slows it down.
    slower = gait(exaggerate(speed_model, walk, 1.0, current=2.0)[0])
    assert slower[0] < before[0] and slower[1] < before[1]


def test_timing_off_keeps_the_inputs_timing(speed_model):
    walk = procedural_walk(6.0, speed=SPEEDS[1])
    out, report = exaggerate(speed_model, walk, 3.0, current=2.0, timing=False)
    assert report.timing is None and out.n_frames == walk.n_frames
    np.testing.assert_allclose(gait(out)[:2], gait(walk)[:2], rtol=0.02)


def test_timing_that_does_not_follow_the_intensity_is_left_alone():
    """The loaded walks share one timing at every intensity: nothing to map, the frames stay."""
    model = train([[loaded_walk(k) for k in LEVELS]], LEVELS)
    assert (model.timing_predictability < 0.5).all()
    walk = loaded_walk(2.0, seconds=5.0)
    out, report = exaggerate(model, walk, 3.0, current=2.0)
    assert report.timing is None and out.n_frames == walk.n_frames


def test_the_swap_test_with_timing_beats_the_one_without():
    people = [[procedural_walk(4.0 + 0.5 * p, speed=s + 0.03 * p) for s in SPEEDS] for p in range(3)]
    *rows, mean = timing_validation(train(people, LEVELS))
    for r in rows:
        assert r.swap_with < 0.5 * r.swap_without and r.warp_with < 0.5 * r.warp_without, r


def test_model_files_keep_the_timing_and_older_files_edit_without_it(speed_model, tmp_path):
    path = tmp_path / "m.npz"
    speed_model.save(path)
    again = ExaggerationModel.load(path)
    for name in TIMING_ARRAYS:
        np.testing.assert_array_equal(getattr(again, name), getattr(speed_model, name))
    walk = procedural_walk(4.0, speed=SPEEDS[1])
    np.testing.assert_allclose(
        exaggerate(again, walk, 3.0, current=2.0)[0].rotations,
        exaggerate(speed_model, walk, 3.0, current=2.0)[0].rotations,
        atol=1e-12,
    )
    with np.load(path) as stored:
        arrays = {k: stored[k] for k in stored.files if k not in TIMING_ARRAYS}
    np.savez(tmp_path / "old.npz", **arrays)
    old = ExaggerationModel.load(tmp_path / "old.npz")
    assert not old.has_timing
    out, report = exaggerate(old, walk, 3.0, current=2.0)
    assert report.timing is None and out.n_frames == walk.n_frames
    arrays["cycle_timing"] = np.zeros((3, 2))
    np.savez(tmp_path / "bad.npz", **arrays)
    with pytest.raises(ModelError, match="cycle_timing"):
        ExaggerationModel.load(tmp_path / "bad.npz")


def real_walk(data, name):
    return em.read_bvh(data / f"dataset-2_walk_{name}.bvh")


def test_an_exaggerated_real_walk_moves_toward_the_active_walks(bandai2_dir):
    """Takes 1-4 of dataset-2's walks as people; a held-out normal walk exaggerated to 'active'
    walks faster, with a higher cadence, toward the same people's real active walks."""
    people = [[real_walk(bandai2_dir, f"{s}_{p:03d}") for s in ("exhausted", "normal", "active")] for p in range(1, 5)]
    model = train(people, LEVELS)
    walk = real_walk(bandai2_dir, "normal_012")
    goal = np.mean([gait(person[2]) for person in people], axis=0)
    before = gait(walk)
    out, report = exaggerate(model, walk, 3.0)
    after = gait(out)
    moved = share_of_the_way(before, after, goal)
    assert moved[0] >= 0.5 and moved[1] >= 0.25, (before, after, goal)
    assert after[2] <= 1.2 * before[2], (before, after)
    assert report.stance_speed_output <= 1.2 * report.stance_speed_input
    still = gait(exaggerate(model, walk, 3.0, timing=False)[0])
    np.testing.assert_allclose(still[:2], before[:2], rtol=0.02)


def test_a_retimed_edit_carries_back_onto_another_skeleton(speed_model, tmp_path):
    """A game-rig walk exaggerated with a model of the Bandai skeleton: the edit, retimed, is laid
    back frame for frame on the input retimed alike, so joints the model lacks (fingers, here
    curled) keep their rotations instead of being retargeted to rest."""
    from expressive_mocap.cli import main
    from expressive_mocap.exaggeration.timing import retime_like
    from expressive_mocap.rotations import quat
    from expressive_mocap.skeletons import retarget, synthetic_walk
    from expressive_mocap.skeletons.canonical import carried_for

    game = synthetic_walk("game").motion
    walk = retarget(procedural_walk(6.0, speed=SPEEDS[1]), game, plant_feet=False)
    fingers = [game.skeleton.names.index(n) for n in ("index_01_l", "thumb_01_r")]
    rotations = walk.rotations.copy()
    rotations[:, fingers] = quat.about("X", 30.0)
    walk = em.Motion(walk.skeleton, rotations, walk.translations, walk.frame_time)
    model, source, result = tmp_path / "speed.npz", tmp_path / "game.bvh", tmp_path / "faster.bvh"
    speed_model.save(model)
    em.write_bvh(walk, source)
    argv = ["exaggerate", "--model", str(model), "--input", str(source), "--from", "2", "--to", "3", "-o", str(result)]
    assert main(argv) == 0
    out, read = em.read_bvh(result), em.read_bvh(source)
    _, report = exaggerate(speed_model, carried_for(read, speed_model).body, 3.0, current=2.0)
    assert report.timing is not None and out.n_frames == len(report.timing.warp) < walk.n_frames
    expected = retime_like(read, report.timing)
    angle = quat.angle(quat.mul(quat.conjugate(expected.rotations[:, fingers]), out.rotations[:, fingers]))
    assert np.degrees(angle).max() < 0.1
