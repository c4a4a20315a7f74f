"""Edits of a motion of another rig, carried back onto the user's own skeleton, keep its stance
feet: after ``decouple``, ``modulate`` and ``mix`` on the canonical body, the feet are planted
again on the user's skeleton through the input's own contacts. Before, the body-mechanics file of
a 21-joint walk had its feet turned 22-26 degrees (mean) and 4 cm under the input's floor, a CMU
walk's 37-42 degrees and 6 cm.

Measured on the files written, as a viewer would (FK, the input's contacts read Y up): each
foot's world rotation against the input's through its contacts, the floor (5th percentile of the
lowest ankle or toe joint), and the stance ankles' horizontal speed."""

from __future__ import annotations

import numpy as np
import pytest

import expressive_mocap as em
from expressive_mocap.body.contacts import foot_contacts
from expressive_mocap.body.conventions import read_conventions, upright
from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.cli import main
from expressive_mocap.procedural import walk_and_wave
from expressive_mocap.rotations import quat
from expressive_mocap.skeletons import synthetic_walk


def feet(edited: em.Motion, source: em.Motion) -> tuple[float, float, float]:
    """(mean turn of the stance feet from the source's, degrees; the floor's change in % of the
    actor's height; the stance ankles' mean speed against the source's)."""
    jmap = find_joint_map(source.skeleton)
    conventions = read_conventions(source, jmap)
    contacts = foot_contacts(upright(source))
    (world_s, points_s), (world_e, points_e) = source.fk(), edited.fk()
    up = quat.rotate(quat.conjugate(conventions.rotation()), np.array([0.0, 1.0, 0.0]))  # in the file's axes
    angles, speeds = [], []
    for s, side in enumerate(("left", "right")):
        foot = jmap[f"{side}_foot"]
        on = contacts[:, s]
        angles.append(np.degrees(quat.angle(quat.mul(world_e[on, foot], quat.conjugate(world_s[on, foot])))))
        for points, store in ((points_s, 0), (points_e, 1)):
            step = np.diff(points[:, foot], axis=0)
            flat = np.linalg.norm(step - np.outer(step @ up, up), axis=1)
            speeds.append((store, flat[on[1:] & on[:-1]].mean()))
    joints = [jmap[f"{s}_{p}"] for s in ("left", "right") for p in ("foot", "toes")]

    def floor(points: np.ndarray) -> float:
        return float(np.percentile((points[:, joints] @ up).min(axis=1), 5))

    ratio = sum(v for k, v in speeds if k == 1) / sum(v for k, v in speeds if k == 0)
    return float(np.concatenate(angles).mean()), 100 * (floor(points_e) - floor(points_s)) / conventions.height, ratio


@pytest.fixture(scope="module")
def cmu_walk(tmp_path_factory):
    path = tmp_path_factory.mktemp("cmu") / "walk.bvh"
    em.write_bvh(synthetic_walk("cmu", seconds=4.0).motion, path)
    return path


def run(argv: list[str]) -> None:
    assert main(argv) == 0, argv


@pytest.mark.parametrize("command", ["decouple", "modulate0", "modulate2", "mix"])
def test_edits_of_a_cmu_walk_keep_its_stance_feet(command, cmu_walk, tmp_path):
    out = tmp_path / "out"
    if command == "decouple":
        run(["decouple", str(cmu_walk), "-o", str(out)])
        written = em.read_bvh(f"{out}_body.bvh")
    elif command == "mix":  # a wave of the Bandai skeleton laid on the CMU walk
        wave = tmp_path / "wave.bvh"
        em.write_bvh(walk_and_wave(seconds=3.0).waving, wave)
        run(["mix", "--body", str(cmu_walk), "--expressive", str(wave), "-o", f"{out}.bvh"])
        written = em.read_bvh(f"{out}.bvh")
    else:
        run(["modulate", str(cmu_walk), "--scale", command[-1], "-o", f"{out}.bvh"])
        written = em.read_bvh(f"{out}.bvh")
    turn, floor, speed = feet(written, em.read_bvh(cmu_walk))
    assert turn < 5.0, turn  # degrees
    assert abs(floor) < 1.0, floor  # % of the actor's height (1.7 cm)
    assert speed < 1.2, speed


@pytest.mark.real_data
@pytest.mark.parametrize("name", ["m21_walk", "cmu_scaled_131_03", "dme_comp_3d_2"])
def test_the_body_mechanics_of_real_walks_of_other_rigs_stand_as_they_do(name, other_dir, tmp_path):
    source = other_dir / f"{name}.bvh"
    run(["decouple", str(source), "-o", str(tmp_path / "x")])
    turn, floor, speed = feet(em.read_bvh(tmp_path / "x_body.bvh"), em.read_bvh(source))
    assert turn < 5.0 and abs(floor) < 1.0 and speed < 1.2, (name, turn, floor, speed)
