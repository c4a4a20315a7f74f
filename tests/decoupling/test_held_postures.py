"""Postures held through a clip, which a model not calibrated to the actor reads as expressive
(decoupling/algebra.py ``Decomposition.held_joints``): named by ``decouple`` so that a user whose
own neutral walk reads active learns why and what to do."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.cli import main
from expressive_mocap.decoupling import BodyModel, decompose, modulate
from expressive_mocap.decoupling.algebra import HELD_ACTIVITY, HELD_SHARE, Decomposition
from expressive_mocap.errors import ArgumentError
from expressive_mocap.procedural import bandai_like_skeleton, walk_and_wave
from expressive_mocap.skeletons.canonical import carried_for


def test_a_joint_is_held_when_active_in_most_frames():
    skeleton = bandai_like_skeleton()
    frames, joints = 100, skeleton.n_joints
    activity = np.zeros((frames, joints))
    held_frames = int(np.ceil(HELD_SHARE * frames))
    activity[:held_frames, 2] = 0.9  # just enough frames
    activity[: held_frames - 1, 3] = 0.9  # one frame short
    activity[:, 4] = HELD_ACTIVITY  # never above the level
    activity[::2, 5] = 1.0  # half the frames: a gesture, not a posture
    rotations = np.tile([0.0, 0.0, 0.0, 1.0], (frames, joints, 1))
    motion = em.Motion(skeleton, rotations, np.zeros((frames, joints, 3)), 1 / 30)
    parts = Decomposition(motion, rotations, rotations, activity)
    assert parts.held_joints() == [skeleton.names[2]]


def test_decouple_names_the_held_postures_of_an_uncalibrated_actor(other_dir, bandai2_dir, tmp_path, capsys):
    # The shared folder's 21-joint neutral walk: its actor's trunk leans and its right upper arm is
    # held otherwise than the training actor's, through the whole clip.
    walk = other_dir / "m21_walk.bvh"
    assert main(["decouple", str(walk), "-o", str(tmp_path / "a")]) == 0
    note = [line for line in capsys.readouterr().out.splitlines() if line.startswith("note:")]
    assert len(note) == 1 and "Spine" in note[0] and "calibrate" in note[0], note
    # The training session's own neutral walk holds nothing.
    neutral = bandai2_dir / "dataset-2_walk_normal_012.bvh"
    assert main(["decouple", str(neutral), "-o", str(tmp_path / "b")]) == 0
    assert "note:" not in capsys.readouterr().out
    # Calibrated to the actor, the model reads the habit as body mechanics: nothing to say.
    assert main(["decouple", str(walk), "--calibrate", str(walk), "-o", str(tmp_path / "c")]) == 0
    assert "note:" not in capsys.readouterr().out


def test_modulate_names_them_too_and_edits_as_before(other_dir, tmp_path, capsys):
    # modulate decomposes once for the edit and the note: the same file as the library's modulate.
    walk = other_dir / "m21_walk.bvh"
    assert main(["modulate", str(walk), "--scale", "0", "-o", str(tmp_path / "m.bvh")]) == 0
    assert "note: Spine" in capsys.readouterr().out
    model = BodyModel.load()
    carried = carried_for(em.read_bvh(walk), model, None)
    expected = carried.back(modulate(carried.body, 0.0, model), plant_feet=True)
    em.write_bvh(expected, tmp_path / "expected.bvh")
    assert (tmp_path / "m.bvh").read_bytes() == (tmp_path / "expected.bvh").read_bytes()
    # A decomposition of another motion is refused, not recomposed onto this one.
    with pytest.raises(ArgumentError, match="parts"):
        modulate(carried.body, 0.0, model, parts=decompose(walk_and_wave()[0], model))
