"""A gesture's own cycles (exaggeration/gestures.py): one per stroke of a wave, the span the hand
moves in for a raise, and models trained on them editing those cycles. The procedural wave needs
no data; the rest reads Bandai-Namco dataset-2 (CC BY-NC 4.0)."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.take import Take
from expressive_mocap.exaggeration import exaggerate, train
from expressive_mocap.exaggeration.cycles import choose_cycles, cycles_for
from expressive_mocap.procedural import walk_and_wave
from expressive_mocap.rotations import quat


def _standing_wave(frequency: float, side: str = "right", seconds: float = 4.0) -> em.Motion:
    """The procedural wave of ``side``'s arm on a body standing in the walk's first pose (the
    walk's own arm swing, a second rhythm, left out): each arm joint turned by what the wave
    turns it by in the walk."""
    pair = walk_and_wave(seconds=seconds, frequency=frequency, side=side)
    walk, waving = pair.walk, pair.waving
    names = walk.skeleton.names
    arm = [names.index(f"{part}_{side[0].upper()}") for part in ("UpperArm", "LowerArm", "Hand")]
    rotations = np.repeat(walk.rotations[:1], walk.n_frames, axis=0)
    wave = quat.mul(waving.rotations[:, arm], quat.conjugate(walk.rotations[:, arm]))
    rotations[:, arm] = quat.mul(wave, rotations[:, arm])
    translations = np.repeat(walk.translations[:1], walk.n_frames, axis=0)
    return em.Motion(walk.skeleton, rotations, translations, walk.frame_time)


@pytest.mark.parametrize("frequency", [1.0, 1.5, 2.5])
@pytest.mark.parametrize("side", ["left", "right"])
def test_a_procedural_wave_comes_apart_into_strokes_of_its_own_period(frequency, side):
    wave = _standing_wave(frequency, side)
    cycles = choose_cycles(wave, "gesture")
    period = wave.fps / frequency
    lengths = np.array([c.end - c.start for c in cycles])
    assert len(cycles) >= 4.0 * frequency - 2  # four seconds of waving: all but the strokes cut at its ends
    assert abs(lengths.mean() - period) <= 1.0 and np.all(np.abs(lengths - period) <= 4), (lengths, period)
    assert all(a.end == b.start for a, b in zip(cycles[:-1], cycles[1:]))  # stroke after stroke


def test_strokes_start_at_the_same_end_of_the_hand_path():
    take = Take(_standing_wave(1.5, "left"))
    points, jmap = take.positions, take.body.joint_map
    hand = points[:, jmap["left_hand"]] - points[:, jmap["chest"]]
    left = points[:, jmap["left_upper_arm"]] - points[:, jmap["right_upper_arm"]]
    sideways = np.sum(hand * left, axis=1) / np.linalg.norm(left, axis=1)
    starts = [c.start for c in choose_cycles(take, "gesture")]
    # Each stroke starts where the hand is farthest to the body's left, not at the other end.
    assert np.all(sideways[starts] >= np.percentile(sideways, 80))


def test_a_motion_without_a_gesture_is_one_cycle():
    walk = walk_and_wave(seconds=2.0).walk
    still = em.Motion(
        walk.skeleton, np.repeat(walk.rotations[:1], 30, 0), np.repeat(walk.translations[:1], 30, 0), walk.frame_time
    )
    assert [(c.start, c.end) for c in choose_cycles(still, "gesture")] == [(0, 29)]


def _dataset_clip(folder, action, style, take):
    return em.read_bvh(folder / f"dataset-2_{action}_{style}_{take:03d}.bvh")


def test_real_waves_come_apart_into_strokes_that_quicken_with_energy(bandai2_dir):
    lengths = {}
    for style in ("exhausted", "normal", "active"):
        found = []
        for take in (9, 10):
            motion = _dataset_clip(bandai2_dir, "wave-right-hand", style, take)
            cycles = choose_cycles(motion, "gesture")
            assert len(cycles) >= 2 and 0 < cycles[0].start and cycles[-1].end < motion.n_frames - 1
            found += [c.end - c.start for c in cycles]
        lengths[style] = np.mean(found)
    assert lengths["active"] < lengths["normal"] < lengths["exhausted"], lengths


def test_a_real_raise_is_one_cycle_over_the_frames_the_hand_moves_in(bandai2_dir):
    motion = _dataset_clip(bandai2_dir, "raise-up-right-hand", "normal", 9)
    take = Take(motion)
    (cycle,) = choose_cycles(take, "gesture")
    hand = take.positions[:, take.body.joint_map["right_hand"]]
    height = hand[:, 1] - hand[0, 1]
    top = int(np.argmax(height))
    assert 0 < cycle.start < top < cycle.end < motion.n_frames - 1  # the idle frames trimmed off
    assert height[cycle.start] < 0.5 * height[top] and height[cycle.end] < 0.5 * height[top]


def test_a_model_trained_on_strokes_edits_the_strokes_of_a_new_wave(bandai2_dir):
    people = [
        [_dataset_clip(bandai2_dir, "wave-right-hand", s, p) for s in ("exhausted", "normal", "active")]
        for p in (1, 2, 3)
    ]
    model = train(people, (1.0, 2.0, 3.0), cycle="gesture")
    assert model.settings.cycle == "gesture"
    wave = _dataset_clip(bandai2_dir, "wave-right-hand", "normal", 9)
    strokes = choose_cycles(wave, "gesture")
    assert cycles_for(wave, model.settings.cycle) == strokes
    out, report = exaggerate(model, wave, to=3.0, current=2.0, timing=False)
    assert report.cycles == strokes
    before, after = Take(wave).positions, Take(out).positions
    hand = Take(wave).body.joint_map["right_hand"]
    moved = np.linalg.norm(after[:, hand] - before[:, hand], axis=1)
    inside = np.zeros(wave.n_frames, bool)
    inside[strokes[0].start : strokes[-1].end + 1] = True
    assert moved[inside].mean() > 1.0  # centimetres: the strokes were edited
    assert moved[: max(strokes[0].start - 8, 1)].max() < 1e-6  # the idle start kept (beyond the fade)
