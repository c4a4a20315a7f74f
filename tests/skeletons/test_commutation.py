"""Edits commute with retargeting: editing a walk on another rig, E(R(x)), gives the motion that
retargeting the edit made on the Bandai-Namco walk gives, R(E(x)), as a user runs both with the
command line. Each frame's mean joint distance between the two stays within 1 % of the rig's
actor height on average and 3 % at worst (experiments/eval_commutation.py measures every rig)."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.cli import main
from expressive_mocap.skeletons import synthetic_walk

# Decoupling edits of the wave (a neutral walk's expression is next to nothing), exaggeration of
# the walk, and the walk's body with the wave's expression.
EDITS = {
    "modulate 0": lambda walk, wave, model, out: ["modulate", wave, "--scale", "0", "-o", out],
    "mix": lambda walk, wave, model, out: ["mix", "--body", walk, "--expressive", wave, "-o", out],
    "exaggerate 3": lambda walk, wave, model, out: [
        *("exaggerate", "--model", model, "--input", walk, "--to", "3", "--no-timing", "-o", out)
    ],
}


def run(*args) -> None:
    with contextlib.redirect_stdout(io.StringIO()):
        assert main([str(a) for a in args]) == 0, args


def apart(a, b, height: float) -> tuple[float, float]:
    """(mean, worst frame) of each frame's mean joint distance, % of ``height``."""
    per_frame = np.linalg.norm(em.read_bvh(a).positions() - em.read_bvh(b).positions(), axis=-1).mean(axis=1)
    return 100 * float(per_frame.mean()) / height, 100 * float(per_frame.max()) / height


@pytest.mark.real_data
@pytest.mark.parametrize("rig", ["cmu", "game"])
def test_edits_of_a_retargeted_walk_are_the_retargeted_edits(rig, bandai2_dir, walks_model, tmp_path):
    walk = bandai2_dir / "dataset-2_walk_normal_010.bvh"
    wave = bandai2_dir / "dataset-2_wave-left-hand_normal_001.bvh"
    model, target = tmp_path / "walks.npz", tmp_path / "target.bvh"
    walks_model.save(model)
    em.write_bvh(synthetic_walk(rig).motion, target)
    on_rig, wave_on_rig = tmp_path / "walk_R.bvh", tmp_path / "wave_R.bvh"
    run("retarget", walk, "--to", target, "-o", on_rig)
    run("retarget", wave, "--to", target, "-o", wave_on_rig)
    height = em.actor_height(em.read_bvh(on_rig).skeleton)
    for name, command in EDITS.items():
        edited_there, edited_here = tmp_path / "E_R.bvh", tmp_path / "E.bvh"
        run(*command(on_rig, wave_on_rig, model, edited_there))  # E(R(x))
        run(*command(walk, wave, model, edited_here))
        run("retarget", edited_here, "--to", target, "-o", tmp_path / "R_E.bvh")  # R(E(x))
        mean, worst = apart(edited_there, tmp_path / "R_E.bvh", height)
        assert mean <= 1.0 and worst <= 3.0, (name, mean, worst)
        start = wave_on_rig if name == "modulate 0" else on_rig
        assert apart(edited_there, start, height)[0] > 2 * max(mean, 0.05), name  # the edit did something


def largest_knee_flexion(path) -> float:
    """The largest angle between thigh and shank over the clip, mean of both knees (degrees)."""
    from expressive_mocap.body.jointmap import find_joint_map

    motion = em.read_bvh(path)
    jmap, p = find_joint_map(motion.skeleton), motion.positions()
    knees = []
    for side in ("left", "right"):
        hip, knee, ankle = (p[:, jmap[f"{side}_{r}"]] for r in ("upper_leg", "lower_leg", "foot"))
        thigh, shank = knee - hip, ankle - knee
        cosine = np.sum(thigh * shank, -1) / np.linalg.norm(thigh, axis=-1) / np.linalg.norm(shank, axis=-1)
        knees.append(np.degrees(np.arccos(np.clip(cosine, -1, 1))).max())
    return float(np.mean(knees))


@pytest.mark.real_data
def test_exaggeration_bends_the_knees_of_another_rig_as_on_the_bandai_body(bandai2_dir, walks_model, tmp_path):
    """A held-out normal walk exaggerated to 4 bends its knees 19 degrees more at their most, on the
    Bandai-Namco skeleton and retargeted onto the CMU-like rig alike (within 25 %). The feet were
    planted there as the decoupling edits plant them, moving the swing too: 13 degrees more."""
    walk = bandai2_dir / "dataset-2_walk_normal_010.bvh"
    model, target, on_rig = tmp_path / "walks.npz", tmp_path / "target.bvh", tmp_path / "walk_R.bvh"
    walks_model.save(model)
    em.write_bvh(synthetic_walk("cmu").motion, target)
    run("retarget", walk, "--to", target, "-o", on_rig)
    changes = []
    for source in (walk, on_rig):
        out = tmp_path / f"{source.stem}_4.bvh"
        run("exaggerate", "--model", model, "--input", source, "--to", "4", "--no-timing", "-o", out)
        changes.append(largest_knee_flexion(out) - largest_knee_flexion(source))
    assert changes[0] > 10 and abs(changes[1] / changes[0] - 1) <= 0.25, changes


@pytest.mark.real_data
def test_a_retimed_exaggeration_keeps_another_rigs_stance_feet(bandai2_dir, walks_model, tmp_path):
    """Exaggerated to 4 at its new timing (fewer frames, a longer stride) and carried back onto
    the CMU-like rig, a walk's stance feet move no faster than the input's own (1.2x at most,
    through each file's own contacts): they are held as the edit holds them on the model's body.
    Locked where the input retimed alike has them, whose feet slide with the stretched travel,
    they moved 3.3x."""
    from expressive_mocap.body.contacts import foot_contacts
    from expressive_mocap.body.conventions import upright
    from expressive_mocap.exaggeration.edit import stance_foot_speed

    model, target, walk, out = (tmp_path / n for n in ("walks.npz", "target.bvh", "walk.bvh", "out.bvh"))
    walks_model.save(model)
    em.write_bvh(synthetic_walk("cmu").motion, target)
    run("retarget", bandai2_dir / "dataset-2_walk_normal_010.bvh", "--to", target, "-o", walk)
    run("exaggerate", "--model", model, "--input", walk, "--to", "4", "-o", out)
    before, after = em.read_bvh(walk), em.read_bvh(out)
    assert after.n_frames != before.n_frames  # retimed
    speeds = [stance_foot_speed(m, foot_contacts(upright(m))) for m in (before, after)]
    assert speeds[1] <= 1.2 * speeds[0], speeds
