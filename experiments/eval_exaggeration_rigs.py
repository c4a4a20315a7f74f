"""Exaggeration on other rigs moves the knees and the trunk as it does on the Bandai-Namco body.

    python experiments/eval_exaggeration_rigs.py [--other DIR] [--data DIR]

A model of dataset-2's walks (takes 1-8 of exhausted, normal and active as 8 people at
intensities 1-3, trained here) exaggerates dataset-2's held-out normal walks (takes 10-13) to 4
and diminishes them to 0 (``exaggerate --no-timing``), on the Bandai-Namco skeleton and, each
walk retargeted first (``retarget --to``), on every synthetic rig and on the skeletons of the
shared folder's walks. On each written file, read with this folder's own BVH reader and SciPy
forward kinematics (:mod:`independent`):

- knee flexion: the largest angle between thigh and shank over the clip (degrees), mean of both
  knees; the edit's change is output minus input;
- lean: the mean angles of the hips-to-chest and the chest-to-head lines from the vertical
  (degrees, the rig's up axis; one hips-to-head line would also measure each rig's neck and
  head proportions).

Printed: per rig, the edits' mean change of knee flexion and of lean over the walks, and the
ratio to the change on the Bandai-Namco skeleton farthest from 1 among the changes of 2 degrees
or more there (target: within 25 %).

Data: Bandai-Namco-Research-Motiondataset (CC BY-NC 4.0); CMU Graphics Lab Motion Capture
Database; the 21-joint walks of the shared folder.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

import expressive_mocap as em
from expressive_mocap.body.conventions import read_conventions
from expressive_mocap.body.jointmap import find_joint_map
from expressive_mocap.rotations import quat
from independent import read_fk
from setting import arguments, bandai_dir, rig_targets, run, walks_model

TAKES = (10, 11, 12, 13)
LEVELS = (4, 0)


def measures(path: Path) -> tuple[float, float, float]:
    """(largest knee flexion, mean lean of the lower and of the upper trunk) of the file, degrees
    (joint roles read from its names)."""
    fk = read_fk(path)
    motion = em.read_bvh(path)  # for the joint map and the up axis only
    jmap = find_joint_map(motion.skeleton)
    up = quat.rotate(quat.conjugate(read_conventions(motion, jmap).rotation()), np.array([0.0, 1.0, 0.0]))
    p = fk.positions
    knees = []
    for side in ("left", "right"):
        hip, knee, ankle = (p[:, jmap[f"{side}_{r}"]] for r in ("upper_leg", "lower_leg", "foot"))
        thigh, shank = knee - hip, ankle - knee
        cosine = np.sum(thigh * shank, -1) / np.linalg.norm(thigh, axis=-1) / np.linalg.norm(shank, axis=-1)
        knees.append(np.degrees(np.arccos(np.clip(cosine, -1, 1))).max())
    leans = []
    for low, high in (("hips", "chest"), ("chest", "head")):
        line = p[:, jmap[high]] - p[:, jmap[low]]
        leans.append(np.degrees(np.arccos(np.clip(line @ up / np.linalg.norm(line, axis=-1), -1, 1))).mean())
    return float(np.mean(knees)), float(leans[0]), float(leans[1])


def main() -> None:
    args = arguments(__doc__)
    dataset = bandai_dir(args.data)
    walks = [dataset / f"dataset-2_walk_normal_{t:03d}.bvh" for t in TAKES]
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        model = work / "walks.npz"
        walks_model(dataset).save(model)
        targets: dict[str, Path | None] = {"bandai": None, **rig_targets(args.other, work)}
        changes: dict[str, np.ndarray] = {}
        for rig, target in targets.items():
            rows = []
            for walk in walks:
                source = walk
                if target is not None:
                    source = work / f"{rig}_{walk.name}"
                    run("retarget", walk, "--to", target, "-o", source)
                before = np.array(measures(source))
                row = []
                for level in LEVELS:
                    out = work / f"{rig}_{level}_{walk.name}"
                    run("exaggerate", "--model", model, "--input", source, "--to", level, "--no-timing", "-o", out)
                    row.append(np.array(measures(out)) - before)
                rows.append(np.concatenate(row))
            changes[rig] = np.mean(rows, axis=0)  # (knee, lower lean, upper lean) to 4, then to 0
        print(
            "| rig | to 4: knee | hips-chest | chest-head | to 0: knee | hips-chest | chest-head "
            "| worst ratio to Bandai's |"
        )
        print("|---|---|---|---|---|---|---|---|")
        bandai = changes["bandai"]
        telling = np.abs(bandai) >= 2.0
        for rig, c in changes.items():
            ratio = c[telling] / bandai[telling]
            worst = ratio[np.argmax(np.abs(ratio - 1))]
            cells = " | ".join(f"{v:+.1f}" for v in c)
            print(f"| {rig} | {cells} | {worst:.2f} |", flush=True)


if __name__ == "__main__":
    main()
