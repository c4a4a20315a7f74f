"""``mix`` and ``blend`` pair their two motions in time, not by frame index: a 30 fps gesture laid
onto a 120 fps walk played 4x too fast, then froze on its last frame, without a word.

The gesture is the demo's wave (2 Hz) on a 30 fps walk; the body is the demo's walk at 120 fps.
What a viewer sees is the waving hand's path about the chest: sampled at the gesture's own
times, it must follow the source's (correlation at least 0.5) at the source's speed (peak speed
within 1.5x: before the decomposition was smoothed in time, single-frame pops peaked at 9x)."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.cli import main
from expressive_mocap.decoupling import BodyModel
from expressive_mocap.decoupling.edits import at_rate_of, blend, mix
from expressive_mocap.errors import ArgumentError
from expressive_mocap.procedural import procedural_walk, walk_and_wave


@pytest.fixture(scope="module")
def model():
    return BodyModel.load()


@pytest.fixture(scope="module")
def gesture():
    """The waving walk at 30 fps, and the same walk without the wave."""
    return walk_and_wave(seconds=3.0, fps=30.0, side="right")


@pytest.fixture(scope="module")
def fast_walk() -> em.Motion:
    return procedural_walk(4.0, fps=120.0)


def hand_about_chest(motion: em.Motion) -> np.ndarray:
    """The right hand's path about the chest ``[F, 3]`` (world axes)."""
    jmap = find_joint_map(motion.skeleton)
    positions = motion.positions()
    return positions[:, jmap["right_hand"]] - positions[:, jmap["chest"]]


def speed(path: np.ndarray, fps: float, statistic=np.median) -> float:
    """The median (or another ``statistic``'s) speed along ``path`` (units/s)."""
    return float(statistic(np.linalg.norm(np.diff(path, axis=0), axis=-1)) * fps)


def follows(out: em.Motion, body: em.Motion, gesture) -> tuple[float, float]:
    """What the wave does to the hand in ``out`` against what it does in the source (each the hand's
    path about the chest minus that of the motion without the wave): (their correlation at the
    source's frame times, the ratio of their peak speeds over the source's duration from the
    start)."""
    step = int(round(out.fps / gesture.waving.fps))
    theirs = hand_about_chest(gesture.waving) - hand_about_chest(gesture.walk)
    mine = hand_about_chest(out) - hand_about_chest(body)
    sampled = mine[::step][: len(theirs)]
    a, b = sampled - sampled.mean(axis=0), theirs - theirs.mean(axis=0)
    correlation = float(np.sum(a * b) / np.sqrt(np.sum(a * a) * np.sum(b * b)))
    first = mine[: len(theirs) * step] if step > 1 else mine[: len(theirs)]
    return correlation, speed(first, out.fps, np.max) / speed(theirs, gesture.waving.fps, np.max)


def test_a_30fps_gesture_on_a_120fps_walk_keeps_its_own_timing(model, gesture, fast_walk):
    out = mix(fast_walk, gesture.waving, model, joints="arms")
    assert out.n_frames == fast_walk.n_frames and out.fps == pytest.approx(120.0)
    correlation, ratio = follows(out, fast_walk, gesture)
    assert correlation >= 0.5, correlation
    assert 1 / 1.5 <= ratio <= 1.5, ratio


def test_a_gesture_mixed_at_its_own_rate_plays_without_pops(model, gesture):
    """The same wave onto the 30 fps walk it was made on: no frame faster than 1.5x the source's
    fastest (the network's pose jumps where a contact flips, and the steep activity index let
    an elbow's expression drop 27 degrees in one frame: 2.6x before the split was smoothed)."""
    correlation, ratio = follows(mix(gesture.walk, gesture.waving, model, joints="arms"), gesture.walk, gesture)
    assert correlation >= 0.5 and 1 / 1.5 <= ratio <= 1.5, (correlation, ratio)


def test_index_alignment_is_still_there_and_plays_the_gesture_4x_too_fast(model, gesture, fast_walk):
    """The old pairing by frame number, now an explicit choice: the wave's 3 s run in its first
    0.75 s (then it holds its last frame)."""
    out = mix(fast_walk, gesture.waving, model, align="index", joints="arms")
    waved = hand_about_chest(out) - hand_about_chest(fast_walk)
    theirs = hand_about_chest(gesture.waving) - hand_about_chest(gesture.walk)
    assert speed(waved[: gesture.waving.n_frames], 120.0) > 2.5 * speed(theirs, 30.0)


def test_blend_takes_the_second_motion_at_the_first_ones_rate(model, gesture, fast_walk):
    wave = gesture.waving
    out = blend(fast_walk, wave, model, (60, 120))
    resampled = at_rate_of(wave, fast_walk)
    assert resampled.fps == pytest.approx(120.0) and out.n_frames == 60 + resampled.n_frames
    assert blend(fast_walk, wave, model, (60, 120), align="index").n_frames == 60 + wave.n_frames
    with pytest.raises(ArgumentError, match="align must be 'time' or 'index'"):
        blend(fast_walk, wave, model, (60, 120), align="resample")


def test_equal_rates_are_left_alone(gesture):
    assert at_rate_of(gesture.waving, gesture.walk) is gesture.waving
    with pytest.raises(ArgumentError, match="align must be one of time, index, resample"):
        at_rate_of(gesture.waving, gesture.walk, "frames")


def test_the_command_says_what_it_resampled(gesture, fast_walk, tmp_path, capsys):
    body, wave = tmp_path / "walk120.bvh", tmp_path / "wave30.bvh"
    em.write_bvh(fast_walk, body)
    em.write_bvh(gesture.waving, wave)
    out = tmp_path / "out.bvh"
    assert main(["mix", "--body", str(body), "--expressive", str(wave), "-o", str(out)]) == 0
    said = capsys.readouterr().out
    assert f"{wave} resampled from 30 to 120 fps to play in its own time (--align time)" in said
    assert em.read_bvh(out).n_frames == fast_walk.n_frames
    assert main(["mix", "--body", str(body), "--expressive", str(wave), "--align", "index", "-o", str(out)]) == 0
    assert "resampled" not in capsys.readouterr().out
